//! A square marker's pose from its four corners: both solutions of the planar problem by
//! Infinitesimal Plane-based Pose Estimation (IPPE, Collins and Bartoli, "Infinitesimal
//! Plane-based Pose Estimation", IJCV 2014), each refined by Levenberg–Marquardt on the pixel
//! reprojection error through the full camera model, and the better one kept.
//!
//! The marker frame is OpenCV's: origin at the marker's centre, x right, y up, z out of the
//! printed face towards the viewer; corners in OpenCV's order (top-left, top-right,
//! bottom-right, bottom-left as printed).

use crate::camera::Intrinsics;
use crate::least_squares::{Settings, minimise};
use crate::linear::solve;
use bevy_math::{DMat2, DMat3, DQuat, DVec2, DVec3};

/// A rigid transform from the marker frame to the camera frame: `camera = R marker + t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// The rotation `R`.
    pub rotation: DMat3,
    /// The translation `t`, metres: the marker's centre in the camera frame.
    pub translation: DVec3,
}

/// The pose chosen for one marker and how sure it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseEstimate {
    /// The solution with the smaller reprojection error.
    pub pose: Pose,
    /// Its root-mean-square reprojection error over the four corners, pixels.
    pub error_px: f64,
    /// The other solution of the planar ambiguity (refined if it is a minimum of its own): its
    /// error is close to `error_px` when the marker is small or seen face on and the choice
    /// is uncertain.
    pub alternative: Pose,
    /// The alternative's root-mean-square reprojection error, pixels.
    pub alternative_error_px: f64,
}

impl Pose {
    /// The pose of a rotation vector (axis times angle in radians, OpenCV's `rvec`) and a
    /// translation (`tvec`).
    pub fn from_rvec(rvec: DVec3, tvec: DVec3) -> Self {
        let angle = rvec.length();
        let rotation = if angle < 1e-15 { DMat3::IDENTITY } else { DMat3::from_axis_angle(rvec / angle, angle) };
        Self { rotation, translation: tvec }
    }

    /// The rotation as OpenCV's `rvec`: axis times angle, the angle in `[0, pi]`.
    pub fn rvec(&self) -> DVec3 {
        let mut q = DQuat::from_mat3(&self.rotation).normalize();
        if q.w < 0.0 {
            q = -q;
        }
        let (axis, angle) = q.to_axis_angle();
        if angle.abs() < 1e-15 { DVec3::ZERO } else { axis * angle }
    }

    /// A marker-frame point in the camera frame.
    pub fn apply(&self, point: DVec3) -> DVec3 {
        self.rotation * point + self.translation
    }

    /// The angle between this pose's rotation and `other`'s, radians.
    pub fn angle_to(&self, other: &Pose) -> f64 {
        let relative = self.rotation.transpose() * other.rotation;
        let cos = ((relative.x_axis.x + relative.y_axis.y + relative.z_axis.z - 1.0) * 0.5).clamp(-1.0, 1.0);
        cos.acos()
    }
}

/// The corners of a square marker `side` metres across in its frame, in OpenCV's order.
pub fn marker_corners(side: f64) -> [DVec3; 4] {
    let h = 0.5 * side;
    [DVec3::new(-h, h, 0.0), DVec3::new(h, h, 0.0), DVec3::new(h, -h, 0.0), DVec3::new(-h, -h, 0.0)]
}

/// The root-mean-square distance in pixels between `pixels` and the projections of `points`
/// under `pose`; infinite if a point falls behind the camera.
pub fn reprojection_error(pose: &Pose, points: &[DVec3], pixels: &[DVec2], camera: &Intrinsics) -> f64 {
    let sum: f64 = points
        .iter()
        .zip(pixels)
        .map(|(&p, &q)| camera.project(pose.apply(p)).map_or(f64::INFINITY, |r| r.distance_squared(q)))
        .sum();
    (sum / points.len() as f64).sqrt()
}

/// The pose of a square marker `side` metres across whose corners were seen at `corners`
/// (pixels, OpenCV's order); `None` if the corners do not make a quadrilateral a plane could
/// project to.
pub fn estimate(corners: &[DVec2; 4], side: f64, camera: &Intrinsics) -> Option<PoseEstimate> {
    let object = marker_corners(side);
    let normalized = corners.map(|c| camera.normalized(c));
    let plane = object.map(|p| p.truncate());
    let homography = homography(&plane, &normalized)?;
    let [first, second] = ippe(&homography)?;
    let start =
        [first, second].map(|rotation| Pose { rotation, translation: translation(&rotation, &object, &normalized) });
    let mut solutions = start.map(|pose| {
        let pose = refine(pose, &object, corners, camera);
        (pose, reprojection_error(&pose, &object, corners, camera))
    });
    solutions.sort_by(|a, b| a.1.total_cmp(&b.1));
    let [(pose, error_px), (mut alternative, mut alternative_error_px)] = solutions;
    if alternative.angle_to(&pose) < 1e-3 {
        // Both refinements reached the same minimum: the other solution is IPPE's mirrored
        // pose as it was, the farther of the two from the one kept.
        alternative = *start.iter().max_by(|a, b| a.angle_to(&pose).total_cmp(&b.angle_to(&pose))).unwrap_or(&start[1]);
        alternative_error_px = reprojection_error(&alternative, &object, corners, camera);
    }
    error_px.is_finite().then_some(PoseEstimate { pose, error_px, alternative, alternative_error_px })
}

