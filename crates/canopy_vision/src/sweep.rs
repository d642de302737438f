//! Harder frames, swept one condition at a time in the manner of published marker benchmarks
//! (distance, viewing angle, motion blur, defocus, noise, contrast, uneven light): a printed
//! marker photographed under a baseline and with one condition worsened step by step, and the
//! detection rate and pose error at each step.
//!
//! The baseline: a 10 cm `6x6_250` marker 60 cm from a 640 x 480 camera of 60 degrees, seen 30
//! degrees from its normal, on a grey table, noise of 2 grey levels. Every frame of a step
//! turns the marker about its normal and moves it in the image, seeded, so each step is the
//! same frames on every machine.

use crate::camera::Intrinsics;
use crate::detect::{Scratch, Settings, detect};
use crate::dictionary::Dictionary;
use crate::gray::Gray;
use crate::pose::{Pose, estimate};
use crate::synth::{Random, gaussian_blur, marker_image, photograph_print};
use bevy_math::{DMat3, DVec2, DVec3};
use std::time::Instant;

/// The marker's id.
pub const ID: u32 = 23;
/// The marker's side, metres.
pub const SIDE_M: f64 = 0.1;

/// One condition made worse.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Condition {
    /// The camera's distance from the marker, metres.
    Distance,
    /// The angle between the marker's normal and the line of sight, degrees.
    Angle,
    /// The length of a straight motion blur, pixels.
    MotionBlur,
    /// The standard deviation of a Gaussian defocus, pixels.
    Defocus,
    /// The standard deviation of the noise, grey levels.
    Noise,
    /// The print's black-to-white difference, a share of full.
    Contrast,
    /// How much darker one side of the image is lit than the other, a share.
    UnevenLight,
}

impl Condition {
    /// Every condition.
    pub const ALL: [Condition; 7] = [
        Condition::Distance,
        Condition::Angle,
        Condition::MotionBlur,
        Condition::Defocus,
        Condition::Noise,
        Condition::Contrast,
        Condition::UnevenLight,
    ];

    /// Its name, as the results name it.
    pub fn name(self) -> &'static str {
        match self {
            Condition::Distance => "distance_m",
            Condition::Angle => "angle_deg",
            Condition::MotionBlur => "motion_blur_px",
            Condition::Defocus => "defocus_px",
            Condition::Noise => "noise",
            Condition::Contrast => "contrast",
            Condition::UnevenLight => "uneven_light",
        }
    }

    /// The steps it is swept through, from the baseline's value.
    pub fn steps(self) -> &'static [f64] {
        match self {
            Condition::Distance => &[0.6, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0],
            Condition::Angle => &[0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0],
            Condition::MotionBlur => &[0.0, 2.0, 4.0, 6.0, 8.0, 12.0, 16.0],
            Condition::Defocus => &[0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0],
            Condition::Noise => &[2.0, 8.0, 16.0, 24.0, 32.0, 48.0],
            Condition::Contrast => &[1.0, 0.5, 0.3, 0.2, 0.1, 0.05],
            Condition::UnevenLight => &[0.0, 0.25, 0.5, 0.75, 0.9],
        }
    }
}

/// The conditions of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Conditions {
    distance_m: f64,
    angle_deg: f64,
    motion_blur_px: f64,
    defocus_px: f64,
    noise: f64,
    contrast: f64,
    uneven_light: f64,
}

impl Conditions {
    const BASELINE: Conditions = Conditions {
        distance_m: 0.6,
        angle_deg: 30.0,
        motion_blur_px: 0.0,
        defocus_px: 0.0,
        noise: 2.0,
        contrast: 1.0,
        uneven_light: 0.0,
    };

    fn with(condition: Condition, value: f64) -> Self {
        let mut out = Self::BASELINE;
        *match condition {
            Condition::Distance => &mut out.distance_m,
            Condition::Angle => &mut out.angle_deg,
            Condition::MotionBlur => &mut out.motion_blur_px,
            Condition::Defocus => &mut out.defocus_px,
            Condition::Noise => &mut out.noise,
            Condition::Contrast => &mut out.contrast,
            Condition::UnevenLight => &mut out.uneven_light,
        } = value;
        out
    }
}

/// A frame of a sweep and the truth about it.
#[derive(Debug, Clone)]
pub struct SweepFrame {
    /// The grey pixels.
    pub image: Gray,
    /// The marker's pose in the camera frame.
    pub pose: Pose,
    /// Its corners as projected, OpenCV's order and pixel convention.
    pub corners: [DVec2; 4],
}

