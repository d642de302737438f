//! The perspective camera and the directional light the rasterizer draws with.

use bevy_math::{Mat4, Vec2, Vec3, Vec4};

/// A perspective camera looking from `eye` towards `target`, with +y up (or +z when looking
/// straight up or down).
///
/// Its projection maps the view volume to normalized device depth in `[0, 1]`: 0 at `near`,
/// 1 at `far` (see [`FAR_DEPTH`](super::framebuffer::FAR_DEPTH)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position in world units (metres).
    pub eye: Vec3,
    /// The point looked at, in world units.
    pub target: Vec3,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    /// Distance to the near clipping plane, > 0.
    pub near: f32,
    /// Distance to the far clipping plane, > `near`.
    pub far: f32,
}

impl Camera {
    /// The world-to-view matrix (right-handed, looking down -z).
    pub fn view(&self) -> Mat4 {
        let mut forward = self.target - self.eye;
        if forward.length_squared() < 1e-12 {
            forward = Vec3::NEG_Z;
        }
        let forward = forward.normalize();
        let up = if forward.y.abs() > 0.999 { Vec3::Z } else { Vec3::Y };
        Mat4::look_at_rh(self.eye, self.eye + forward, up)
    }

    /// The view-to-clip matrix for an image of the given width / height ratio.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y, aspect, self.near, self.far)
    }

    /// The world-to-clip matrix.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// The ray through a point of the image, given in normalized device coordinates (x right,
    /// y up, both -1 to 1): its start on the near plane and its unit direction.
    pub fn ray(&self, ndc: Vec2, aspect: f32) -> (Vec3, Vec3) {
        let world_from_ndc = self.view_projection(aspect).inverse();
        let near = world_from_ndc.project_point3(ndc.extend(0.0));
        let far = world_from_ndc.project_point3(ndc.extend(1.0));
        (near, (far - near).normalize_or(Vec3::NEG_Z))
    }
}

/// A directional light with Lambert diffuse reflection, a constant fill term and an ambient
/// floor: a surface with unit normal `n` that the light reaches receives
/// `max(fill + diffuse * max(n . -direction, 0), ambient)`, and one in shadow
/// `max(fill, ambient)`.
///
/// The sources' model `I = I0 K max(cos, 0)`, never below an ambient minimum, is `fill = 0`;
/// the standard benchmark scene's `0.15 + 0.85 max(n . l, 0)` is `ambient = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Unit vector along which the light travels (from the light towards the scene).
    pub direction: Vec3,
    /// Diffuse coefficient `I0 * K` in `[0, 1]`.
    pub diffuse: f32,
    /// Intensity added everywhere, in `[0, 1]`.
    pub fill: f32,
    /// The least intensity any surface receives, in `[0, 1]`.
    pub ambient: f32,
}

impl Light {
    /// The diffuse term `diffuse * max(n . -direction, 0)` for a unit normal.
    pub fn diffuse_term(&self, normal: Vec3) -> f32 {
        self.diffuse_lanes(normal.to_array().map(Vec4::splat)).x
    }

    /// [`Light::diffuse_term`] of four unit normals at once, given as lanes of their x, y and
    /// z.
    #[inline(always)]
    pub(crate) fn diffuse_lanes(&self, [x, y, z]: [Vec4; 3]) -> Vec4 {
        let towards = -self.direction;
        (x * towards.x + y * towards.y + z * towards.z).max(Vec4::ZERO) * self.diffuse
    }

    /// Total intensity from a diffuse term scaled by `visibility` (1 lit, 0 in shadow).
    pub fn combine(&self, diffuse_term: f32, visibility: f32) -> f32 {
        self.combine_lanes(Vec4::splat(diffuse_term), Vec4::splat(visibility)).x
    }

    /// [`Light::combine`] of four diffuse terms and visibilities at once.
    #[inline(always)]
    pub(crate) fn combine_lanes(&self, diffuse_term: Vec4, visibility: Vec4) -> Vec4 {
        (Vec4::splat(self.fill) + diffuse_term * visibility).max(Vec4::splat(self.ambient))
    }

    /// Light intensity on a fully lit surface with unit normal `normal`.
    pub fn intensity(&self, normal: Vec3) -> f32 {
        self.combine(self.diffuse_term(normal), 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_and_far_map_to_zero_and_one() {
        let camera = Camera { eye: Vec3::new(0.0, 0.0, 5.0), target: Vec3::ZERO, fov_y: 1.0, near: 0.5, far: 20.0 };
        let clip = camera.view_projection(1.5);
        let near = clip.project_point3(Vec3::new(0.0, 0.0, 4.5));
        let far = clip.project_point3(Vec3::new(0.0, 0.0, -15.0));
        assert!(near.z.abs() < 1e-5 && (far.z - 1.0).abs() < 1e-5, "{near} {far}");
    }

    #[test]
    fn the_ray_through_a_projected_point_passes_through_it() {
        let camera = Camera { eye: Vec3::new(1.0, 2.0, 5.0), target: Vec3::ZERO, fov_y: 0.9, near: 0.1, far: 50.0 };
        let point = Vec3::new(0.7, -0.4, 1.3);
        let ndc = camera.view_projection(1.6).project_point3(point);
        let (origin, direction) = camera.ray(ndc.truncate(), 1.6);
        let along = (point - origin).dot(direction);
        assert!((origin + direction * along).distance(point) < 1e-4);
        assert!((direction.length() - 1.0).abs() < 1e-6 && along > 0.0);
    }

    #[test]
    fn looking_straight_down_is_well_defined() {
        let camera = Camera { eye: Vec3::new(0.0, 10.0, 0.0), target: Vec3::ZERO, fov_y: 1.0, near: 0.1, far: 100.0 };
        let centre = camera.view_projection(1.0).project_point3(Vec3::ZERO);
        assert!(centre.is_finite() && centre.x.abs() < 1e-5 && centre.y.abs() < 1e-5);
    }

    #[test]
    fn intensity_never_drops_below_ambient() {
        let light = Light { direction: -Vec3::Y, diffuse: 0.9, fill: 0.0, ambient: 0.2 };
        assert!((light.intensity(Vec3::Y) - 0.9).abs() < 1e-6);
        assert_eq!(light.intensity(-Vec3::Y), 0.2);
        assert_eq!(light.intensity(Vec3::X), 0.2);
        let filled = Light { fill: 0.15, ambient: 0.0, ..light };
        assert!((filled.intensity(Vec3::Y) - 1.05).abs() < 1e-6);
        assert!((filled.combine(0.9, 0.0) - 0.15).abs() < 1e-6);
    }
}
