//! Dynamic soft bodies: volumes of tetrahedra under extended position-based dynamics that
//! sag, wobble, hang from branches by stems, rest on the ground and the terrain, and follow
//! the user's mouse.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`ElasticBodyKind`]: the body meshed into tetrahedra while checking, spawned and saved; its panel, keys and actions |
//! | [`def`] | the `elastic_body:` entry of a scene file: a closed surface, its size, material and stem |
//! | [`plugin`] | [`ElasticPlugin`]: the solids gathered, the fixed step, keys, dragging, actions, the write-back, the dump; the panel section |
//! | [`tet_mesh`] | tetrahedral meshes: a lattice, or filled into a closed surface with the surface embedded |
//! | [`material`] | a body's material and the compliance each constraint takes from it |
//! | `hinge` | the skin's hinges between neighbouring surface triangles, held at their rest angle |
//! | `colouring` | the order constraints are projected in: a greedy colouring of their particles |
//! | [`xpbd`] | the solver: small steps of edges, volumes and hinges, contacts with the solids, stems and the hand |

mod colouring;
pub mod def;
mod hinge;
pub mod kind;
pub mod material;
mod panel;
pub mod plugin;
pub mod tet_mesh;
pub mod xpbd;

pub use def::ElasticBodyDef;
pub use kind::ElasticBodyKind;
pub use plugin::{ElasticAction, ElasticBody, ElasticParams, ElasticPlugin, ElasticSystems};
