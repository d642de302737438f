//! `canopy play`, `canopy run` and `canopy check`: a scene in a window, headless, or only read
//! and checked.

use super::{parse_seconds, parse_size};
use crate::app::{FIXED_HZ, entity_kinds, window_app};
use crate::foundation::dump::write_dump;
use crate::run::{Recording, RunOptions, run_headless, run_recorded};
use crate::ui::WindowCapture;
use crate::ui::pacing::FramePacing;
use bevy::math::UVec2;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The scene played when none is named.
const DEFAULT_SCENE: &str = "scenes/canopy.yaml";

/// `canopy play`.
#[derive(Args, Debug)]
pub struct PlayArgs {
    /// The scene file [default: scenes/canopy.yaml]
    scene: Option<PathBuf>,
    /// Save a screenshot of the whole window to this file after `--frames` frames, then
    /// exit.
    #[arg(long, value_name = "OUT.png")]
    screenshot: Option<PathBuf>,
    /// Frames to show before the `--screenshot`.
    #[arg(long, default_value_t = 30, requires = "screenshot")]
    frames: u32,
    /// Also write the state as JSON to this file with the `--screenshot`.
    #[arg(long, value_name = "STATE.json", requires = "screenshot")]
    dump: Option<PathBuf>,
    /// Frames a second at most; 0 draws frames back to back (for measuring).
    #[arg(long, default_value_t = 60, value_name = "FPS")]
    max_fps: u32,
}

impl Default for PlayArgs {
    /// The default scene in a window at 60 frames a second: what `canopy` alone does.
    fn default() -> Self {
        Self { scene: None, screenshot: None, frames: 0, dump: None, max_fps: 60 }
    }
}

/// `canopy run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// The scene file.
    scene: PathBuf,
    /// Fixed steps to run [default: 60, one second].
    #[arg(long, conflicts_with = "seconds")]
    frames: Option<u64>,
    /// Simulated seconds to run (rounded to whole steps).
    #[arg(long, value_parser = |text: &str| parse_seconds(text, 1.0e6))]
    seconds: Option<f64>,
    /// A timeline of scripted key presses and parameter settings (YAML).
    #[arg(long, value_name = "TIMELINE.yaml")]
    input: Option<PathBuf>,
    /// Write the final state as JSON to this file.
    #[arg(long, value_name = "STATE.json")]
    dump: Option<PathBuf>,
    /// Write the last frame as PNG to this file.
    #[arg(long, value_name = "OUT.png")]
    screenshot: Option<PathBuf>,
    /// Frame size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = parse_size)]
    size: UVec2,
    /// Write frames as PNG files into this folder while running (`frame-00001.png`, ...).
    #[arg(long, value_name = "DIR")]
    record: Option<PathBuf>,
    /// Steps between recorded frames: 2 records 30 frames a second.
    #[arg(long, default_value_t = 1, requires = "record", value_parser = clap::value_parser!(u64).range(1..))]
    record_every: u64,
}

/// `canopy check`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// The scene files.
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
}

/// `scenes/canopy.yaml` from the working directory, else from the source tree.
fn default_scene() -> PathBuf {
    let local = PathBuf::from(DEFAULT_SCENE);
    if local.exists() { local } else { Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_SCENE) }
}

impl PlayArgs {
    /// Plays the scene in a window; without a display, renders it headless to a PNG and prints
    /// where.
    pub fn play(self) -> ExitCode {
        let scene = self.scene.unwrap_or_else(default_scene);
        let capture = self.screenshot.map(|path| WindowCapture::new(path, self.frames, self.dump));
        let pacing = FramePacing::max_fps(self.max_fps);
        if !scene.is_file() {
            eprintln!("{}: no such scene file", scene.display());
            return ExitCode::from(1);
        }
        let set = |name: &str| std::env::var_os(name).is_some_and(|value| !value.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            return render_headless(scene, capture);
        }
        if let Err(error) = entity_kinds().load(&scene) {
            // The window opens anyway and shows the error until the file is fixed.
            eprintln!("{error}");
        }
        match window_app(&scene, capture, pacing) {
            Ok(mut app) => match app.run() {
                bevy::app::AppExit::Success => ExitCode::SUCCESS,
                bevy::app::AppExit::Error(code) => ExitCode::from(code.get()),
            },
            Err(error) => {
                eprintln!("{}: {error}", scene.display());
                ExitCode::from(1)
            }
        }
    }
}

/// `canopy play` without a display: one second of `scene` headless, its last frame written
/// where the capture asks (a temporary file otherwise) and its path printed.
fn render_headless(scene: PathBuf, capture: Option<WindowCapture>) -> ExitCode {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let dump = capture.as_ref().and_then(|c| c.dump.clone());
    let out = capture.map_or_else(|| std::env::temp_dir().join(format!("canopy-{stem}.png")), |c| c.path);
    eprintln!(
        "no display available (neither DISPLAY nor WAYLAND_DISPLAY is set): rendering {} headless instead",
        scene.display()
    );
    let options = RunOptions { scene, frames: FIXED_HZ as u64, timeline: None, size: UVec2::new(1280, 720), log: true };
    match run_headless(&options).map_err(|e| e.to_string()).and_then(|output| {
        output.framebuffer.save_png(&out).map_err(|e| format!("{}: {e}", out.display()))?;
        dump.map_or(Ok(()), |path| write_dump(&path, &output.dump).map_err(|e| format!("{}: {e}", path.display())))
    }) {
        Ok(()) => {
            println!("{}", out.display());
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("{error}");
            ExitCode::from(1)
        }
    }
}

impl RunArgs {
    /// Runs the scene headless and writes what was asked.
    pub fn run(self) -> ExitCode {
        let frames = match (self.frames, self.seconds) {
            (Some(frames), _) => frames,
            (None, Some(seconds)) => (seconds * FIXED_HZ).round() as u64,
            (None, None) => FIXED_HZ as u64,
        };
        let options = RunOptions { scene: self.scene, frames, timeline: self.input, size: self.size, log: true };
        let recording = self.record.map(|folder| Recording { folder, every: self.record_every });
        let output = match run_recorded(&options, recording.as_ref()) {
            Ok(output) => output,
            Err(error) => {
                eprintln!("{error}");
                return ExitCode::from(1);
            }
        };
        if let Some(path) = &self.dump
            && let Err(error) = write_dump(path, &output.dump)
        {
            eprintln!("{}: cannot write the dump: {error}", path.display());
            return ExitCode::from(1);
        }
        if let Some(path) = &self.screenshot
            && let Err(error) = output.framebuffer.save_png(path)
        {
            eprintln!("{}: cannot write the screenshot: {error}", path.display());
            return ExitCode::from(1);
        }
        ExitCode::SUCCESS
    }
}

impl CheckArgs {
    /// Reads and checks every scene, printing each one's verdict.
    pub fn check(self) -> ExitCode {
        let kinds = entity_kinds();
        let mut valid = true;
        for scene in &self.scenes {
            match kinds.load(scene) {
                Ok(loaded) => println!("{}: ok ({} entities)", scene.display(), loaded.def.entities.len()),
                Err(error) => {
                    eprintln!("{error}");
                    valid = false;
                }
            }
        }
        if valid { ExitCode::SUCCESS } else { ExitCode::from(1) }
    }
}
