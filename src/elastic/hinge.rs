//! The skin's hinges: two surface triangles sharing an edge, held at their rest dihedral angle
//! with a stiffness from a bending rigidity as in discrete shells (Grinspun et al. 2003), the
//! angle's gradient after Bridson, Marino and Fedkiw (2003).

use super::material::Material;
use super::tet_mesh::TetMesh;
use bevy::math::Vec3;
use std::collections::BTreeMap;
use std::f32::consts::{PI, TAU};

/// A hinge of the surface: two triangles sharing the edge `[p, q]`, `[p, q, r]` and `[q, p, s]`
/// turned outwards, held at their rest dihedral angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Hinge {
    /// `[r, s, p, q]`: the wings' tips, then the shared edge's ends.
    pub(super) corners: [u32; 4],
    /// The angle between the triangles' normals at rest, radians (0: flat).
    pub(super) rest_rad: f32,
    /// `3 |e|^2 / (A1 + A2)` at rest, which makes the stiffness a rigidity's.
    pub(super) weight: f32,
    pub(super) compliance: f32,
}

impl Hinge {
    /// How far `angle` is from the rest angle, radians, the short way round.
    pub(super) fn bend(&self, angle: f32) -> f32 {
        (angle - self.rest_rad + PI).rem_euclid(TAU) - PI
    }
}

/// The dihedral angle of a hinge's corners `[r, s, p, q]` (radians, 0 when its triangles lie
/// flat, positive where the surface is convex) and its gradient at each corner, or `None` for a
/// hinge with a collapsed triangle or edge.
pub(super) fn dihedral([r, s, p, q]: [Vec3; 4]) -> Option<(f32, [Vec3; 4])> {
    let edge = q - p;
    let length = edge.length();
    let (n1, n2) = ((r - p).cross(r - q), (s - q).cross(s - p));
    let (a1, a2) = (n1.length_squared(), n2.length_squared());
    if length < 1e-12 || a1 < 1e-24 || a2 < 1e-24 {
        return None;
    }
    let angle = n1.cross(n2).dot(edge / length).atan2(n1.dot(n2));
    let (n1, n2) = (n1 / a1, n2 / a2);
    let along = |v: Vec3| v.dot(edge) / length;
    let gradients =
        [-length * n1, -length * n2, -(along(r - q) * n1 + along(s - q) * n2), along(r - p) * n1 + along(s - p) * n2];
    Some((angle, gradients))
}

/// The hinges of the surface of the tetrahedral `mesh`: its triangles that belong to one
/// tetrahedron each, turned outwards, taken two by two at every edge that exactly two share,
/// with the compliance `material` gives them.
pub(super) fn hinges(mesh: &TetMesh, material: &Material) -> Vec<Hinge> {
    let mut faces: BTreeMap<[u32; 3], ([u32; 3], u32)> = BTreeMap::new();
    for &[a, b, c, d] in &mesh.tets {
        for (face, opposite) in [([b, c, d], a), ([a, c, d], b), ([a, b, d], c), ([a, b, c], d)] {
            let mut key = face;
            key.sort_unstable();
            let [x, y, z] = face.map(|p| mesh.positions[p as usize]);
            let outwards = (y - x).cross(z - x).dot(x - mesh.positions[opposite as usize]) > 0.0;
            let oriented = if outwards { face } else { [face[0], face[2], face[1]] };
            faces.entry(key).or_insert((oriented, 0)).1 += 1;
        }
    }
    // Each surface edge with the tips of the triangles that run along it either way.
    let mut wings: BTreeMap<[u32; 2], Vec<(bool, u32)>> = BTreeMap::new();
    for ([a, b, c], _) in faces.into_values().filter(|&(_, uses)| uses == 1) {
        for [p, q, r] in [[a, b, c], [b, c, a], [c, a, b]] {
            wings.entry([p.min(q), p.max(q)]).or_default().push((p < q, r));
        }
    }
    let area = |[p, q, r]: [u32; 3]| {
        let [x, y, z] = [p, q, r].map(|i| mesh.positions[i as usize]);
        (y - x).cross(z - x).length() / 2.0
    };
    wings
        .into_iter()
        .filter_map(|([low, high], tips)| {
            let (&[(true, r), (false, s)] | &[(false, s), (true, r)]) = tips.as_slice() else { return None };
            let (p, q) = (low, high);
            let corners = [r, s, p, q];
            let (rest_rad, _) = dihedral(corners.map(|i| mesh.positions[i as usize]))?;
            let length = mesh.positions[p as usize].distance(mesh.positions[q as usize]);
            let weight = 3.0 * length * length / (area([p, q, r]) + area([q, p, s]));
            Some(Hinge { corners, rest_rad, weight, compliance: material.hinge_compliance(weight) })
        })
        .collect()
}
