//! Marker detection per frame against aruco-rs (a pure-Rust port of js-aruco), one core: the
//! same synthetic frames of an `aruco_original` marker (the dictionary both read) on a
//! cluttered table, with noise, blur and changing light, at 640 x 480 and 1280 x 720. Each
//! side starts from the RGBA frame; Canopy's time is shown for detection alone and with the
//! pose. Runs alternate between the two; the median run is reported, with how many frames
//! each found the marker in and how far its corners were from the truth. A last row times a
//! grid board's markers found and its pose from them, Canopy alone (the peer has no boards).
//!
//! Run with `cargo bench -p canopy_bench --bench detection`.

use aruco_rs::ImageBuffer;
use aruco_rs::core::detector::Detector;
use aruco_rs::core::dictionary::{DICTIONARY_ARUCO, Dictionary as PeerDictionary};
use aruco_rs::simd::native::NativeCV;
use bevy_math::{DMat3, DVec2, DVec3};
use canopy_vision::Pose;
use canopy_vision::board::{Board, CharucoBoard, GridBoard};
use canopy_vision::camera::Intrinsics;
use canopy_vision::detect::{Scratch, Settings, detect};
use canopy_vision::dictionary::Dictionary;
use canopy_vision::gray::Gray;
use canopy_vision::pose::estimate;
use canopy_vision::synth::{SequenceSettings, photograph_print, render_frame};
use std::hint::black_box;
use std::time::Instant;

/// Frames a size.
const FRAMES: u32 = 24;
/// Timed runs of each side, alternating.
const RUNS: usize = 7;
/// The marker: an id of the dictionary both detectors know.
const ID: u32 = 300;

struct Frame {
    rgba: Vec<u8>,
    corners: [DVec2; 4],
}

