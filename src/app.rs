//! Assembly of the app, windowed or headless, in one place: the list of entity kinds and the
//! plugin group.

use crate::ar::ArKind;
use crate::controls::ControlsPlugin;
use crate::elastic::ElasticBodyKind;
use crate::foundation::FoundationPlugin;
use crate::foundation::schedule::LongWorkArrival;
use crate::muscle::MuscleKind;
use crate::raster::lines::LinesPlugin;
use crate::raster::{RasterPlugin, RenderSettingsPlugin};
use crate::scene::kinds::{KindRegistry, Kinds};
use crate::scene::{ScenePlugin, register_scene_source};
use crate::shape::ShapeKind;
use crate::sloth::SlothKind;
use crate::soft_body::SoftBodyKind;
use crate::spatial::SpatialPlugin;
use crate::terrain::TerrainKind;
use crate::tree::TreeKind;
use crate::ui::pacing::FramePacing;
use crate::ui::{UiPlugin, WindowCapture};
use crate::view::ViewPlugin;
use crate::world::WorldKind;
use bevy::app::{PluginGroupBuilder, TaskPoolOptions, TaskPoolPlugin};
use bevy::asset::AssetMetaCheck;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Every entity kind, in the order their keys are listed in messages and in which they are
/// built (a kind's checks see what the kinds before it built). A new kind is its folder and
/// one line here.
pub fn entity_kinds() -> KindRegistry {
    Kinds::new()
        .with::<ShapeKind>()
        .with::<MuscleKind>()
        .with::<TerrainKind>()
        .with::<WorldKind>()
        .with::<TreeKind>()
        .with::<SlothKind>()
        .with::<SoftBodyKind>()
        .with::<ElasticBodyKind>()
        .with::<ArKind>()
        .build()
}

/// The fixed simulation rate, steps per second.
pub const FIXED_HZ: f64 = 60.0;

/// Where frames go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Display {
    /// A window with the egui panel; frames follow the window's size.
    Window,
    /// No window: frames of `size` pixels, drawn when asked for.
    Headless {
        /// Framebuffer size in pixels.
        size: UVec2,
    },
}

/// Every Canopy plugin, for an app that already has Bevy's base plugins (and, for
/// [`Display::Window`], a window and `bevy_egui`'s `EguiPlugin`): the foundation, the scene,
/// the camera and light, the render settings, each kind of [`entity_kinds`], the rasterizer
/// and the window. The scene's asset source must be registered first with
/// [`register_scene_source`].
pub struct CanopyPlugins {
    /// The scene file to play.
    pub scene: PathBuf,
    /// Where frames go.
    pub display: Display,
}

impl PluginGroup for CanopyPlugins {
    fn build(self) -> PluginGroupBuilder {
        let (size, every_frame) = match self.display {
            Display::Window => (UVec2::new(1280, 720), true),
            Display::Headless { size } => (size, false),
        };
        let kinds = Arc::new(entity_kinds());
        let group = PluginGroupBuilder::start::<Self>()
            .add(FoundationPlugin)
            .add(ControlsPlugin)
            .add(ScenePlugin { path: self.scene, kinds: kinds.clone() })
            .add(ViewPlugin)
            .add(SpatialPlugin)
            .add(RenderSettingsPlugin);
        let group = kinds.add_plugins(group).add(RasterPlugin { size, every_frame }).add(LinesPlugin);
        match self.display {
            Display::Window => group.add(UiPlugin),
            Display::Headless { .. } => group,
        }
    }
}

/// Bevy's task pools, the async compute pool's threads at background priority: the work they
/// do (a world's chunks, a terrain's new map) is wanted a few frames later, and on a machine
/// with few cores a chunk being made while the rasterizer draws its bands held a band's core
/// and made the whole frame wait (frames of a streamed flight up to 2.8 times its median, the
/// main thread waiting 18-25 ms for a core). At background priority they take only what the
/// frame leaves idle.
fn task_pools() -> TaskPoolPlugin {
    let mut options = TaskPoolOptions::default();
    options.async_compute.on_thread_spawn = Some(Arc::new(background_priority));
    TaskPoolPlugin { task_pool_options: options }
}

