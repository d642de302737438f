//! `canopy ar`: printable markers, synthetic camera sequences with known poses, and the marker
//! detector on images.

use super::ar_calibrate::CalibrateArgs;
use super::ar_sweep::SweepArgs;
use super::board_layout::BoardLayout;
use super::{dictionary_of, parse_size, refuse_to_replace};
use crate::ar::calibration as calib;
use crate::ar::frames::load_image;
use crate::ar::report::marker_json;
use crate::ar::sample::{FrameFormat, write_sequence};
use bevy::math::UVec2;
use canopy_vision::board::Board;
use canopy_vision::synth::{SequenceSettings, marker_image};
use canopy_vision::{Gray, Intrinsics, Scratch, Settings, detect, pose::estimate};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Subcommand, Debug)]
/// `canopy ar ...`.
pub enum ArCommand {
    /// Write a marker as a PNG for printing: its black border, its cells and a white margin.
    Marker {
        /// The dictionary, by OpenCV's name (4x4_50, 5x5_100, 6x6_250, aruco_original, ...) or a
        /// dictionary file as OpenCV writes it.
        #[arg(long, default_value = "6x6_250")]
        dictionary: String,
        /// The marker's id in the dictionary.
        #[arg(long)]
        id: u32,
        /// Pixels a cell, 1 to 1000.
        #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u32).range(1..=1000))]
        cell_px: u32,
        /// White margin around the border, in cells (0 to 10).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=10))]
        margin: u32,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
        /// Replace `--out` if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Write a board as a PNG for printing: an ArUco grid board or a ChArUco board, laid out as
    /// OpenCV's `GridBoard` and `CharucoBoard`.
    Board(BoardArgs),
    /// Calibrate a camera from photographs of a printed board, without OpenCV: Zhang's method
    /// refined by Levenberg-Marquardt over the focal lengths, principal point and OpenCV's
    /// five distortion coefficients; prints each view's reprojection error and writes the
    /// calibration file.
    Calibrate(CalibrateArgs),
    /// Measure the marker detector on harder and harder synthetic frames, one condition at a
    /// time (distance, angle, motion blur, defocus, noise, contrast, uneven light): detection
    /// rate and pose error at each step, as a table, JSON and a plot.
    Sweep(SweepArgs),
    /// Write a synthetic camera sequence of a marker on a table under known poses, with noise,
    /// blur, changing light and occlusions: frames, `calibration.yaml` and `truth.json`.
    Sequence(SequenceArgs),
    /// Find markers in images and print them as JSON: per image its markers, each with its id,
    /// corners (OpenCV's order and pixel convention) and, given a calibration and a side, its
    /// pose as OpenCV's rvec and tvec with the reprojection error.
    Detect {
        /// PNG or JPEG images.
        #[arg(required = true)]
        images: Vec<PathBuf>,
        /// The camera's calibration in OpenCV's YAML or JSON layout.
        #[arg(long)]
        calibration: Option<PathBuf>,
        /// The dictionary, by OpenCV's name or a dictionary file as OpenCV writes it.
        #[arg(long, default_value = "6x6_250")]
        dictionary: String,
        /// The markers' side (the black square) in metres, for their poses.
        #[arg(long, value_parser = parse_side)]
        side: Option<f64>,
    },
}

/// `canopy ar board`.
#[derive(Args, Debug)]
pub struct BoardArgs {
    #[command(flatten)]
    layout: BoardLayout,
    /// Pixels a printed metre: 11811 prints at 300 dots an inch.
    #[arg(long, default_value_t = 11811.0)]
    pixels_per_metre: f64,
    /// White margin round the board, metres (a grid's separation, or a ChArUco board's square
    /// less its marker, by default).
    #[arg(long)]
    margin_m: Option<f64>,
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
}

/// `canopy ar sequence`.
#[derive(Args, Debug)]
pub struct SequenceArgs {
    /// The folder to write (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// Frames, 1 to 10000.
    #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    frames: u32,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "640x480", value_parser = parse_size)]
    size: UVec2,
    /// The camera's vertical field of view, degrees (10 to 120).
    #[arg(long, default_value_t = 50.0)]
    fov: f64,
    /// The dictionary, by OpenCV's name or a dictionary file as OpenCV writes it.
    #[arg(long, default_value = "6x6_250")]
    dictionary: String,
    /// The marker's id.
    #[arg(long, default_value_t = 23)]
    id: u32,
    /// The marker's side (the black square) in metres.
    #[arg(long, default_value_t = 0.1, value_parser = parse_side)]
    side: f64,
    /// The seed of the noise, occlusions and clutter.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Noise, standard deviation in grey levels (0 to 50).
    #[arg(long, default_value_t = 3.0)]
    noise: f32,
    /// The largest blur, standard deviation in pixels (0 to 5).
    #[arg(long, default_value_t = 1.0)]
    blur: f32,
    /// The lens's radial distortion k1 (-0.5 to 0.5; negative for barrel distortion), written
    /// to the calibration with the rest.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    k1: f64,
    /// Keep the light steady.
    #[arg(long)]
    steady_light: bool,
    /// Nothing passes in front of the marker.
    #[arg(long)]
    no_occlusion: bool,
    /// The camera never looks away from the marker.
    #[arg(long)]
    no_look_away: bool,
    /// Write JPEG frames at this quality (1 to 100) instead of PNG.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100))]
    jpeg: Option<u8>,
    /// Write into `--out` even if it holds files.
    #[arg(long)]
    force: bool,
}

/// A marker's side in metres, above 0 and at most 100.
fn parse_side(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(side) if side.is_finite() && side > 0.0 && side <= 100.0 => Ok(side),
        _ => Err(format!("expected a side in metres greater than 0 and at most 100, found `{text}`")),
    }
}