/// Root-mean-square corner error over the frames where the marker was found, pixels.
fn corner_rms(found: &[Option<[DVec2; 4]>], frames: &[Frame]) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for (corners, frame) in found.iter().zip(frames) {
        // Either detector may start at another corner: the best of the four turns.
        if let Some(corners) = corners {
            let best = (0..4)
                .map(|turn| (0..4).map(|i| corners[(i + turn) % 4].distance_squared(frame.corners[i])).sum::<f64>())
                .fold(f64::INFINITY, f64::min);
            sum += best;
            n += 4;
        }
    }
    (sum / f64::from(n.max(1))).sqrt()
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let dictionary = Dictionary::named("aruco_original").expect("a predefined dictionary");
    let peer_dictionary = PeerDictionary::new(&DICTIONARY_ARUCO);
    let peer = Detector::new(&peer_dictionary, NativeCV);
    println!(
        "{FRAMES} frames a size, an aruco_original marker 0.1 m at 0.3 to 0.7 m, noise 3, blur up to 1 px, one core"
    );
    println!("| frame | detector | ms / frame | found | corner RMS px |");
    println!("|---|---|---|---|---|");
    for size in [[640, 480], [1280, 720]] {
        let settings = SequenceSettings {
            camera: Intrinsics::pinhole(size, 50.0),
            dictionary: dictionary.clone(),
            id: ID,
            side_m: 0.1,
            frames: FRAMES,
            distance_m: [0.3, 0.7],
            seed: 5,
            noise: 3.0,
            max_blur_px: 1.0,
            lighting: true,
            occlusion: false,
            look_away: false,
        };
        let frames: Vec<Frame> = (0..FRAMES)
            .map(|i| {
                let frame = render_frame(&settings, i);
                let rgba = frame.rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
                Frame { rgba, corners: frame.corners }
            })
            .collect();
        let [width, height] = size;
        let detector = Settings::default();
        let mut scratch = Scratch::default();
        let mut ours = |with_pose: bool| {
            frames
                .iter()
                .map(|frame| {
                    let gray = Gray::from_rgba(width, height, &frame.rgba);
                    let markers = detect(&gray, &dictionary, &detector, None, &mut scratch);
                    let marker = markers.into_iter().find(|m| m.id == ID)?;
                    let corners = marker.corners_f64();
                    if with_pose {
                        black_box(estimate(&corners, 0.1, &settings.camera));
                    }
                    Some(corners)
                })
                .collect::<Vec<_>>()
        };
        let theirs = || {
            frames
                .iter()
                .map(|frame| {
                    let image = ImageBuffer { data: &frame.rgba, width, height };
                    let marker = peer.detect(&image).into_iter().find(|m| m.id == ID as i32)?;
                    Some(marker.corners.map(|c| DVec2::new(f64::from(c.x), f64::from(c.y))))
                })
                .collect::<Vec<_>>()
        };
        let mut times = [Vec::new(), Vec::new(), Vec::new()];
        let (mut found_ours, mut found_theirs) = (Vec::new(), Vec::new());
        for run in 0..RUNS {
            for side in if run % 2 == 0 { [0, 1, 2] } else { [2, 1, 0] } {
                let started = Instant::now();
                match side {
                    0 => found_ours = ours(false),
                    1 => {
                        black_box(ours(true));
                    }
                    _ => found_theirs = theirs(),
                };
                times[side].push(started.elapsed().as_secs_f64() * 1e3 / f64::from(FRAMES));
            }
        }
        let count = |found: &[Option<[DVec2; 4]>]| found.iter().filter(|f| f.is_some()).count();
        let label = format!("{width} x {height}");
        let [detection, with_pose, peer_ms] = times.map(median);
        let rows = [
            ("Canopy, detection", detection, &found_ours),
            ("Canopy, detection and pose", with_pose, &found_ours),
            ("aruco-rs 0.1.0, detection", peer_ms, &found_theirs),
        ];
        for (name, ms, found) in rows {
            println!("| {label} | {name} | {ms:.2} | {}/{FRAMES} | {:.2} |", count(found), corner_rms(found, &frames));
        }
        println!("| {label} | ratio aruco-rs / Canopy detection | {:.2} | | |", peer_ms / detection);
    }
    let dictionary = Dictionary::named("6x6_250").expect("a predefined dictionary");
    let grid = GridBoard::new([5, 4], 0.03, 0.006, 0, &dictionary).expect("a board the dictionary holds");
    board_row(RUNS, Board::Grid(grid), "a 5 x 4 grid board");
    let charuco = CharucoBoard::new([6, 5], 0.027, 0.018, 0, false, &dictionary).expect("a board the dictionary holds");
    board_row(RUNS, Board::Charuco(charuco), "a 6 x 5 ChArUco board");
}

/// A board photographed from ten sides at 640 x 480: the board's markers and points found and
/// its pose from them, per frame (the AR scene's work when it stands on a board).
fn board_row(runs: usize, board: Board, label: &str) {
    let dictionary = Dictionary::named("6x6_250").expect("a predefined dictionary");
    let print = board.image(&dictionary, 4000.0, 0.006).expect("a printable board");
    let camera = Intrinsics::pinhole([640, 480], 50.0);
    let centre = (board.size_m() * 0.5).extend(0.0);
    let frames: Vec<Gray> = (0..10)
        .map(|k| {
            let turn = -0.45 + 0.1 * f64::from(k);
            let rotation = DMat3::from_rotation_y(turn) * DMat3::from_rotation_x(-0.4);
            let pose = Pose { rotation, translation: DVec3::new(0.0, 0.0, 0.4) - rotation * centre };
            photograph_print(&print, 4000.0, 0.006, &pose, &camera)
        })
        .collect();
    let mut scratch = Scratch::default();
    let mut times = Vec::new();
    let mut found = 0;
    for _ in 0..runs {
        let started = Instant::now();
        found = frames
            .iter()
            .filter_map(|frame| {
                let markers = detect(frame, &dictionary, &Settings::default(), Some(&camera), &mut scratch);
                black_box(board.pose(&board.points(frame, &markers), &markers, &camera))
            })
            .count();
        times.push(started.elapsed().as_secs_f64() * 1e3 / frames.len() as f64);
    }
    println!("| 640 x 480 | Canopy, {label}: detection and pose | {:.2} | {found}/{} | |", median(times), frames.len());
}
