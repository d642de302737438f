//! Finding square markers in a grey image, after OpenCV's ArUco detector (Garrido-Jurado et
//! al., "Automatic generation and detection of highly reliable fiducial markers under
//! occlusion", Pattern Recognition 47(6), 2014, and OpenCV's `aruco` module):
//!
//! 1. adaptive thresholds at a few window sizes, each giving dark regions' outer boundaries;
//! 2. boundaries simplified to polygons, kept if convex quadrilaterals of plausible size away
//!    from the image edge, near-duplicates merged;
//! 3. the perspective removed by the homography of each quadrilateral, each cell sampled in its
//!    middle and split into black and white at Otsu's threshold;
//! 4. the black border checked, the inner cells matched against the dictionary in four
//!    rotations with error correction;
//! 5. each corner refined to sub-pixel precision by fitting lines to the marker's four edges
//!    (the intensity's steepest rise across each edge) and intersecting them.

use crate::camera::Intrinsics;
use crate::contour::{Integral, outer_contours, simplify_closed};
use crate::dictionary::{Dictionary, pack};
use crate::gray::Gray;
use bevy_math::{DVec2, Mat3, Vec2, Vec3};

/// The detector's settings; the defaults are OpenCV's where it has the same setting.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Sides of the adaptive threshold's windows, pixels (odd).
    pub threshold_windows: Vec<u32>,
    /// How much darker than its window's mean a pixel must be to count as dark.
    pub threshold_offset: f32,
    /// The shortest marker outline as a share of the image's longer side.
    pub min_perimeter_rate: f32,
    /// The longest marker outline as a share of the image's longer side.
    pub max_perimeter_rate: f32,
    /// How far the outline may stray from its polygon, as a share of the outline's length.
    pub polygon_accuracy_rate: f32,
    /// The shortest side of a quadrilateral as a share of its perimeter.
    pub min_corner_distance_rate: f32,
    /// How close to the image's edge a corner may be, pixels.
    pub min_border_distance_px: f32,
    /// Two candidates closer than this share of the perimeter (mean corner distance) are one.
    pub min_marker_distance_rate: f32,
    /// The part of each cell's side left out on each side when sampling it.
    pub cell_margin_rate: f32,
    /// The share of border cells that may read white.
    pub max_border_error_rate: f32,
    /// Below this standard deviation of the samples (grey levels) a candidate is uniform.
    pub min_contrast: f32,
    /// The share of the dictionary's correctable cells that are corrected (OpenCV's
    /// `errorCorrectionRate`).
    pub error_correction_rate: f32,
    /// Whether corners are refined to sub-pixel precision.
    pub refine_corners: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            threshold_windows: vec![3, 13, 23],
            threshold_offset: 7.0,
            min_perimeter_rate: 0.03,
            max_perimeter_rate: 4.0,
            polygon_accuracy_rate: 0.03,
            min_corner_distance_rate: 0.05,
            min_border_distance_px: 3.0,
            min_marker_distance_rate: 0.125,
            cell_margin_rate: 0.13,
            max_border_error_rate: 0.35,
            min_contrast: 5.0,
            error_correction_rate: 0.6,
            refine_corners: true,
        }
    }
}

/// A marker found in an image.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Its index in the dictionary.
    pub id: u32,
    /// Its corners in pixels, in OpenCV's order: the printed marker's top-left, top-right,
    /// bottom-right and bottom-left (clockwise on the image when it faces the camera).
    pub corners: [Vec2; 4],
    /// Inner cells read wrong and corrected.
    pub corrected_cells: u32,
}

impl Marker {
    /// The corners in double precision, to a ten-thousandth of a pixel (what their single
    /// precision holds at image scale, without its binary tail: 302.36 rather than
    /// 302.3599853515625).
    pub fn corners_f64(&self) -> [DVec2; 4] {
        self.corners.map(|c| (c.as_dvec2() * 1e4).round() / 1e4)
    }
}

/// Reusable buffers, so that a sequence of frames allocates once.
#[derive(Debug, Default)]
pub struct Scratch {
    mask: Vec<u8>,
    labels: Vec<u32>,
}

