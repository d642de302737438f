//! The `shape` entity kind: primitive solids (box, sphere, cylinder, plane) and props drawn
//! from mesh files (OBJ, PLY, STL, glTF with its materials and textures) that give scenes
//! real 3D content, optionally spinning at a constant rate.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`ShapeKind`]: textures and meshes read, shapes spawned and saved |
//! | [`def`] | the `shape:` entry of a scene file |
//! | [`mesh`] | a mesh file's parts as the rasterizer draws them |
//! | [`plugin`] | [`ShapePlugin`] and its set [`ShapeSystems`]: parameters, dump, spinning, writing the transform and colour |
//!
//! Parameters (`<name>.<parameter>`, all from [`ShapeParams`]): `position.{x,y,z}` (metres),
//! `rotation_deg.{x,y,z}`, `size.{x,y,z}` (metres, > 0), `color.{red,green,blue}` (0 to 1),
//! `spin_deg_per_s.{x,y,z}`.
//!
//! A shape may carry a texture: a PNG or BMP file in the scene's folder, modulated by its
//! colour, read with nearest, bilinear or trilinear (mip-mapped) filtering, repeated or clamped at its edges.

pub mod def;
pub mod kind;
pub mod mesh;
pub mod plugin;

pub use def::ShapeDef;
pub use kind::ShapeKind;
pub use plugin::{Shape, ShapeParams, ShapePart, ShapePlugin, ShapeSystems};