impl ArCommand {
    /// Runs the augmented-reality command.
    pub fn run(self) -> ExitCode {
        match self {
            ArCommand::Marker { dictionary, id, cell_px, margin, out, force } => {
                write_marker(&dictionary, id, cell_px, margin, &out, force)
            }
            ArCommand::Board(args) => write_board(&args),
            ArCommand::Calibrate(args) => args.run(),
            ArCommand::Sequence(args) => sequence(&args),
            ArCommand::Sweep(args) => args.run(),
            ArCommand::Detect { images, calibration, dictionary, side } => {
                detect_markers(&images, calibration.as_deref(), &dictionary, side)
            }
        }
    }
}

/// `canopy ar marker`: exit 0 with the file written, 1 if it could not be, 2 for bad settings.
fn write_marker(dictionary: &str, id: u32, cell_px: u32, margin: u32, out: &Path, force: bool) -> ExitCode {
    let dictionary = match dictionary_of(dictionary) {
        Ok(dictionary) => dictionary,
        Err(error) => {
            eprintln!("canopy ar marker: {error}");
            return ExitCode::from(2);
        }
    };
    if let Some(refused) = refuse_to_replace(out, force) {
        return refused;
    }
    let Some(marker) = marker_image(&dictionary, id, cell_px, margin) else {
        eprintln!("canopy ar marker: {dictionary} has markers 0 to {}, not {id}", dictionary.len() - 1);
        return ExitCode::from(2);
    };
    let (width, height) = (marker.width, marker.height);
    match save_gray(marker, out) {
        Ok(()) => {
            println!("{}: {dictionary} marker {id}, {width} x {height} pixels", out.display());
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("{error}");
            ExitCode::from(1)
        }
    }
}