/// The homography taking four plane points to four image points (`h33 = 1`), by solving the
/// eight linear equations of the direct linear transform.
fn homography(from: &[DVec2; 4], to: &[DVec2; 4]) -> Option<DMat3> {
    let (mut system, mut right) = ([[0.0f64; 8]; 8], [0.0f64; 8]);
    for (i, (p, q)) in from.iter().zip(to).enumerate() {
        system[2 * i] = [p.x, p.y, 1.0, 0.0, 0.0, 0.0, -p.x * q.x, -p.y * q.x];
        system[2 * i + 1] = [0.0, 0.0, 0.0, p.x, p.y, 1.0, -p.x * q.y, -p.y * q.y];
        (right[2 * i], right[2 * i + 1]) = (q.x, q.y);
    }
    let h = solve(&mut system, &mut right, 1e-14)?;
    Some(DMat3::from_cols_array(&[h[0], h[3], h[6], h[1], h[4], h[7], h[2], h[5], 1.0]))
}

/// The two rotations IPPE finds from the homography's first-order behaviour at the plane's
/// origin.
fn ippe(h: &DMat3) -> Option<[DMat3; 2]> {
    // The origin's image and the homography's Jacobian there (h is column-major: h.col(c)[r]).
    let (u0, v0) = (h.z_axis.x, h.z_axis.y);
    let jacobian = DMat2::from_cols(
        DVec2::new(h.x_axis.x - h.x_axis.z * u0, h.x_axis.y - h.x_axis.z * v0),
        DVec2::new(h.y_axis.x - h.y_axis.z * u0, h.y_axis.y - h.y_axis.z * v0),
    );
    // A rotation whose third column points along the ray to the origin's image.
    let ray = DVec3::new(u0, v0, 1.0).normalize();
    let rv = DMat3::from_quat(DQuat::from_rotation_arc(DVec3::Z, ray));
    let b = DMat2::from_cols(
        DVec2::new(rv.x_axis.x - u0 * rv.x_axis.z, rv.x_axis.y - v0 * rv.x_axis.z),
        DVec2::new(rv.y_axis.x - u0 * rv.y_axis.z, rv.y_axis.y - v0 * rv.y_axis.z),
    );
    if b.determinant().abs() < 1e-12 {
        return None;
    }
    let a = b.inverse() * jacobian;
    // The largest singular value of A is the inverse depth; A over it is the top-left block
    // of the rotation in the ray's frame.
    let (p, q, r) = (a.x_axis.length_squared(), a.x_axis.dot(a.y_axis), a.y_axis.length_squared());
    let gamma = (0.5 * (p + r + ((p - r) * (p - r) + 4.0 * q * q).sqrt())).sqrt();
    if gamma.is_nan() || gamma <= 1e-12 {
        return None;
    }
    let block = a * (1.0 / gamma);
    let b0 = (1.0 - block.x_axis.length_squared()).max(0.0).sqrt();
    let mut b1 = (1.0 - block.y_axis.length_squared()).max(0.0).sqrt();
    if block.x_axis.dot(block.y_axis) > 0.0 {
        b1 = -b1;
    }
    Some([1.0, -1.0].map(|sign| {
        let first = DVec3::new(block.x_axis.x, block.x_axis.y, sign * b0);
        let second = DVec3::new(block.y_axis.x, block.y_axis.y, sign * b1);
        rv * DMat3::from_cols(first, second, first.cross(second))
    }))
}

/// The translation that best places the rotated points on their normalized image points: the
/// linear least-squares solution of `(R p + t) x (u, v, 1) = 0`.
fn translation(rotation: &DMat3, object: &[DVec3], normalized: &[DVec2]) -> DVec3 {
    let mut normal = DMat3::ZERO;
    let mut right = DVec3::ZERO;
    for (&p, &u) in object.iter().zip(normalized) {
        let rp = *rotation * p;
        for (row, value) in
            [(DVec3::new(1.0, 0.0, -u.x), u.x * rp.z - rp.x), (DVec3::new(0.0, 1.0, -u.y), u.y * rp.z - rp.y)]
        {
            normal += DMat3::from_cols(row * row.x, row * row.y, row * row.z);
            right += row * value;
        }
    }
    normal.inverse() * right
}

