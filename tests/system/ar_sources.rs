//! The overlay's other sources of frames: the sample sequence encoded by FFmpeg as an H.264 MP4
//! and an MJPEG AVI and played from the file at its own rate, tracked as from the folder; a
//! video looping; files that are not videos or are cut short as located errors; a camera that
//! is not there as a message while the scene plays on.

use crate::ar::{SAMPLE, assert_tracked, run};
use crate::common::{entity, path};
use bevy::math::UVec2;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Encodes the sample's frames at 30 a second into `folder/name` with FFmpeg's `codec` options,
/// with a scene playing it (`loop` as given) beside it.
fn encoded_scene(folder: &Path, name: &str, codec: &[&str], repeat: bool) -> PathBuf {
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-framerate", "30", "-i"])
        .arg(path(SAMPLE).join("frame-%04d.jpg"))
        .args(codec)
        .arg(folder.join(name))
        .status()
        .expect("FFmpeg is installed (the README says so)");
    assert!(status.success(), "ffmpeg encoded {name}");
    std::fs::copy(path(SAMPLE).join("calibration.yaml"), folder.join("camera.yaml")).unwrap();
    let scene = folder.join("scene.yaml");
    std::fs::write(
        &scene,
        format!(
            "entities:\n  - name: overlay\n    ar: {{video: {name}, loop: {repeat}, calibration: camera.yaml, \
             dictionary: 6x6_250, marker_id: 23, marker_side_m: 0.1, scale: 0.02}}\n  \
             - shape: {{primitive: box, size: 2}}\n"
        ),
    )
    .unwrap();
    scene
}

#[test]
fn videos_in_h264_and_mjpeg_are_tracked_as_their_frames_were() {
    let codecs: [(&str, &[&str]); 2] = [
        ("clip.mp4", &["-c:v", "libx264", "-crf", "18", "-pix_fmt", "yuv420p"]),
        ("clip.avi", &["-c:v", "mjpeg", "-q:v", "3"]),
    ];
    for (name, codec) in codecs {
        let folder = tempfile::tempdir().unwrap();
        let dump = run(&encoded_scene(folder.path(), name, codec, false), 3.0, UVec2::new(320, 240), false);
        let overlay = entity(&dump, "overlay");
        assert_eq!((overlay["source"].as_str(), overlay["fps"].as_f64()), (Some("video"), Some(30.0)), "{name}");
        assert_eq!(overlay["frame_size"], serde_json::json!([640, 480]), "{name}");
        let records = overlay["poses"].as_array().unwrap();
        assert_eq!(records.len(), 90, "{name}: every frame of the 3 s at the video's 30 a second shown once");
        let frames: Vec<u64> = records.iter().map(|r| r["frame"].as_u64().unwrap()).collect();
        assert_eq!(frames, (0..90).collect::<Vec<u64>>(), "{name}: in order");
        // The encoding's loss moves corners a little: within 2 % and 2 degrees.
        let (whole, absent) = assert_tracked(overlay, 0.02, 2.0, 1.0);
        assert!(whole >= 60 && absent >= 5, "{name}: {whole} whole, {absent} absent");
    }
}

#[test]
fn a_looping_video_starts_over_after_its_last_frame() {
    let folder = tempfile::tempdir().unwrap();
    let codec = ["-c:v", "mjpeg", "-q:v", "5", "-frames:v", "20"];
    let dump = run(&encoded_scene(folder.path(), "clip.avi", &codec, true), 1.0, UVec2::new(160, 120), false);
    let frames: Vec<u64> =
        entity(&dump, "overlay")["poses"].as_array().unwrap().iter().map(|r| r["frame"].as_u64().unwrap()).collect();
    let expected: Vec<u64> = (0..30).map(|position| position % 20).collect();
    assert_eq!(frames, expected);
}

#[test]
fn files_that_are_not_videos_or_are_cut_short_are_located_errors() {
    let kinds = canopy::app::entity_kinds();
    let folder = tempfile::tempdir().unwrap();
    let scene = encoded_scene(folder.path(), "clip.mp4", &["-c:v", "libx264", "-frames:v", "10"], false);
    // The same scene over a file that is not a video, and over the video cut in half.
    let bytes = std::fs::read(folder.path().join("clip.mp4")).unwrap();
    for (content, what) in [(b"a shopping list".to_vec(), "not a"), (bytes[..bytes.len() / 2].to_vec(), "not a")] {
        std::fs::write(folder.path().join("clip.mp4"), content).unwrap();
        let error = kinds.load(&scene).unwrap_err();
        assert_eq!(error.location.map(|l| l.0), Some(3), "{error}");
        assert!(error.message.contains("entities[0].ar.video") && error.message.contains(what), "{error}");
        assert!(error.message.contains("clip.mp4"), "{error}");
    }
}

#[test]
fn a_camera_that_is_not_there_is_a_message_and_the_scene_plays_on() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::copy(path(SAMPLE).join("calibration.yaml"), folder.path().join("camera.yaml")).unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(
        &scene,
        "entities:\n  - name: overlay\n    ar: {camera: {device: /dev/video-not-there, size: [640, 480]}, \
         calibration: camera.yaml, dictionary: 6x6_250, marker_id: 23, marker_side_m: 0.1}\n  \
         - name: box\n    shape: {primitive: box, size: 2}\n",
    )
    .unwrap();
    let dump = run(&scene, 0.2, UVec2::new(160, 120), false);
    let overlay = entity(&dump, "overlay");
    assert_eq!(overlay["source"], "camera");
    assert_eq!(overlay["source_error"], "/dev/video-not-there: no camera there");
    assert_eq!((overlay["poses"].as_array().unwrap().len(), &overlay["overlay_visible"]), (0, &false.into()));
    assert!(entity(&dump, "box").is_object(), "the rest of the scene is there");
}
