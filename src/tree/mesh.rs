//! The render mesh of a tree: each support a tube around its polyline
//! ([`add_tube`](crate::spatial::tube::add_tube)).

use super::model::Tree;
use crate::raster::MeshData;
use crate::spatial::tube::add_tube;

/// The mesh of every support of `tree`, `sides` vertices around each ring (at least 3).
pub fn tree_mesh(tree: &Tree, sides: usize) -> MeshData {
    let mut mesh = MeshData::default();
    for support in &tree.supports {
        add_tube(&mut mesh, &support.points, &support.radii, sides.max(3));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::model::{Shape, SupportSpec, Tree};
    use bevy::math::Vec3;

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
