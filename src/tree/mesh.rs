//! The render mesh of a tree: each support a tapered tube around its polyline with smooth
//! normals, rings turned by parallel transport (no twisting at bends), and rounded, closed tips
//! matching the spheres of the geometry queries.

use super::model::Tree;
use crate::raster::MeshData;
use bevy::math::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, TAU};

/// Rings of each rounded tip, not counting the tip point.
const TIP_RINGS: usize = 3;

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

/// The mesh of every support of `tree`, `sides` vertices around each ring (at least 3).
pub fn tree_mesh(tree: &Tree, sides: usize) -> MeshData {
    let mut mesh = MeshData::default();
    for support in &tree.supports {
        add_tube(&mut mesh, &support.points, &support.radii, sides.max(3));
    }
    mesh
}

/// Appends the tube around `points` with `radii`.
pub(crate) fn add_tube(mesh: &mut MeshData, points: &[Vec3], radii: &[f32], sides: usize) {
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
    let mut rings = Vec::with_capacity(n + 2 * TIP_RINGS + 2);
    // The start tip, from its pole to the first point's ring.
    for k in (1..=TIP_RINGS + 1).rev() {
        let angle = FRAC_PI_2 * k as f32 / (TIP_RINGS + 1) as f32;
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
    for k in 1..=TIP_RINGS + 1 {
        let angle = FRAC_PI_2 * k as f32 / (TIP_RINGS + 1) as f32;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::model::{Shape, SupportSpec, Tree};

    fn bent_tree() -> Tree {
        let spec = SupportSpec {
            name: "bough".into(),
            shape: Shape::Polyline {
                points: vec![Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.8, 1.6, 0.2), Vec3::new(1.5, 1.7, 0.9)],
                radii: vec![0.2, 0.15, 0.1, 0.05],
            },
            kind: None,
        };
        Tree::build(&[spec]).unwrap()
    }

    #[test]
    fn faces_point_outwards_and_normals_are_unit() {
        let tree = bent_tree();
        let mesh = tree_mesh(&tree, 12);
        for n in &mesh.normals {
            assert!((n.length() - 1.0).abs() < 1e-4);
        }
        let mut faces = 0;
        for &[a, b, c] in &mesh.triangles {
            let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
            let face = (pb - pa).cross(pc - pa);
            if face.length() < 1e-9 {
                continue; // the degenerate fans at the poles
            }
            let mean = mesh.normals[a as usize] + mesh.normals[b as usize] + mesh.normals[c as usize];
            assert!(face.dot(mean) > 0.0, "triangle {a} {b} {c} faces inwards");
            faces += 1;
        }
        assert!(faces > 100);
    }

    #[test]
    fn the_surface_matches_the_query_geometry() {
        // Every vertex lies on the surface the geometry queries use, to within the error of
        // a straight tube against the round cone between rings.
        let tree = bent_tree();
        let mesh = tree_mesh(&tree, 16);
        let segments: Vec<_> = tree.segments().map(|(_, s)| s).collect();
        for (p, normal) in mesh.positions.iter().zip(&mesh.normals) {
            let nearest =
                segments.iter().map(|s| s.closest(*p)).min_by(|a, b| a.distance.total_cmp(&b.distance)).unwrap();
            assert!(nearest.distance.abs() < 0.02, "{p} is {} m off the surface", nearest.distance);
            // Normals point out of the surface, as the geometry's do.
            assert!(normal.dot(nearest.normal) > 0.7, "normal {normal} at {p}, surface normal {}", nearest.normal);
        }
    }
}
