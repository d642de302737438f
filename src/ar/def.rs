//! The `ar:` entry of a scene file, and the kind that reads and spawns it.

use super::calibration::Calibration;
use super::source::{CameraSettings, Source};
use crate::foundation::values::{FileType, FolderFile, PositiveMetres, checked_number, inside_folder};
use crate::foundation::yaml::deserialize_str_with;
use canopy_vision::board::{Board, CharucoBoard, GridBoard};
use canopy_vision::camera::Intrinsics;
use canopy_vision::dictionary::Dictionary;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::sync::Arc;

checked_number!(
    /// Camera frames a second.
    FrameRate(f64),
    "frames a second greater than 0 and at most 1000",
    |v| v > 0.0 && v <= 1000.0
);
checked_number!(
    /// Marker metres to the world metre.
    Scale(f64),
    "a scale greater than 0 and at most 1000",
    |v| v > 0.0 && v <= 1000.0
);
checked_number!(
    /// Seconds a lost marker's pose is kept.
    HoldSeconds(f64),
    "seconds from 0 to 3600",
    |v| (0.0..=3600.0).contains(&v)
);

/// Calibration files: OpenCV's YAML or JSON.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CalibrationFile;

impl FileType for CalibrationFile {
    const EXTENSIONS: &'static [&'static str] = &[".yaml", ".yml", ".json"];
    const EXPECTING: &'static str = "a .yaml, .yml or .json calibration file in the scene's folder";
    const FILES: &'static str = "a .yaml, .yml or .json file";
}

/// Video files FFmpeg reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VideoFileType;

impl FileType for VideoFileType {
    const EXTENSIONS: &'static [&'static str] =
        &[".mp4", ".m4v", ".mov", ".mkv", ".webm", ".avi", ".mjpeg", ".mjpg", ".ogv"];
    const EXPECTING: &'static str = "a video file (.mp4, .mov, .mkv, .webm, .avi, .mjpeg) in the scene's folder";
    const FILES: &'static str = "a video file (.mp4, .m4v, .mov, .mkv, .webm, .avi, .mjpeg, .mjpg or .ogv)";
}

/// A live camera in a scene file: a Video4Linux2 device and what is asked of it.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    /// The device; `/dev/video0` by default.
    #[serde(default = "first_camera")]
    pub device: String,
    /// The frames' width and height, pixels; 640 x 480 by default.
    #[serde(default = "vga")]
    pub size: [u32; 2],
    /// Frames a second asked of it; 30 by default.
    #[serde(default = "thirty")]
    pub fps: FrameRate,
}

impl CameraDef {
    /// The settings the camera is opened with.
    pub fn settings(&self) -> CameraSettings {
        CameraSettings { device: self.device.clone(), size: self.size, fps: self.fps.0 }
    }
}

fn first_camera() -> String {
    "/dev/video0".into()
}

fn vga() -> [u32; 2] {
    [640, 480]
}

/// A folder next to the scene: relative, without `..`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FolderPath(pub String);

impl Serialize for FolderPath {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.0)
    }
}

impl<'de> Deserialize<'de> for FolderPath {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize_str_with(deserializer, "a folder inside the scene's folder", |path| {
            if inside_folder(path) {
                Ok(FolderPath(path.to_string()))
            } else {
                Err(format!("expected a folder inside the scene's folder (relative, without `..`), found \"{path}\""))
            }
        })
    }
}

/// Marker dictionary files: OpenCV's YAML or JSON.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DictionaryFile;

impl FileType for DictionaryFile {
    const EXTENSIONS: &'static [&'static str] = &[".yaml", ".yml", ".json"];
    const EXPECTING: &'static str = "a .yaml, .yml or .json dictionary file in the scene's folder";
    const FILES: &'static str = "a .yaml, .yml or .json file";
}

