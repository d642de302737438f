//! The augmented-reality overlay over the sample sequence, whose true poses are in its
//! `truth.json`: the marker found in every frame showing it whole, its pose within 1 % of the
//! distance and 1 degree, nothing taken for it in frames without it, the drawn marker within
//! a pixel of the photographed one, a lost marker held then hidden, and bad input reported
//! with its file.

use crate::common::{entity, path};
use bevy::math::{DVec3, UVec2};
use canopy::run::{Recording, RunOptions, run_recorded};
use canopy_vision::pose::Pose;
use serde_json::Value;
use std::path::Path;

pub(crate) const SAMPLE: &str = "scenes/ar/table";

pub(crate) fn run(scene: &Path, seconds: f64, size: UVec2, record: bool) -> Value {
    let frames_folder = tempfile::tempdir().unwrap();
    let options =
        RunOptions { scene: scene.to_path_buf(), frames: (seconds * 60.0) as u64, timeline: None, size, log: false };
    let recording = Recording { folder: frames_folder.path().to_path_buf(), every: 1 };
    let output = run_recorded(&options, record.then_some(&recording)).unwrap_or_else(|e| panic!("{e}"));
    if record {
        let written = std::fs::read_dir(frames_folder.path()).unwrap().count() as u64;
        assert_eq!(written, options.frames, "one recorded frame a step");
    }
    output.dump
}

fn vector(value: &Value) -> DVec3 {
    let a: Vec<f64> = value.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    DVec3::new(a[0], a[1], a[2])
}

pub(crate) fn truth() -> Value {
    serde_json::from_str(&std::fs::read_to_string(path(SAMPLE).join("truth.json")).unwrap()).unwrap()
}

/// Checks an overlay's records of the sample sequence against its truth: the marker found in
/// every frame showing it whole, within `distance_share` of the distance, `degrees` and
/// `error_px` of reprojection error; nothing taken for it in frames without it (held for half
/// a second). Returns the frames showing it whole and those without it.
pub(crate) fn assert_tracked(overlay: &Value, distance_share: f64, degrees: f64, error_px: f64) -> (usize, usize) {
    let truth = truth();
    let truth_frames = truth["frames"].as_array().unwrap();
    let (mut whole, mut absent, mut last_found_s) = (0, 0, f64::NEG_INFINITY);
    for record in overlay["poses"].as_array().unwrap() {
        let index = record["frame"].as_u64().unwrap() as usize;
        let time = record["time_s"].as_f64().unwrap();
        let expected = &truth_frames[index];
        let marker = record["marker"].as_str().unwrap();
        match expected["view"].as_str().unwrap() {
            "whole" => {
                whole += 1;
                assert_eq!(marker, "found", "frame {index}");
                let true_pose = Pose::from_rvec(vector(&expected["rvec"]), vector(&expected["tvec"]));
                let pose = Pose::from_rvec(vector(&record["rvec"]), vector(&record["tvec"]));
                let distance = true_pose.translation.length();
                let position = pose.translation.distance(true_pose.translation) / distance;
                let angle = pose.angle_to(&true_pose).to_degrees();
                assert!(
                    position < distance_share && angle < degrees,
                    "frame {index}: {position} of the distance, {angle} degrees"
                );
                assert!(record["reprojection_error_px"].as_f64().unwrap() < error_px, "frame {index}");
            }
            "absent" => {
                absent += 1;
                let expected = if time - last_found_s <= 0.5 { "held" } else { "not found" };
                assert_eq!(marker, expected, "frame {index}: nothing is taken for the marker");
            }
            _ => assert!(["found", "held"].contains(&marker), "frame {index}: {marker}"),
        }
        if marker == "found" {
            last_found_s = time;
        }
    }
    (whole, absent)
}

