//! Headless runs: load a scene, optionally play a timeline, take a number of fixed steps, and
//! return the state dump and the last frame. Used by `canopy run`, by the `play` fallback
//! without a display, and by the system tests.

use crate::app::{entity_kinds, headless_app};
use crate::controls::timeline::{Timeline, TimelineError};
use crate::foundation::dump::dump_state;
use crate::foundation::schedule::SimControl;
use crate::foundation::yaml::FileError;
use crate::raster::Framebuffer;
use crate::raster::plugin::{RasterTarget, RenderPolicy};
use crate::scene::{ActiveScene, SceneStatus};
use bevy::app::App;
use bevy::math::UVec2;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How long a scene may take to load before the run gives up (wall-clock).
const LOAD_TIMEOUT: Duration = Duration::from_secs(60);

/// What to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// Fixed steps to take.
    pub frames: u64,
    /// A timeline file of scripted input.
    pub timeline: Option<PathBuf>,
    /// Framebuffer size in pixels.
    pub size: UVec2,
    /// Print warnings and errors from the app (once per process).
    pub log: bool,
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// The state dump after the last step (see [`crate::foundation::dump`]).
    pub dump: serde_json::Value,
    /// The frame drawn after the last step.
    pub framebuffer: Framebuffer,
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene or the timeline file is invalid.
    #[error("{0}")]
    Invalid(#[from] FileError),
    /// The timeline sets a parameter, or sends an action, that the scene does not take.
    #[error("{path}: {error}")]
    Parameter {
        /// The timeline file.
        path: PathBuf,
        /// What is wrong.
        error: TimelineError,
    },
    /// The scene could not be read or loaded.
    #[error("{0}")]
    Load(String),
}

/// Updates a headless app of `scene` until the scene is live; fails if it failed to load or
/// did not load within [`LOAD_TIMEOUT`].
pub fn update_until_loaded(app: &mut App, scene: &Path) -> Result<(), RunError> {
    let started = Instant::now();
    loop {
        app.update();
        let active = app.world().resource::<ActiveScene>();
        match active.status {
            SceneStatus::Live => return Ok(()),
            SceneStatus::Failed => return Err(RunError::Load(active.error.clone().unwrap_or_default())),
            SceneStatus::Loading if started.elapsed() > LOAD_TIMEOUT => {
                return Err(RunError::Load(format!("{}: the scene did not load within a minute", scene.display())));
            }
            SceneStatus::Loading => std::thread::yield_now(),
        }
    }
}

/// A headless app of `scene` at `size` pixels, loaded and live, playing `timeline` (read from
/// the file `from`, named in its errors) once every setting and action in it is checked
/// against the scene.
pub fn live_app(scene: &Path, size: UVec2, timeline: Option<(Timeline, &Path)>, log: bool) -> Result<App, RunError> {
    let mut app =
        headless_app(scene, size, log).map_err(|error| RunError::Load(format!("{}: {error}", scene.display())))?;
    update_until_loaded(&mut app, scene)?;
    if let Some((timeline, from)) = timeline {
        timeline.check(app.world_mut()).map_err(|error| RunError::Parameter { path: from.to_path_buf(), error })?;
        app.insert_resource(timeline);
    }
    Ok(app)
}

/// Frames written while a run goes: every `every`-th step's frame into `folder` as
/// `frame-00001.png`, ... (an augmented-reality scene's composited frames, a video's stills).
#[derive(Debug, Clone)]
pub struct Recording {
    /// Where the frames go (created if needed).
    pub folder: PathBuf,
    /// Steps between recorded frames, at least 1.
    pub every: u64,
}

/// Runs a scene headless.
pub fn run_headless(options: &RunOptions) -> Result<RunOutput, RunError> {
    run_recorded(options, None)
}

/// Runs a scene headless, writing frames as it goes when `recording` says so.
pub fn run_recorded(options: &RunOptions, recording: Option<&Recording>) -> Result<RunOutput, RunError> {
    // Check the files first, so that errors come out before any app is built.
    entity_kinds().load(&options.scene)?;
    let timeline = match &options.timeline {
        Some(path) => Some((Timeline::load(path)?, path.as_path())),
        None => None,
    };
    let mut app = live_app(&options.scene, options.size, timeline, options.log)?;
    if let Some(recording) = recording {
        std::fs::create_dir_all(&recording.folder)
            .map_err(|error| RunError::Load(format!("{}: {error}", recording.folder.display())))?;
    }
    let mut recorded = 0;
    for frame in 0..options.frames {
        let record = recording.filter(|r| frame % r.every.max(1) == 0);
        if frame + 1 == options.frames || record.is_some() {
            app.world_mut().resource_mut::<RenderPolicy>().requested = true;
        }
        app.update();
        if let Some(recording) = record {
            recorded += 1;
            let path = recording.folder.join(format!("frame-{recorded:05}.png"));
            app.world()
                .resource::<RasterTarget>()
                .framebuffer
                .save_png(&path)
                .map_err(|error| RunError::Load(format!("{}: {error}", path.display())))?;
        }
    }
    if options.frames == 0 {
        // Draw the initial state without stepping.
        app.world_mut().resource_mut::<SimControl>().paused = true;
        app.world_mut().resource_mut::<RenderPolicy>().requested = true;
        app.update();
    }
    let dump = dump_state(app.world_mut());
    let framebuffer = app.world().resource::<RasterTarget>().framebuffer.clone();
    Ok(RunOutput { dump, framebuffer })
}
