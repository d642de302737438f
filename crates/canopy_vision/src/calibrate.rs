//! A camera calibrated from views of a flat target, without OpenCV: Zhang's closed form ("A
//! flexible new technique for camera calibration", 2000) from each view's homography, then
//! Levenberg-Marquardt over the focal lengths, the principal point, OpenCV's five distortion
//! coefficients (`k1 k2 p1 p2 k3`) and every view's pose, on the pixel reprojection error.

use crate::camera::{Distortion, Intrinsics};
use crate::linear::solve;
use crate::pose::Pose;
use bevy_math::{DMat3, DVec2, DVec3};

/// The fewest views a calibration takes (Zhang's closed form needs three).
pub const MIN_VIEWS: usize = 3;

/// One view of the target: its points (metres, in the target's plane z = 0) and where they
/// were seen (pixels).
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The target's points.
    pub object: Vec<DVec2>,
    /// Where each was seen.
    pub pixels: Vec<DVec2>,
}

/// A calibration and how well it fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibrated {
    /// The camera.
    pub camera: Intrinsics,
    /// Each view's pose (target to camera).
    pub poses: Vec<Pose>,
    /// Each view's root-mean-square reprojection error, pixels.
    pub view_errors_px: Vec<f64>,
    /// The root-mean-square reprojection error over every point, pixels.
    pub error_px: f64,
}

/// The camera of `size` pixels that saw `views`, or why it cannot be found.
pub fn calibrate(views: &[View], size: [u32; 2]) -> Result<Calibrated, String> {
    if views.len() < MIN_VIEWS {
        return Err(format!("a calibration needs at least {MIN_VIEWS} views of the target, found {}", views.len()));
    }
    if let Some(k) = views.iter().position(|v| v.object.len() < 6 || v.object.len() != v.pixels.len()) {
        return Err(format!("view {k} has fewer than 6 points of the target"));
    }
    let homographies = views.iter().map(|v| homography(&v.object, &v.pixels)).collect::<Option<Vec<_>>>();
    let homographies = homographies.ok_or("a view's points lie on a line: its homography is undetermined")?;
    // Two starts: Zhang's closed form, and OpenCV's (the principal point at the image's middle,
    // the focal lengths from the vanishing points); a few views near alike determine the
    // principal point poorly, and the closed form can then start far from it. The refinement
    // that fits best is kept.
    let starts = [closed_form(&homographies, size), centred_start(&homographies, size)];
    let (camera, poses) = starts
        .into_iter()
        .flatten()
        .map(|camera| {
            let poses: Vec<Pose> = homographies.iter().map(|h| pose_of(h, &camera)).collect();
            refine(views, camera, poses)
        })
        .min_by(|a, b| total_error(views, a).total_cmp(&total_error(views, b)))
        .ok_or("the views do not determine the camera (too alike?)")?;
    let view_errors_px: Vec<f64> = views.iter().zip(&poses).map(|(v, p)| rms(&residuals(v, &camera, p))).collect();
    let count: usize = views.iter().map(|v| v.object.len()).sum();
    let squares: f64 = views.iter().zip(&view_errors_px).map(|(v, e)| e * e * v.object.len() as f64).sum();
    let error_px = (squares / count as f64).sqrt();
    if !error_px.is_finite() {
        return Err("the refinement did not converge".into());
    }
    Ok(Calibrated { camera, poses, view_errors_px, error_px })
}

/// The homography taking the plane's points to the pixels, by the normalized direct linear
/// transform: the eigenvector of the smallest eigenvalue of `A^T A`.
pub(crate) fn homography(object: &[DVec2], pixels: &[DVec2]) -> Option<DMat3> {
    let (to_object, _) = normalizer(object)?;
    let (to_pixels, from_pixels) = normalizer(pixels)?;
    let mut ata = [[0.0; 9]; 9];
    for (&p, &q) in object.iter().zip(pixels) {
        let (p, q) = ((to_object * p.extend(1.0)).truncate(), (to_pixels * q.extend(1.0)).truncate());
        let rows = [
            [p.x, p.y, 1.0, 0.0, 0.0, 0.0, -q.x * p.x, -q.x * p.y, -q.x],
            [0.0, 0.0, 0.0, p.x, p.y, 1.0, -q.y * p.x, -q.y * p.y, -q.y],
        ];
        for row in rows {
            for a in 0..9 {
                for b in 0..9 {
                    ata[a][b] += row[a] * row[b];
                }
            }
        }
    }
    let h = smallest_eigenvector(ata);
    let normalized = DMat3::from_cols_array(&[h[0], h[3], h[6], h[1], h[4], h[7], h[2], h[5], h[8]]);
    let h = from_pixels * normalized * to_object;
    (h.determinant().abs() > 1e-300).then_some(h)
}

