//! The `ar` entity kind: the scene drawn over a camera's frames, standing on an ArUco marker
//! or a board found in each frame (the source's augmented reality): frames from a folder of
//! images, a video file or a live camera.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`ArKind`]: the frames and calibration read, the overlay spawned; its panel |
//! | [`def`] | the `ar:` entry of a scene file and its checks |
//! | [`calibration`] | OpenCV's calibration files (YAML and JSON), read and written |
//! | [`dictionary_file`] | marker dictionaries of the user's, in OpenCV's dictionary files |
//! | [`opencv_file`] | OpenCV's YAML and JSON files read as a mapping |
//! | [`source`] | where frames come from: a folder, a video file or a live camera |
//! | [`frames`] | a folder of PNG and JPEG frames in name order |
//! | [`video`] | video files decoded by the system's FFmpeg |
//! | [`camera`] | live Video4Linux2 cameras |
//! | [`stream`] | frames read and searched for markers ahead, on a thread of their own |
//! | [`overlay`] | the world on the marker, the render camera from the pose, the photograph fitted behind, the pose held |
//! | [`report`] | a found marker and its pose as JSON, as `canopy ar detect` prints it and the dump records it |
//! | [`panel`] | the panel's section: the frame, the marker's pose and errors, an outline switch |
//! | [`sample`] | synthetic sequences written with their calibration and ground truth |
//! | [`plugin`] | [`ArPlugin`]: frames shown at their rate, the marker found, the camera placed, the frame laid over the photograph |
//!
//! Detection and pose are the `canopy_vision` crate's: OpenCV's dictionaries, sub-pixel
//! corners, IPPE refined on reprojection error. The scene's other entities stand on the marker:
//! the world's origin at its centre, its ground the marker's plane, shrunk by `scale`.

pub mod calibration;
pub mod camera;
pub mod def;
pub mod dictionary_file;
pub mod frames;
pub mod kind;
pub mod opencv_file;
pub mod overlay;
pub mod panel;
pub mod plugin;
pub mod report;
pub mod sample;
pub mod source;
pub mod stream;
pub mod video;

pub use def::ArDef;
pub use kind::ArKind;
pub use plugin::{ArPlugin, ArState, ArView};