/// The markers of `dictionary` in `image`, each id at most once (the largest if repeated),
/// sorted by id. With the camera's `lens`, the marker's edges are straightened (its distortion
/// removed) before the corners are fitted to them.
pub fn detect(
    image: &Gray,
    dictionary: &Dictionary,
    settings: &Settings,
    lens: Option<&Intrinsics>,
    scratch: &mut Scratch,
) -> Vec<Marker> {
    let candidates = candidates(image, settings, scratch);
    let max_wrong = (dictionary.max_correction_bits as f32 * settings.error_correction_rate) as u32;
    let mut markers: Vec<(Marker, f32)> = Vec::new();
    for quad in candidates {
        // The outline runs through the outermost dark pixels' centres, half a pixel inside the
        // marker's edge: on a marker of two or three pixels a cell, reading the cells within it
        // misreads the far ones.
        let Some((id, rotation, corrected_cells)) = read(image, &outward(&quad, 0.5), dictionary, max_wrong, settings)
        else {
            continue;
        };
        let mut corners = [0; 4].map(|_| Vec2::ZERO);
        for (i, corner) in corners.iter_mut().enumerate() {
            // The grid read from corner 0 shows the marker turned `rotation` quarter turns
            // clockwise: the printed top-left corner is candidate corner `rotation`.
            *corner = quad[(i + rotation as usize) % 4];
        }
        if settings.refine_corners {
            corners = refine(image, &corners, dictionary.cells + 2, lens);
        }
        let perimeter = perimeter(&corners);
        match markers.iter_mut().find(|(m, _)| m.id == id) {
            Some(existing) if existing.1 >= perimeter => {}
            Some(existing) => *existing = (Marker { id, corners, corrected_cells }, perimeter),
            None => markers.push((Marker { id, corners, corrected_cells }, perimeter)),
        }
    }
    let mut markers: Vec<Marker> = markers.into_iter().map(|(m, _)| m).collect();
    markers.sort_by_key(|m| m.id);
    markers
}

fn perimeter(quad: &[Vec2; 4]) -> f32 {
    (0..4).map(|i| quad[i].distance(quad[(i + 1) % 4])).sum()
}

/// Convex quadrilaterals outlined by dark regions, corners clockwise on the image, one per
/// place.
fn candidates(image: &Gray, settings: &Settings, scratch: &mut Scratch) -> Vec<[Vec2; 4]> {
    let longer = image.width.max(image.height) as f32;
    let (min_perimeter, max_perimeter) = (settings.min_perimeter_rate * longer, settings.max_perimeter_rate * longer);
    let integral = Integral::new(image);
    let mut found: Vec<([Vec2; 4], f32)> = Vec::new();
    for &window in &settings.threshold_windows {
        integral.threshold(image, window.max(3) | 1, settings.threshold_offset, &mut scratch.mask);
        let min_side = (min_perimeter / 4.0).floor() as u32;
        let max_side = (max_perimeter / 4.0).ceil() as u32 + 1;
        for contour in outer_contours(&scratch.mask, image.width, image.height, min_side, max_side, &mut scratch.labels)
        {
            let length = contour.points.len() as f32;
            if length < min_perimeter || length > max_perimeter {
                continue;
            }
            let polygon = simplify_closed(&contour.points, length * settings.polygon_accuracy_rate);
            let Ok(mut quad) = <[Vec2; 4]>::try_from(polygon) else { continue };
            if !is_convex(&quad) {
                continue;
            }
            let perimeter = perimeter(&quad);
            let shortest = (0..4).map(|i| quad[i].distance(quad[(i + 1) % 4])).fold(f32::INFINITY, f32::min);
            if shortest < perimeter * settings.min_corner_distance_rate
                || quad.iter().any(|&c| !image.contains(c, settings.min_border_distance_px))
            {
                continue;
            }
            // Clockwise on the image (y down): positive cross product at corner 0.
            if (quad[1] - quad[0]).perp_dot(quad[2] - quad[0]) < 0.0 {
                quad.swap(1, 3);
            }
            // Near-duplicates (the same outline at another window size): the larger stays. An
            // outline around another, such as the paper's around its marker, is kept apart by
            // its size.
            let close = found.iter().position(|(other, other_perimeter)| {
                let mean = (0..4)
                    .map(|shift| (0..4).map(|i| quad[i].distance(other[(i + shift) % 4])).sum::<f32>() / 4.0)
                    .fold(f32::INFINITY, f32::min);
                let similar = perimeter.max(*other_perimeter) < 1.2 * perimeter.min(*other_perimeter);
                similar && mean < settings.min_marker_distance_rate * perimeter.min(*other_perimeter)
            });
            match close {
                Some(index) if found[index].1 < perimeter => found[index] = (quad, perimeter),
                Some(_) => {}
                None => found.push((quad, perimeter)),
            }
        }
    }
    found.into_iter().map(|(quad, _)| quad).collect()
}