/// Levenberg–Marquardt on the rotation vector and translation, minimising the squared pixel
/// distances between the projected `object` points and `pixels` (as many of each).
pub(crate) fn refine(start: Pose, object: &[DVec3], pixels: &[DVec2], camera: &Intrinsics) -> Pose {
    let pack = |pose: &Pose| {
        let (r, t) = (pose.rvec(), pose.translation);
        [r.x, r.y, r.z, t.x, t.y, t.z]
    };
    let unpack = |x: &[f64; 6]| Pose::from_rvec(DVec3::new(x[0], x[1], x[2]), DVec3::new(x[3], x[4], x[5]));
    let residuals = |x: &[f64; 6]| -> Option<Vec<f64>> {
        let pose = unpack(x);
        let mut out = Vec::with_capacity(2 * object.len());
        for (&p, &q) in object.iter().zip(pixels) {
            let r = camera.project(pose.apply(p))? - q;
            out.extend([r.x, r.y]);
        }
        Some(out)
    };
    let settings = Settings { max_steps: 50, step_rate: 1e-7, least_step: 1e-2 };
    minimise(pack(&start), residuals, |x| x, settings).map_or(start, |x| unpack(&x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Distortion;

    fn camera() -> Intrinsics {
        Intrinsics {
            fx: 900.0,
            fy: 905.0,
            cx: 641.0,
            cy: 358.0,
            distortion: Distortion([-0.12, 0.05, 0.0005, -0.0003, 0.0, 0.0, 0.0, 0.0]),
            size: [1280, 720],
        }
    }

    fn seen(pose: &Pose, side: f64, camera: &Intrinsics) -> [DVec2; 4] {
        marker_corners(side).map(|p| camera.project(pose.apply(p)).unwrap())
    }

    #[test]
    fn rotation_vectors_round_trip() {
        for rvec in [DVec3::new(0.3, -1.2, 2.0), DVec3::new(3.0, 0.1, 0.0), DVec3::ZERO] {
            let pose = Pose::from_rvec(rvec, DVec3::ONE);
            assert!(pose.rvec().distance(rvec) < 1e-9, "{rvec} came back as {}", pose.rvec());
        }
    }

    #[test]
    fn exact_corners_give_the_pose_back() {
        let camera = camera();
        for (rvec, tvec) in [
            (DVec3::new(2.9, 0.2, -0.3), DVec3::new(0.05, -0.03, 0.6)),
            (DVec3::new(2.2, 0.9, 0.4), DVec3::new(-0.2, 0.1, 1.1)),
            (DVec3::new(0.1, 3.0, 0.2), DVec3::new(0.0, 0.0, 0.4)),
            (DVec3::new(-0.6, 0.2, 0.1), DVec3::new(0.1, 0.15, 0.9)),
        ] {
            let truth = Pose::from_rvec(rvec, tvec);
            let found = estimate(&seen(&truth, 0.1, &camera), 0.1, &camera).unwrap();
            assert!(found.error_px < 1e-6, "error {}", found.error_px);
            assert!(found.pose.translation.distance(tvec) < 1e-7, "{} for {tvec}", found.pose.translation);
            assert!(found.pose.angle_to(&truth) < 1e-7);
        }
    }

    #[test]
    fn a_tilted_marker_has_a_worse_mirror_solution() {
        let camera = camera();
        // Tilted 43 and 30 degrees from facing the camera (the second close to it, where
        // refining the mirrored pose slides into the true one's minimum).
        for (rvec, tvec) in [
            (DVec3::new(2.4, 0.0, 0.0), DVec3::new(0.0, 0.0, 0.5)),
            (DVec3::new(2.62, 0.0, 0.0), DVec3::new(-0.06, 0.0, 0.3)),
        ] {
            let truth = Pose::from_rvec(rvec, tvec);
            let found = estimate(&seen(&truth, 0.1, &camera), 0.1, &camera).unwrap();
            assert!(found.pose.angle_to(&truth) < 1e-6);
            assert!(found.alternative.angle_to(&truth) > 0.3, "the alternative is the mirrored tilt");
            assert!(found.alternative_error_px > 1.0, "{}", found.alternative_error_px);
        }
    }

    #[test]
    fn the_reprojection_error_is_in_pixels() {
        let camera = camera();
        let truth = Pose::from_rvec(DVec3::new(2.9, 0.2, -0.3), DVec3::new(0.05, -0.03, 0.6));
        let mut pixels = seen(&truth, 0.1, &camera);
        let error = reprojection_error(&truth, &marker_corners(0.1), &pixels, &camera);
        assert!(error < 1e-9);
        pixels[0].x += 2.0;
        let error = reprojection_error(&truth, &marker_corners(0.1), &pixels, &camera);
        assert!((error - 1.0).abs() < 1e-9, "{error}");
    }
}
