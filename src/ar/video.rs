//! Video files as camera frames, decoded by the system's FFmpeg: `ffprobe` reads the first
//! picture stream's size and rate, `ffmpeg` decodes it to raw RGBA on a pipe, frame after frame,
//! in its own process. Every container and codec FFmpeg reads (MP4 and H.264, MJPEG, Matroska,
//! WebM, ...) plays; frames are shown in decoding order at the stream's average rate.

use super::frames::MAX_FRAME_SIDE;
use super::stream::FrameReader;
use image::RgbaImage;
use serde::Deserialize;
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, ErrorKind, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};

/// What to tell a user whose system has no FFmpeg.
pub const INSTALL_FFMPEG: &str = "video files are read with FFmpeg's `ffprobe` and `ffmpeg`: install FFmpeg (on Debian and Ubuntu, `apt install ffmpeg`)";

/// The lines of FFmpeg's messages kept to explain a failure.
const MESSAGE_LINES: usize = 8;

/// A video file's first picture stream, as `ffprobe` describes it.
#[derive(Debug, Clone, PartialEq)]
pub struct VideoFile {
    /// The file.
    pub path: PathBuf,
    /// Every frame's width and height, pixels.
    pub size: [u32; 2],
    /// Its average rate, frames a second.
    pub fps: f64,
    /// The frames the container says it holds, if it says.
    pub frames: Option<u64>,
    /// The codec's short name (`h264`, `mjpeg`, ...).
    pub codec: String,
}

#[derive(Deserialize)]
struct Probe {
    #[serde(default)]
    streams: Vec<ProbedStream>,
}

#[derive(Deserialize)]
struct ProbedStream {
    codec_name: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    avg_frame_rate: Option<String>,
    r_frame_rate: Option<String>,
    nb_frames: Option<String>,
}

impl VideoFile {
    /// Reads `path`'s first picture stream's description; errors name the file.
    pub fn probe(path: &Path) -> Result<Self, String> {
        let name = path.display().to_string();
        if !path.is_file() {
            return Err(format!("{name}: no such file"));
        }
        let output = Command::new("ffprobe")
            .args(["-v", "error", "-select_streams", "v:0", "-show_entries"])
            .arg("stream=codec_name,width,height,avg_frame_rate,r_frame_rate,nb_frames")
            .args(["-of", "json"])
            .arg(path)
            .stdin(Stdio::null())
            .output()
            .map_err(|error| cannot_run(&name, "ffprobe", &error))?;
        if !output.status.success() {
            let message = String::from_utf8_lossy(&output.stderr);
            let reason = message.lines().rev().find(|line| !line.trim().is_empty()).unwrap_or("unknown error");
            return Err(format!("{name}: not a readable video: {}", without_path(reason, path)));
        }
        let probe: Probe = serde_json::from_slice(&output.stdout)
            .map_err(|error| format!("{name}: ffprobe's description could not be read: {error}"))?;
        let stream = probe.streams.into_iter().next().filter(|s| s.width.is_some() && s.height.is_some());
        let Some(stream) = stream else {
            return Err(format!("{name}: not a video: it holds no picture stream"));
        };
        let size = [stream.width.unwrap_or(0), stream.height.unwrap_or(0)];
        if size[0] == 0 || size[1] == 0 || size[0].max(size[1]) > MAX_FRAME_SIDE {
            return Err(format!(
                "{name}: {} x {} pixels; a frame is 1 to {MAX_FRAME_SIDE} pixels a side",
                size[0], size[1]
            ));
        }
        let fps = [&stream.avg_frame_rate, &stream.r_frame_rate]
            .into_iter()
            .find_map(|rate| rate.as_deref().and_then(parse_rate))
            .ok_or_else(|| format!("{name}: the video gives no frame rate; give the scene's `fps`"))?;
        Ok(Self {
            path: path.to_path_buf(),
            size,
            fps,
            frames: stream.nb_frames.and_then(|n| n.parse().ok()),
            codec: stream.codec_name.unwrap_or_default(),
        })
    }

    /// Starts decoding from the first frame.
    pub fn reader(&self) -> Result<VideoReader, String> {
        VideoReader::start(self.clone())
    }
}

/// A rate as FFmpeg writes it, `30000/1001` or `25`; `None` for `0/0` and other non-rates.
fn parse_rate(rate: &str) -> Option<f64> {
    let value = match rate.split_once('/') {
        Some((numerator, denominator)) => numerator.parse::<f64>().ok()? / denominator.parse::<f64>().ok()?,
        None => rate.parse().ok()?,
    };
    (value.is_finite() && value > 0.0 && value <= 1000.0).then_some(value)
}

/// Why `program` could not be started for the file `name`: FFmpeg missing, or the system's
/// reason.
fn cannot_run(name: &str, program: &str, error: &std::io::Error) -> String {
    match error.kind() {
        ErrorKind::NotFound => format!("{name}: {INSTALL_FFMPEG}"),
        _ => format!("{name}: cannot run {program}: {error}"),
    }
}

