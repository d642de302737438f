//! What surgery planning measures between two points of a surface: the distance along the
//! surface (a tape measure laid on the skin) and the straight one (calipers), on the original
//! and on every model, so that a tightening's effect on two landmarks can be read off.

use crate::spatial::geodesic::along_surface;
use bevy::math::Vec3;
use serde::Serialize;

/// The two distances between two vertices of a surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Distances {
    /// Along the surface, metres; `None` where no way on the surface joins them.
    pub along_m: Option<f64>,
    /// Straight through space, metres.
    pub straight_m: f64,
}

impl Distances {
    /// Between vertices `a` and `b` of the surface of `triangles` at `positions`; `None` if
    /// either vertex does not exist.
    pub fn between(positions: &[Vec3], triangles: &[[u32; 3]], [a, b]: [u32; 2]) -> Option<Self> {
        let straight_m = f64::from(positions.get(a as usize)?.distance(*positions.get(b as usize)?));
        Some(Self { along_m: along_surface(positions, triangles, a, b), straight_m })
    }
}

/// The distances between two measured vertices before a shrink and after it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Measured {
    /// The two vertices.
    pub vertices: [u32; 2],
    /// On the surface the shrink started from.
    pub before: Distances,
    /// On the shrunk surface.
    pub after: Distances,
}

impl Measured {
    /// Between `vertices` of the surface of `triangles`, before (`before`) and after
    /// (`after`) a shrink.
    pub fn of(before: &[Vec3], after: &[Vec3], triangles: &[[u32; 3]], vertices: [u32; 2]) -> Option<Self> {
        Some(Self {
            vertices,
            before: Distances::between(before, triangles, vertices)?,
            after: Distances::between(after, triangles, vertices)?,
        })
    }
}
