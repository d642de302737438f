//! Global keys and scripted input.
//!
//! | key | action |
//! |---|---|
//! | Space | pause / resume the simulation |
//! | Period | advance one fixed step while paused |
//! | F1 | show / hide the key help |
//! | F5 | reload the scene from disk |
//! | F12 | save a screenshot of the 3D view |
//!
//! [`timeline`] plays the same keys (and direct parameter settings) from a file in headless
//! runs.

pub mod timeline;

use crate::foundation::keys::{KeyHelp, KeyScope, RegisterKeys};
use crate::foundation::messages::{ReloadScene, SaveScreenshot};
use crate::foundation::schedule::{ControlSystems, SimControl};
use bevy::prelude::*;

/// The key that pauses and resumes the simulation.
pub const PAUSE: KeyCode = KeyCode::Space;
/// The key that advances one fixed step while paused.
pub const STEP: KeyCode = KeyCode::Period;
/// The key that shows or hides the key help.
pub const HELP: KeyCode = KeyCode::F1;
/// The key that reloads the scene.
pub const RELOAD: KeyCode = KeyCode::F5;
/// The key that saves a screenshot.
pub const SCREENSHOT: KeyCode = KeyCode::F12;

/// Whether the key help is shown over the 3D view; hidden at start (it would cover a third of
/// the view), shown by F1 or the panel's Keys button.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HelpVisible(pub bool);

/// The global keys and scripted input.
pub struct ControlsPlugin;

impl Plugin for ControlsPlugin {
    fn build(&self, app: &mut App) {
        let global = [
            (PAUSE, "pause / resume the simulation"),
            (STEP, "advance one fixed step while paused"),
            (HELP, "show / hide this key help"),
            (RELOAD, "reload the scene from disk"),
            (SCREENSHOT, "save a screenshot of the 3D view"),
        ]
        .map(|(key, action)| KeyHelp { key, action, scope: KeyScope::Global });
        app.init_resource::<HelpVisible>()
            .register_keys(&global)
            .add_plugins(timeline::TimelinePlugin)
            .add_systems(RunFixedMainLoop, global_keys.in_set(ControlSystems::Input));
    }
}

fn global_keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut control: ResMut<SimControl>,
    mut help: ResMut<HelpVisible>,
    mut reload: MessageWriter<ReloadScene>,
    mut screenshot: MessageWriter<SaveScreenshot>,
) {
    if keys.just_pressed(PAUSE) {
        control.paused = !control.paused;
    }
    if keys.just_pressed(STEP) && control.paused {
        control.step_once = true;
    }
    if keys.just_pressed(HELP) {
        help.0 = !help.0;
    }
    if keys.just_pressed(RELOAD) {
        reload.write(ReloadScene);
    }
    if keys.just_pressed(SCREENSHOT) {
        screenshot.write(SaveScreenshot);
    }
}
