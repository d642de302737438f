//! What a soft body shows, as rasterizer meshes: the surface with its region tinted or its
//! shift from the original as a heat map, and the marks as small balls.

use crate::raster::{MeshData, vertex_normals};
use bevy::math::Vec3;

/// The tint of the region's inside (multiplies the surface colour).
pub const REGION_TINT: Vec3 = Vec3::new(0.5, 0.8, 1.25);
/// The tint of the region's outline.
pub const OUTLINE_TINT: Vec3 = Vec3::new(1.0, 0.35, 0.25);
/// The tint of the vertex that moved farthest from the original, in the overlay.
pub const FARTHEST_TINT: Vec3 = Vec3::new(1.0, 0.15, 0.05);

/// The surface at `positions` as a mesh with a tint per vertex (white leaves the surface's
/// colour as it is).
pub fn surface_mesh(positions: &[Vec3], triangles: &[[u32; 3]], tints: Vec<Vec3>) -> MeshData {
    MeshData {
        positions: positions.to_vec(),
        normals: vertex_normals(positions, triangles),
        colors: tints,
        triangles: triangles.to_vec(),
        ..Default::default()
    }
}

/// Per-vertex tints showing a region: `inside` vertices (which may move) and the `outline`.
pub fn region_tints(count: usize, inside: &[u32], outline: &[u32]) -> Vec<Vec3> {
    let mut tints = vec![Vec3::ONE; count];
    for &v in inside {
        tints[v as usize] = REGION_TINT;
    }
    for &v in outline {
        tints[v as usize] = OUTLINE_TINT;
    }
    tints
}

/// Per-vertex tints showing how far each vertex of `after` lies from `before`: white where
/// it did not move, [`FARTHEST_TINT`] at the largest shift; and that shift, metres.
pub fn shift_tints(before: &[Vec3], after: &[Vec3]) -> (Vec<Vec3>, f32) {
    let shifts: Vec<f32> = before.iter().zip(after).map(|(a, b)| a.distance(*b)).collect();
    let largest = shifts.iter().copied().fold(0.0f32, f32::max);
    let tints = shifts.iter().map(|&s| Vec3::ONE.lerp(FARTHEST_TINT, s / largest.max(f32::MIN_POSITIVE))).collect();
    (tints, largest)
}

/// Balls of `radius_m` metres at `points`, one mesh.
pub fn marker_mesh(points: &[Vec3], radius_m: f32) -> MeshData {
    let ball = MeshData::sphere(6, 10);
    let mut mesh = MeshData::default();
    for &point in points {
        let first = mesh.positions.len() as u32;
        // The primitive sphere is 1 across.
        mesh.positions.extend(ball.positions.iter().map(|&p| point + p * (2.0 * radius_m)));
        mesh.normals.extend_from_slice(&ball.normals);
        mesh.triangles.extend(ball.triangles.iter().map(|t| t.map(|v| v + first)));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::super::sample;
    use super::*;

    #[test]
    fn normals_face_out_and_tints_mark_what_they_say() {
        let sphere = sample::sphere(1.0, 8, 16);
        let normals = vertex_normals(&sphere.positions, &sphere.triangles);
        assert!(sphere.positions.iter().zip(&normals).all(|(p, n)| p.dot(*n) > 0.9 && (n.length() - 1.0).abs() < 1e-5));
        let tints = region_tints(5, &[1, 2], &[3]);
        assert_eq!(tints, [Vec3::ONE, REGION_TINT, REGION_TINT, OUTLINE_TINT, Vec3::ONE]);
        let before = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let after = [Vec3::ZERO, Vec3::X * 1.5, Vec3::Y * 2.0];
        let (tints, largest) = shift_tints(&before, &after);
        assert_eq!((tints[0], tints[2], largest), (Vec3::ONE, FARTHEST_TINT, 1.0));
        let (still, none) = shift_tints(&before, &before);
        assert!(still.iter().all(|&t| t == Vec3::ONE) && none == 0.0);
        let balls = marker_mesh(&[Vec3::ZERO, Vec3::X], 0.01);
        assert!(balls.positions[..balls.positions.len() / 2].iter().all(|p| (p.length() - 0.01).abs() < 1e-4));
        assert_eq!(balls.triangles.len(), 2 * MeshData::sphere(6, 10).triangles.len());
    }
}
