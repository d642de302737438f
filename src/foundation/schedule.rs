//! The app-wide phases of a frame, in one place, and the simulated clock.
//!
//! | schedule | sets, in order | what runs there |
//! |---|---|---|
//! | `PreUpdate` | [`ControlSystems::Script`] (before Bevy's input) | scripted timelines |
//! | `RunFixedMainLoop` | [`ControlSystems::Input`] -> [`ControlSystems::Apply`] (before the fixed steps) | keys and mouse edit parameters; parameters are applied to components |
//! | `FixedUpdate` | [`SimSystems::Deform`] -> [`SimSystems::Locomotion`] -> [`SimSystems::Dynamics`] -> [`SimSystems::Streaming`] -> [`SimSystems::Clock`] | the simulations, one fixed step; only while a scene is live and not paused |
//! | `Update` | [`ControlSystems::Load`] | the scene is (re)spawned after a (re)load |
//! | `PostUpdate` | [`WriteBackSystems`] (after the panel, before transform propagation) | each kind updates its `RasterMesh` when its shape changed, and nowhere else |
//! | `PostUpdate` | [`RenderSystems::Collect`] -> [`RenderSystems::Camera`] -> [`RenderSystems::Raster`] -> [`RenderSystems::Composite`] -> [`RenderSystems::Present`] (after transform propagation) | meshes and transforms gathered; the camera taken over by an overlay; shadow map and frame drawn; laid over a photograph; the frame handed on |
//!
//! Input is read before the fixed steps of its frame (Bevy's pattern for fixed timesteps), so a
//! key held for a frame acts in that frame's step. Nothing in the simulation reads the wall
//! clock: [`SimClock`] counts fixed steps.

use bevy::input::InputSystems;
use bevy::prelude::*;
use bevy::transform::TransformSystems;
use bevy_egui::EguiPostUpdateSet;
use std::time::{Duration, Instant};

/// Sets that turn input into parameter changes, and the scene's (re)spawning.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ControlSystems {
    /// `PreUpdate`, before Bevy reads input: scripted key events and parameter settings.
    Script,
    /// `RunFixedMainLoop`, before the fixed steps: keyboard and mouse change parameters.
    Input,
    /// `RunFixedMainLoop`, before the fixed steps: parameter components are written into the
    /// components they drive.
    Apply,
    /// `Update`: the scene is spawned or respawned after a (re)load.
    Load,
}

/// Sets of `FixedUpdate`, run once per fixed step while the simulation runs.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SimSystems {
    /// Shapes that change by themselves: the muscle follows its flexion, shapes spin.
    Deform,
    /// Animals move: gait, footholds, inverse kinematics, body.
    Locomotion,
    /// Bodies move under forces: elastic bodies sag, fall and rest on what is there.
    Dynamics,
    /// Content that arrives over time is requested and taken in.
    Streaming,
    /// Advances [`SimClock`].
    Clock,
}

/// The `PostUpdate` set in which each kind writes its shape into its `RasterMesh`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct WriteBackSystems;

/// The ordered sets of `PostUpdate` in which a frame is drawn.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RenderSystems {
    /// Gather what to draw and from where.
    Collect,
    /// Views that take the camera over move it here: the augmented-reality overlay puts it
    /// where the camera that took the photograph was.
    Camera,
    /// Draw the shadow map and the frame.
    Raster,
    /// Lay the drawn frame over what shows behind it: the overlay's photograph.
    Composite,
    /// Hand the frame to the window or to files.
    Present,
}

/// Simulated time: fixed steps taken since the scene was (re)loaded.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SimClock {
    /// Fixed steps taken.
    pub frame: u64,
    /// Simulated time elapsed.
    pub elapsed: Duration,
}

/// Whether the simulation advances: the scene is live, and it is running or one step was
/// asked for while paused.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SimControl {
    /// A scene is loaded and spawned.
    pub live: bool,
    /// The user paused the simulation.
    pub paused: bool,
    /// Take one step even though paused.
    pub step_once: bool,
}

impl SimControl {
    fn runs(control: Res<SimControl>) -> bool {
        control.live && (!control.paused || control.step_once)
    }
}

/// Wall-clock time the last frame's fixed steps took, input excluded: for display only (the
/// panel's split of the frame time); nothing in the simulation reads it.
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct FixedStepTime {
    /// The fixed steps of the last frame, together.
    pub last: Duration,
    started: Option<Instant>,
}

/// When the results of long work done off the main thread (a surface shrunk, say) are taken
/// in: headless runs take them a fixed number of frames after they were asked for, waiting if
/// need be, so that the same input gives the same dump; the window takes them once done, so
/// that no frame waits for work of seconds.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum LongWorkArrival {
    /// A fixed number of frames after they were asked for.
    #[default]
    FixedFrames,
    /// In the first frame that finds them done.
    WhenReady,
}

/// Configures every phase and the simulation clock.
pub struct SchedulePlugin;

impl Plugin for SchedulePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SimClock>()
            .init_resource::<SimControl>()
            .init_resource::<LongWorkArrival>()
            .configure_sets(PreUpdate, ControlSystems::Script.before(InputSystems))
            .configure_sets(
                FixedUpdate,
                (
                    SimSystems::Deform,
                    SimSystems::Locomotion,
                    SimSystems::Dynamics,
                    SimSystems::Streaming,
                    SimSystems::Clock,
                )
                    .chain()
                    .run_if(SimControl::runs),
            )
            .configure_sets(
                RunFixedMainLoop,
                (ControlSystems::Input, ControlSystems::Apply)
                    .chain()
                    .in_set(RunFixedMainLoopSystems::BeforeFixedMainLoop),
            )
            .configure_sets(
                PostUpdate,
                WriteBackSystems.after(EguiPostUpdateSet::EndPass).before(TransformSystems::Propagate),
            )
            .configure_sets(
                PostUpdate,
                (
                    RenderSystems::Collect,
                    RenderSystems::Camera,
                    RenderSystems::Raster,
                    RenderSystems::Composite,
                    RenderSystems::Present,
                )
                    .chain()
                    .after(TransformSystems::Propagate)
                    .after(EguiPostUpdateSet::EndPass),
            )
            .init_resource::<FixedStepTime>()
            .add_systems(
                RunFixedMainLoop,
                (
                    start_fixed_step_timer
                        .in_set(RunFixedMainLoopSystems::BeforeFixedMainLoop)
                        .after(ControlSystems::Apply),
                    stop_fixed_step_timer.in_set(RunFixedMainLoopSystems::AfterFixedMainLoop),
                ),
            )
            .add_systems(FixedUpdate, advance_clock.in_set(SimSystems::Clock));
    }
}

fn start_fixed_step_timer(mut timer: ResMut<FixedStepTime>) {
    timer.started = Some(Instant::now());
}

fn stop_fixed_step_timer(mut timer: ResMut<FixedStepTime>) {
    if let Some(started) = timer.started.take() {
        timer.last = started.elapsed();
    }
}

fn advance_clock(time: Res<Time>, mut clock: ResMut<SimClock>, mut control: ResMut<SimControl>) {
    clock.frame += 1;
    clock.elapsed += time.delta();
    control.step_once = false;
}
