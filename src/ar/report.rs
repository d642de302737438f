//! A found marker written as JSON: the form `canopy ar detect` prints and the overlay's dump
//! records, so that both can be compared with OpenCV's output.

use bevy::math::DVec2;
use canopy_vision::pose::PoseEstimate;
use serde_json::{Value, json};

/// A marker as `canopy ar detect` prints it and the dump records it: its corners (pixels,
/// OpenCV's order) and, with a pose, OpenCV's `rvec` and `tvec` and both solutions' errors.
pub fn marker_json(corners: &[DVec2; 4], estimate: Option<&PoseEstimate>) -> Value {
    let mut out = json!({"corners": corners.map(|c| c.to_array())});
    if let Some(estimate) = estimate {
        out["rvec"] = json!(estimate.pose.rvec().to_array());
        out["tvec"] = json!(estimate.pose.translation.to_array());
        out["reprojection_error_px"] = json!(estimate.error_px);
        out["alternative_error_px"] = json!(estimate.alternative_error_px);
    }
    out
}