/// The sweep's dictionary, `6x6_250` (the predefined set of that name, always there).
pub fn dictionary() -> Dictionary {
    Dictionary::ALL.iter().find(|d| d.name == "6x6_250").cloned().unwrap_or_else(|| Dictionary::ALL[0].clone())
}

/// The sweep's camera.
pub fn camera() -> Intrinsics {
    Intrinsics::pinhole([640, 480], 60.0)
}

/// Frame `index` of `condition` at `value`.
pub fn frame(condition: Condition, value: f64, index: u32) -> SweepFrame {
    let conditions = Conditions::with(condition, value);
    let camera = camera();
    let mut random = Random(0x5eed_0000 + u64::from(index) * 7919 + (value * 1000.0) as u64);
    let dictionary = dictionary();
    // The print: 8 cells of 40 px with a white margin of one cell, its contrast about mid-grey.
    let mut print = marker_image(&dictionary, ID, 40, 1).unwrap_or_else(|| Gray::filled(400, 400, 255));
    for value in &mut print.pixels {
        *value = (127.5 + (f64::from(*value) - 127.5) * conditions.contrast).round() as u8;
    }
    let pixels_per_metre = 320.0 / SIDE_M;
    let margin_m = 40.0 / pixels_per_metre;
    // Turned about its normal, tilted about a random axis in its plane, placed in the middle
    // half of the image.
    let spin = random.unit() * std::f64::consts::TAU;
    let tilt_axis = random.unit() * std::f64::consts::TAU;
    let tilt =
        DMat3::from_axis_angle(DVec3::new(tilt_axis.cos(), tilt_axis.sin(), 0.0), conditions.angle_deg.to_radians());
    // The print's frame (x right, y down the print, z into it) as the camera's when face on.
    let rotation = tilt * DMat3::from_rotation_z(spin);
    let offset = DVec2::new(random.unit() - 0.5, random.unit() - 0.5) * 0.5;
    let aim = camera.normalized(DVec2::new(
        f64::from(camera.size[0]) * (0.5 + offset.x),
        f64::from(camera.size[1]) * (0.5 + offset.y),
    ));
    let centre = aim.extend(1.0).normalize() * conditions.distance_m;
    let centre_on_print = DVec3::new(SIDE_M * 0.5, SIDE_M * 0.5, 0.0);
    let pose = Pose { rotation, translation: centre - rotation * centre_on_print };
    let photo = photograph_print(&print, pixels_per_metre, margin_m, &pose, &camera);
    let (width, height) = (camera.size[0] as usize, camera.size[1] as usize);
    let mut values: Vec<f32> = photo.pixels.iter().map(|&v| f32::from(v)).collect();
    if conditions.motion_blur_px > 0.0 {
        let direction = random.unit() * std::f64::consts::TAU;
        motion_blur(&mut values, width, height, conditions.motion_blur_px, direction);
    }
    if conditions.defocus_px > 0.0 {
        gaussian_blur(&mut values, width, height, conditions.defocus_px as f32);
    }
    // Light falling off across the image in a random direction, then the sensor's noise.
    let light = random.unit() * std::f64::consts::TAU;
    let across = DVec2::new(light.cos(), light.sin());
    let half = DVec2::new(width as f64, height as f64) * 0.5;
    let reach = half.length();
    let mut pixels = Vec::with_capacity(values.len());
    for (i, value) in values.iter().enumerate() {
        let p = DVec2::new((i % width) as f64, (i / width) as f64) - half;
        let gain = 1.0 - conditions.uneven_light * (0.5 + 0.5 * p.dot(across) / reach);
        let noisy = f64::from(*value) * gain + conditions.noise * random.gaussian();
        pixels.push(noisy.round().clamp(0.0, 255.0) as u8);
    }
    let corners = crate::pose::marker_corners(SIDE_M).map(|corner| {
        // The marker frame of `marker_corners` (centred, y up) in the print's frame.
        let on_print = centre_on_print + DVec3::new(corner.x, -corner.y, 0.0);
        camera.project(pose.apply(on_print)).unwrap_or(DVec2::splat(-1.0))
    });
    SweepFrame { image: Gray { width: camera.size[0], height: camera.size[1], pixels }, pose, corners }
}

/// A straight blur `length` pixels long at `direction` radians: each pixel the mean of the
/// image along the segment through it.
fn motion_blur(values: &mut [f32], width: usize, height: usize, length: f64, direction: f64) {
    let steps = (length.ceil() as usize).max(1) * 2 + 1;
    let step = DVec2::new(direction.cos(), direction.sin()) * (length / (steps - 1) as f64);
    let source = Gray {
        width: width as u32,
        height: height as u32,
        pixels: values.iter().map(|v| v.round().clamp(0.0, 255.0) as u8).collect(),
    };
    for (i, value) in values.iter_mut().enumerate() {
        let p = DVec2::new((i % width) as f64, (i / width) as f64);
        let sum: f32 =
            (0..steps).map(|k| source.sample((p + step * (k as f64 - (steps - 1) as f64 * 0.5)).as_vec2())).sum();
        *value = sum / steps as f32;
    }
}

