//! The calibrated camera: OpenCV's pinhole model with radial and tangential distortion.
//!
//! A point `(X, Y, Z)` in the camera frame (x right, y down, z forward, metres) goes to the
//! normalized point `(x, y) = (X / Z, Y / Z)`, is distorted
//! (`r² = x² + y²`, `radial = (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)`,
//! `x' = x radial + 2 p1 x y + p2 (r² + 2 x²)`, `y' = y radial + p1 (r² + 2 y²) + 2 p2 x y`),
//! and lands on pixel `(fx x' + cx, fy y' + cy)`, pixel centres at whole numbers.

use bevy_math::{DVec2, DVec3};

/// Lens distortion coefficients in OpenCV's order `k1 k2 p1 p2 k3 k4 k5 k6` (missing ones 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Distortion(pub [f64; 8]);

/// A camera's intrinsics: focal lengths and principal point in pixels, distortion, and the
/// size of the images it was calibrated for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// The lens distortion.
    pub distortion: Distortion,
    /// Image width and height in pixels.
    pub size: [u32; 2],
}

impl Distortion {
    /// Whether every coefficient is zero: a pinhole.
    pub fn is_none(&self) -> bool {
        self.0.iter().all(|&k| k == 0.0)
    }

    /// The distorted position of a normalized point.
    pub fn apply(&self, point: DVec2) -> DVec2 {
        let [k1, k2, p1, p2, k3, k4, k5, k6] = self.0;
        let (x, y) = (point.x, point.y);
        let r2 = x * x + y * y;
        let radial = (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1.0 + r2 * (k4 + r2 * (k5 + r2 * k6)));
        DVec2::new(
            x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        )
    }

    /// The normalized point whose distorted position is `distorted`, by OpenCV's fixed-point
    /// iteration (`undistortPoints`: divide out the radial factor, subtract the tangential
    /// shift), until it moves less than 1e-12.
    pub fn remove(&self, distorted: DVec2) -> DVec2 {
        if self.is_none() {
            return distorted;
        }
        let [k1, k2, p1, p2, k3, k4, k5, k6] = self.0;
        let mut point = distorted;
        for _ in 0..100 {
            let (x, y) = (point.x, point.y);
            let r2 = x * x + y * y;
            let inverse_radial = (1.0 + r2 * (k4 + r2 * (k5 + r2 * k6))) / (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)));
            let tangential =
                DVec2::new(2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x), p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
            let next = (distorted - tangential) * inverse_radial;
            if next.distance_squared(point) < 1e-24 {
                return next;
            }
            point = next;
        }
        point
    }
}

impl Intrinsics {
    /// A pinhole camera without distortion whose vertical field of view is `fov_y_deg`, its
    /// principal point at the image centre.
    pub fn pinhole(size: [u32; 2], fov_y_deg: f64) -> Self {
        let f = 0.5 * f64::from(size[1]) / (0.5 * fov_y_deg.to_radians()).tan();
        Self {
            fx: f,
            fy: f,
            cx: 0.5 * f64::from(size[0]) - 0.5,
            cy: 0.5 * f64::from(size[1]) - 0.5,
            distortion: Distortion::default(),
            size,
        }
    }

    /// The pixel a point in the camera frame projects to; `None` behind the camera.
    pub fn project(&self, camera_point: DVec3) -> Option<DVec2> {
        (camera_point.z > 1e-9).then(|| self.pixel_of(camera_point.truncate() / camera_point.z))
    }

    /// The pixel of a normalized (undistorted) point.
    pub fn pixel_of(&self, normalized: DVec2) -> DVec2 {
        let d = self.distortion.apply(normalized);
        DVec2::new(self.fx * d.x + self.cx, self.fy * d.y + self.cy)
    }

    /// The normalized (undistorted) point a pixel sees.
    pub fn normalized(&self, pixel: DVec2) -> DVec2 {
        self.distortion.remove(DVec2::new((pixel.x - self.cx) / self.fx, (pixel.y - self.cy) / self.fy))
    }

    /// Where a pinhole camera with the same focal lengths and principal point would have seen
    /// what this one saw at `pixel`: the pixel with the lens's distortion removed.
    pub fn straightened(&self, pixel: DVec2) -> DVec2 {
        let n = self.normalized(pixel);
        DVec2::new(self.fx * n.x + self.cx, self.fy * n.y + self.cy)
    }

    /// The inverse of [`Intrinsics::straightened`]: where this camera sees what a pinhole
    /// camera saw at `pixel`.
    pub fn bent(&self, pixel: DVec2) -> DVec2 {
        self.pixel_of(DVec2::new((pixel.x - self.cx) / self.fx, (pixel.y - self.cy) / self.fy))
    }

    /// The same camera for images scaled to `size` (focal lengths and principal point scaled
    /// with the pixels, their edges kept: a pixel centre `c` maps to `(c + 0.5) s - 0.5`).
    pub fn scaled_to(&self, size: [u32; 2]) -> Self {
        let sx = f64::from(size[0]) / f64::from(self.size[0]);
        let sy = f64::from(size[1]) / f64::from(self.size[1]);
        Self {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
            distortion: self.distortion,
            size,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Intrinsics {
        Intrinsics {
            fx: 800.0,
            fy: 790.0,
            cx: 639.5,
            cy: 360.0,
            distortion: Distortion([-0.28, 0.09, 0.001, -0.0015, -0.01, 0.0, 0.0, 0.0]),
            size: [1280, 720],
        }
    }

    #[test]
    fn undistorting_inverts_distortion_across_the_image() {
        let camera = camera();
        for pixel in
            [DVec2::new(0.0, 0.0), DVec2::new(1279.0, 719.0), DVec2::new(640.0, 100.0), DVec2::new(321.3, 502.9)]
        {
            let back = camera.pixel_of(camera.normalized(pixel));
            assert!(back.distance(pixel) < 1e-6, "{pixel} came back as {back}");
        }
    }

    #[test]
    fn projection_divides_by_depth_and_refuses_points_behind() {
        let pinhole = Intrinsics::pinhole([640, 480], 90.0);
        assert!((pinhole.fy - 240.0).abs() < 1e-9);
        let pixel = pinhole.project(DVec3::new(0.5, -0.25, 2.0)).unwrap();
        assert!(pixel.distance(DVec2::new(319.5 + 60.0, 239.5 - 30.0)) < 1e-9);
        assert_eq!(pinhole.project(DVec3::new(0.0, 0.0, -1.0)), None);
    }

    #[test]
    fn scaling_keeps_the_image_edges_in_place() {
        let half = Intrinsics::pinhole([640, 480], 60.0).scaled_to([320, 240]);
        assert!((half.cx - 159.5).abs() < 1e-12 && (half.cy - 119.5).abs() < 1e-12);
    }
}
