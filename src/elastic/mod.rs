//! Dynamic soft bodies: volumes of tetrahedra under extended position-based dynamics that
//! sag, wobble, hang from branches by stems, rest on the ground and the terrain, and follow
//! the user's mouse.
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`ElasticBodyKind`]: the body meshed into tetrahedra while checking, spawned and saved; its panel, keys and actions |
//! | [`def`] | the `elastic_body:` entry of a scene file: a closed surface, its size, material and stem |
//! | [`plugin`] | [`ElasticPlugin`]: the solids gathered, the fixed step, keys, dragging, actions, the write-back, the dump; the panel section |
//! | [`xpbd`] | the pure core: tetrahedral meshes filled into closed surfaces, the solver's small steps, stems and the hand |
//! | [`collide`] | the static solids: planes, balls, boxes, the scene's shapes, the terrain's ground, the trees' supports |

pub mod collide;
pub mod def;
pub mod kind;
mod panel;
pub mod plugin;
pub mod xpbd;

pub use def::ElasticBodyDef;
pub use kind::ElasticBodyKind;
pub use plugin::{ElasticAction, ElasticBody, ElasticParams, ElasticPlugin, ElasticSystems};
