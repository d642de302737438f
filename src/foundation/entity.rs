//! The marker every entity spawned from a scene file carries, and the point a camera can follow.

use bevy::prelude::*;

/// Identifies a spawned scene entity: its place in the file, its name and its kind.
#[derive(Component, Debug, Clone, PartialEq, Eq)]
pub struct SceneEntity {
    /// Order in the scene: the camera, the light, the render settings, then the file's entities.
    pub index: usize,
    /// The name parameters and dumps use.
    pub name: String,
    /// The kind (`camera`, `light`, `render`, or an entity kind's key).
    pub kind: &'static str,
}

/// A point of an entity that the camera can follow (an animal's body), metres, kept up to date
/// by the entity's kind.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct FocusPoint(pub Vec3);
