//! Drawing the scene over a camera frame: the scene's world placed in the marker's frame, the
//! rasterizer's camera made from the marker's pose and the calibration for the frame as it is
//! fitted into the view, and the pose held for a while when the marker is lost.
//!
//! The scene's world has +y up; the marker's frame (OpenCV's) has +z out of the marker. The
//! world's origin is the marker's centre, its ground the marker's plane, its +x the marker's
//! +x and its -z the marker's +y (away from the viewer of the printed marker), shrunk by the
//! scene's `scale`.

use crate::raster::{Camera, Lens, Pinhole};
use bevy::math::{DVec3, UVec2, Vec2, Vec3};
use canopy_vision::camera::Intrinsics;
use canopy_vision::fit::Fit;
use canopy_vision::pose::Pose;

/// A world point (metres, +y up) in the marker's frame (metres), `scale` marker metres to the
/// world metre.
pub fn marker_from_world(point: Vec3, scale: f64) -> DVec3 {
    DVec3::new(f64::from(point.x), -f64::from(point.z), f64::from(point.y)) * scale
}

/// A marker-frame point in the world.
pub fn world_from_marker(point: DVec3, scale: f64) -> Vec3 {
    let p = point / scale;
    Vec3::new(p.x as f32, p.z as f32, -p.y as f32)
}

/// The rasterizer's camera that sees the world as the calibrated camera at `pose` saw the
/// marker, for a view of `target` pixels showing the frame as `fit` places it (without its
/// distortion); `near` and `far` in world metres.
pub fn render_camera(
    pose: &Pose,
    camera: &Intrinsics,
    fit: &Fit,
    target: UVec2,
    scale: f64,
    near: f32,
    far: f32,
) -> Camera {
    let inverse = pose.rotation.transpose();
    let centre = world_from_marker(-(inverse * pose.translation), scale);
    // The camera's axes in the marker frame are the rows of R: x right, y down, z forward.
    let forward = world_from_marker(inverse * DVec3::Z, 1.0).normalize();
    let up = -world_from_marker(inverse * DVec3::Y, 1.0).normalize();
    let (tw, th) = (f64::from(target.x), f64::from(target.y));
    let pinhole = Pinhole {
        focal: Vec2::new((camera.fx * fit.scale / tw) as f32, (camera.fy * fit.scale / th) as f32),
        centre: Vec2::new(
            ((fit.offset.x + (camera.cx + 0.5) * fit.scale) / tw) as f32,
            ((fit.offset.y + (camera.cy + 0.5) * fit.scale) / th) as f32,
        ),
        up,
    };
    Camera { eye: centre, target: centre + forward, lens: Lens::Pinhole(pinhole), near, far }
}

/// The pose shown: the latest found, kept for `hold_s` seconds of frames without the marker,
/// then none.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tracker {
    /// The pose shown and the time it was found, seconds.
    last: Option<(Pose, f64)>,
}

impl Tracker {
    /// Takes frame time `time_s`'s finding; returns the pose to show and whether it is held
    /// from an earlier frame (a microsecond's rounding of the frame times is forgiven).
    pub fn update(&mut self, found: Option<Pose>, time_s: f64, hold_s: f64) -> Option<(Pose, bool)> {
        if let Some(pose) = found {
            self.last = Some((pose, time_s));
            return Some((pose, false));
        }
        match self.last {
            Some((pose, seen)) if time_s - seen <= hold_s + 1e-6 => Some((pose, true)),
            _ => {
                self.last = None;
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::math::DVec2;
    use canopy_vision::pose::marker_corners;

    #[test]
    fn world_and_marker_frames_map_both_ways() {
        let p = Vec3::new(1.0, 2.0, -3.0);
        assert_eq!(marker_from_world(p, 0.5), DVec3::new(0.5, 1.5, 1.0));
        assert!(world_from_marker(marker_from_world(p, 0.01), 0.01).distance(p) < 1e-5);
    }

    #[test]
    fn the_render_camera_sees_the_marker_where_the_camera_did() {
        let camera = Intrinsics { cx: 300.0, cy: 260.0, ..Intrinsics::pinhole([640, 480], 55.0) };
        let pose = Pose::from_rvec(DVec3::new(2.6, 0.3, -0.2), DVec3::new(0.03, -0.02, 0.5));
        let scale = 0.01;
        // A view of another shape: the frame is scaled and centred in it.
        for target in [UVec2::new(640, 480), UVec2::new(1000, 500)] {
            let fit = Fit::new(camera.size, target.to_array());
            let render = render_camera(&pose, &camera, &fit, target, scale, 0.1, 1000.0);
            let clip = render.view_projection(target.x as f32 / target.y as f32);
            for corner in marker_corners(0.1) {
                let seen = fit.to_view(camera.project(pose.apply(corner)).unwrap());
                let ndc = clip.project_point3(world_from_marker(corner, scale));
                let pixel = DVec2::new(
                    f64::from((ndc.x + 1.0) * 0.5 * target.x as f32) - 0.5,
                    f64::from((1.0 - ndc.y) * 0.5 * target.y as f32) - 0.5,
                );
                assert!(pixel.distance(seen) < 0.01, "{target}: {pixel} for {seen}");
            }
        }
    }

    #[test]
    fn a_lost_marker_is_held_then_dropped() {
        let pose = Pose::from_rvec(DVec3::X, DVec3::Z);
        let mut tracker = Tracker::default();
        assert_eq!(tracker.update(None, 0.0, 0.5), None);
        assert_eq!(tracker.update(Some(pose), 1.0, 0.5), Some((pose, false)));
        assert_eq!(tracker.update(None, 1.5, 0.5), Some((pose, true)));
        assert_eq!(tracker.update(None, 1.6, 0.5), None);
        assert_eq!(tracker.update(None, 1.7, 0.5), None);
    }
}
