//! The standard benchmark scene, defined once: a lit heightfield grid seen from two cameras.
//!
//! A 128 x 128-vertex grid over `x, z` in `[-1, 1]` with height
//! `y = 0.15 sin(3x) cos(2z) + 0.05 sin(7x + 5z)` (32,258 triangles), normals from the analytic
//! gradient, colour (0.35, 0.65, 0.25) lit per vertex by `0.15 + 0.85 max(n . l, 0)` with
//! `l = normalize(0.4, 0.8, 0.3)`, drawn at 1280 x 720 with a 60 degree vertical field of view,
//! near 0.1 and far 10, depth-tested with back faces culled.

use crate::{Camera, Frame, Instance, Lens, Light, Material, MeshData, RenderSettings};
use bevy_math::{Mat4, Vec3};
use std::sync::Arc;

/// Vertices along each side of the grid.
pub const GRID_VERTICES: u32 = 128;

/// Image width in pixels.
pub const WIDTH: u32 = 1280;

/// Image height in pixels.
pub const HEIGHT: u32 = 720;

/// Surface colour, linear RGB.
pub const COLOR: Vec3 = Vec3::new(0.35, 0.65, 0.25);

/// Background colour, RGBA8.
pub const BACKGROUND: [u8; 4] = [0, 0, 0, 255];

/// A named viewpoint on the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandardCamera {
    /// Short name used in reports.
    pub name: &'static str,
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
}

impl StandardCamera {
    /// The rasterizer camera for this viewpoint.
    pub fn camera(&self) -> Camera {
        Camera { eye: self.eye, target: self.target, lens: Lens::FieldOfView(60f32.to_radians()), near: 0.1, far: 10.0 }
    }
}

/// The two viewpoints: "overview" covers about 40% of the image, "close" about 60%.
pub const CAMERAS: [StandardCamera; 2] = [
    StandardCamera { name: "overview", eye: Vec3::new(0.0, 0.9, 1.6), target: Vec3::new(0.0, -0.1, -0.1) },
    StandardCamera { name: "close", eye: Vec3::new(0.0, 0.55, 1.25), target: Vec3::new(0.0, -0.05, 0.0) },
];

/// Unit vector towards the light.
pub fn towards_light() -> Vec3 {
    Vec3::new(0.4, 0.8, 0.3).normalize()
}

/// The light: `0.15 + 0.85 max(n . l, 0)`.
pub fn light() -> Light {
    Light { direction: -towards_light(), diffuse: 0.85, fill: 0.15, ambient: 0.0 }
}

/// Height of the surface above `(x, z)`.
pub fn height(x: f32, z: f32) -> f32 {
    0.15 * (3.0 * x).sin() * (2.0 * z).cos() + 0.05 * (7.0 * x + 5.0 * z).sin()
}

/// Unit normal of the surface above `(x, z)`, from the analytic gradient of [`height`].
pub fn normal(x: f32, z: f32) -> Vec3 {
    let ridge = 0.05 * (7.0 * x + 5.0 * z).cos();
    let dx = 0.45 * (3.0 * x).cos() * (2.0 * z).cos() + 7.0 * ridge;
    let dz = -0.3 * (3.0 * x).sin() * (2.0 * z).sin() + 5.0 * ridge;
    Vec3::new(-dx, 1.0, -dz).normalize()
}

/// The grid mesh, in world coordinates, front faces up.
pub fn grid() -> MeshData {
    let n = GRID_VERTICES;
    let coordinate = |i: u32| -1.0 + 2.0 * i as f32 / (n - 1) as f32;
    let mut mesh = MeshData::default();
    for j in 0..n {
        for i in 0..n {
            let (x, z) = (coordinate(i), coordinate(j));
            mesh.positions.push(Vec3::new(x, height(x, z), z));
            mesh.normals.push(normal(x, z));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b, c, d) = (j * n + i, (j + 1) * n + i, (j + 1) * n + i + 1, j * n + i + 1);
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

/// The grid as one untextured instance.
pub fn instance() -> Instance {
    Instance { mesh: Arc::new(grid()), model: Mat4::IDENTITY, material: Material::colored(COLOR) }
}

/// The frame for one viewpoint, drawing `instances` with `settings`.
pub fn frame<'a>(camera: &StandardCamera, instances: &'a [Instance], settings: RenderSettings) -> Frame<'a> {
    Frame { camera: camera.camera(), light: light(), background: BACKGROUND, instances, settings }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_has_the_documented_size_and_faces_up() {
        let mesh = grid();
        assert_eq!(mesh.positions.len(), 128 * 128);
        assert_eq!(mesh.triangle_count(), 32_258);
        for &[a, b, c] in &mesh.triangles {
            let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
            assert!((pb - pa).cross(pc - pa).y > 0.0);
        }
    }

    #[test]
    fn normals_match_finite_differences() {
        let h = 1e-3;
        for (x, z) in [(0.1, -0.3), (-0.7, 0.5), (0.9, 0.9)] {
            let dx = (height(x + h, z) - height(x - h, z)) / (2.0 * h);
            let dz = (height(x, z + h) - height(x, z - h)) / (2.0 * h);
            let expected = Vec3::new(-dx, 1.0, -dz).normalize();
            assert!(normal(x, z).distance(expected) < 1e-3, "at ({x}, {z})");
        }
    }
}
