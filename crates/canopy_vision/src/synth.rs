//! Images with known answers: a marker drawn for printing, and a camera's frames of a marker
//! lying on a table under known poses, with blur, noise, changing light and things passing
//! in front of it.
//!
//! Frames are ray-cast: each pixel's ray (through the camera model, distortion included) meets
//! the table's plane, the marker's plane, which shows the marker, its white margin, the table's
//! grain and some dark clutter; four rays a pixel are averaged.

use crate::camera::Intrinsics;
use crate::dictionary::Dictionary;
use crate::gray::Gray;
use crate::pose::{Pose, marker_corners};
use bevy_math::{DMat3, DVec2, DVec3};

/// Marker `id` of `dictionary` as a grey image for printing: `cell_px` pixels a cell, a black
/// border a cell wide, and a white margin of `margin_cells` cells around it. `None` if the id
/// is not in the dictionary.
pub fn marker_image(dictionary: &Dictionary, id: u32, cell_px: u32, margin_cells: u32) -> Option<Gray> {
    let cells = dictionary.cells_of(id)?;
    let n = dictionary.cells;
    let side = (n + 2 + 2 * margin_cells) * cell_px;
    let mut image = Gray::filled(side, side, 255);
    for y in 0..side {
        for x in 0..side {
            let (col, row) =
                ((x / cell_px) as i64 - i64::from(margin_cells), (y / cell_px) as i64 - i64::from(margin_cells));
            let inside = |v: i64| (0..i64::from(n + 2)).contains(&v);
            if !inside(col) || !inside(row) {
                continue;
            }
            let inner = |v: i64| (1..=i64::from(n)).contains(&v);
            let white = inner(col) && inner(row) && cells[((row - 1) * i64::from(n) + col - 1) as usize];
            image.pixels[(y * side + x) as usize] = if white { 255 } else { 0 };
        }
    }
    Some(image)
}

/// Samples across and down each pixel of a photographed print: enough that an edge's place in
/// the photograph is exact to a twentieth of a pixel.
pub const SAMPLES: u32 = 4;

/// A print lying flat photographed: `image` printed at `pixels_per_metre` in the plane z = 0
/// of its frame, x right and y down the print, the print's top-left corner at `(-margin_m,
/// -margin_m)` (a board's frame, its margin round it), seen by `camera` from `pose` (print
/// frame to camera frame) on a grey table, [`SAMPLES`] x [`SAMPLES`] samples a pixel.
pub fn photograph_print(image: &Gray, pixels_per_metre: f64, margin_m: f64, pose: &Pose, camera: &Intrinsics) -> Gray {
    let [width, height] = camera.size;
    let to_print = pose.rotation.transpose();
    let eye = -(to_print * pose.translation);
    let mut out = Gray::filled(width, height, 0);
    for y in 0..height {
        for x in 0..width {
            let mut sum = 0.0;
            for k in 0..SAMPLES * SAMPLES {
                let (dx, dy) = ((k % SAMPLES) as f64, (k / SAMPLES) as f64);
                let (dx, dy) = ((dx + 0.5) / SAMPLES as f64 - 0.5, (dy + 0.5) / SAMPLES as f64 - 0.5);
                let ray = to_print * camera.normalized(DVec2::new(f64::from(x) + dx, f64::from(y) + dy)).extend(1.0);
                let s = -eye.z / ray.z;
                let pixel = ((eye + ray * s).truncate() + DVec2::splat(margin_m)) * pixels_per_metre;
                let on_print = s > 0.0
                    && pixel.x >= 0.0
                    && pixel.y >= 0.0
                    && pixel.x < f64::from(image.width)
                    && pixel.y < f64::from(image.height);
                sum += match on_print {
                    true => f64::from(image.pixels[(pixel.y as u32 * image.width + pixel.x as u32) as usize]),
                    false => 110.0,
                };
            }
            out.pixels[(y * width + x) as usize] = (sum / f64::from(SAMPLES * SAMPLES)).round() as u8;
        }
    }
    out
}