/// `quad` (clockwise on the image) with each side moved `by` pixels outwards.
fn outward(quad: &[Vec2; 4], by: f32) -> [Vec2; 4] {
    // The outward normal of side i (from corner i to corner i + 1), clockwise with y down.
    let normal = |i: usize| {
        let side = (quad[(i + 1) % 4] - quad[i]).normalize_or_zero();
        Vec2::new(side.y, -side.x)
    };
    std::array::from_fn(|i| {
        let (before, after) = (normal((i + 3) % 4), normal(i));
        let bend = 1.0 + before.dot(after);
        if bend < 0.1 { quad[i] } else { quad[i] + (before + after) * (by / bend) }
    })
}

fn is_convex(quad: &[Vec2; 4]) -> bool {
    let turns: Vec<f32> =
        (0..4).map(|i| (quad[(i + 1) % 4] - quad[i]).perp_dot(quad[(i + 2) % 4] - quad[(i + 1) % 4])).collect();
    turns.iter().all(|&t| t > 0.0) || turns.iter().all(|&t| t < 0.0)
}

/// The homography taking the square `[0, side]²` (x right, y down) to `quad` (its corners
/// clockwise from the top-left).
fn square_to_quad(quad: &[Vec2; 4], side: f32) -> Option<Mat3> {
    // The unit square to the quadrilateral in closed form (Heckbert, "Fundamentals of texture
    // mapping and image warping", 1989), then scaled.
    let [p0, p1, p2, p3] = *quad;
    let s = p0 - p1 + p2 - p3;
    let (d1, d2) = (p1 - p2, p3 - p2);
    let det = d1.perp_dot(d2);
    if det.abs() < 1e-9 {
        return None;
    }
    let g = s.perp_dot(d2) / det;
    let h = d1.perp_dot(s) / det;
    let unit = Mat3::from_cols(
        Vec3::new(p1.x - p0.x + g * p1.x, p1.y - p0.y + g * p1.y, g),
        Vec3::new(p3.x - p0.x + h * p3.x, p3.y - p0.y + h * p3.y, h),
        Vec3::new(p0.x, p0.y, 1.0),
    );
    Some(unit * Mat3::from_diagonal(Vec3::new(1.0 / side, 1.0 / side, 1.0)))
}

/// Reads the cells inside `quad` and matches them: the marker's id, the quarter turns it shows
/// and the corrected cells; `None` if it is not a marker of the dictionary.
fn read(
    image: &Gray,
    quad: &[Vec2; 4],
    dictionary: &Dictionary,
    max_wrong: u32,
    settings: &Settings,
) -> Option<(u32, u32, u32)> {
    const SAMPLES: u32 = 4;
    let cells = dictionary.cells + 2;
    let warp = square_to_quad(quad, cells as f32)?;
    let margin = settings.cell_margin_rate.clamp(0.0, 0.45);
    let mut samples = Vec::with_capacity((cells * cells * SAMPLES * SAMPLES) as usize);
    for row in 0..cells {
        for col in 0..cells {
            for sy in 0..SAMPLES {
                for sx in 0..SAMPLES {
                    let fx = margin + (1.0 - 2.0 * margin) * (sx as f32 + 0.5) / SAMPLES as f32;
                    let fy = margin + (1.0 - 2.0 * margin) * (sy as f32 + 0.5) / SAMPLES as f32;
                    let point = warp * Vec3::new(col as f32 + fx, row as f32 + fy, 1.0);
                    samples.push(image.sample(point.truncate() / point.z));
                }
            }
        }
    }
    let count = samples.len() as f32;
    let mean = samples.iter().sum::<f32>() / count;
    let deviation = (samples.iter().map(|s| (s - mean) * (s - mean)).sum::<f32>() / count).sqrt();
    if deviation < settings.min_contrast {
        return None;
    }
    let threshold = otsu(&samples);
    let per_cell = (SAMPLES * SAMPLES) as usize;
    let white: Vec<bool> = samples
        .chunks_exact(per_cell)
        .map(|cell| cell.iter().filter(|&&s| s > threshold).count() * 2 > per_cell)
        .collect();
    let border_white = (0..cells * cells)
        .filter(|&i| {
            let (row, col) = (i / cells, i % cells);
            (row == 0 || col == 0 || row == cells - 1 || col == cells - 1) && white[i as usize]
        })
        .count() as f32;
    if border_white > settings.max_border_error_rate * (4 * cells - 4) as f32 {
        return None;
    }
    let inner: Vec<bool> = (1..cells - 1)
        .flat_map(|row| (1..cells - 1).map(move |col| (row, col)))
        .map(|(row, col)| white[(row * cells + col) as usize])
        .collect();
    let found = dictionary.identify(pack(&inner), max_wrong)?;
    Some((found.id, found.rotation, found.wrong_cells))
}

