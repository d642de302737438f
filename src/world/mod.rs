//! The `world` entity kind: an unbounded terrain streamed in chunks around the camera.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`WorldKind`]: the world's heights made while checking, spawned and saved; its panel |
//! | [`def`] | the `world:` entry of a scene file and its checks |
//! | [`plugin`] | [`WorldPlugin`] and its set [`WorldSystems`]: the streaming plan, chunks made off the main thread (or in advance) and spawned within a budget, skirts where levels meet, the dump |
//! | [`panel`] | the window's world section: chunks per level, arriving a second, time to make one |
//!
//! The heights, chunks, levels of detail and the plan are the terrain kind's pure cores
//! ([`crate::terrain::chunk`], [`crate::terrain::stream`]).

pub mod def;
pub mod kind;
pub mod panel;
pub mod plugin;

pub use def::{WorldBuilt, WorldDef};
pub use kind::WorldKind;
pub use plugin::{ChunkSkirt, WorldBody, WorldChunk, WorldPlugin, WorldSystems};
