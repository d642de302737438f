//! Canopy's CPU rasterizer: every 3D view in Canopy is drawn here, never by a GPU pipeline.
//!
//! | module | what it holds |
//! |---|---|
//! | [`framebuffer`] | RGBA8 colour and `f32` depth targets, PNG output |
//! | [`mesh`] | indexed triangle meshes and the primitive shapes |
//! | [`camera`] | the perspective camera and the directional light |
//! | [`clip`] | near-plane and guard-band clipping in clip space |
//! | [`pipeline`] | the frame: vertex stage, shadow map, sorting, parallel bands |
//! | `sort` | sorting triangles into strips of rows |
//! | `setup` | triangle setup: bounds, edge functions, interpolation planes |
//! | `tile` | the colour bands: coverage walks and the pixel loops of a tile |
//! | `depth` | the shadow map's depth pass |
//! | [`shade`] | materials, shading modes, interpolated values |
//! | [`texture`] | PNG/BMP textures, nearest and bilinear sampling, repeat and clamp |
//! | [`shadow`] | the light's fitted orthographic shadow map and its lookup |
//! | [`standard`] | the standard benchmark scene |
//!
//! Everything here is plain data in, pixels out: it takes a task pool and is tested and
//! benchmarked without an app. The Bevy side lives in the `canopy` crate.

#![forbid(unsafe_code)]

pub mod camera;
pub mod clip;
mod depth;
pub mod framebuffer;
pub mod mesh;
pub mod pipeline;
mod schedule;
mod setup;
pub mod shade;
pub mod shadow;
mod sort;
pub mod standard;
pub mod texture;
mod tile;

pub use camera::{Camera, Light};
pub use framebuffer::Framebuffer;
pub use mesh::MeshData;
pub use pipeline::{Frame, Instance, MAX_TARGET_SIZE, RenderSettings, RenderStats, Renderer};
pub use shade::{Material, Shading};
pub use shadow::ShadowMap;
pub use texture::{Address, Filter, Sampler, Texture};