/// The figures of one step of a sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The condition swept.
    pub condition: Condition,
    /// Its value at this step.
    pub value: f64,
    /// Frames rendered.
    pub frames: u32,
    /// Frames in which the marker was found where it is (its corners within 2 pixels or a
    /// tenth of its side of the truth).
    pub found: u32,
    /// Markers reported that are not the marker where it is.
    pub false_detections: u32,
    /// The found markers' position errors as a share of the distance, median.
    pub position_rel: f64,
    /// Their orientation errors, degrees, median.
    pub angle_deg: f64,
    /// Detection's wall-clock time a frame, milliseconds, mean.
    pub detect_ms: f64,
}

/// Runs `frames` frames at each step of `condition`.
pub fn sweep(condition: Condition, frames: u32) -> Vec<Step> {
    let camera = camera();
    let dictionary = dictionary();
    let mut scratch = Scratch::default();
    condition
        .steps()
        .iter()
        .map(|&value| {
            let (mut found, mut false_detections, mut seconds) = (0, 0, 0.0);
            let (mut positions, mut angles) = (Vec::new(), Vec::new());
            for index in 0..frames {
                let frame = frame(condition, value, index);
                let started = Instant::now();
                let markers = detect(&frame.image, &dictionary, &Settings::default(), Some(&camera), &mut scratch);
                seconds += started.elapsed().as_secs_f64();
                // Found where it is: its id, its corners within 2 pixels or a tenth of its side
                // of the truth (a blurred marker's corners are not sharp points).
                let side = frame.corners[0].distance(frame.corners[1]);
                for marker in &markers {
                    let corners = marker.corners_f64();
                    let worst = corners.iter().zip(&frame.corners).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
                    if marker.id != ID || worst > (0.1 * side).max(2.0) {
                        false_detections += 1;
                        continue;
                    }
                    found += 1;
                    if let Some(pose) = estimate(&corners, SIDE_M, &camera) {
                        // `estimate` gives the marker's centred frame, y up the print.
                        let truth = centred(&frame.pose);
                        positions.push(pose.pose.translation.distance(truth.translation) / truth.translation.length());
                        angles.push(pose.pose.angle_to(&truth).to_degrees());
                    }
                }
            }
            Step {
                condition,
                value,
                frames,
                found,
                false_detections,
                position_rel: median(&mut positions),
                angle_deg: median(&mut angles),
                detect_ms: seconds * 1e3 / f64::from(frames.max(1)),
            }
        })
        .collect()
}

/// The pose of the marker's centred frame (x right, y up the print, z out of it) from the
/// print's pose.
fn centred(pose: &Pose) -> Pose {
    let axes = DMat3::from_cols(DVec3::X, DVec3::NEG_Y, DVec3::NEG_Z);
    let centre = DVec3::new(SIDE_M * 0.5, SIDE_M * 0.5, 0.0);
    Pose { rotation: pose.rotation * axes, translation: pose.translation + pose.rotation * centre }
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_baseline_is_found_with_its_pose_and_the_worst_steps_are_harder() {
        let baseline = &sweep(Condition::Distance, 4)[0];
        assert_eq!((baseline.found, baseline.false_detections), (4, 0), "{baseline:?}");
        assert!(baseline.position_rel < 0.01 && baseline.angle_deg < 1.0, "{baseline:?}");
        // The truth's corners are where the frame shows them: the detector's lie within a
        // pixel of them.
        let frame = frame(Condition::Noise, 2.0, 1);
        let markers = detect(&frame.image, &dictionary(), &Settings::default(), None, &mut Scratch::default());
        let corners = markers.iter().find(|m| m.id == ID).unwrap().corners_f64();
        for (found, truth) in corners.iter().zip(&frame.corners) {
            assert!(found.distance(*truth) < 1.0, "{found} against {truth}");
        }
        // Nearly no contrast left: not found, and nothing else taken for it.
        let faint = frame_steps(Condition::Contrast, 0.05);
        assert_eq!(faint.false_detections, 0, "{faint:?}");
    }

    fn frame_steps(condition: Condition, value: f64) -> Step {
        *sweep(condition, 2).iter().find(|s| s.value == value).unwrap()
    }
}