#[test]
fn the_sample_sequence_is_tracked_within_a_percent_and_a_degree() {
    let dump = run(&path("scenes/ar.yaml"), 3.0, UVec2::new(640, 480), true);
    let overlay = entity(&dump, "overlay");
    let records = overlay["poses"].as_array().unwrap();
    assert_eq!(records.len(), 90, "every frame of the 3 s at 30 a second shown once");
    let (whole, absent) = assert_tracked(overlay, 0.01, 1.0, 0.5);
    assert!(whole >= 60 && absent >= 5, "{whole} whole, {absent} absent");
    let drawn = overlay["overlay_error_max_px"].as_f64().unwrap();
    assert!(drawn > 0.0 && drawn < 1.0, "the drawn marker's corners are {drawn} px from the found ones");
}

#[test]
fn the_marker_found_is_drawn_over_and_the_photograph_shows_around_it() {
    let options =
        RunOptions { scene: path("scenes/ar.yaml"), frames: 2, timeline: None, size: UVec2::new(640, 480), log: false };
    let output = run_recorded(&options, None).unwrap();
    let overlay = entity(&output.dump, "overlay");
    assert_eq!(overlay["overlay_visible"], true);
    // The first frame as the camera took it: where the scene is not drawn, the framebuffer
    // holds its pixels (no distortion in the sample, the same size).
    let photograph = image::open(path(SAMPLE).join("frame-0001.jpg")).unwrap().to_rgba8();
    let (mut same, mut drawn) = (0, 0);
    for (pixel, photo) in output.framebuffer.color().chunks_exact(4).zip(photograph.as_raw().chunks_exact(4)) {
        if pixel.iter().zip(photo).all(|(a, b)| a.abs_diff(*b) <= 1) {
            same += 1;
        } else {
            drawn += 1;
        }
    }
    assert!(same > 640 * 480 / 2, "the photograph fills the background: {same} pixels");
    assert!(drawn > 2000, "the scene is drawn over it: {drawn} pixels");
}

/// A scene over `frames` of the sample copied into a folder, with `hold_s`.
fn copied_scene(folder: &Path, frames: &[usize], hold_s: f64) -> std::path::PathBuf {
    let clip = folder.join("clip");
    std::fs::create_dir_all(&clip).unwrap();
    for (i, &frame) in frames.iter().enumerate() {
        let name = format!("frame-{frame:04}.jpg");
        std::fs::copy(path(SAMPLE).join(&name), clip.join(format!("{i:03}.jpg"))).unwrap();
    }
    std::fs::copy(path(SAMPLE).join("calibration.yaml"), folder.join("camera.yaml")).unwrap();
    let scene = folder.join("scene.yaml");
    std::fs::write(
        &scene,
        format!(
            "entities:\n  - name: overlay\n    ar: {{frames: clip, fps: 30, loop: false, calibration: camera.yaml, \
             dictionary: 6x6_250, marker_id: 23, marker_side_m: 0.1, scale: 0.02, hold_s: {hold_s}}}\n  \
             - shape: {{primitive: box, size: 2}}\n"
        ),
    )
    .unwrap();
    scene
}

#[test]
fn a_lost_marker_is_held_for_its_time_then_the_scene_is_hidden() {
    let truth = truth();
    let view = |i: usize| truth["frames"][i - 1]["view"].as_str().unwrap().to_string();
    let whole = (1..=90).find(|&i| view(i) == "whole").unwrap();
    let absent = (1..=90).find(|&i| view(i) == "absent").unwrap();
    // One frame with the marker, then 20 without (two thirds of a second at 30 a second).
    let frames: Vec<usize> = std::iter::once(whole).chain(std::iter::repeat_n(absent, 20)).collect();
    for (hold_s, held) in [(0.3, 9), (0.0, 0)] {
        let folder = tempfile::tempdir().unwrap();
        let dump = run(&copied_scene(folder.path(), &frames, hold_s), 0.7, UVec2::new(320, 240), false);
        let overlay = entity(&dump, "overlay");
        let marks: Vec<&str> =
            overlay["poses"].as_array().unwrap().iter().map(|r| r["marker"].as_str().unwrap()).collect();
        assert_eq!(marks[0], "found");
        assert_eq!(marks.iter().filter(|m| **m == "held").count(), held, "hold {hold_s} s: {marks:?}");
        assert!(marks[1 + held..].iter().all(|m| *m == "not found"), "{marks:?}");
        assert_eq!(overlay["overlay_visible"], false, "hidden once the hold is over");
    }
}

