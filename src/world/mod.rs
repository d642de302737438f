//! The `world` entity kind: an unbounded terrain streamed in chunks around the camera.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`WorldKind`]: the world's heights made while checking, spawned and saved; its panel |
//! | [`def`] | the `world:` entry of a scene file and its checks |
//! | [`plugin`] | [`WorldPlugin`] and its set [`WorldSystems`]: the streaming plan, chunks made off the main thread (or in advance) and spawned within a budget, skirts where levels meet, the dump |
//! | [`panel`] | the window's world section: chunks per level, arriving a second, time to make one |
//! | [`chunk`] | chunks of an unbounded world: heights at world positions and levels of detail, edges shared bit for bit |
//! | [`stream`] | which chunks to have around a camera: nearest and ahead first, unloaded beyond a larger radius |
//! | [`ground`] | the world's heights as the ground solids meet |
//!
//! The heights are made by the terrain kind's generators, its recipes and noise.

pub mod chunk;
pub mod def;
pub mod ground;
pub mod kind;
pub mod panel;
pub mod plugin;
pub mod stream;

pub use def::{WorldBuilt, WorldDef};
pub use kind::WorldKind;
pub use plugin::{ChunkSkirt, WorldBody, WorldChunk, WorldPlugin, WorldSystems};