/// What a synthetic sequence shows and how it is spoilt.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceSettings {
    /// The camera.
    pub camera: Intrinsics,
    /// The marker's dictionary and id.
    pub dictionary: Dictionary,
    /// The marker's id.
    pub id: u32,
    /// The marker's side (its black square), metres.
    pub side_m: f64,
    /// Frames.
    pub frames: u32,
    /// The closest and farthest camera distance from the marker's centre, metres.
    pub distance_m: [f64; 2],
    /// The seed of the noise, the clutter and the occlusions.
    pub seed: u64,
    /// The standard deviation of the added noise, grey levels (0 for none).
    pub noise: f32,
    /// The largest blur, the standard deviation of a Gaussian, pixels (0 for none).
    pub max_blur_px: f32,
    /// Whether the light's strength and direction change from frame to frame.
    pub lighting: bool,
    /// Whether an object passes in front of the marker in some frames.
    pub occlusion: bool,
    /// Whether some frames look away from the marker (to count false detections).
    pub look_away: bool,
}

/// One frame of a synthetic sequence and the truth about it.
#[derive(Debug, Clone)]
pub struct SyntheticFrame {
    /// RGB pixels, row by row.
    pub rgb: Vec<u8>,
    /// The marker's pose in the camera frame.
    pub pose: Pose,
    /// The marker's corners as projected (OpenCV's order and pixel convention).
    pub corners: [DVec2; 4],
    /// What the frame shows of the marker.
    pub view: MarkerView,
    /// The blur's standard deviation in this frame, pixels.
    pub blur_px: f32,
}

/// How much of the marker a frame shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerView {
    /// Entirely in the frame, nothing in front of it.
    Whole,
    /// In the frame with something in front of part of it.
    Occluded,
    /// Not in the frame, or cut by its edge.
    Absent,
}

impl MarkerView {
    /// The word the ground truth files use.
    pub fn key(self) -> &'static str {
        match self {
            MarkerView::Whole => "whole",
            MarkerView::Occluded => "occluded",
            MarkerView::Absent => "absent",
        }
    }
}

/// The camera's path: a slow orbit around the marker at changing height and distance, looking
/// near its centre, with a little roll; every eleventh frame (when looking away is on) it
/// turns to the empty table.
pub fn camera_pose(settings: &SequenceSettings, frame: u32) -> (Pose, bool) {
    let t = f64::from(frame) / f64::from(settings.frames.max(1));
    let [near, far] = settings.distance_m;
    let distance = near + (far - near) * (0.5 - 0.5 * (std::f64::consts::TAU * 1.5 * t).cos());
    let azimuth = std::f64::consts::TAU * t + 0.4;
    // Tilt of the view from the marker's normal: 10 to 50 degrees.
    let tilt = (30.0 + 20.0 * (std::f64::consts::TAU * 2.0 * t).sin()).to_radians();
    let eye = DVec3::new(tilt.sin() * azimuth.cos(), tilt.sin() * azimuth.sin(), tilt.cos()) * distance;
    let away = settings.look_away && frame % 11 == 10;
    let wander = DVec3::new((7.3 * t).sin(), (5.1 * t).cos(), 0.0) * settings.side_m * 0.6;
    // Looking away: outwards over the table, nearly level, the marker behind the camera.
    let outwards = eye.truncate().normalize_or(DVec2::X).extend(-0.2);
    let target = if away { eye + outwards } else { wander };
    let roll = 0.25 * (std::f64::consts::TAU * 3.0 * t).sin();
    (look_at(eye, target, roll), away)
}

