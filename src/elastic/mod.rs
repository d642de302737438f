//! Dynamic soft bodies: volumes of tetrahedra under extended position-based dynamics that
//! sag, wobble, hang from branches by stems, rest on the ground and the terrain, and follow
//! the user's mouse.
//!
//! | module | what it holds |
//! |---|---|
//! | [`xpbd`] | the pure core: tetrahedral meshes filled into closed surfaces, the solver's small steps, stems and the hand |
//! | [`collide`] | the static solids: planes, balls, boxes, the scene's shapes, the terrain's ground, the trees' supports |

pub mod collide;
pub mod xpbd;
