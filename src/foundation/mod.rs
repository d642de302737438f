//! The foundation every domain builds on; it imports no domain and no scene code.
//!
//! | module | what it holds |
//! |---|---|
//! | [`entity`] | [`SceneEntity`](entity::SceneEntity), the marker of every entity a scene spawned |
//! | [`kind`] | [`EntityKind`](kind::EntityKind), the trait through which a kind plugs in |
//! | [`values`] | checked numbers, points, sizes, colours and file paths of scene files |
//! | [`yaml`] | reading user-written YAML with errors at file, line, column and field |
//! | [`params`] | named parameters through reflection: timelines, keys and the panel edit them |
//! | [`actions`] | what entities can be told to do beyond parameters: timelines send them |
//! | [`dump`] | the JSON state dump each kind contributes to |
//! | [`random`] | a seeded stream of numbers, the same on every machine |
//! | [`keys`] | the key help every plugin registers its keys with |
//! | [`messages`] | the app-wide requests: reload, screenshot, view clicked, select |
//! | [`panel`] | the kinds' sections of the window's panel |
//! | [`schedule`] | the phases of a frame and the simulated clock |

pub mod actions;
pub mod dump;
pub mod entity;
pub mod frame_times;
pub mod keys;
pub mod kind;
pub mod messages;
pub mod panel;
pub mod params;
pub mod random;
pub mod schedule;
pub mod values;
pub mod yaml;

use bevy::prelude::*;

/// The foundation's resources, messages and phases.
pub struct FoundationPlugin;

impl Plugin for FoundationPlugin {
    fn build(&self, app: &mut App) {
        messages::add_messages(app);
        app.init_resource::<actions::ActionKinds>();
        app.add_plugins(schedule::SchedulePlugin);
    }
}