/// The marker-to-camera pose of a camera at `eye` looking at `target` (marker frame), turned
/// `roll` radians about its axis; the camera frame is OpenCV's (x right, y down, z forward).
fn look_at(eye: DVec3, target: DVec3, roll: f64) -> Pose {
    let forward = (target - eye).normalize();
    let up_hint = if forward.cross(DVec3::Z).length() > 1e-6 { DVec3::Z } else { DVec3::Y };
    let right = forward.cross(up_hint).normalize();
    let down = forward.cross(right);
    let (s, c) = roll.sin_cos();
    let (right, down) = (right * c + down * s, down * c - right * s);
    // Rows of the rotation are the camera axes in the marker frame.
    let rotation = DMat3::from_cols(right, down, forward).transpose();
    Pose { rotation, translation: -(rotation * eye) }
}

/// Frame `index` of the sequence `settings` describes.
pub fn render_frame(settings: &SequenceSettings, index: u32) -> SyntheticFrame {
    let camera = &settings.camera;
    let [width, height] = camera.size;
    let (pose, _) = camera_pose(settings, index);
    let corners = marker_corners(settings.side_m).map(|p| camera.project(pose.apply(p)).unwrap_or(DVec2::splat(-1e6)));
    let inside = corners
        .iter()
        .all(|c| c.x >= 4.0 && c.y >= 4.0 && c.x <= f64::from(width) - 5.0 && c.y <= f64::from(height) - 5.0);
    let mut random = Random(settings.seed ^ u64::from(index).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    // An occluder in one frame of seven: a disc in the marker's plane, a little above it,
    // over part of the marker.
    let occluder = (settings.occlusion && index % 7 == 3).then(|| {
        let angle = random.unit() * std::f64::consts::TAU;
        let reach = settings.side_m * (0.25 + 0.2 * random.unit());
        (DVec2::new(angle.cos(), angle.sin()) * reach, settings.side_m * (0.12 + 0.08 * random.unit()))
    });
    let view = match (inside, occluder) {
        (false, _) => MarkerView::Absent,
        (true, Some(_)) => MarkerView::Occluded,
        (true, None) => MarkerView::Whole,
    };
    let lighting = if settings.lighting {
        let phase = f64::from(index) * 0.37;
        (0.75 + 0.3 * phase.sin(), DVec2::new(phase.cos(), (1.3 * phase).sin()) * 0.35)
    } else {
        (1.0, DVec2::ZERO)
    };
    let scene = Scene {
        settings,
        pose_inverse: inverse(&pose),
        cells: settings.dictionary.cells_of(settings.id).unwrap_or_default(),
        occluder,
    };
    let mut colour = vec![[0f32; 3]; width as usize * height as usize];
    const OFFSETS: [[f64; 2]; 4] = [[-0.25, -0.25], [0.25, -0.25], [-0.25, 0.25], [0.25, 0.25]];
    for y in 0..height {
        for x in 0..width {
            let mut sum = [0.0f32; 3];
            for [dx, dy] in OFFSETS {
                let ray = camera.normalized(DVec2::new(f64::from(x) + dx, f64::from(y) + dy));
                let c = scene.shade(ray);
                for k in 0..3 {
                    sum[k] += c[k] * 0.25;
                }
            }
            // The light: stronger or weaker, brighter towards one side of the image.
            let across = DVec2::new(f64::from(x) / f64::from(width) - 0.5, f64::from(y) / f64::from(height) - 0.5);
            let light = (lighting.0 * (1.0 + across.dot(lighting.1))) as f32;
            let i = (y * width + x) as usize;
            colour[i] = sum.map(|c| c * light);
        }
    }
    let blur_px = settings.max_blur_px * (0.5 - 0.5 * (f64::from(index) * 0.9).cos() as f32);
    let mut rgb = vec![0u8; width as usize * height as usize * 3];
    let mut gray = vec![0f32; colour.len()];
    for channel in 0..3 {
        for (g, c) in gray.iter_mut().zip(&colour) {
            *g = c[channel];
        }
        if blur_px > 0.05 {
            gaussian_blur(&mut gray, width as usize, height as usize, blur_px);
        }
        let mut noise = Random(settings.seed.wrapping_add(u64::from(index) * 3 + channel as u64 + 1));
        for (i, &g) in gray.iter().enumerate() {
            let value = g * 255.0 + settings.noise * noise.gaussian() as f32;
            rgb[i * 3 + channel] = value.round().clamp(0.0, 255.0) as u8;
        }
    }
    SyntheticFrame { rgb, pose, corners, view, blur_px }
}

fn inverse(pose: &Pose) -> Pose {
    let rotation = pose.rotation.transpose();
    Pose { rotation, translation: -(rotation * pose.translation) }
}

struct Scene<'a> {
    settings: &'a SequenceSettings,
    /// Camera frame to marker frame.
    pose_inverse: Pose,
    cells: Vec<bool>,
    /// Centre (marker frame, metres) and radius of a disc held 2 cm above the marker.
    occluder: Option<(DVec2, f64)>,
}