/// Otsu's threshold of grey samples: the level that best separates them into two classes
/// (the largest between-class variance), over 256 bins.
fn otsu(samples: &[f32]) -> f32 {
    let mut histogram = [0u32; 256];
    for &s in samples {
        histogram[s.clamp(0.0, 255.0) as usize] += 1;
    }
    let total = samples.len() as f64;
    let sum: f64 = histogram.iter().enumerate().map(|(i, &n)| i as f64 * f64::from(n)).sum();
    let (mut below, mut below_sum, mut best, mut level) = (0.0, 0.0, -1.0, 0usize);
    for (i, &n) in histogram.iter().enumerate() {
        below += f64::from(n);
        below_sum += i as f64 * f64::from(n);
        let above = total - below;
        if below == 0.0 || above == 0.0 {
            continue;
        }
        let difference = below_sum / below - (sum - below_sum) / above;
        let between = below * above * difference * difference;
        if between > best {
            best = between;
            level = i;
        }
    }
    level as f32 + 0.5
}

/// Corners moved onto the intersections of lines fitted to the four edges of the marker,
/// `cells` cells a side (border included); a corner whose fit fails or moves it by more than
/// a third of a cell keeps its place. With a `lens`, the lines are fitted where a pinhole
/// camera would have seen the edge points, and the corners taken back through the lens.
fn refine(image: &Gray, corners: &[Vec2; 4], cells: u32, lens: Option<&Intrinsics>) -> [Vec2; 4] {
    let distorting = lens.filter(|lens| !lens.distortion.is_none());
    let straighten = |p: Vec2| distorting.map_or(p, |lens| lens.straightened(p.as_dvec2()).as_vec2());
    let bend = |p: Vec2| distorting.map_or(p, |lens| lens.bent(p.as_dvec2()).as_vec2());
    let centre = corners.iter().copied().sum::<Vec2>() / 4.0;
    let lines: Vec<Option<(Vec2, Vec2)>> =
        (0..4).map(|i| edge_line(image, corners[i], corners[(i + 1) % 4], centre, cells, &straighten)).collect();
    std::array::from_fn(|i| {
        let before = (i + 3) % 4;
        let cell = corners[before].distance(corners[i]).min(corners[i].distance(corners[(i + 1) % 4])) / cells as f32;
        match (lines[before], lines[i]) {
            (Some(a), Some(b)) => {
                intersect(a, b).map(bend).filter(|p| p.distance(corners[i]) < cell / 3.0 + 1.0).unwrap_or(corners[i])
            }
            _ => corners[i],
        }
    })
}

