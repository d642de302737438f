//! Where an overlay's camera frames come from, behind one interface: a folder of images, a
//! video file, or a live camera.

use super::camera::CameraReader;
use super::frames::{FolderReader, FrameFolder};
use super::stream::FrameReader;
use super::video::VideoFile;
use std::path::PathBuf;
use std::sync::Arc;

/// The frames a folder shows a second unless the scene says.
pub const FOLDER_FPS: f64 = 30.0;

/// A live camera: the device and what is asked of it.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraSettings {
    /// The device's path, `/dev/video0` say.
    pub device: String,
    /// The frames' width and height, pixels.
    pub size: [u32; 2],
    /// Frames a second asked for.
    pub fps: f64,
}

/// A source of camera frames.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// A folder's images in name order.
    Folder {
        /// The folder.
        path: PathBuf,
        /// Its frames.
        frames: Arc<FrameFolder>,
    },
    /// A video file, decoded by FFmpeg.
    Video(Arc<VideoFile>),
    /// A live camera.
    Camera(CameraSettings),
}

impl Source {
    /// Every frame's width and height, pixels.
    pub fn size(&self) -> [u32; 2] {
        match self {
            Source::Folder { frames, .. } => frames.size,
            Source::Video(video) => video.size,
            Source::Camera(camera) => camera.size,
        }
    }

    /// Frames a second: the scene's rate if it gives one, else the folder's default or the
    /// video's own; a camera's is asked of the camera.
    pub fn fps(&self, scene_fps: Option<f64>) -> f64 {
        match self {
            Source::Folder { .. } => scene_fps.unwrap_or(FOLDER_FPS),
            Source::Video(video) => scene_fps.unwrap_or(video.fps),
            Source::Camera(camera) => camera.fps,
        }
    }

    /// Whether frames come when the camera takes them rather than when the clock says.
    pub fn live(&self) -> bool {
        matches!(self, Source::Camera(_))
    }

    /// The frames it holds, where that is known.
    pub fn frame_count(&self) -> Option<u64> {
        match self {
            Source::Folder { frames, .. } => Some(frames.len() as u64),
            Source::Video(video) => video.frames,
            Source::Camera(_) => None,
        }
    }

    /// What kind of source it is, as the dump names it.
    pub fn kind(&self) -> &'static str {
        match self {
            Source::Folder { .. } => "folder",
            Source::Video(_) => "video",
            Source::Camera(_) => "camera",
        }
    }

    /// Where the frames come from: the folder, the file or the device.
    pub fn location(&self) -> String {
        match self {
            Source::Folder { path, .. } => path.display().to_string(),
            Source::Video(video) => video.path.display().to_string(),
            Source::Camera(camera) => camera.device.clone(),
        }
    }

    /// Frame `index`'s name: its file in a folder, its number elsewhere.
    pub fn frame_name(&self, index: usize) -> String {
        match self {
            Source::Folder { frames, .. } => frames
                .files
                .get(index)
                .and_then(|file| file.file_name())
                .map(|name| name.to_string_lossy().into_owned())
                .unwrap_or_default(),
            _ => format!("frame {}", index + 1),
        }
    }

    /// Starts reading from the first frame.
    pub fn open(&self) -> Result<Box<dyn FrameReader>, String> {
        Ok(match self {
            Source::Folder { frames, .. } => Box::new(FolderReader { frames: frames.clone(), next: 0 }),
            Source::Video(video) => Box::new(video.reader()?),
            Source::Camera(camera) => Box::new(CameraReader::open(&camera.device, camera.size, camera.fps)?),
        })
    }
}