#[test]
fn an_unreadable_frame_is_named_and_the_run_goes_on() {
    let folder = tempfile::tempdir().unwrap();
    let scene = copied_scene(folder.path(), &[1, 2, 3], 0.5);
    std::fs::write(folder.path().join("clip/001.jpg"), b"no image").unwrap();
    let dump = run(&scene, 0.1, UVec2::new(320, 240), false);
    let records = entity(&dump, "overlay")["poses"].as_array().unwrap().clone();
    let marks: Vec<&str> = records.iter().map(|r| r["marker"].as_str().unwrap()).collect();
    assert_eq!(marks, vec!["found", "unreadable", "found"]);
    assert!(records[1]["error"].as_str().unwrap().contains("001.jpg"), "{}", records[1]["error"]);
}

#[test]
fn bad_sources_and_calibrations_are_located_errors() {
    let kinds = canopy::app::entity_kinds();
    let folder = tempfile::tempdir().unwrap();
    let scene = copied_scene(folder.path(), &[1], 0.5);
    let text = std::fs::read_to_string(&scene).unwrap();
    let check = |scene_text: &str| {
        std::fs::write(&scene, scene_text).unwrap();
        kinds.load(&scene).unwrap_err()
    };
    // No frames in the folder.
    std::fs::create_dir_all(folder.path().join("nothing")).unwrap();
    let error = check(&text.replace("frames: clip", "frames: nothing"));
    assert_eq!(error.location.map(|l| l.0), Some(3), "{error}");
    assert!(error.message.contains("entities[0].ar.frames") && error.message.contains("no frames"), "{error}");
    // An unknown dictionary and a marker the dictionary lacks.
    let error = check(&text.replace("6x6_250", "6x6_9"));
    assert!(error.message.contains("unknown dictionary `6x6_9`") && error.location.is_some(), "{error}");
    let error = check(&text.replace("marker_id: 23", "marker_id: 250"));
    assert!(error.message.contains("marker_id") && error.message.contains("0 to 249"), "{error}");
    // A calibration without its distortion: the calibration file is named.
    let calibration = std::fs::read_to_string(folder.path().join("camera.yaml")).unwrap();
    let cut = calibration.split("distortion_coefficients").next().unwrap().to_string();
    std::fs::write(folder.path().join("camera.yaml"), cut).unwrap();
    let error = check(&text);
    assert_eq!(error.path, folder.path().join("camera.yaml"), "{error}");
    assert!(error.message.contains("missing distortion_coefficients"), "{error}");
    // A calibration for frames of another shape.
    std::fs::write(folder.path().join("camera.yaml"), calibration.replace("image_height: 480", "image_height: 400"))
        .unwrap();
    let error = check(&text);
    assert!(error.message.contains("entities[0].ar.calibration") && error.message.contains("another shape"), "{error}");
}

