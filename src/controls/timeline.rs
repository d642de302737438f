//! Scripted input for headless runs: a YAML list of events at simulated times, each pressing
//! or releasing keys (Bevy `KeyCode` names) or setting parameters directly:
//!
//! ```yaml
//! - { at: 0.0, set: { "light.azimuth_deg": 45 } }
//! - { at: 0.5, press: [KeyW] }
//! - { at: 2.0, release: [KeyW] }
//! - { at: 3.0, act: { torso: [{ mark_vertex: 120 }, apply] } }
//! ```
//!
//! `act` sends entities the actions of their kind (see [`crate::foundation::actions`]).
//!
//! An event fires at the start of the first frame whose time has reached `at`: seconds since
//! the scene was loaded, counted as frames times the fixed step, so the script keeps time
//! while the simulation is paused (and can resume it). Keys go through Bevy's input like real
//! key presses, so scripts and the keyboard drive the same systems.

use crate::foundation::actions::{ActionError, act};
use crate::foundation::params::{ParamError, ParamValue, check_param, set_param};
use crate::foundation::schedule::{ControlSystems, SimControl};
use crate::foundation::values::checked_number;
use crate::foundation::yaml::{FileError, deserialize_str_with, read_yaml_file};
use bevy::input::ButtonState;
use bevy::input::keyboard::{Key, KeyboardInput};
use bevy::prelude::*;
use bevy::reflect::FromReflect;
use bevy::reflect::enums::{DynamicEnum, DynamicVariant};
use serde::Deserialize;
use serde::Deserializer;
use std::collections::BTreeMap;
use std::path::Path;

/// A key named as Bevy's `KeyCode` variant (`KeyW`, `Space`, `ArrowLeft`, `Digit1`, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyName(pub KeyCode);

impl<'de> Deserialize<'de> for KeyName {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        const EXPECTED: &str = "a Bevy KeyCode name such as KeyW, Space, ArrowLeft, Digit1, F5";
        deserialize_str_with(deserializer, EXPECTED, |name| {
            let variant = DynamicEnum::new(name, DynamicVariant::Unit);
            KeyCode::from_reflect(&variant)
                .map(KeyName)
                .ok_or_else(|| format!("unknown key `{name}`: expected {EXPECTED}"))
        })
    }
}

checked_number!(
    /// Seconds since the scene was loaded, finite and not negative.
    Seconds(f64),
    "a time in seconds, 0 or more",
    |v| v >= 0.0
);

/// One scripted event.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimelineEvent {
    /// When it fires, seconds of simulated time.
    pub at: Seconds,
    /// Keys pressed.
    #[serde(default)]
    pub press: Vec<KeyName>,
    /// Keys released.
    #[serde(default)]
    pub release: Vec<KeyName>,
    /// Parameters set, by name (see [`crate::foundation::params`]).
    #[serde(default)]
    pub set: BTreeMap<String, ParamValue>,
    /// Actions sent, by entity name: one action or a list, done after the parameters are set.
    #[serde(default)]
    pub act: BTreeMap<String, serde_yaml::Value>,
}

/// Why a timeline does not fit the scene it is to play.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TimelineError {
    /// A parameter setting.
    #[error(transparent)]
    Parameter(#[from] ParamError),
    /// An action.
    #[error(transparent)]
    Action(#[from] ActionError),
}

/// A script of events, ordered by time (events at the same time keep their file order).
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct Timeline {
    events: Vec<TimelineEvent>,
    next: usize,
    /// Frames played since the scene went live.
    frames: u64,
}

impl Timeline {
    /// Reads a timeline file.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        Ok(Self::new(read_yaml_file(path, "a list of timeline events")?))
    }

    /// A timeline of `events`, in any order.
    pub fn new(mut events: Vec<TimelineEvent>) -> Self {
        events.sort_by(|a, b| a.at.0.total_cmp(&b.at.0));
        Self { events, next: 0, frames: 0 }
    }

    /// Checks every parameter setting and action against the entities of the loaded scene.
    pub fn check(&self, world: &mut World) -> Result<(), TimelineError> {
        for event in &self.events {
            for (name, value) in &event.set {
                check_param(world, name, value.clone())?;
            }
            for (entity, actions) in &event.act {
                act(world, entity, actions, false)?;
            }
        }
        Ok(())
    }

    /// The events due at time `now` (seconds) that have not fired yet.
    fn take_due(&mut self, now: f64) -> &[TimelineEvent] {
        // Steps are whole nanoseconds: allow for their rounding.
        let start = self.next;
        while self.events.get(self.next).is_some_and(|event| event.at.0 <= now + 1e-6) {
            self.next += 1;
        }
        &self.events[start..self.next]
    }
}

