//! The window, without a GPU: the rasterizer's frame beside the egui side panel, composed on
//! the CPU and handed to the display server through `softbuffer`. `bevy_egui` keeps the
//! context and turns window input into egui input; its tessellated output is painted here.
//!
//! | module | what it holds |
//! |---|---|
//! | [`panel`] | the panel: scene, timings, entities and parameters; key help and load errors; mouse orbit on the view |
//! | [`compose`] | the window's pixels from the frame and the panel's paint jobs; pure |
//! | [`surface`] | the primary window's `softbuffer` surface |
//! | [`pacing`] | the frame rate cap |
//! | [`plot`] | egui drawings (plots) written as image files, painted without a window |
//!
//! | schedule | system | what it does |
//! |---|---|---|
//! | `PreUpdate`, before egui's contexts | `size_egui_camera` | the window's size and scale factor become egui's screen |
//! | `EguiPrimaryContextPass` | `draw_ui` | builds the panel; places the 3D view |
//! | `PostUpdate`, [`RenderSystems::Present`] after egui's output | `present_window` | composes the window, saves a capture, presents |
//! | `PostUpdate`, after it | `dump_at_capture` | the state dump a capture asks for |
//! | `Last` | `pace_frames` | waits out the rest of the frame interval |

pub mod compose;
pub mod pacing;
pub mod panel;
pub mod plot;
pub mod surface;

use crate::foundation::dump::{dump_state, write_dump};
use crate::foundation::schedule::{FixedStepTime, RenderSystems};
use crate::raster::plugin::{RasterTarget, RenderView};
use crate::scene::{ActiveScene, SceneStatus};
use bevy::camera::{Camera, RenderTargetInfo};
use bevy::prelude::*;
use bevy::window::{PrimaryWindow, RawHandleWrapper};
use bevy_egui::{
    EguiGlobalSettings, EguiOutput, EguiPostUpdateSet, EguiPreUpdateSet, EguiRenderOutput, PrimaryEguiContext,
};
use compose::{PanelPaint, WindowPainter, save_window_png};
use pacing::{FramePacing, pace_frames};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use surface::WindowSurface;

/// The window's view, panel and presentation.
pub struct UiPlugin;

impl Plugin for UiPlugin {
    fn build(&self, app: &mut App) {
        // While an egui field has the keyboard (typing a value), the scene's keys stay quiet.
        app.world_mut().get_resource_or_init::<EguiGlobalSettings>().enable_absorb_bevy_input_system = true;
        app.init_resource::<panel::UiState>()
            .init_resource::<ViewArea>()
            .init_resource::<WindowTimes>()
            .init_resource::<FramePacing>()
            .init_non_send::<WindowSurface>()
            .init_non_send::<WindowPainter>()
            .add_systems(Startup, spawn_egui_camera)
            .add_systems(PreUpdate, size_egui_camera.before(EguiPreUpdateSet::InitContexts))
            .add_systems(Update, count_capture_frames.run_if(resource_exists::<WindowCapture>))
            .add_systems(bevy_egui::EguiPrimaryContextPass, panel::draw_ui)
            .add_systems(
                PostUpdate,
                present_window.in_set(RenderSystems::Present).after(EguiPostUpdateSet::ProcessOutput),
            )
            .add_systems(
                PostUpdate,
                dump_at_capture
                    .after(RenderSystems::Present)
                    .run_if(|capture: Option<Res<WindowCapture>>| capture.is_some_and(|capture| capture.due())),
            )
            .add_systems(Last, pace_frames);
    }
}

/// Saves the whole window (view and panel, as composed) once the scene has been shown for some
/// frames, after which the app exits: for smoke tests and documentation.
#[derive(Resource, Debug, Clone)]
pub struct WindowCapture {
    /// The PNG file to write.
    pub path: PathBuf,
    /// Frames to show after the scene has loaded (or failed to) before the capture.
    pub after_frames: u32,
    /// A JSON file for the state dump at the time of the capture (see
    /// [`dump`](crate::foundation::dump)): what the window's input did, for tests.
    pub dump: Option<PathBuf>,
    /// Frames shown so far.
    shown: u32,
    /// Wall-clock time of the frames shown, together: whole frames, their fixed steps, their
    /// rasters. Reported with the capture, for measurements.
    spent: [Duration; 3],
}

impl WindowCapture {
    /// A capture into `path` after `after_frames` frames of the loaded scene, with a state
    /// dump into `dump` if given.
    pub fn new(path: PathBuf, after_frames: u32, dump: Option<PathBuf>) -> Self {
        Self { path, after_frames, dump, shown: 0, spent: [Duration::ZERO; 3] }
    }

    fn due(&self) -> bool {
        self.shown == self.after_frames.max(1)
    }

    /// The mean milliseconds of a frame, its fixed steps and its raster, over the frames shown
    /// after the first (which loaded the scene).
    fn means(&self) -> [f64; 3] {
        self.spent.map(|time| time.as_secs_f64() * 1000.0 / f64::from(self.shown.saturating_sub(1).max(1)))
    }
}

