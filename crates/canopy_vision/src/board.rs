//! ArUco grid boards, laid out as OpenCV's `GridBoard` lays them out, and a board's pose from
//! every marker of it that was found: many corners spread over the board hold the pose
//! steadier than one marker's four, and leave no planar ambiguity to flip between.
//!
//! The board frame is OpenCV's (4.7 and later): origin at the top-left corner of the top-left
//! marker, x right, y down the printed board, z into it; markers in rows from the top-left,
//! their ids counting up from the first.

use crate::camera::Intrinsics;
use crate::detect::Marker;
use crate::dictionary::Dictionary;
use crate::gray::Gray;
use crate::pose::{Pose, estimate, reprojection_error};
use bevy_math::{DMat3, DVec2, DVec3};

/// The most markers along either side of a board.
pub const MAX_MARKERS_A_SIDE: u32 = 64;

/// A grid of markers with gaps between them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridBoard {
    /// Markers across and down.
    pub markers: [u32; 2],
    /// Each marker's side, metres.
    pub marker_m: f64,
    /// The gap between neighbouring markers, metres.
    pub separation_m: f64,
    /// The id of the top-left marker; the others count up along the rows.
    pub first_id: u32,
}

/// A marker's own frame's axes in a board's frame (its own inverse): x along the board's x,
/// y and z against the board's y (down the print) and z (into it).
const MARKER_AXES: DMat3 = DMat3::from_cols(DVec3::X, DVec3::NEG_Y, DVec3::NEG_Z);

/// A board's pose from the markers of it found in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardPose {
    /// Board frame to camera frame.
    pub pose: Pose,
    /// Root-mean-square reprojection error over every corner used, pixels.
    pub error_px: f64,
    /// The board's markers used.
    pub markers: usize,
}

impl GridBoard {
    /// A board of `markers` across and down, or what is wrong with it for `dictionary`.
    pub fn new(
        markers: [u32; 2],
        marker_m: f64,
        separation_m: f64,
        first_id: u32,
        dictionary: &Dictionary,
    ) -> Result<Self, String> {
        if markers.iter().any(|&n| !(1..=MAX_MARKERS_A_SIDE).contains(&n)) {
            return Err(format!(
                "expected 1 to {MAX_MARKERS_A_SIDE} markers a side, found {}x{}",
                markers[0], markers[1]
            ));
        }
        if !(marker_m.is_finite() && marker_m > 0.0 && marker_m <= 10.0) {
            return Err(format!("expected a marker side greater than 0 and at most 10 m, found {marker_m}"));
        }
        if !(separation_m.is_finite() && (0.0..=10.0).contains(&separation_m)) {
            return Err(format!("expected a separation from 0 to 10 m, found {separation_m}"));
        }
        let count = markers[0] * markers[1];
        if u64::from(first_id) + u64::from(count) > u64::from(dictionary.len()) {
            return Err(format!(
                "{count} markers from id {first_id} need ids up to {}, but {dictionary} has {}",
                u64::from(first_id) + u64::from(count) - 1,
                dictionary.len()
            ));
        }
        Ok(Self { markers, marker_m, separation_m, first_id })
    }

    /// The board's width and height from the first marker's outer edge to the last's, metres.
    pub fn size_m(&self) -> DVec2 {
        let side = |n: u32| f64::from(n) * self.marker_m + f64::from(n - 1) * self.separation_m;
        DVec2::new(side(self.markers[0]), side(self.markers[1]))
    }

    /// The corners of marker `id` in the board frame, in OpenCV's order; `None` for an id not
    /// on the board.
    pub fn corners(&self, id: u32) -> Option<[DVec3; 4]> {
        let index = id.checked_sub(self.first_id).filter(|&i| i < self.markers[0] * self.markers[1])?;
        let pitch = self.marker_m + self.separation_m;
        let top_left =
            DVec3::new(f64::from(index % self.markers[0]) * pitch, f64::from(index / self.markers[0]) * pitch, 0.0);
        let l = self.marker_m;
        Some([top_left, top_left + DVec3::X * l, top_left + DVec3::new(l, l, 0.0), top_left + DVec3::Y * l])
    }