#[test]
fn through_a_distorting_lens_the_straightened_frame_and_the_scene_line_up() {
    use canopy::ar::sample::{FrameFormat, write_sequence};
    use canopy_vision::camera::{Distortion, Intrinsics};
    use canopy_vision::dictionary::Dictionary;
    use canopy_vision::synth::SequenceSettings;
    let folder = tempfile::tempdir().unwrap();
    let camera = Intrinsics {
        distortion: Distortion([-0.3, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ..Intrinsics::pinhole([480, 360], 60.0)
    };
    let settings = SequenceSettings {
        camera,
        dictionary: Dictionary::named("5x5_100").unwrap(),
        id: 42,
        side_m: 0.08,
        frames: 12,
        distance_m: [0.25, 0.5],
        seed: 3,
        noise: 2.0,
        max_blur_px: 0.8,
        lighting: true,
        occlusion: false,
        look_away: false,
    };
    write_sequence(&settings, &folder.path().join("clip"), FrameFormat::Png, 2).unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(
        &scene,
        "entities:\n  - name: overlay\n    ar: {frames: clip, calibration: clip/calibration.yaml, dictionary: 5x5_100, \
         marker_id: 42, marker_side_m: 0.08, scale: 0.02}\n  - shape: {primitive: box, size: [4, 1, 4]}\n",
    )
    .unwrap();
    // A view of another shape than the frames': the straightened frame is scaled into it.
    let dump = run(&scene, 0.4, UVec2::new(400, 400), true);
    let overlay = entity(&dump, "overlay");
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(folder.path().join("clip/truth.json")).unwrap()).unwrap();
    for record in overlay["poses"].as_array().unwrap() {
        let expected = &truth["frames"][record["frame"].as_u64().unwrap() as usize];
        assert_eq!(record["marker"], "found", "{record}");
        let true_pose = Pose::from_rvec(vector(&expected["rvec"]), vector(&expected["tvec"]));
        let pose = Pose::from_rvec(vector(&record["rvec"]), vector(&record["tvec"]));
        assert!(pose.translation.distance(true_pose.translation) < 0.01 * true_pose.translation.length());
        assert!(pose.angle_to(&true_pose).to_degrees() < 1.0);
    }
    let drawn = overlay["overlay_error_max_px"].as_f64().unwrap();
    assert!(drawn > 0.0 && drawn < 1.0, "the drawn marker is {drawn} px from the found one, its distortion removed");
}

#[test]
fn a_scene_stands_on_a_grid_or_charuco_board_found_from_all_of_it() {
    use canopy_vision::board::{Board, CharucoBoard, GridBoard};
    use canopy_vision::synth::photograph_print;
    use canopy_vision::{Dictionary, Intrinsics};
    let dictionary = Dictionary::named("6x6_250").unwrap();
    let grid = Board::Grid(GridBoard::new([4, 3], 0.04, 0.01, 0, &dictionary).unwrap());
    let charuco = Board::Charuco(CharucoBoard::new([5, 4], 0.035, 0.025, 0, false, &dictionary).unwrap());
    // The grid's pose from every marker's corners, the ChArUco board's from its 12 inner
    // chessboard corners.
    let boards = [
        (grid, "{markers: [4, 3], marker_m: 0.04, separation_m: 0.01}", 12, 48),
        (charuco, "{squares: [5, 4], square_m: 0.035, marker_m: 0.025}", 10, 12),
    ];
    for (board, entry, markers, points) in boards {
        // Three photographs of the board from different sides, and their calibration.
        let folder = tempfile::tempdir().unwrap();
        let (pixels_per_metre, margin_m) = (4000.0, 0.01);
        let print = board.image(&dictionary, pixels_per_metre, margin_m).unwrap();
        let camera = Intrinsics::pinhole([640, 480], 50.0);
        let clip = folder.path().join("clip");
        std::fs::create_dir(&clip).unwrap();
        let centre = (board.size_m() * 0.5).extend(0.0);
        let mut truths = Vec::new();
        for (k, (turn, tilt)) in [(0.3, -0.5), (-0.2, -0.7), (0.1, -0.3)].into_iter().enumerate() {
            let rotation = bevy::math::DMat3::from_rotation_y(turn) * bevy::math::DMat3::from_rotation_x(tilt);
            let pose = Pose { rotation, translation: DVec3::new(0.01, 0.0, 0.5) - rotation * centre };
            let frame = photograph_print(&print, pixels_per_metre, margin_m, &pose, &camera);
            image::GrayImage::from_raw(640, 480, frame.pixels).unwrap().save(clip.join(format!("{k}.png"))).unwrap();
            truths.push(pose);
        }
        std::fs::write(folder.path().join("camera.yaml"), canopy::ar::calibration::to_yaml(&camera)).unwrap();
        let scene = folder.path().join("scene.yaml");
        std::fs::write(
            &scene,
            format!(
                "entities:\n  - name: overlay\n    ar: {{frames: clip, fps: 30, loop: false, calibration: camera.yaml, \
                 dictionary: 6x6_250, board: {entry}, scale: 0.02}}\n  - shape: {{primitive: box, size: 2}}\n"
            ),
        )
        .unwrap();
        let dump = run(&scene, 0.1, UVec2::new(320, 240), false);
        let overlay = entity(&dump, "overlay");
        assert!(overlay["board"].is_object(), "{overlay}");
        let poses = overlay["poses"].as_array().unwrap();
        assert_eq!(poses.len(), 3);
        for (pose, truth) in poses.iter().zip(&truths) {
            let found = (pose["marker"].as_str(), pose["board_markers"].as_u64(), pose["board_points"].as_u64());
            assert_eq!(found, (Some("found"), Some(markers), Some(points)), "{pose}");
            // The pose is the board's centre, as a marker there would have it.
            let tvec = vector(&pose["tvec"]);
            assert!(tvec.distance(truth.apply(centre)) < 1e-3, "{tvec} against {}", truth.apply(centre));
            assert!(pose["reprojection_error_px"].as_f64().unwrap() < 0.3, "{pose}");
        }
        // Drawn within a pixel of where every point of the board was photographed.
        assert!(overlay["overlay_error_max_px"].as_f64().unwrap() < 1.0, "{overlay}");
    }
}

#[test]
fn a_scene_reads_its_markers_from_a_dictionary_file_of_the_users() {
    use canopy_vision::synth::{marker_image, photograph_print};
    use canopy_vision::{Intrinsics, Pose};
    let folder = tempfile::tempdir().unwrap();
    std::fs::copy(path("tests/charuco/opencv_dictionary.yml"), folder.path().join("mine.yml")).unwrap();
    let dictionary = canopy::ar::dictionary_file::read(&folder.path().join("mine.yml")).unwrap();
    // Marker 2, 6 cells of 50 px with a margin of one, printed 6 cm across, photographed.
    let print = marker_image(&dictionary, 2, 50, 1).unwrap();
    let camera = Intrinsics::pinhole([640, 480], 50.0);
    let (pixels_per_metre, margin_m) = (5000.0, 0.01);
    let centre = DVec3::new(0.03, 0.03, 0.0);
    let rotation = bevy::math::DMat3::from_rotation_x(-0.4);
    let pose = Pose { rotation, translation: DVec3::new(0.0, 0.0, 0.4) - rotation * centre };
    let frame = photograph_print(&print, pixels_per_metre, margin_m, &pose, &camera);
    std::fs::create_dir(folder.path().join("clip")).unwrap();
    image::GrayImage::from_raw(640, 480, frame.pixels).unwrap().save(folder.path().join("clip/0.png")).unwrap();
    std::fs::write(folder.path().join("camera.yaml"), canopy::ar::calibration::to_yaml(&camera)).unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(
        &scene,
        "entities:\n  - name: overlay\n    ar: {frames: clip, calibration: camera.yaml, dictionary: mine.yml, \
         marker_id: 2, marker_side_m: 0.06}\n  - shape: {primitive: box, size: 2}\n",
    )
    .unwrap();
    let dump = run(&scene, 0.05, UVec2::new(160, 120), false);
    let overlay = entity(&dump, "overlay");
    assert_eq!(overlay["dictionary"], "mine");
    assert_eq!(overlay["poses"][0]["marker"], "found", "{overlay}");
    // A marker the file does not hold is an error at its line.
    std::fs::write(&scene, std::fs::read_to_string(&scene).unwrap().replace("marker_id: 2", "marker_id: 5")).unwrap();
    let error = canopy::app::entity_kinds().load(&scene).unwrap_err();
    assert!(error.message.contains("mine has markers 0 to 4, not 5") && error.location.is_some(), "{error}");
}
