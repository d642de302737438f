//! Ground that comes and goes: a patch of a streamed ground (a world's chunk), as whatever grows
//! on the ground sees it.

use bevy::math::{IVec2, Vec2};
use bevy::prelude::Component;

/// A square patch of ground, a child of the entity whose [`Solid`](super::solid::Solid) is the
/// ground it is part of. Patches come in and go as the ground streams
/// ([`SpatialSystems::Ground`](super::SpatialSystems::Ground)).
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct GroundPatch {
    /// The patch's place in the ground's grid of patches, along x and z.
    pub key: IVec2,
    /// Its level of detail: 0 the finest.
    pub level: u8,
    /// Its corner of least x and z, metres.
    pub corner: Vec2,
    /// Its side, metres.
    pub side: f32,
}
