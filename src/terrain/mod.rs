//! The `terrain` entity kind: a heightmap, generated or read from an image, of which a visible
//! section is shown as a textured mesh that can be moved over the map, turned and scaled.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`TerrainKind`]: the map read or made while checking, spawned and saved; its panel and keys |
//! | [`def`] | the `terrain:` entry of a scene file and its checks |
//! | [`plugin`] | [`TerrainPlugin`] and its set [`TerrainSystems`]: parameters, keys, regeneration off the main thread, meshes, dump |
//! | [`panel`] | the window's terrain section: figures, new seed, save |
//! | [`heightmap`] | the grid of heights and the map algebra |
//! | [`noise`] | Perlin noise and fBm: the reference formula and the fast row path |
//! | [`recipe`] | the layered recipe of generated heights, as terrains and worlds hold it, and its checks |
//! | [`recipe_editor`] | the whole recipe edited in the panel: size, seed, layers, generators, operations, weights, functions |
//! | [`generate`] | the generators (fBm, diamond-square, hills) and a recipe's heights from them |
//! | [`image_io`] | heightmaps as grayscale PNG and BMP files |
//! | [`section`] | the visible section and its mesh, split by band |
//! | [`surfaces`] | the surfaces a terrain is drawn in, a band or a border each, with their materials |
//! | [`ground`] | the visible section as a solid: height and normal under a point, on the triangles drawn |
//! | [`bands`] | the height bands, their rule and the project's band textures |
//!
//! Parameters (`<name>.<parameter>`, all from [`TerrainParams`]): `section.{x,z}` (the
//! section's first map sample), `section.{width,depth}` (vertices), `rotation_deg`,
//! `scale.{x,y,z}`, `position.{x,y,z}` (metres), `height_m`, and for generated maps
//! `noise.{seed,scale,octaves,lacunarity,persistence}` (the first Perlin layer's; a change
//! makes the map again).

pub mod bands;
pub mod def;
pub mod generate;
pub mod ground;
pub mod heightmap;
pub mod image_io;
pub mod kind;
pub mod noise;
pub mod panel;
pub mod plugin;
pub mod recipe;
pub mod recipe_editor;
pub mod section;
pub mod surfaces;

pub use def::TerrainDef;
pub use heightmap::Heightmap;
pub use kind::TerrainKind;
pub use plugin::{TerrainBody, TerrainParams, TerrainPlugin, TerrainSystems};