/// Puts the calling thread at the scheduler's idle priority, where the system has one: it
/// then runs only on cores no other thread wants.
#[allow(unsafe_code)]
fn background_priority() {
    #[cfg(target_os = "linux")]
    {
        let idle = libc::sched_param { sched_priority: 0 };
        // SAFETY: `sched_setscheduler` reads the parameter it is given, which outlives the
        // call; pid 0 names the calling thread.
        if unsafe { libc::sched_setscheduler(0, libc::SCHED_IDLE, &idle) } != 0 {
            warn!("background threads keep their priority: {}", std::io::Error::last_os_error());
        }
    }
}

/// The base plugins of asset loading with our settings: no `.meta` files, watching as asked.
fn asset_plugin(watch: bool) -> AssetPlugin {
    AssetPlugin { meta_check: AssetMetaCheck::Never, watch_for_changes_override: Some(watch), ..default() }
}

/// A headless app playing `scene`: no window, no GPU, one fixed step per `update()`.
///
/// With `log`, warnings and errors are printed (Bevy's logger can be installed only once per
/// process, so tests leave it out).
pub fn headless_app(scene: &Path, size: UVec2, log: bool) -> std::io::Result<App> {
    let mut app = App::new();
    register_scene_source(&mut app, scene)?;
    app.add_plugins((
        task_pools(),
        bevy::time::TimePlugin,
        bevy::transform::TransformPlugin,
        bevy::input::InputPlugin,
        asset_plugin(false),
    ));
    if log {
        app.add_plugins(bevy::log::LogPlugin { level: bevy::log::Level::WARN, ..default() });
    }
    app.insert_resource(Time::<Fixed>::from_hz(FIXED_HZ))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
        .add_plugins(CanopyPlugins { scene: scene.to_path_buf(), display: Display::Headless { size } });
    run_systems_in_turn(&mut app);
    Ok(app)
}

/// A windowed app playing `scene`, hot-reloading it on change, at most as fast as `pacing`
/// lets it; with `capture`, it saves a picture of the window and exits.
pub fn window_app(scene: &Path, capture: Option<WindowCapture>, pacing: FramePacing) -> std::io::Result<App> {
    let mut app = App::new();
    register_scene_source(&mut app, scene)?;
    let title = format!("Canopy: {}", scene.display());
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: Some(Window { title, resolution: (1280, 720).into(), ..default() }),
                ..default()
            })
            .set(asset_plugin(true))
            .set(task_pools())
            // The camera only carries egui's context: nothing is culled or projected for it.
            .disable::<bevy::camera::CameraPlugin>(),
    )
    .add_plugins(bevy_egui::EguiPlugin::default())
    .insert_resource(Time::<Fixed>::from_hz(FIXED_HZ))
    // Bevy's default slows an unfocused window down to 60 updates a second of its own; frames
    // are paced by `FramePacing` alone, so a scene keeps its rate behind other windows too.
    .insert_resource(bevy::winit::WinitSettings::continuous())
    .insert_resource(pacing)
    .add_plugins(CanopyPlugins { scene: scene.to_path_buf(), display: Display::Window })
    .insert_resource(LongWorkArrival::WhenReady);
    if let Some(capture) = capture {
        app.insert_resource(capture);
    }
    run_systems_in_turn(&mut app);
    Ok(app)
}

/// Runs the systems of every schedule of a frame one after another on the main thread.
/// Canopy's systems are small except the rasterizer's, which spreads its own work over the
/// compute task pool. Handing each system to a worker thread cost more than running them in
/// parallel gained: waking threads took an eighth of the main thread's time, and the workers
/// the executor kept busy slowed the rasterizer's bands (the demo scene's window frames took
/// 9 ms instead of 17, the raster 6 ms instead of 11, on two cores).
fn run_systems_in_turn(app: &mut App) {
    use bevy::ecs::schedule::{ScheduleLabel, SingleThreadedExecutor};
    let schedules = [
        First.intern(),
        PreUpdate.intern(),
        RunFixedMainLoop.intern(),
        FixedPreUpdate.intern(),
        FixedUpdate.intern(),
        FixedPostUpdate.intern(),
        Update.intern(),
        PostUpdate.intern(),
        Last.intern(),
    ];
    // egui's pass is a schedule of the window only.
    let egui = app
        .get_schedule(bevy_egui::EguiPrimaryContextPass)
        .is_some()
        .then(|| bevy_egui::EguiPrimaryContextPass.intern());
    for label in schedules.into_iter().chain(egui) {
        app.edit_schedule(label, |schedule| {
            schedule.set_executor(SingleThreadedExecutor::new());
        });
    }
}
