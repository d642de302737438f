//! The CPU rasterizer: every 3D view in Canopy is drawn here, never by Bevy's GPU pipeline.
//!
//! | module | what it holds |
//! |---|---|
//! | [`framebuffer`] | RGBA8 colour and `f32` depth targets, PNG output |
//! | [`mesh`] | indexed triangle meshes and the primitive shapes |
//! | [`camera`] | the perspective camera and the directional light |
//! | [`clip`] | near-plane and guard-band clipping in clip space |
//! | [`pipeline`] | vertex lighting, setup, binning, parallel band rasterization |
//! | [`plugin`] | the ECS side: [`RasterMesh`](plugin::RasterMesh) in, framebuffer out |
//!
//! Everything but [`plugin`] is pure: it takes plain data and a task pool and is tested
//! without an app.

pub mod camera;
pub mod clip;
pub mod framebuffer;
pub mod mesh;
pub mod pipeline;
pub mod plugin;

pub use camera::{Camera, Light};
pub use framebuffer::Framebuffer;
pub use mesh::MeshData;
pub use pipeline::{Frame, Instance, RenderStats, Renderer};
pub use plugin::{RasterMesh, RasterPlugin, RenderSystems, RenderView};