    /// The printable board: `pixels_per_metre` of the printed size, a white margin of
    /// `margin_m` round it; `None` if the image would be empty or larger than 16,384 pixels a
    /// side.
    pub fn image(&self, dictionary: &Dictionary, pixels_per_metre: f64, margin_m: f64) -> Option<Gray> {
        let extent = (self.size_m() + DVec2::splat(2.0 * margin_m)) * pixels_per_metre;
        if !(extent.x >= 1.0 && extent.y >= 1.0 && extent.max_element() <= 16_384.0) {
            return None;
        }
        let (width, height) = (extent.x.round() as u32, extent.y.round() as u32);
        let mut image = Gray::filled(width, height, 255);
        let n = f64::from(dictionary.cells + 2);
        let cells: Vec<Vec<bool>> = (0..self.markers[0] * self.markers[1])
            .map(|i| dictionary.cells_of(self.first_id + i).unwrap_or_default())
            .collect();
        for y in 0..height {
            for x in 0..width {
                // The board point at the pixel's centre.
                let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5) / pixels_per_metre - DVec2::splat(margin_m);
                let pitch = self.marker_m + self.separation_m;
                let (column, row) = ((p.x / pitch).floor(), (p.y / pitch).floor());
                if column < 0.0
                    || row < 0.0
                    || column >= f64::from(self.markers[0])
                    || row >= f64::from(self.markers[1])
                {
                    continue;
                }
                let within = (p - DVec2::new(column, row) * pitch) / self.marker_m;
                if within.x >= 1.0 || within.y >= 1.0 {
                    continue; // in the gap between markers
                }
                let (col, cell_row) = ((within.x * n) as u32, (within.y * n) as u32);
                let inner = |k: u32| (1..=dictionary.cells).contains(&k);
                let marker = &cells[(row as u32 * self.markers[0] + column as u32) as usize];
                let white =
                    inner(col) && inner(cell_row) && marker[((cell_row - 1) * dictionary.cells + col - 1) as usize];
                image.pixels[(y * width + x) as usize] = if white { 255 } else { 0 };
            }
        }
        Some(image)
    }

    /// The board's markers among `markers` (those of its ids found once: an id found twice
    /// cannot say which is the board's), each with its corners in the board's frame.
    pub fn matched<'a>(&self, markers: &'a [Marker]) -> Vec<(&'a Marker, [DVec3; 4])> {
        let seen_once = |id: u32| markers.iter().filter(|m| m.id == id).count() == 1;
        markers.iter().filter(|m| seen_once(m.id)).filter_map(|m| Some((m, self.corners(m.id)?))).collect()
    }

    /// The pose of the frame at the board's centre with a marker's axes (x right, y up the
    /// print, z out of it), from the board's `pose`.
    pub fn centred(&self, pose: &Pose) -> Pose {
        let centre = self.centre();
        Pose { rotation: pose.rotation * MARKER_AXES, translation: pose.translation + pose.rotation * centre }
    }

    /// A point of the board's frame in the frame of [`Self::centred`].
    pub fn from_board(&self, point: DVec3) -> DVec3 {
        MARKER_AXES * (point - self.centre())
    }

    /// The board's centre in its frame.
    fn centre(&self) -> DVec3 {
        (self.size_m() * 0.5).extend(0.0)
    }

    /// The board's pose from the `markers` found in a frame, those [`Self::matched`]: each of
    /// both planar solutions of its two largest markers in the image tried as a start, refined
    /// over every corner, the one that fits best kept; `None` if none of its markers was
    /// found.
    pub fn pose(&self, markers: &[Marker], camera: &Intrinsics) -> Option<BoardPose> {
        let mut used = self.matched(markers);
        if used.is_empty() {
            return None;
        }
        let area = |m: &Marker| {
            let c = m.corners_f64();
            0.5 * (0..4).map(|i| c[i].perp_dot(c[(i + 1) % 4])).sum::<f64>().abs()
        };
        used.sort_by(|a, b| area(b.0).total_cmp(&area(a.0)));
        let object: Vec<DVec3> = used.iter().flat_map(|(_, corners)| *corners).collect();
        let pixels: Vec<DVec2> = used.iter().flat_map(|(m, _)| m.corners_f64()).collect();
        // A marker's pose puts its own frame (at its centre) where the board's lies.
        let starts = used.iter().take(2).filter_map(|(m, corners)| {
            let found = estimate(&m.corners_f64(), self.marker_m, camera)?;
            let centre = (corners[0] + corners[2]) * 0.5;
            Some([found.pose, found.alternative].map(|marker| {
                let rotation = marker.rotation * MARKER_AXES;
                Pose { rotation, translation: marker.translation - rotation * centre }
            }))
        });
        starts
            .flatten()
            .map(|start| {
                let pose = crate::pose::refine(start, &object, &pixels, camera);
                (pose, reprojection_error(&pose, &object, &pixels, camera))
            })
            .filter(|(_, error)| error.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(pose, error_px)| BoardPose { pose, error_px, markers: used.len() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::{Scratch, Settings, detect};
    use crate::synth::photograph_print;

    fn board() -> (GridBoard, Dictionary) {
        let dictionary = Dictionary::named("6x6_250").unwrap();
        (GridBoard::new([4, 3], 0.04, 0.01, 10, &dictionary).unwrap(), dictionary)
    }

    #[test]
    fn layout_follows_opencv_and_bad_boards_are_refused() {
        let (board, dictionary) = board();
        assert!((board.size_m() - DVec2::new(0.19, 0.14)).length() < 1e-12);
        // Marker 15 (the sixth): second row, second column.
        let corners = board.corners(15).unwrap();
        assert!((corners[0] - DVec3::new(0.05, 0.05, 0.0)).length() < 1e-12);
        assert!((corners[2] - DVec3::new(0.09, 0.09, 0.0)).length() < 1e-12);
        assert_eq!((board.corners(9), board.corners(22)), (None, None));
        assert!(GridBoard::new([0, 3], 0.04, 0.01, 0, &dictionary).unwrap_err().contains("1 to 64"));
        assert!(GridBoard::new([4, 3], f64::NAN, 0.01, 0, &dictionary).unwrap_err().contains("marker side"));
        assert!(GridBoard::new([20, 20], 0.04, 0.01, 0, &dictionary).unwrap_err().contains("has 250"));
    }

    #[test]
    fn a_photographed_board_gives_its_pose_from_every_marker() {
        let (board, dictionary) = board();
        let (pixels_per_metre, margin_m) = (4000.0, 0.01);
        let image = board.image(&dictionary, pixels_per_metre, margin_m).unwrap();
        assert_eq!((image.width, image.height), (840, 640));
        let camera = Intrinsics::pinhole([640, 480], 50.0);
        // Tilted 35 degrees about x and turned 20 about y, 45 cm away, its middle near the
        // image's centre.
        let rotation = DMat3::from_rotation_y(0.35) * DMat3::from_rotation_x(-0.6);
        let translation = DVec3::new(0.0, 0.0, 0.45) - rotation * (board.size_m() * 0.5).extend(0.0);
        let truth = Pose { rotation, translation };
        let frame = photograph_print(&image, pixels_per_metre, margin_m, &truth, &camera);
        let markers = detect(&frame, &dictionary, &Settings::default(), Some(&camera), &mut Scratch::default());
        let found = board.pose(&markers, &camera).unwrap();
        assert_eq!(found.markers, 12, "every marker of the board");
        assert!(found.error_px < 0.5, "{} px", found.error_px);
        assert!(found.pose.angle_to(&truth).to_degrees() < 0.2, "{} degrees", found.pose.angle_to(&truth).to_degrees());
        let centre = (board.size_m() * 0.5).extend(0.0);
        assert!(found.pose.apply(centre).distance(truth.apply(centre)) < 1e-3);
        // Markers of another board, or none: no pose.
        let other = GridBoard { first_id: 100, ..board };
        assert!(other.pose(&markers, &camera).is_none());
    }
}
