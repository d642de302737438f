//! Keyboard controls and scripted input.
//!
//! Every key a plugin reacts to is registered with [`RegisterKeys::register_keys`], so the
//! help overlay and the README list exactly the keys that work. Global keys:
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

use crate::schedule::{ControlSystems, SimControl};
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

/// Where a key works: everywhere, or in scenes holding an entity of one kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyScope {
    /// In every scene.
    Global,
    /// In scenes with an entity of this kind.
    Kind(&'static str),
}

/// One key and what it does, for the help overlay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyHelp {
    /// The key.
    pub key: KeyCode,
    /// What it does, as a short phrase.
    pub action: &'static str,
    /// Where it works.
    pub scope: KeyScope,
}

impl KeyHelp {
    /// The key's name as printed on a keyboard: `J` for `KeyJ`, `5` for `Digit5`,
    /// `ArrowLeft` as is.
    pub fn key_name(&self) -> String {
        let name = format!("{:?}", self.key);
        name.strip_prefix("Key").or_else(|| name.strip_prefix("Digit")).unwrap_or(&name).to_string()
    }
}

/// Every registered key, in registration order.
#[derive(Resource, Debug, Default)]
pub struct KeyMap(pub Vec<KeyHelp>);

impl KeyMap {
    /// The keys that work in a scene holding entities of `kinds`.
    pub fn active<'a>(&'a self, kinds: &'a [&str]) -> impl Iterator<Item = &'a KeyHelp> + 'a {
        self.0.iter().filter(move |help| match help.scope {
            KeyScope::Global => true,
            KeyScope::Kind(kind) => kinds.contains(&kind),
        })
    }
}

/// Registration of keys on the app.
pub trait RegisterKeys {
    /// Adds keys to the [`KeyMap`].
    fn register_keys(&mut self, keys: &[KeyHelp]) -> &mut Self;
}

impl RegisterKeys for App {
    fn register_keys(&mut self, keys: &[KeyHelp]) -> &mut Self {
        self.world_mut().get_resource_or_init::<KeyMap>().0.extend_from_slice(keys);
        self
    }
}

/// Asks for the scene to be read from disk again.
#[derive(Message, Debug, Clone, Copy)]
pub struct ReloadScene;

/// Asks for a screenshot of the 3D view.
#[derive(Message, Debug, Clone, Copy)]
pub struct SaveScreenshot;

/// A click on the 3D view: where, in normalized device coordinates (x right, y up, -1 to 1),
/// and the view's width / height ratio.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct ViewClicked {
    /// The point clicked.
    pub ndc: Vec2,
    /// Width / height of the view.
    pub aspect: f32,
}

/// Asks the window to select (show the parameters of) the scene entity with this name.
#[derive(Message, Debug, Clone, PartialEq, Eq)]
pub struct SelectEntity(pub String);

/// Whether the key help is shown; it is at start, until F1 hides it.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct HelpVisible(pub bool);

impl Default for HelpVisible {
    fn default() -> Self {
        Self(true)
    }
}

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
            .add_message::<ReloadScene>()
            .add_message::<SaveScreenshot>()
            .add_message::<ViewClicked>()
            .add_message::<SelectEntity>()
            .register_keys(&global)
            .add_plugins(timeline::TimelinePlugin)
            .add_systems(Update, global_keys.in_set(ControlSystems::Input));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_names_read_like_the_keyboard() {
        let help = |key| KeyHelp { key, action: "", scope: KeyScope::Global };
        assert_eq!(help(KeyCode::KeyJ).key_name(), "J");
        assert_eq!(help(KeyCode::Digit5).key_name(), "5");
        assert_eq!(help(KeyCode::ArrowLeft).key_name(), "ArrowLeft");
    }

    #[test]
    fn kind_keys_show_only_where_the_kind_is() {
        let map = KeyMap(vec![
            KeyHelp { key: KeyCode::Space, action: "a", scope: KeyScope::Global },
            KeyHelp { key: KeyCode::KeyW, action: "b", scope: KeyScope::Kind("sloth") },
        ]);
        assert_eq!(map.active(&["shape"]).count(), 1);
        assert_eq!(map.active(&["sloth"]).count(), 2);
    }
}