/// Plays the [`Timeline`] resource, when there is one.
pub struct TimelinePlugin;

impl Plugin for TimelinePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(PreUpdate, play_timeline.in_set(ControlSystems::Script).run_if(resource_exists::<Timeline>));
    }
}

fn play_timeline(world: &mut World) {
    if !world.resource::<SimControl>().live {
        return;
    }
    let step = world.resource::<Time<Fixed>>().timestep();
    let mut timeline = world.resource_mut::<Timeline>();
    let now = step.as_secs_f64() * timeline.frames as f64;
    timeline.frames += 1;
    let due = timeline.take_due(now).to_vec();
    for event in due {
        let keys = event.press.iter().map(|k| (k.0, ButtonState::Pressed));
        for (key_code, state) in keys.chain(event.release.iter().map(|k| (k.0, ButtonState::Released))) {
            world.write_message(KeyboardInput {
                key_code,
                logical_key: Key::Unidentified(bevy::input::keyboard::NativeKey::Unidentified),
                state,
                text: None,
                repeat: false,
                window: Entity::PLACEHOLDER,
            });
        }
        for (name, value) in event.set {
            if let Err(error) = set_param(world, &name, value) {
                error!("timeline at {}s: {error}", event.at.0);
            }
        }
        for (entity, actions) in &event.act {
            if let Err(error) = act(world, entity, actions, true) {
                error!("timeline at {}s: {error}", event.at.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::foundation::yaml::parse_yaml;

    fn parse(text: &str) -> Result<Vec<TimelineEvent>, FileError> {
        parse_yaml(Path::new("t.yaml"), text.as_bytes(), "events")
    }

    #[test]
    fn reads_the_documented_example() {
        let events = parse(
            "- { at: 0.0, set: { \"light.azimuth_deg\": 45 } }\n- { at: 0.5, press: [KeyW] }\n- { at: 2.0, release: [KeyW] }\n",
        )
        .unwrap();
        assert_eq!(events.len(), 3);
        assert_eq!(events[0].set["light.azimuth_deg"], ParamValue::Number(45.0));
        assert_eq!(events[1].press, [KeyName(KeyCode::KeyW)]);
        assert_eq!(events[2].at.0, 2.0);
    }

    #[test]
    fn unknown_keys_and_negative_times_are_located() {
        let error = parse("- { at: 0.5, press: [KeyWW] }\n").unwrap_err();
        assert_eq!(error.location.map(|l| l.0), Some(1));
        assert!(error.message.contains("unknown key `KeyWW`"), "{error}");
        let error = parse("- at: 1\n- at: -2\n").unwrap_err();
        assert_eq!(error.location.map(|l| l.0), Some(2));
        assert!(error.message.contains("expected a time in seconds"), "{error}");
        let error = parse("- { at: 1, pres: [KeyW] }\n").unwrap_err();
        assert!(error.message.contains("unknown field `pres`"), "{error}");
    }

    #[test]
    fn events_fire_once_in_time_order() {
        let mut timeline = Timeline { events: parse("- at: 0.5\n- at: 0.0\n- at: 0.1\n").unwrap(), next: 0, frames: 0 };
        timeline.events.sort_by(|a, b| a.at.0.total_cmp(&b.at.0));
        assert_eq!(timeline.take_due(0.0).len(), 1);
        assert_eq!(timeline.take_due(0.0).len(), 0);
        assert_eq!(timeline.take_due(6.0 * 0.016_666_667).len(), 1);
        assert_eq!(timeline.take_due(10.0).len(), 1);
    }
}
