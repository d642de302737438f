//! The muscle's surface: the node profile revolved about the muscle's axis (local +x), closed
//! by a hemisphere at each end, with smooth per-vertex normals for Gouraud shading.
//!
//! The normal at node `i` lies in the profile plane at the angle
//! `atan(slope_left) / 2 + atan(slope_right) / 2 + 90 deg` from the axis (one slope at the
//! ends), so a bulge shades as a bulge rather than as rings of flat bands.

use crate::raster::MeshData;
use bevy::math::Vec3;
use std::f64::consts::FRAC_PI_2;

/// Rings of latitude on each end hemisphere, besides the equator shared with the body.
const CAP_RINGS: usize = 6;

/// Writes the surface of a muscle with `radii` at node spacing `dx` into `mesh`, using
/// `segments` vertices around each ring. The triangles are rebuilt only when the ring or
/// node count changed, so a deformation only rewrites positions and normals.
pub fn build_surface(radii: &[f64], dx: f64, segments: usize, mesh: &mut MeshData) {
    let segments = segments.max(3);
    let n = radii.len();
    let rings = n + 2 * CAP_RINGS;
    let around: Vec<(f32, f32)> = (0..segments)
        .map(|j| {
            let angle = std::f64::consts::TAU * j as f64 / segments as f64;
            (angle.cos() as f32, angle.sin() as f32)
        })
        .collect();
    // Rings as (centre x, radius, normal angle from +x), from the back cap's pole to the
    // front cap's pole.
    let mut profile: Vec<(f64, f64, f64)> = Vec::with_capacity(rings + 2);
    let slope = |i: usize| (radii[i + 1] - radii[i]) / dx;
    for k in 0..=CAP_RINGS {
        // Back cap: from the pole (angle pi) towards the first node's equator.
        let angle = std::f64::consts::PI - FRAC_PI_2 * k as f64 / (CAP_RINGS + 1) as f64;
        profile.push((radii[0] * angle.cos(), radii[0] * angle.sin(), angle));
    }
    for (i, &radius) in radii.iter().enumerate() {
        // One slope only at the ends.
        let left = slope(i.saturating_sub(1)).atan();
        let right = slope(i.min(n - 2)).atan();
        profile.push((i as f64 * dx, radius, FRAC_PI_2 + (left + right) / 2.0));
    }
    let end = (n - 1) as f64 * dx;
    for k in (0..=CAP_RINGS).rev() {
        let angle = FRAC_PI_2 * k as f64 / (CAP_RINGS + 1) as f64;
        profile.push((end + radii[n - 1] * angle.cos(), radii[n - 1] * angle.sin(), angle));
    }

    mesh.positions.clear();
    mesh.normals.clear();
    for &(x, radius, angle) in &profile {
        let (axial, radial) = (angle.cos() as f32, angle.sin() as f32);
        for &(c, s) in &around {
            mesh.positions.push(Vec3::new(x as f32, radius as f32 * c, radius as f32 * s));
            mesh.normals.push(Vec3::new(axial, radial * c, radial * s));
        }
    }
    // The triangles depend only on the ring and segment counts, which the last triangle
    // encodes; rebuild them when it differs.
    let (rings, segments) = (profile.len() as u32, segments as u32);
    let quad = |ring: u32, j: u32| {
        let (a, b) = (ring * segments + j, ring * segments + (j + 1) % segments);
        let (c, d) = (a + segments, b + segments);
        [[a, b, c], [b, d, c]]
    };
    let expected_last = quad(rings - 2, segments - 1)[1];
    if mesh.triangles.len() != ((rings - 1) * segments * 2) as usize || mesh.triangles.last() != Some(&expected_last) {
        mesh.triangles.clear();
        for ring in 0..rings - 1 {
            for j in 0..segments {
                mesh.triangles.extend(quad(ring, j));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cylinder_profile_has_radial_normals_and_outward_faces() {
        let mut mesh = MeshData::default();
        build_surface(&[2.0; 4], 1.0, 16, &mut mesh);
        assert_eq!(mesh.positions.len(), (4 + 2 * CAP_RINGS + 2) * 16);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((n.length() - 1.0).abs() < 1e-5);
            if (0.0..=3.0).contains(&p.x) && (p.y * p.y + p.z * p.z - 4.0).abs() < 1e-4 && p.x > 0.0 && p.x < 3.0 {
                assert!(n.x.abs() < 1e-6, "body normals are radial: {n} at {p}");
            }
        }
        for &[a, b, c] in &mesh.triangles {
            let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
            let face = (pb - pa).cross(pc - pa);
            let normal = mesh.normals[a as usize] + mesh.normals[b as usize] + mesh.normals[c as usize];
            // Pole rings collapse to points: skip their degenerate triangles.
            if face.length() > 1e-6 {
                assert!(face.dot(normal) > 0.0, "triangle {a} {b} {c} faces inwards");
            }
        }
    }

    #[test]
    fn a_widening_profile_tilts_its_normals_backwards() {
        let mut mesh = MeshData::default();
        build_surface(&[1.0, 2.0, 3.0], 1.0, 8, &mut mesh);
        let middle = (CAP_RINGS + 1 + 1) * 8;
        let n = mesh.normals[middle];
        assert!(n.x < 0.0 && (n.x + (1.0f32).atan().sin()).abs() < 1e-5, "{n}");
    }

    #[test]
    fn remeshing_keeps_the_triangles_when_the_topology_is_unchanged() {
        let mut mesh = MeshData::default();
        build_surface(&[1.0, 2.0, 1.0], 1.0, 12, &mut mesh);
        let triangles = mesh.triangles.clone();
        build_surface(&[1.5, 2.5, 1.5], 1.2, 12, &mut mesh);
        assert_eq!(mesh.triangles, triangles);
        build_surface(&[1.5, 2.5, 1.5, 1.0], 1.2, 12, &mut mesh);
        assert_ne!(mesh.triangles.len(), triangles.len());
    }
}
