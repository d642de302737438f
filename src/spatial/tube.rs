//! Tubes: a tapered tube around a polyline with smooth normals, rings turned by parallel
//! transport (no twisting at bends), and rounded, closed tips matching the spheres of the
//! segments' queries. The trees' supports, the sloth's limbs and the stems of hanging bodies
//! are drawn with them.

use crate::raster::MeshData;
use bevy::math::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, TAU};

/// Rings of each rounded tip, not counting the tip point.
pub const TIP_RINGS: usize = 3;

/// One ring of a tube: its centre, axis direction, radius, and how far its normals lean along
/// the axis (0 on the side, +-1 at the tips).
#[derive(Debug, Clone, Copy)]
struct Ring {
    centre: Vec3,
    axis: Vec3,
    radius: f32,
    lean: f32,
    /// Distance along the support, for the texture's v.
    along: f32,
}

/// Appends the tube around `points` with `radii`, `sides` vertices around each ring.
pub fn add_tube(mesh: &mut MeshData, points: &[Vec3], radii: &[f32], sides: usize) {
    add_tube_with_tips(mesh, points, radii, sides, TIP_RINGS);
}

/// Rings of a rounded tip that keep it within `tolerance` of the round one on a tube of
/// `radius` (the same units): from none (a cone to the pole) to the tips' most.
pub fn tip_rings(radius: f32, tolerance: f32) -> usize {
    // Each of a tip's k + 1 pieces spans a quarter turn over k + 1; its sagitta is the error.
    (0..TIP_RINGS)
        .find(|&k| radius * (1.0 - (FRAC_PI_2 / 2.0 / (k + 1) as f32).cos()) <= tolerance)
        .unwrap_or(TIP_RINGS)
}

/// Triangles of the tube [`add_tube_with_tips`] makes around `points` points, `sides` around
/// and `tip` rings rounding each tip: two a side between each pair of consecutive rings.
pub fn tube_triangles(points: usize, sides: usize, tip: usize) -> usize {
    2 * sides * (points + 2 * tip.min(TIP_RINGS) + 1)
}

/// Appends the tube around `points` with `radii`, `sides` vertices around each ring and
/// `tip` rings (at most the tips' most) rounding each tip.
pub fn add_tube_with_tips(mesh: &mut MeshData, points: &[Vec3], radii: &[f32], sides: usize, tip: usize) {
    let tip = tip.min(TIP_RINGS);
    let n = points.len();
    // Tangents: the mean direction of the two segments at inner points.
    let direction = |i: usize| (points[i + 1] - points[i]).normalize_or_zero();
    let tangents: Vec<Vec3> = (0..n)
        .map(|i| match i {
            0 => direction(0),
            i if i == n - 1 => direction(n - 2),
            i => (direction(i - 1) + direction(i)).normalize_or(direction(i)),
        })
        .collect();
    let mut along = 0.0;
    let mut rings = Vec::with_capacity(n + 2 * tip + 2);
    // The start tip, from its pole to the first point's ring.
    for k in (1..=tip + 1).rev() {
        let angle = FRAC_PI_2 * k as f32 / (tip + 1) as f32;
        rings.push(Ring {
            centre: points[0] - tangents[0] * radii[0] * angle.sin(),
            axis: tangents[0],
            radius: radii[0] * angle.cos(),
            lean: -angle.sin(),
            along: -radii[0] * angle.sin(),
        });
    }
    for i in 0..n {
        if i > 0 {
            along += points[i].distance(points[i - 1]);
        }
        rings.push(Ring { centre: points[i], axis: tangents[i], radius: radii[i], lean: 0.0, along });
    }
    for k in 1..=tip + 1 {
        let angle = FRAC_PI_2 * k as f32 / (tip + 1) as f32;
        rings.push(Ring {
            centre: points[n - 1] + tangents[n - 1] * radii[n - 1] * angle.sin(),
            axis: tangents[n - 1],
            radius: radii[n - 1] * angle.cos(),
            lean: angle.sin(),
            along: along + radii[n - 1] * angle.sin(),
        });
    }

    // Parallel transport: each ring's reference direction is the previous one's, turned onto
    // the new ring's plane, so that the tube does not twist.
    let mut reference = tangents[0].any_orthonormal_vector();
    let first = mesh.positions.len() as u32;
    for ring in &rings {
        reference = (reference - ring.axis * reference.dot(ring.axis)).normalize_or(ring.axis.any_orthonormal_vector());
        let side = ring.axis.cross(reference);
        for j in 0..=sides {
            let angle = TAU * (j % sides) as f32 / sides as f32;
            let radial = reference * angle.cos() + side * angle.sin();
            let lean = ring.lean;
            let normal = (radial * (1.0 - lean * lean).max(0.0).sqrt() + ring.axis * lean).normalize_or(ring.axis);
            mesh.positions.push(ring.centre + radial * ring.radius);
            mesh.normals.push(normal);
            mesh.uvs.push(Vec2::new(j as f32 / sides as f32, ring.along));
        }
    }
    // Quads between consecutive rings, counter-clockwise seen from outside.
    let row = sides as u32 + 1;
    for r in 0..rings.len() as u32 - 1 {
        for j in 0..sides as u32 {
            let a = first + r * row + j;
            let b = a + row;
            mesh.triangles.push([a, a + 1, b]);
            mesh.triangles.push([a + 1, b + 1, b]);
        }
    }
}