impl Scene<'_> {
    /// The linear RGB colour (0 to 1) seen along the ray through a normalized point.
    fn shade(&self, normalized: DVec2) -> [f32; 3] {
        let origin = self.pose_inverse.translation;
        let direction = self.pose_inverse.rotation * normalized.extend(1.0);
        if let Some((centre, radius)) = self.occluder {
            let height = 0.02;
            let s = (height - origin.z) / direction.z;
            if s > 0.0 && (origin + direction * s).truncate().distance(centre) < radius {
                return [0.55, 0.38, 0.3];
            }
        }
        let s = -origin.z / direction.z;
        if s <= 0.0 {
            // Above the horizon: a plain wall.
            return [0.7, 0.72, 0.75];
        }
        let hit = (origin + direction * s).truncate();
        self.surface(hit)
    }

    /// The table's colour at a point of its plane (marker frame, metres).
    fn surface(&self, p: DVec2) -> [f32; 3] {
        let side = self.settings.side_m;
        let n = self.settings.dictionary.cells as f64 + 2.0;
        let cell = side / n;
        // The marker, with a white margin of a cell and a half.
        let (u, v) = (p.x / side + 0.5, 0.5 - p.y / side);
        if (0.0..1.0).contains(&u) && (0.0..1.0).contains(&v) {
            let (col, row) = ((u * n) as usize, (v * n) as usize);
            let n = n as usize;
            let inner = |k: usize| (1..n - 1).contains(&k);
            let white = inner(col) && inner(row) && self.cells[(row - 1) * (n - 2) + col - 1];
            return if white { [0.92, 0.92, 0.9] } else { [0.05, 0.05, 0.06] };
        }
        let margin = 0.5 * side + 1.5 * cell;
        if p.x.abs() < margin && p.y.abs() < margin {
            return [0.92, 0.92, 0.9];
        }
        // Clutter on the table: dark squares and a chequered card that is no marker.
        for (centre, half, chequered) in CLUTTER {
            let q = (p - DVec2::from(centre) * side) / (half * side);
            if q.x.abs() < 1.0 && q.y.abs() < 1.0 {
                let dark = !chequered || ((q.x * 2.0).floor() as i64 + (q.y * 2.0).floor() as i64) % 2 == 0;
                return if dark { [0.08, 0.07, 0.07] } else { [0.85, 0.85, 0.82] };
            }
        }
        // Wood grain.
        let grain =
            0.5 + 0.5 * ((p.x * 40.0 + (p.y * 7.0).sin() * 1.5).sin() * 0.6 + (p.y * 3.0 + p.x * 90.0).sin() * 0.4);
        let g = 0.45 + 0.15 * grain as f32;
        [g * 1.1, g * 0.85, g * 0.6]
    }
}

/// Clutter on the table: centres and half-sides in marker sides, and whether chequered.
const CLUTTER: [([f64; 2], f64, bool); 3] =
    [([2.2, 0.4], 0.35, false), ([-1.9, -1.6], 0.45, true), ([0.3, 2.4], 0.25, false)];