/// A marker dictionary in a scene file: OpenCV's name of a predefined one, or a file of the
/// user's next to the scene, as OpenCV's `writeDictionary` writes it.
#[derive(Debug, Clone, PartialEq)]
pub enum DictionaryName {
    /// A predefined dictionary.
    Named(Dictionary),
    /// A dictionary file.
    File {
        /// The file, relative to the scene's folder.
        file: FolderFile<DictionaryFile>,
        /// The dictionary, read when the scene is resolved.
        read: Option<Arc<Dictionary>>,
    },
}

impl DictionaryName {
    /// The dictionary; `None` for a file not read yet.
    pub fn dictionary(&self) -> Option<&Dictionary> {
        match self {
            DictionaryName::Named(dictionary) => Some(dictionary),
            DictionaryName::File { read, .. } => read.as_deref(),
        }
    }
}

impl Serialize for DictionaryName {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            DictionaryName::Named(dictionary) => serializer.serialize_str(&dictionary.name),
            DictionaryName::File { file, .. } => file.serialize(serializer),
        }
    }
}

impl<'de> Deserialize<'de> for DictionaryName {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize_str_with(deserializer, "a marker dictionary such as 6x6_250, or a dictionary file", |name| {
            let lower = name.to_ascii_lowercase();
            if DictionaryFile::EXTENSIONS.iter().any(|extension| lower.ends_with(extension)) {
                FolderFile::new(name).map(|file| DictionaryName::File { file, read: None })
            } else {
                Dictionary::named(name).map(DictionaryName::Named).map_err(|error| error.to_string())
            }
        })
    }
}

/// An `ar` entity: the scene drawn over a camera's frames, on a marker.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArDef {
    /// A folder of frames (PNG or JPEG files, shown in name order), next to the scene; or a
    /// `video` or a `camera`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<FolderPath>,
    /// A video file next to the scene, decoded by FFmpeg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub video: Option<FolderFile<VideoFileType>>,
    /// A live camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraDef>,
    /// Frames a second of a folder (30 by default) or a video (its own rate by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<FrameRate>,
    /// Whether a folder's or a video's frames start over after the last; yes by default.
    #[serde(default = "yes", rename = "loop")]
    pub repeat: bool,
    /// The camera's calibration in OpenCV's layout.
    pub calibration: FolderFile<CalibrationFile>,
    /// The markers' dictionary, by OpenCV's name (`4x4_50`, `6x6_250`, `aruco_original`, ...)
    /// or a dictionary file next to the scene.
    pub dictionary: DictionaryName,
    /// The marker the scene stands on (with `marker_side_m`; or a `board`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub marker_id: Option<u32>,
    /// The marker's side (its black square), metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub marker_side_m: Option<PositiveMetres>,
    /// Or a board the scene stands on, at its centre: a grid of markers or a ChArUco board.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub board: Option<BoardDef>,
    /// Marker metres to the world metre: the scene shrunk onto the marker; 1 by default.
    #[serde(default = "one")]
    pub scale: Scale,
    /// Seconds a lost marker's last pose is kept before the scene is hidden; 0.5 by default.
    #[serde(default = "half_second")]
    pub hold_s: HoldSeconds,
    /// The calibration, read when the scene is resolved.
    #[serde(skip)]
    pub calibration_read: Option<Arc<Calibration>>,
}

fn thirty() -> FrameRate {
    FrameRate(30.0)
}

fn yes() -> bool {
    true
}

pub(super) fn one() -> Scale {
    Scale(1.0)
}

fn half_second() -> HoldSeconds {
    HoldSeconds(0.5)
}

/// A board in a scene file: an ArUco grid board (`markers` and `separation_m`) or a ChArUco
/// board (`squares` and `square_m`), laid out as OpenCV's `GridBoard` and `CharucoBoard` (see
/// `canopy ar board`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoardDef {
    /// A grid board's markers across and down.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub markers: Option<[u32; 2]>,
    /// A grid board's gap between neighbouring markers, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub separation_m: Option<f64>,
    /// A ChArUco board's squares across and down.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub squares: Option<[u32; 2]>,
    /// A ChArUco board's square side, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub square_m: Option<f64>,
    /// Each marker's side, metres.
    pub marker_m: f64,
    /// The first marker's id; 0 by default.
    #[serde(default)]
    pub first_id: u32,
    /// A ChArUco board of an even number of rows made by OpenCV before 4.6; no by default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub legacy: bool,
}

