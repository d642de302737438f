//! The perspective camera and the directional light the rasterizer draws with.

use bevy_math::{Mat4, Vec2, Vec3, Vec4};

/// A perspective camera looking from `eye` towards `target`, with +y up (or +z when looking
/// straight up or down) unless its lens says otherwise.
///
/// Its projection maps the view volume to normalized device depth in `[0, 1]`: 0 at `near`,
/// 1 at `far` (see [`FAR_DEPTH`](super::framebuffer::FAR_DEPTH)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position in world units (metres).
    pub eye: Vec3,
    /// The point looked at, in world units.
    pub target: Vec3,
    /// How view directions map to the image.
    pub lens: Lens,
    /// Distance to the near clipping plane, > 0.
    pub near: f32,
    /// Distance to the far clipping plane, > `near`.
    pub far: f32,
}

/// How a camera maps view directions to the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lens {
    /// A symmetric perspective with this vertical field of view in radians; the image's
    /// width over height sets the horizontal one.
    FieldOfView(f32),
    /// A calibrated pinhole camera, so that a render lines up with a photograph taken by it.
    Pinhole(Pinhole),
}

/// A pinhole camera as computer vision calibrates one (OpenCV's camera matrix without
/// distortion), in shares of the image so that it fits any resolution of the same shape: a
/// point at `(X, Y, Z)` in the camera's frame (x right, y down, z along the view) is seen at
/// `(focal.x X / Z + centre.x, focal.y Y / Z + centre.y)` times the image's width and height,
/// from the image's top-left corner.
///
/// From a calibration in pixels of a `W x H` image: `focal = (fx / W, fy / H)` and
/// `centre = ((cx + 0.5) / W, (cy + 0.5) / H)` (OpenCV puts pixel centres at whole numbers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    /// Focal lengths over the image's width and height.
    pub focal: Vec2,
    /// The principal point as a share of the image's width and height.
    pub centre: Vec2,
    /// The world direction the image's up points along (the camera's -y), perpendicular to
    /// the view direction: the roll a look-at camera cannot express.
    pub up: Vec3,
}

impl Camera {
    /// The world-to-view matrix (right-handed, looking down -z).
    pub fn view(&self) -> Mat4 {
        let mut forward = self.target - self.eye;
        if forward.length_squared() < 1e-12 {
            forward = Vec3::NEG_Z;
        }
        let forward = forward.normalize();
        let up = match self.lens {
            Lens::Pinhole(pinhole) => pinhole.up,
            Lens::FieldOfView(_) if forward.y.abs() > 0.999 => Vec3::Z,
            Lens::FieldOfView(_) => Vec3::Y,
        };
        Mat4::look_at_rh(self.eye, self.eye + forward, up)
    }

