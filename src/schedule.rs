//! The app-wide system sets and the simulation clock.
//!
//! | schedule | sets, in order | what runs there |
//! |---|---|---|
//! | `PreUpdate` | [`ControlSystems::Script`] (before Bevy's input) | scripted timelines |
//! | `Update` | [`ControlSystems::Load`] -> [`ControlSystems::Input`] -> [`ControlSystems::Apply`] | the scene is (re)spawned; keys edit parameters; parameters are applied to components |
//! | `FixedUpdate` | [`SimSystems::Step`] -> [`SimSystems::Clock`] | domain simulation, then the clock; only while a scene is live and not paused |
//! | `PostUpdate` | [`RenderSystems`](crate::raster::RenderSystems) | drawing, after transform propagation |

use bevy::input::InputSystems;
use bevy::prelude::*;
use std::time::Duration;

/// Sets of `PreUpdate` and `Update` that turn input into parameter changes.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ControlSystems {
    /// `PreUpdate`, before Bevy reads input: scripted key events and parameter settings.
    Script,
    /// `Update`: the scene is spawned or respawned after a (re)load.
    Load,
    /// `Update`: keyboard, mouse and UI change parameters.
    Input,
    /// `Update`: parameter components are written into the components they drive.
    Apply,
}

/// Sets of `FixedUpdate`, run once per fixed step while the simulation runs.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SimSystems {
    /// Domain simulation for one fixed step.
    Step,
    /// Advances [`SimClock`].
    Clock,
}

/// Simulated time: fixed steps taken since the scene was (re)loaded. Nothing in the
/// simulation reads the wall clock.
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

/// Configures the sets and the simulation clock.
pub struct SchedulePlugin;

impl Plugin for SchedulePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SimClock>()
            .init_resource::<SimControl>()
            .configure_sets(PreUpdate, ControlSystems::Script.before(InputSystems))
            .configure_sets(Update, (ControlSystems::Load, ControlSystems::Input, ControlSystems::Apply).chain())
            .configure_sets(FixedUpdate, (SimSystems::Step, SimSystems::Clock).chain().run_if(SimControl::runs))
            .add_systems(FixedUpdate, advance_clock.in_set(SimSystems::Clock));
    }
}

fn advance_clock(time: Res<Time>, mut clock: ResMut<SimClock>, mut control: ResMut<SimControl>) {
    clock.frame += 1;
    clock.elapsed += time.delta();
    control.step_once = false;
}
