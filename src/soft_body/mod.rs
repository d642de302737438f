//! Soft bodies: surfaces shrunk over a marked region with their border held, as in planning
//! plastic surgery, after a surgery-planning program's library of surface deformers.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`SoftBodyKind`]: the mesh read once, spawned and saved; its panel, keys and actions |
//! | [`def`] | the `soft_body:` entry of a scene file: a mesh file or a sample, where it stands, the deformer |
//! | [`plugin`] | [`SoftBodyPlugin`]: marks picked in the view, actions and keys, the write-back, the dump; the panel section |
//! | [`draw`] | the meshes shown: the surface tinted by region or by shift, the marks as balls |
//! | [`deform`] | the deformers: per-edge lengths, the sum of edge lengths, the area; their stopping rules and reports |
//! | [`measure`] | two points' distances along the surface and straight, before and after a shrink |
//! | [`region`] | the region outlined by marks on a surface: the loop along the surface, the smaller side, cut out and put back |
//! | [`sample`] | sample surfaces made by the project: a belly patch, a cap, a sphere, a torus, a torso |
//! | [`workbench`] | the workflow: marks, the region, shrinks kept as a collection of models |

pub mod def;
pub mod deform;
pub mod draw;
pub mod kind;
pub mod measure;
mod panel;
pub mod plugin;
pub mod region;
pub mod sample;
pub mod workbench;

pub use def::SoftBodyDef;
pub use kind::SoftBodyKind;
pub use plugin::{ShrinkParams, SoftBody, SoftBodyAction, SoftBodyPlugin, SoftBodySystems};
