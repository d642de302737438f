//! Soft bodies: surfaces shrunk over a marked region with their border held, as in planning
//! plastic surgery, after a surgery-planning program's library of surface deformers.
//!
//! | module | what it holds |
//! |---|---|
//! | [`batch`] | the batch deformation of `canopy deform`: a mesh file, a region, a deformer, a report |
//! | [`surface`] | a triangle surface with its derived edges and adjacency, and the facts a deformation is judged by |
//! | [`deform`] | the deformers: per-edge lengths, the sum of edge lengths, the area; their stopping rules and reports |
//! | [`mesh_io`] | OBJ, PLY and STL meshes read and welded, OBJ and PLY written |
//! | [`region`] | the region outlined by marks on a surface: the loop along the surface, the smaller side, cut out and put back |
//! | [`sample`] | sample surfaces made by the project |

pub mod batch;
pub mod deform;
pub mod mesh_io;
pub mod region;
pub mod sample;
pub mod surface;