/// `canopy ar board`: exit 0 with the file written, 1 if it could not be, 2 for bad settings.
fn write_board(args: &BoardArgs) -> ExitCode {
    let usage = |error: String| {
        eprintln!("canopy ar board: {error}");
        ExitCode::from(2)
    };
    let (board, dictionary) = match args.layout.board() {
        Ok(found) => found,
        Err(error) => return usage(error),
    };
    let margin_m = args.margin_m.unwrap_or(match board {
        Board::Grid(grid) => grid.separation_m,
        Board::Charuco(charuco) => charuco.square_m - charuco.marker_m,
    });
    let image = match (margin_m.is_finite() && margin_m >= 0.0 && args.pixels_per_metre.is_finite())
        .then(|| board.image(&dictionary, args.pixels_per_metre, margin_m))
        .flatten()
    {
        Some(image) => image,
        None => return usage("the image would be empty or more than 16384 pixels a side".into()),
    };
    if let Some(refused) = refuse_to_replace(&args.out, args.force) {
        return refused;
    }
    let (width, height) = (image.width, image.height);
    match save_gray(image, &args.out) {
        Ok(()) => {
            let (first, count) = match board {
                Board::Grid(grid) => (grid.first_id, grid.markers[0] * grid.markers[1]),
                Board::Charuco(charuco) => (charuco.first_id, charuco.marker_count()),
            };
            println!(
                "{}: {dictionary} markers {first} to {}, {width} x {height} pixels; print it {:.1} x {:.1} cm",
                args.out.display(),
                first + count - 1,
                f64::from(width) / args.pixels_per_metre * 100.0,
                f64::from(height) / args.pixels_per_metre * 100.0
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("{error}");
            ExitCode::from(1)
        }
    }
}

/// Writes a grey image as a PNG, or says why it could not be.
fn save_gray(image: Gray, out: &Path) -> Result<(), String> {
    let Some(png) = image::GrayImage::from_raw(image.width, image.height, image.pixels) else {
        return Err(format!("{}: the image's pixels do not fill it", out.display()));
    };
    png.save(out).map_err(|error| format!("{}: {error}", out.display()))
}

/// `canopy ar sequence`: exit 0 with the files written, 1 if they could not be, 2 for bad
/// settings.
fn sequence(args: &SequenceArgs) -> ExitCode {
    let settings = dictionary_of(&args.dictionary).and_then(|dictionary| {
        if args.id >= dictionary.len() {
            return Err(format!("{dictionary} has markers 0 to {}, not {}", dictionary.len() - 1, args.id));
        }
        if !(10.0..=120.0).contains(&args.fov)
            || !(0.0..=50.0).contains(&args.noise)
            || !(0.0..=5.0).contains(&args.blur)
        {
            return Err("--fov is 10 to 120 degrees, --noise 0 to 50, --blur 0 to 5".into());
        }
        Ok(SequenceSettings {
            camera: Intrinsics::pinhole([args.size.x, args.size.y], args.fov),
            dictionary,
            id: args.id,
            side_m: args.side,
            frames: args.frames,
            distance_m: [3.0 * args.side, 7.0 * args.side],
            seed: args.seed,
            noise: args.noise,
            max_blur_px: args.blur,
            lighting: !args.steady_light,
            occlusion: !args.no_occlusion,
            look_away: !args.no_look_away,
        })
    });
    let settings = match settings {
        Ok(settings) => settings,
        Err(error) => {
            eprintln!("canopy ar sequence: {error}");
            return ExitCode::from(2);
        }
    };
    let occupied = std::fs::read_dir(&args.out).is_ok_and(|mut entries| entries.next().is_some());
    if occupied && !args.force {
        eprintln!(
            "{}: the folder holds files; choose another --out, or add --force to write into it",
            args.out.display()
        );
        return ExitCode::from(1);
    }
    let format = args.jpeg.map_or(FrameFormat::Png, FrameFormat::Jpeg);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    match write_sequence(&settings, &args.out, format, threads) {
        Ok(files) => {
            println!("{}: {} frames, calibration.yaml, truth.json", args.out.display(), files.len().saturating_sub(2));
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("canopy ar sequence: {error}");
            ExitCode::from(1)
        }
    }
}

/// `canopy ar detect`: prints the JSON; exit 0 if every image was read, 1 if some could not
/// be, 2 for bad settings.
fn detect_markers(images: &[PathBuf], calibration: Option<&Path>, dictionary: &str, side: Option<f64>) -> ExitCode {
    let dictionary = match dictionary_of(dictionary) {
        Ok(dictionary) => dictionary,
        Err(error) => {
            eprintln!("canopy ar detect: {error}");
            return ExitCode::from(2);
        }
    };
    let calibration = match calibration.map(calib::read).transpose() {
        Ok(calibration) => calibration,
        Err(error) => {
            eprintln!("{error}");
            return ExitCode::from(2);
        }
    };
    let mut scratch = Scratch::default();
    let mut all_read = true;
    let mut results = Vec::new();
    for path in images {
        let image = match load_image(path, None) {
            Ok(image) => image,
            Err(error) => {
                eprintln!("{error}");
                all_read = false;
                results.push(serde_json::json!({"image": path, "error": error}));
                continue;
            }
        };
        let size = [image.width(), image.height()];
        let camera = match calibration.as_ref().map(|c| c.for_frames(size)).transpose() {
            Ok(camera) => camera,
            Err(error) => {
                eprintln!("{}: {error}", path.display());
                all_read = false;
                results.push(serde_json::json!({"image": path, "error": error}));
                continue;
            }
        };
        let gray = Gray::from_rgba(size[0], size[1], image.as_raw());
        let markers: Vec<serde_json::Value> =
            detect(&gray, &dictionary, &Settings::default(), camera.as_ref(), &mut scratch)
                .into_iter()
                .map(|marker| {
                    let corners = marker.corners_f64();
                    let pose = camera.as_ref().zip(side).and_then(|(camera, side)| estimate(&corners, side, camera));
                    let mut entry = marker_json(&corners, pose.as_ref());
                    entry["id"] = serde_json::json!(marker.id);
                    entry
                })
                .collect();
        results.push(serde_json::json!({"image": path, "markers": markers}));
    }
    println!("{}", serde_json::to_string_pretty(&results).unwrap_or_default());
    if all_read { ExitCode::SUCCESS } else { ExitCode::from(1) }
}