/// A separable Gaussian blur with standard deviation `sigma` pixels, edges clamped.
pub(crate) fn gaussian_blur(values: &mut [f32], width: usize, height: usize, sigma: f32) {
    let radius = (3.0 * sigma).ceil() as isize;
    let mut kernel: Vec<f32> = (-radius..=radius).map(|i| (-0.5 * (i as f32 / sigma).powi(2)).exp()).collect();
    let total: f32 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= total);
    let mut scratch = vec![0f32; values.len()];
    let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
    for y in 0..height {
        for x in 0..width {
            scratch[y * width + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * values[y * width + clamp(x as isize + k as isize - radius, width)])
                .sum();
        }
    }
    for y in 0..height {
        for x in 0..width {
            values[y * width + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * scratch[clamp(y as isize + k as isize - radius, height) * width + x])
                .sum();
        }
    }
}

/// SplitMix64 with Gaussian draws (Box–Muller): the same frames on every machine.
pub(crate) struct Random(pub(crate) u64);

impl Random {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// In `(0, 1]`.
    pub(crate) fn unit(&mut self) -> f64 {
        ((self.next() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    pub(crate) fn gaussian(&mut self) -> f64 {
        let (a, b) = (self.unit(), self.unit());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::{Scratch, Settings, detect};

    #[test]
    fn a_printed_marker_has_its_cells_border_and_margin() {
        let dictionary = Dictionary::named("4x4_50").unwrap();
        let image = marker_image(&dictionary, 0, 10, 1).unwrap();
        assert_eq!(image.width, 80);
        assert_eq!(image.at(5, 5), 255, "margin");
        assert_eq!(image.at(15, 15), 0, "border");
        // Marker 0's first row is 1011: white, black, white, white.
        let row: Vec<u8> = (0..4).map(|c| image.at(25 + c * 10, 25)).collect();
        assert_eq!(row, vec![255, 0, 255, 255]);
        assert!(marker_image(&dictionary, 50, 10, 1).is_none());
    }

    #[test]
    fn printed_markers_are_read_back_in_every_dictionary() {
        for dictionary in Dictionary::ALL {
            for id in [0, dictionary.len() / 2, dictionary.len() - 1] {
                let image = marker_image(&dictionary, id, 8, 2).unwrap();
                let found = detect(&image, &dictionary, &Settings::default(), None, &mut Scratch::default());
                assert_eq!(found.iter().map(|m| m.id).collect::<Vec<_>>(), vec![id], "{dictionary}");
                // Corners on the outer edge of the black border, pixel centres at whole numbers.
                let (low, high) = (16.0 - 0.5, (16 + (dictionary.cells + 2) * 8) as f32 - 0.5);
                let expected = [[low, low], [high, low], [high, high], [low, high]];
                for (corner, expected) in found[0].corners.iter().zip(expected) {
                    assert!(corner.distance(expected.into()) < 0.1, "{dictionary}: {corner} for {expected:?}");
                }
            }
        }
    }

    #[test]
    fn frames_follow_from_the_seed() {
        let settings = SequenceSettings {
            camera: Intrinsics::pinhole([96, 64], 60.0),
            dictionary: Dictionary::named("6x6_250").unwrap(),
            id: 3,
            side_m: 0.1,
            frames: 4,
            distance_m: [0.3, 0.5],
            seed: 9,
            noise: 3.0,
            max_blur_px: 1.0,
            lighting: true,
            occlusion: true,
            look_away: true,
        };
        assert_eq!(render_frame(&settings, 1).rgb, render_frame(&settings, 1).rgb);
        assert_ne!(
            render_frame(&settings, 1).rgb,
            render_frame(&SequenceSettings { seed: 10, ..settings.clone() }, 1).rgb
        );
    }
}