/// The line (a point and a unit direction) through the steepest rise of intensity across the
/// edge from `a` to `b`, going outwards from `centre`: dark marker inside, light outside; the
/// edge points are mapped by `straighten` before the line is fitted.
fn edge_line(
    image: &Gray,
    a: Vec2,
    b: Vec2,
    centre: Vec2,
    cells: u32,
    straighten: &dyn Fn(Vec2) -> Vec2,
) -> Option<(Vec2, Vec2)> {
    let along = b - a;
    let length = along.length();
    let direction = along / length;
    let mut normal = direction.perp();
    if normal.dot((a + b) * 0.5 - centre) < 0.0 {
        normal = -normal;
    }
    let cell = length / cells as f32;
    // Search half a cell inwards (the border is a cell wide) and as far outwards, at most 6 px.
    let reach = (0.5 * cell).clamp(1.5, 6.0);
    const STEP: f32 = 0.25;
    let steps = (reach / STEP) as i32;
    let mut points: Vec<(Vec2, f32)> = Vec::new();
    let samples = (length as usize).clamp(8, 400);
    for k in 0..samples {
        // Away from the corners, where the other edge and the contour's rounding interfere.
        let t = 0.12 + 0.76 * (k as f32 + 0.5) / samples as f32;
        let base = a + along * t;
        let profile: Vec<f32> = (-steps..=steps).map(|s| image.sample(base + normal * (s as f32 * STEP))).collect();
        let rises: Vec<f32> = profile.windows(3).map(|w| w[2] - w[0]).collect();
        let (peak, &rise) = rises.iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1))?;
        if rise <= 2.0 {
            continue;
        }
        // The centroid of the rise over the run of samples above half the peak around it:
        // the middle of the edge, whether it is sharp (a plateau of equal rises) or blurred.
        let half = 0.5 * rise;
        let first = (0..=peak).rev().take_while(|&k| rises[k] > half).last().unwrap_or(peak);
        let last = (peak..rises.len()).take_while(|&k| rises[k] > half).last().unwrap_or(peak);
        if first == 0 || last + 1 == rises.len() {
            continue;
        }
        let mass: f32 = rises[first..=last].iter().map(|r| r - half).sum();
        let centre = (first..=last).map(|k| k as f32 * (rises[k] - half)).sum::<f32>() / mass;
        let s = (centre + 1.0 - steps as f32) * STEP;
        points.push((straighten(base + normal * s), rise));
    }
    if points.len() < 4 {
        return None;
    }
    // The weighted total-least-squares line: through the weighted mean, along the principal
    // axis of the points' scatter.
    let weight: f32 = points.iter().map(|p| p.1).sum();
    let mean = points.iter().map(|(p, w)| *p * *w).sum::<Vec2>() / weight;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (p, w) in &points {
        let d = *p - mean;
        sxx += w * d.x * d.x;
        sxy += w * d.x * d.y;
        syy += w * d.y * d.y;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    Some((mean, Vec2::from_angle(angle)))
}

/// Where two lines (point, unit direction) cross; `None` if they are nearly parallel.
fn intersect((p, d): (Vec2, Vec2), (q, e): (Vec2, Vec2)) -> Option<Vec2> {
    let det = d.perp_dot(e);
    (det.abs() > 1e-3).then(|| p + d * ((q - p).perp_dot(e) / det))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn otsu_splits_two_clusters_between_them() {
        let samples: Vec<f32> =
            (0..50).map(|i| 30.0 + (i % 5) as f32).chain((0..50).map(|i| 200.0 + (i % 7) as f32)).collect();
        let t = otsu(&samples);
        assert!((34.0..200.0).contains(&t), "{t}");
    }

    #[test]
    fn the_square_maps_onto_the_quadrilateral_corner_for_corner() {
        let quad = [Vec2::new(10.0, 12.0), Vec2::new(90.0, 20.0), Vec2::new(80.0, 95.0), Vec2::new(5.0, 70.0)];
        let warp = square_to_quad(&quad, 6.0).unwrap();
        for (corner, expected) in [(0.0, 0.0), (6.0, 0.0), (6.0, 6.0), (0.0, 6.0)].into_iter().zip(quad) {
            let p = warp * Vec3::new(corner.0, corner.1, 1.0);
            assert!((p.truncate() / p.z).distance(expected) < 1e-3);
        }
    }

    #[test]
    fn lines_cross_where_they_meet() {
        let p = intersect((Vec2::new(0.0, 1.0), Vec2::X), (Vec2::new(3.0, 0.0), Vec2::Y)).unwrap();
        assert!(p.distance(Vec2::new(3.0, 1.0)) < 1e-6);
        assert_eq!(intersect((Vec2::ZERO, Vec2::X), (Vec2::Y, Vec2::X)), None);
    }

    #[test]
    fn an_outline_moved_outwards_keeps_its_sides_parallel() {
        // Clockwise on the image (y down).
        let square = [Vec2::new(0.0, 0.0), Vec2::new(10.0, 0.0), Vec2::new(10.0, 10.0), Vec2::new(0.0, 10.0)];
        let moved = outward(&square, 0.5);
        let expected = [Vec2::new(-0.5, -0.5), Vec2::new(10.5, -0.5), Vec2::new(10.5, 10.5), Vec2::new(-0.5, 10.5)];
        for (got, want) in moved.iter().zip(expected) {
            assert!(got.distance(want) < 1e-5, "{moved:?}");
        }
    }
}
