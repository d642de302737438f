//! The detector and the pose measured against a synthetic sequence's known answers: how often
//! the marker is found, how far its corners and pose are from the truth, and whether anything
//! else is ever taken for it.

use crate::camera::Intrinsics;
use crate::detect::{Scratch, Settings, detect};
use crate::gray::Gray;
use crate::pose::estimate;
use crate::synth::{MarkerView, SequenceSettings, render_frame};
use bevy_math::DVec2;

/// Figures over a whole sequence.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Evaluation {
    /// Frames showing the whole marker, and in how many it was found.
    pub whole: [u32; 2],
    /// Frames with something in front of the marker, and in how many it was found.
    pub occluded: [u32; 2],
    /// Frames without the marker (or cut by the edge).
    pub absent: u32,
    /// Markers reported that are not the marker where it is: another id, or corners more than
    /// two pixels from the truth.
    pub false_detections: u32,
    /// Corner errors of the found whole markers, pixels: root mean square and largest.
    pub corner_px: [f64; 2],
    /// Position errors as a share of the distance: median, 95th percentile and largest.
    pub position_rel: [f64; 3],
    /// Orientation errors, degrees: median, 95th percentile and largest.
    pub angle_deg: [f64; 3],
    /// The camera's distance from the marker over the frames, metres: nearest and farthest.
    pub distance_m: [f64; 2],
}

impl Evaluation {
    /// The share of whole-marker frames in which it was found.
    pub fn detection_rate(&self) -> f64 {
        f64::from(self.whole[1]) / f64::from(self.whole[0].max(1))
    }
}

/// Renders every frame of `sequence`, detects and estimates the pose, and compares.
pub fn evaluate(sequence: &SequenceSettings, detector: &Settings) -> Evaluation {
    let camera: &Intrinsics = &sequence.camera;
    let mut scratch = Scratch::default();
    let mut out = Evaluation { distance_m: [f64::INFINITY, 0.0], ..Evaluation::default() };
    let (mut corner_sq, mut corner_n) = (0.0, 0usize);
    let (mut positions, mut angles) = (Vec::new(), Vec::new());
    for index in 0..sequence.frames {
        let frame = render_frame(sequence, index);
        let gray = Gray::from_rgb(camera.size[0], camera.size[1], &frame.rgb);
        let markers = detect(&gray, &sequence.dictionary, detector, Some(camera), &mut scratch);
        let truth = frame.corners;
        let mut found = false;
        for marker in &markers {
            let corners = marker.corners.map(|c| DVec2::new(f64::from(c.x), f64::from(c.y)));
            let worst = corners.iter().zip(&truth).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
            if marker.id != sequence.id || frame.view == MarkerView::Absent || worst > 2.0 {
                out.false_detections += 1;
                continue;
            }
            found = true;
            if frame.view != MarkerView::Whole {
                continue;
            }
            for (a, b) in corners.iter().zip(&truth) {
                let d = a.distance(*b);
                corner_sq += d * d;
                corner_n += 1;
                out.corner_px[1] = out.corner_px[1].max(d);
            }
            if let Some(pose) = estimate(&corners, sequence.side_m, camera) {
                let distance = frame.pose.translation.length();
                out.distance_m = [out.distance_m[0].min(distance), out.distance_m[1].max(distance)];
                positions.push(pose.pose.translation.distance(frame.pose.translation) / distance);
                angles.push(pose.pose.angle_to(&frame.pose).to_degrees());
            }
        }
        match frame.view {
            MarkerView::Whole => out.whole = [out.whole[0] + 1, out.whole[1] + u32::from(found)],
            MarkerView::Occluded => out.occluded = [out.occluded[0] + 1, out.occluded[1] + u32::from(found)],
            MarkerView::Absent => out.absent += 1,
        }
    }
    out.corner_px[0] = (corner_sq / corner_n.max(1) as f64).sqrt();
    out.position_rel = spread(&mut positions);
    out.angle_deg = spread(&mut angles);
    out
}

/// Median, 95th percentile and largest value (zeros when empty).
fn spread(values: &mut [f64]) -> [f64; 3] {
    if values.is_empty() {
        return [0.0; 3];
    }
    values.sort_by(f64::total_cmp);
    let at = |q: f64| values[((values.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.95), values[values.len() - 1]]
}