fn count_capture_frames(
    mut capture: ResMut<WindowCapture>,
    scene: Res<ActiveScene>,
    time: Res<Time<Real>>,
    steps: Res<FixedStepTime>,
    target: Res<RasterTarget>,
) {
    if scene.status == SceneStatus::Loading {
        return;
    }
    // Each frame's time is known one frame later: the first counted frame is the loading one.
    if capture.shown > 0 {
        let [frame, simulation, raster] = &mut capture.spent;
        *frame += time.delta();
        *simulation += steps.last;
        *raster += target.raster_time;
    }
    capture.shown += 1;
}

/// Writes the state dump of a capture that asks for one.
fn dump_at_capture(world: &mut World) {
    let Some(path) = world.resource::<WindowCapture>().dump.clone() else { return };
    let dump = dump_state(world);
    if let Err(error) = write_dump(&path, &dump) {
        error!("could not write the state dump to {}: {error}", path.display());
        world.write_message(AppExit::error());
    }
}

/// Where the 3D view sits in the window: the top-left pixel of the room the panel leaves.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ViewArea {
    /// Window pixel (column, row) of the view's top-left corner.
    pub origin: UVec2,
}

/// Wall-clock time the window's own phases took last frame (for display only).
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct WindowTimes {
    /// Painting the panel over the view.
    pub paint: Duration,
    /// Copying the frame into the window and handing the window to the display server.
    pub present: Duration,
    /// Waiting for the next frame's turn under the frame cap.
    pub wait: Duration,
}

/// The camera egui's primary context lives on. Nothing renders through it: it only tells
/// egui which window it belongs to.
fn spawn_egui_camera(mut commands: Commands) {
    commands.spawn((Name::new("egui context"), Camera::default()));
}

/// Gives egui's camera the primary window's size and scale factor, which Bevy's renderer would
/// otherwise compute: egui takes its screen and its pixels per point from them.
fn size_egui_camera(
    window: Query<&Window, With<PrimaryWindow>>,
    mut cameras: Query<&mut Camera, With<PrimaryEguiContext>>,
) {
    let Ok(window) = window.single() else { return };
    let (physical_size, scale_factor) = (window.physical_size(), window.scale_factor());
    for mut camera in &mut cameras {
        let known = camera.computed.target_info.as_ref();
        if known.is_none_or(|info| info.physical_size != physical_size || info.scale_factor != scale_factor) {
            camera.computed.target_info = Some(RenderTargetInfo { physical_size, scale_factor });
        }
    }
}

/// Composes the window from the last frame and the panel, saves it when a capture is due, and
/// presents it.
#[allow(clippy::too_many_arguments)]
fn present_window(
    mut surface: NonSendMut<WindowSurface>,
    mut painter: NonSendMut<WindowPainter>,
    window: Query<(&Window, &RawHandleWrapper), With<PrimaryWindow>>,
    mut egui: Query<(&mut EguiRenderOutput, &EguiOutput), With<PrimaryEguiContext>>,
    target: Res<RasterTarget>,
    view: Res<RenderView>,
    area: Res<ViewArea>,
    capture: Option<Res<WindowCapture>>,
    mut times: ResMut<WindowTimes>,
    mut exit: MessageWriter<AppExit>,
) {
    let Ok((mut egui, egui_output)) = egui.single_mut() else { return };
    painter.take_textures(std::mem::take(&mut egui.textures_delta));
    let Ok((window, handles)) = window.single() else { return };
    let started = Instant::now();
    let size = window.physical_size();
    let mut buffer = match surface.buffer(handles, size) {
        Ok(Some(buffer)) => buffer,
        Ok(None) => return,
        Err(error) => {
            error!("{error}");
            return;
        }
    };
    let [r, g, b, _] = view.background;
    let panel = PanelPaint { primitives: &egui.paint_jobs, pixels_per_point: egui_output.pixels_per_point };
    times.paint = painter.paint(&mut buffer, size, &target.framebuffer, area.origin, [r, g, b], panel);
    if let Some(capture) = capture.filter(|capture| capture.due()) {
        exit.write(match save_window_png(&buffer, size, &capture.path) {
            Ok(()) => {
                let [frame, simulation, raster] = capture.means();
                info!(
                    "window saved to {} after {} frames: {frame:.2} ms a frame on average, {simulation:.2} ms \
                     simulation, {raster:.2} ms raster",
                    capture.path.display(),
                    capture.shown
                );
                AppExit::Success
            }
            Err(error) => {
                error!("could not save the window to {}: {error}", capture.path.display());
                AppExit::error()
            }
        });
    }
    if let Err(error) = buffer.present() {
        error!("cannot show the window: {error}");
    }
    times.present = started.elapsed().saturating_sub(times.paint);
}