/// FFmpeg's message with the file's path (which the caller names already) left out.
fn without_path(message: &str, path: &Path) -> String {
    message.replace(&format!("{}: ", path.display()), "").trim().to_string()
}

/// A video decoded by an `ffmpeg` process, frame after frame.
pub struct VideoReader {
    video: VideoFile,
    child: Child,
    pixels: ChildStdout,
    /// FFmpeg's last messages, gathered by a thread so that its pipe never fills.
    messages: Arc<Mutex<VecDeque<String>>>,
    /// Whether the end (or a failure) was reached.
    finished: bool,
}

impl VideoReader {
    fn start(video: VideoFile) -> Result<Self, String> {
        let name = video.path.display().to_string();
        let mut child = Command::new("ffmpeg")
            .args(["-nostdin", "-v", "error", "-noautorotate", "-i"])
            .arg(&video.path)
            .args(["-map", "0:v:0", "-fps_mode", "passthrough", "-f", "rawvideo", "-pix_fmt", "rgba", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|error| cannot_run(&name, "ffmpeg", &error))?;
        let (Some(pixels), Some(errors)) = (child.stdout.take(), child.stderr.take()) else {
            let _ = child.kill();
            return Err(format!("{name}: ffmpeg's output could not be read"));
        };
        let messages = Arc::new(Mutex::new(VecDeque::new()));
        let gathered = messages.clone();
        std::thread::Builder::new()
            .name("canopy-ffmpeg-messages".into())
            .spawn(move || {
                for line in BufReader::new(errors).lines().map_while(Result::ok) {
                    let mut lines = gathered.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
                    if lines.len() == MESSAGE_LINES {
                        lines.pop_front();
                    }
                    lines.push_back(line);
                }
            })
            .map_err(|error| format!("{name}: cannot start reading ffmpeg's messages: {error}"))?;
        Ok(Self { video, child, pixels, messages, finished: false })
    }

    /// Why decoding stopped early, from FFmpeg's messages and exit status.
    fn failure(&mut self) -> Option<String> {
        let status = self.child.wait().ok()?;
        if status.success() {
            return None;
        }
        let lines = self.messages.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let reason = lines.back().map_or_else(|| format!("ffmpeg stopped ({status})"), |line| line.clone());
        Some(format!("{}: decoding failed: {}", self.video.path.display(), without_path(&reason, &self.video.path)))
    }
}

impl FrameReader for VideoReader {
    fn next_frame(&mut self) -> Option<Result<RgbaImage, String>> {
        if self.finished {
            return None;
        }
        let [width, height] = self.video.size;
        let mut pixels = vec![0; width as usize * height as usize * 4];
        let mut filled = 0;
        while filled < pixels.len() {
            match self.pixels.read(&mut pixels[filled..]) {
                Ok(0) => break,
                Ok(read) => filled += read,
                Err(error) if error.kind() == ErrorKind::Interrupted => {}
                Err(error) => {
                    self.finished = true;
                    return Some(Err(format!("{}: {error}", self.video.path.display())));
                }
            }
        }
        if filled == pixels.len() {
            return RgbaImage::from_raw(width, height, pixels).map(Ok);
        }
        // The end: a clean one, a failure, or a frame cut short.
        self.finished = true;
        match (self.failure(), filled) {
            (Some(failure), _) => Some(Err(failure)),
            (None, 0) => None,
            (None, _) => Some(Err(format!("{}: the last frame is cut short", self.video.path.display()))),
        }
    }

    fn rewind(&mut self) -> Result<(), String> {
        *self = VideoReader::start(self.video.clone())?;
        Ok(())
    }
}

impl Drop for VideoReader {
    fn drop(&mut self) {
        // FFmpeg is stopped rather than left decoding a file nobody reads.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_as_ffmpeg_writes_them() {
        assert_eq!(parse_rate("30/1"), Some(30.0));
        assert!((parse_rate("30000/1001").unwrap() - 29.97).abs() < 1e-3);
        assert_eq!(parse_rate("25"), Some(25.0));
        assert_eq!(parse_rate("0/0"), None);
        assert_eq!(parse_rate("90000/0"), None);
        assert_eq!(parse_rate("fast"), None);
    }

    #[test]
    fn files_that_are_not_videos_are_named() {
        let folder = tempfile::tempdir().unwrap();
        let missing = VideoFile::probe(&folder.path().join("clip.mp4")).unwrap_err();
        assert!(missing.contains("clip.mp4: no such file"), "{missing}");
        let text = folder.path().join("notes.mp4");
        std::fs::write(&text, "a shopping list, not a video\n").unwrap();
        let error = VideoFile::probe(&text).unwrap_err();
        assert!(error.starts_with(&format!("{}: ", text.display())), "{error}");
        assert!(error.contains("not a"), "{error}");
    }
}