    /// The view-to-clip matrix for an image of the given width / height ratio (a pinhole's
    /// calibration fixes its own).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        match self.lens {
            Lens::FieldOfView(fov_y) => Mat4::perspective_rh(fov_y, aspect, self.near, self.far),
            Lens::Pinhole(Pinhole { focal, centre, .. }) => {
                // x_ndc = 2 (focal.x x / -z + centre.x) - 1, y_ndc = 1 - 2 (focal.y -y / -z + centre.y),
                // both times w = -z; depth as `perspective_rh`'s.
                let r = self.far / (self.near - self.far);
                Mat4::from_cols(
                    Vec4::new(2.0 * focal.x, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, 2.0 * focal.y, 0.0, 0.0),
                    Vec4::new(1.0 - 2.0 * centre.x, 2.0 * centre.y - 1.0, r, -1.0),
                    Vec4::new(0.0, 0.0, r * self.near, 0.0),
                )
            }
        }
    }
    /// Pixels a unit length spans at unit distance straight ahead (the focal length in
    /// pixels), in an image `height` pixels high.
    pub fn focal_px(&self, height: u32) -> f32 {
        match self.lens {
            Lens::FieldOfView(fov_y) => 0.5 * height as f32 / (0.5 * fov_y).tan(),
            Lens::Pinhole(pinhole) => pinhole.focal.y * height as f32,
        }
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
    fn the_focal_length_in_pixels_scales_sizes_at_a_distance() {
        let camera = Camera {
            eye: Vec3::ZERO,
            target: Vec3::NEG_Z,
            lens: Lens::FieldOfView(60f32.to_radians()),
            near: 0.1,
            far: 100.0,
        };
        let height = 480;
        // 10 cm up at 10 m: its pixels from the image's centre line.
        let clip = camera.view_projection(4.0 / 3.0) * Vec4::new(0.0, 0.1, -10.0, 1.0);
        let pixels = clip.y / clip.w * height as f32 / 2.0;
        assert!((pixels - camera.focal_px(height) * 0.1 / 10.0).abs() < 1e-3, "{pixels}");
    }

    #[test]
    fn a_pinhole_sees_points_where_its_calibration_puts_them() {
        // A 640 x 480 calibration: fx 500, fy 520, principal point (300.5, 250).
        let (fx, fy, cx, cy) = (500.0, 520.0, 300.5, 250.0);
        let pinhole = Pinhole {
            focal: Vec2::new(fx / 640.0, fy / 480.0),
            centre: Vec2::new((cx + 0.5) / 640.0, (cy + 0.5) / 480.0),
            up: Vec3::Y,
        };
        let camera =
            Camera { eye: Vec3::ZERO, target: Vec3::NEG_Z, lens: Lens::Pinhole(pinhole), near: 0.1, far: 50.0 };
        // (0.4, -0.3, 2) in the computer-vision frame is (0.4, 0.3, -2) in the view frame.
        let ndc = camera.view_projection(4.0 / 3.0).project_point3(Vec3::new(0.4, 0.3, -2.0));
        let pixel = Vec2::new((ndc.x + 1.0) * 0.5 * 640.0 - 0.5, (1.0 - ndc.y) * 0.5 * 480.0 - 0.5);
        let expected = Vec2::new(fx * 0.4 / 2.0 + cx, fy * -0.3 / 2.0 + cy);
        assert!(pixel.distance(expected) < 1e-3, "{pixel} for {expected}");
        assert!(ndc.z > 0.0 && ndc.z < 1.0);
        // The up vector rolls the image: with +x up, a point to the right of centre (+x)
        // shows above it.
        let rolled = Camera { lens: Lens::Pinhole(Pinhole { up: Vec3::X, ..pinhole }), ..camera };
        let ndc = rolled.view_projection(4.0 / 3.0).project_point3(Vec3::new(0.4, 0.0, -2.0));
        assert!(ndc.y > 0.3 && ndc.x.abs() < 0.1, "{ndc}");
    }

    #[test]
    fn near_and_far_map_to_zero_and_one() {
        let camera = Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            lens: Lens::FieldOfView(1.0),
            near: 0.5,
            far: 20.0,
        };
        let clip = camera.view_projection(1.5);
        let near = clip.project_point3(Vec3::new(0.0, 0.0, 4.5));
        let far = clip.project_point3(Vec3::new(0.0, 0.0, -15.0));
        assert!(near.z.abs() < 1e-5 && (far.z - 1.0).abs() < 1e-5, "{near} {far}");
    }

    #[test]
    fn the_ray_through_a_projected_point_passes_through_it() {
        let camera = Camera {
            eye: Vec3::new(1.0, 2.0, 5.0),
            target: Vec3::ZERO,
            lens: Lens::FieldOfView(0.9),
            near: 0.1,
            far: 50.0,
        };
        let point = Vec3::new(0.7, -0.4, 1.3);
        let ndc = camera.view_projection(1.6).project_point3(point);
        let (origin, direction) = camera.ray(ndc.truncate(), 1.6);
        let along = (point - origin).dot(direction);
        assert!((origin + direction * along).distance(point) < 1e-4);
        assert!((direction.length() - 1.0).abs() < 1e-6 && along > 0.0);
    }

    #[test]
    fn looking_straight_down_is_well_defined() {
        let camera = Camera {
            eye: Vec3::new(0.0, 10.0, 0.0),
            target: Vec3::ZERO,
            lens: Lens::FieldOfView(1.0),
            near: 0.1,
            far: 100.0,
        };
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