/// The similarity that moves `points` to their centroid and scales their mean distance to
/// `sqrt(2)`, and its inverse.
fn normalizer(points: &[DVec2]) -> Option<(DMat3, DMat3)> {
    let centre = points.iter().copied().sum::<DVec2>() / points.len() as f64;
    let spread = points.iter().map(|p| p.distance(centre)).sum::<f64>() / points.len() as f64;
    if spread < 1e-12 {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / spread;
    let forward = DMat3::from_cols(DVec3::new(s, 0.0, 0.0), DVec3::new(0.0, s, 0.0), (-centre * s).extend(1.0));
    let inverse = DMat3::from_cols(DVec3::new(1.0 / s, 0.0, 0.0), DVec3::new(0.0, 1.0 / s, 0.0), centre.extend(1.0));
    Some((forward, inverse))
}

/// Zhang's closed form: the intrinsics (no skew, no distortion) whose image of the absolute
/// conic every homography's first two columns satisfy.
fn closed_form(homographies: &[DMat3], size: [u32; 2]) -> Option<Intrinsics> {
    let v = |h: &DMat3, i: usize, j: usize| {
        let (a, b) = (h.col(i), h.col(j));
        [a.x * b.x, a.x * b.y + a.y * b.x, a.y * b.y, a.z * b.x + a.x * b.z, a.z * b.y + a.y * b.z, a.z * b.z]
    };
    let mut vtv = [[0.0; 6]; 6];
    for h in homographies {
        // Scaled so that every view weighs alike.
        let h = *h * (1.0 / h.col(2).length());
        let (v12, v11, v22) = (v(&h, 0, 1), v(&h, 0, 0), v(&h, 1, 1));
        let difference: [f64; 6] = std::array::from_fn(|k| v11[k] - v22[k]);
        for row in [v12, difference] {
            for a in 0..6 {
                for b in 0..6 {
                    vtv[a][b] += row[a] * row[b];
                }
            }
        }
    }
    let [b11, b12, b22, b13, b23, b33] = smallest_eigenvector(vtv);
    let cy = (b12 * b13 - b11 * b23) / (b11 * b22 - b12 * b12);
    let lambda = b33 - (b13 * b13 + cy * (b12 * b13 - b11 * b23)) / b11;
    let fx = (lambda / b11).sqrt();
    let fy = (lambda * b11 / (b11 * b22 - b12 * b12)).sqrt();
    let cx = -b13 * fx * fx / lambda;
    let camera = Intrinsics { fx, fy, cx, cy, distortion: Distortion::default(), size };
    [fx, fy, cx, cy].iter().all(|v| v.is_finite()).then_some(camera).filter(|c| c.fx > 0.0 && c.fy > 0.0)
}

/// OpenCV's start (`initIntrinsicParams2D`): the principal point at the image's middle, and
/// the focal lengths for which each view's two vanishing points, and those of its diagonals,
/// are perpendicular, by least squares.
fn centred_start(homographies: &[DMat3], size: [u32; 2]) -> Option<Intrinsics> {
    let (cx, cy) = ((f64::from(size[0]) - 1.0) * 0.5, (f64::from(size[1]) - 1.0) * 0.5);
    let to_centre = DMat3::from_cols(DVec3::X, DVec3::Y, DVec3::new(-cx, -cy, 1.0));
    let (mut ata, mut atb) = ([[0.0; 2]; 2], [0.0; 2]);
    for h in homographies {
        let h = to_centre * *h;
        let (a, b) = (h.col(0).normalize(), h.col(1).normalize());
        let (d1, d2) = (((a + b) * 0.5).normalize(), ((a - b) * 0.5).normalize());
        for (p, q) in [(a, b), (d1, d2)] {
            let (row, rhs) = ([p.x * q.x, p.y * q.y], -p.z * q.z);
            for i in 0..2 {
                atb[i] += row[i] * rhs;
                for j in 0..2 {
                    ata[i][j] += row[i] * row[j];
                }
            }
        }
    }
    let det = ata[0][0] * ata[1][1] - ata[0][1] * ata[1][0];
    let inverse_fx2 = (atb[0] * ata[1][1] - atb[1] * ata[0][1]) / det;
    let inverse_fy2 = (ata[0][0] * atb[1] - ata[1][0] * atb[0]) / det;
    let (fx, fy) = ((1.0 / inverse_fx2.abs()).sqrt(), (1.0 / inverse_fy2.abs()).sqrt());
    let camera = Intrinsics { fx, fy, cx, cy, distortion: Distortion::default(), size };
    (fx.is_finite() && fy.is_finite() && fx > 0.0 && fy > 0.0).then_some(camera)
}

/// The sum of squared pixel residuals of a calibration over every view.
fn total_error(views: &[View], (camera, poses): &(Intrinsics, Vec<Pose>)) -> f64 {
    let total: f64 =
        views.iter().zip(poses).map(|(v, p)| residuals(v, camera, p).iter().map(|r| r * r).sum::<f64>()).sum();
    if total.is_finite() { total } else { f64::INFINITY }
}

/// A view's pose from its homography and the camera: `[r1 r2 t] = K^-1 H` scaled to unit
/// columns, the rotation made orthonormal.
fn pose_of(h: &DMat3, camera: &Intrinsics) -> Pose {
    let k_inverse = DMat3::from_cols(
        DVec3::new(1.0 / camera.fx, 0.0, 0.0),
        DVec3::new(0.0, 1.0 / camera.fy, 0.0),
        DVec3::new(-camera.cx / camera.fx, -camera.cy / camera.fy, 1.0),
    );
    let m = k_inverse * *h;
    let mut scale = 1.0 / m.col(0).length();
    if (m.col(2) * scale).z < 0.0 {
        scale = -scale; // the target lies in front of the camera
    }
    let (r1, r2, t) = (m.col(0) * scale, m.col(1) * scale, m.col(2) * scale);
    let r1 = r1.normalize();
    let r2 = (r2 - r1 * r1.dot(r2)).normalize();
    Pose { rotation: DMat3::from_cols(r1, r2, r1.cross(r2)), translation: t }
}

/// The pixel residuals of one view.
fn residuals(view: &View, camera: &Intrinsics, pose: &Pose) -> Vec<f64> {
    let mut out = Vec::with_capacity(2 * view.object.len());
    for (&p, &q) in view.object.iter().zip(&view.pixels) {
        let r = camera.project(pose.apply(p.extend(0.0))).map_or(DVec2::splat(1e6), |r| r - q);
        out.extend([r.x, r.y]);
    }
    out
}

fn rms(residuals: &[f64]) -> f64 {
    (residuals.iter().map(|r| r * r).sum::<f64>() / (residuals.len() / 2).max(1) as f64).sqrt()
}

/// The intrinsics' nine parameters: focal lengths, principal point, `k1 k2 p1 p2 k3`.
const INTRINSICS: usize = 9;

/// Levenberg-Marquardt over the intrinsics and every pose (rotation vector and translation).
fn refine(views: &[View], camera: Intrinsics, poses: Vec<Pose>) -> (Intrinsics, Vec<Pose>) {
    let unpack = |x: &[f64]| {
        let d = camera.distortion.0;
        let distortion = Distortion([x[4], x[5], x[6], x[7], x[8], d[5], d[6], d[7]]);
        let camera = Intrinsics { fx: x[0], fy: x[1], cx: x[2], cy: x[3], distortion, size: camera.size };
        let poses: Vec<Pose> = x[INTRINSICS..]
            .chunks_exact(6)
            .map(|p| Pose::from_rvec(DVec3::new(p[0], p[1], p[2]), DVec3::new(p[3], p[4], p[5])))
            .collect();
        (camera, poses)
    };
    let mut x: Vec<f64> = vec![camera.fx, camera.fy, camera.cx, camera.cy, 0.0, 0.0, 0.0, 0.0, 0.0];
    for pose in &poses {
        let (r, t) = (pose.rvec(), pose.translation);
        x.extend([r.x, r.y, r.z, t.x, t.y, t.z]);
    }
    let view_residuals = |x: &[f64], k: usize| {
        let (camera, poses) = unpack(x);
        residuals(&views[k], &camera, &poses[k])
    };
    let cost =
        |x: &[f64]| (0..views.len()).map(|k| view_residuals(x, k).iter().map(|r| r * r).sum::<f64>()).sum::<f64>();
    let n = x.len();
    let mut lambda = 1e-3;
    let mut current = cost(&x);
    for _ in 0..100 {
        let mut jtj = vec![vec![0.0; n]; n];
        let mut jtr = vec![0.0; n];
        for k in 0..views.len() {
            // A view's residuals depend on the intrinsics and its own pose alone.
            let columns: Vec<usize> = (0..INTRINSICS).chain(INTRINSICS + 6 * k..INTRINSICS + 6 * k + 6).collect();
            let r = view_residuals(&x, k);
            let jacobian: Vec<Vec<f64>> = columns
                .iter()
                .map(|&c| {
                    let step = 1e-6 * x[c].abs().max(1e-3);
                    let (mut plus, mut minus) = (x.clone(), x.clone());
                    plus[c] += step;
                    minus[c] -= step;
                    let (rp, rm) = (view_residuals(&plus, k), view_residuals(&minus, k));
                    rp.iter().zip(&rm).map(|(p, m)| (p - m) / (2.0 * step)).collect()
                })
                .collect();
            for (a, &ca) in columns.iter().enumerate() {
                jtr[ca] += jacobian[a].iter().zip(&r).map(|(j, r)| j * r).sum::<f64>();
                for (b, &cb) in columns.iter().enumerate() {
                    jtj[ca][cb] += jacobian[a].iter().zip(&jacobian[b]).map(|(p, q)| p * q).sum::<f64>();
                }
            }
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut system = jtj.clone();
            for (a, row) in system.iter_mut().enumerate() {
                row[a] *= 1.0 + lambda;
                row[a] += 1e-12;
            }
            let Some(delta) = solve(&mut system, &mut jtr.clone(), 1e-300) else { break };
            let candidate: Vec<f64> = x.iter().zip(&delta).map(|(x, d)| x - d).collect();
            let candidate_cost = cost(&candidate);
            if candidate_cost < current {
                improved = (current - candidate_cost) > 1e-12 * current;
                x = candidate;
                current = candidate_cost;
                lambda = (lambda * 0.1).max(1e-15);
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    unpack(&x)
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric matrix, by Jacobi rotations.
fn smallest_eigenvector<const N: usize>(mut a: [[f64; N]; N]) -> [f64; N] {
    let mut vectors = [[0.0; N]; N];
    for (i, row) in vectors.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _ in 0..100 {
        let off: f64 = (0..N)
            .flat_map(|i| (0..N).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for (k, (apk, aqk)) in row_p.into_iter().zip(row_q).enumerate() {
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in vectors.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let smallest = (0..N).min_by(|&i, &j| a[i][i].total_cmp(&a[j][j])).unwrap_or(0);
    std::array::from_fn(|k| vectors[k][smallest])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::{Board, GridBoard};
    use crate::detect::{Scratch, Settings, detect};
    use crate::dictionary::Dictionary;
    use crate::synth::photograph_print;

    #[test]
    fn a_known_camera_is_recovered_from_synthetic_views_of_a_board() {
        let dictionary = Dictionary::named("6x6_250").unwrap();
        let board = Board::Grid(GridBoard::new([5, 4], 0.03, 0.006, 0, &dictionary).unwrap());
        let (pixels_per_metre, margin_m) = (4000.0, 0.006);
        let print = board.image(&dictionary, pixels_per_metre, margin_m).unwrap();
        let truth = Intrinsics {
            fx: 520.0,
            fy: 515.0,
            cx: 322.0,
            cy: 236.0,
            distortion: Distortion([-0.12, 0.06, 0.001, -0.0005, 0.0, 0.0, 0.0, 0.0]),
            size: [640, 480],
        };
        let centre = (board.size_m() * 0.5).extend(0.0);
        let mut views = Vec::new();
        for (turn, tilt, roll, x) in [
            (0.35, -0.3, 0.1, -0.03),
            (-0.3, -0.4, -0.2, 0.02),
            (0.1, 0.45, 0.3, 0.0),
            (-0.45, 0.2, 0.0, 0.04),
            (0.2, -0.55, -0.4, -0.02),
            (0.0, 0.0, 0.6, 0.0),
        ] {
            let rotation = DMat3::from_rotation_z(roll) * DMat3::from_rotation_y(turn) * DMat3::from_rotation_x(tilt);
            let pose = Pose { rotation, translation: DVec3::new(x, 0.01, 0.32) - rotation * centre };
            let frame = photograph_print(&print, pixels_per_metre, margin_m, &pose, &truth);
            let markers = detect(&frame, &dictionary, &Settings::default(), None, &mut Scratch::default());
            let (object, pixels): (Vec<DVec2>, Vec<DVec2>) = board
                .matched(&markers)
                .into_iter()
                .flat_map(|(marker, object)| object.into_iter().map(|p| p.truncate()).zip(marker.corners_f64()))
                .unzip();
            assert!(object.len() >= 40, "view sees {} corners", object.len() / 4);
            views.push(View { object, pixels });
        }
        let found = calibrate(&views, [640, 480]).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() / b;
        for (got, want, what) in [
            (found.camera.fx, truth.fx, "fx"),
            (found.camera.fy, truth.fy, "fy"),
            (found.camera.cx, truth.cx, "cx"),
            (found.camera.cy, truth.cy, "cy"),
        ] {
            assert!(close(got, want) < 0.005, "{what}: {got} against {want}");
        }
        assert!((found.camera.distortion.0[0] - truth.distortion.0[0]).abs() < 0.02, "{:?}", found.camera.distortion);
        assert!(found.error_px < 0.3, "{} px", found.error_px);
        assert_eq!(found.view_errors_px.len(), 6);
        assert!(calibrate(&views[..2], [640, 480]).unwrap_err().contains("at least 3 views"));
    }
}
