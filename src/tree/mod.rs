//! Trees: supports (trunks and branches) as chains of tapered segments, and the geometry
//! queries the sloth and the editor need.
//!
//! | module | what it holds |
//! |---|---|
//! | [`geometry`] | one tapered segment: signed distance, closest surface point, ray hit |
//! | [`bvh`] | a bounding volume hierarchy over all segments: ray cast, nearest, within a radius |
//!
//! Both are pure and tested against brute force.

pub mod bvh;
pub mod geometry;

pub use bvh::{Nearest, RayHit, SegmentBvh};
pub use geometry::{SegmentHit, SurfacePoint, TaperedSegment};