impl BoardDef {
    /// The board described, or what is wrong with it for `dictionary`.
    pub fn board(&self, dictionary: &Dictionary) -> Result<Board, String> {
        match (self.markers, self.separation_m, self.squares, self.square_m) {
            (Some(markers), Some(separation_m), None, None) if !self.legacy => {
                Ok(Board::Grid(GridBoard::new(markers, self.marker_m, separation_m, self.first_id, dictionary)?))
            }
            (None, None, Some(squares), Some(square_m)) => Ok(Board::Charuco(CharucoBoard::new(
                squares,
                square_m,
                self.marker_m,
                self.first_id,
                self.legacy,
                dictionary,
            )?)),
            _ => Err(
                "expected `markers` and `separation_m` (a grid board), or `squares` and `square_m` (a ChArUco board, \
                      which alone takes `legacy`)"
                    .into(),
            ),
        }
    }
}

/// What an `ar` entity is built into: its source of frames and the camera for their size.
#[derive(Debug, Clone)]
pub struct ArBuilt {
    /// Where the frames come from.
    pub source: Source,
    /// The calibrated camera for the frames' size.
    pub camera: Intrinsics,
    /// The calibration, for a camera opened at another size.
    pub calibration: Arc<Calibration>,
    /// The board the scene stands on, if not a marker.
    pub board: Option<Board>,
    /// The markers' dictionary.
    pub dictionary: Dictionary,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_checked_values() {
        let def: ArDef = serde_yaml::from_str(
            "{frames: clip, calibration: cam.yaml, dictionary: DICT_6X6_250, marker_id: 3, marker_side_m: 0.1}",
        )
        .unwrap();
        assert_eq!((def.fps, def.repeat, def.scale, def.hold_s), (None, true, Scale(1.0), HoldSeconds(0.5)));
        let camera: ArDef = serde_yaml::from_str(
            "{camera: {size: [1280, 720]}, calibration: cam.yaml, dictionary: 4x4_50, marker_id: 3, marker_side_m: 0.1}",
        )
        .unwrap();
        let expected = CameraSettings { device: "/dev/video0".into(), size: [1280, 720], fps: 30.0 };
        assert_eq!(camera.camera.unwrap().settings(), expected);
        let error = serde_yaml::from_str::<ArDef>(
            "{video: clip.txt, calibration: cam.yaml, dictionary: 4x4_50, marker_id: 3, marker_side_m: 0.1}",
        )
        .unwrap_err()
        .to_string();
        assert!(error.contains("a video file"), "{error}");
        assert_eq!(def.dictionary.dictionary().map(|d| d.name.as_ref()), Some("6x6_250"));
        let error = serde_yaml::from_str::<ArDef>(
            "{frames: clip, calibration: cam.yaml, dictionary: 9x9, marker_id: 3, marker_side_m: 0.1}",
        )
        .unwrap_err()
        .to_string();
        assert!(error.contains("unknown dictionary `9x9`"), "{error}");
        let error = serde_yaml::from_str::<ArDef>(
            "{frames: ../clip, calibration: cam.yaml, dictionary: 4x4_50, marker_id: 3, marker_side_m: 0.1}",
        )
        .unwrap_err()
        .to_string();
        assert!(error.contains("a folder inside the scene's folder"), "{error}");
        let error = serde_yaml::from_str::<ArDef>(
            "{frames: clip, calibration: cam.txt, dictionary: 4x4_50, marker_id: 3, marker_side_m: 0.1}",
        )
        .unwrap_err()
        .to_string();
        assert!(error.contains(".json"), "{error}");
    }
}
