//! Canopy's CPU rasterizer: every 3D view in Canopy is drawn here, never by a GPU pipeline.
//!
//! | module | what it holds |
//! |---|---|
//! | [`framebuffer`] | RGBA8 colour and `f32` depth targets, PNG output |
//! | [`mesh`] | indexed triangle meshes and the primitive shapes |
//! | [`camera`] | the perspective camera and the directional light |
//! | `lanes` | SIMD lanes and the conversions between glam vectors and `wide` lanes |
//! | `screen` | fixed point: tile and target sizes, sub-pixel positions, projected vertices, edge functions |
//! | [`clip`] | near-plane and guard-band clipping in clip space |
//! | [`frame`] | what a frame is made of: instances, settings, figures, the global numbering, the view |
//! | `vertex` | the vertex stage: transform, projection and lighting in parallel runs |
//! | `sort` | sorting triangles into strips of rows |
//! | `setup` | triangle setup: bounds, edge functions with the top-left fill rule, interpolation planes |
//! | `coverage` | a triangle's walk over a tile's pixels, shared by both passes |
//! | `color_pass` | the colour bands: the pixel loops of a tile, then the shadow lookups |
//! | `shadow_pass` | the shadow map's depth pass, strip by strip |
//! | `work_queue` | handing bands and strips to the threads, the slowest of the last frame first |
//! | [`shade`] | materials, shading modes, interpolated values |
//! | [`texture`] | PNG/BMP textures, nearest and bilinear sampling, repeat and clamp |
//! | [`shadow`] | the light's fitted orthographic shadow map and its lookup |
//! | [`pipeline`] | the [`Renderer`]: the order of the stages of a frame |
//! | [`benchmark_scene`] | the standard benchmark scene |
//!
//! Modules import only downwards in this table's dependency order (lanes and screen at the
//! bottom, the pipeline at the top); none imports the pipeline.
//!
//! Everything here is plain data in, pixels out: it takes a task pool and is tested and
//! benchmarked without an app. The Bevy side lives in the `canopy` crate.

#![forbid(unsafe_code)]

pub mod benchmark_scene;
pub mod camera;
pub mod clip;
mod color_pass;
mod coverage;
pub mod frame;
pub mod framebuffer;
mod lanes;
pub mod mesh;
pub mod pipeline;
mod screen;
mod setup;
pub mod shade;
pub mod shadow;
mod shadow_pass;
mod sort;
pub mod texture;
mod vertex;
mod work_queue;

pub use camera::{Camera, Lens, Light, Pinhole};
pub use frame::{Fog, Frame, Instance, RenderSettings, RenderStats};
pub use framebuffer::Framebuffer;
pub use mesh::{MeshData, Morph, vertex_normals};
pub use pipeline::Renderer;
pub use screen::MAX_TARGET_SIZE;
pub use shade::{Material, Shading};
pub use shadow::ShadowMap;
pub use texture::{Address, Filter, Sampler, Texture};
