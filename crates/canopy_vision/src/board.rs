//! Boards of markers, grid or ChArUco, and a board's pose from what of it was found: many
//! points spread over the board hold the pose steadier than one marker's four corners, and
//! leave no planar ambiguity to flip between.
//!
//! A grid board's pose is fitted to its markers' corners; a ChArUco board's to its chessboard
//! corners (found between its markers and placed to a fraction of a pixel), as OpenCV fits it.

use crate::camera::Intrinsics;
pub use crate::charuco::CharucoBoard;
use crate::detect::Marker;
use crate::dictionary::Dictionary;
use crate::gray::Gray;
pub use crate::grid::GridBoard;
use crate::pose::{Pose, estimate, refine, reprojection_error};
use bevy_math::{DMat3, DVec2, DVec3};

/// A marker's own frame's axes in a board's frame (its own inverse): x along the board's x,
/// y and z against the board's y (down the print) and z (into it).
const MARKER_AXES: DMat3 = DMat3::from_cols(DVec3::X, DVec3::NEG_Y, DVec3::NEG_Z);

/// The fewest chessboard corners a ChArUco board's pose is fitted to.
pub const MIN_CHESSBOARD_CORNERS: usize = 4;

/// A board of markers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Board {
    /// Markers in a grid with gaps between them.
    Grid(GridBoard),
    /// A chessboard with markers in its white squares.
    Charuco(CharucoBoard),
}

/// A board's pose from what of it was found in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardPose {
    /// Board frame to camera frame.
    pub pose: Pose,
    /// Root-mean-square reprojection error over every point used, pixels.
    pub error_px: f64,
    /// The board's markers found.
    pub markers: usize,
}

impl Board {
    /// The board's width and height, metres.
    pub fn size_m(&self) -> DVec2 {
        match self {
            Board::Grid(grid) => grid.size_m(),
            Board::Charuco(charuco) => charuco.size_m(),
        }
    }

    /// The corners of marker `id` in the board frame, in OpenCV's order; `None` for an id not
    /// on the board.
    pub fn corners(&self, id: u32) -> Option<[DVec3; 4]> {
        match self {
            Board::Grid(grid) => grid.corners(id),
            Board::Charuco(charuco) => charuco.corners(id),
        }
    }

    /// Each marker's side, metres.
    fn marker_m(&self) -> f64 {
        match self {
            Board::Grid(grid) => grid.marker_m,
            Board::Charuco(charuco) => charuco.marker_m,
        }
    }

    /// The printable board: `pixels_per_metre` of the printed size, a white margin of
    /// `margin_m` round it; `None` if the image would be empty or larger than 16,384 pixels a
    /// side.
    pub fn image(&self, dictionary: &Dictionary, pixels_per_metre: f64, margin_m: f64) -> Option<Gray> {
        match self {
            Board::Grid(grid) => grid.image(dictionary, pixels_per_metre, margin_m),
            Board::Charuco(charuco) => charuco.image(dictionary, pixels_per_metre, margin_m),
        }
    }

    /// The board's markers among `markers` (those of its ids found once: an id found twice
    /// cannot say which is the board's), each with its corners in the board's frame.
    pub fn matched<'a>(&self, markers: &'a [Marker]) -> Vec<(&'a Marker, [DVec3; 4])> {
        let seen_once = |id: u32| markers.iter().filter(|m| m.id == id).count() == 1;
        markers.iter().filter(|m| seen_once(m.id)).filter_map(|m| Some((m, self.corners(m.id)?))).collect()
    }

    /// The points of the board found in `image`, where its `markers` were found, each with
    /// where it lies on the board (metres): a grid board's marker corners, a ChArUco board's
    /// chessboard corners.
    pub fn points(&self, image: &Gray, markers: &[Marker]) -> Vec<(DVec3, DVec2)> {
        match self {
            Board::Grid(_) => self
                .matched(markers)
                .into_iter()
                .flat_map(|(marker, object)| object.into_iter().zip(marker.corners_f64()))
                .collect(),
            Board::Charuco(charuco) => charuco
                .find_corners(image, markers)
                .into_iter()
                .map(|(index, pixel)| (charuco.chessboard_corner(index), pixel))
                .collect(),
        }
    }

    /// The board's pose fitted to its `points` found (see [`Self::points`]), started from
    /// both planar solutions of each of its two largest `markers` in the image, the start that
    /// fits best kept; `None` without a marker of it, or, for a ChArUco board, with fewer than
    /// [`MIN_CHESSBOARD_CORNERS`] corners.
    pub fn pose(&self, points: &[(DVec3, DVec2)], markers: &[Marker], camera: &Intrinsics) -> Option<BoardPose> {
        let mut used = self.matched(markers);
        let enough = match self {
            Board::Grid(_) => !points.is_empty(),
            Board::Charuco(_) => points.len() >= MIN_CHESSBOARD_CORNERS,
        };
        if used.is_empty() || !enough {
            return None;
        }
        let area = |m: &Marker| {
            let c = m.corners_f64();
            0.5 * (0..4).map(|i| c[i].perp_dot(c[(i + 1) % 4])).sum::<f64>().abs()
        };
        used.sort_by(|a, b| area(b.0).total_cmp(&area(a.0)));
        let (object, pixels): (Vec<DVec3>, Vec<DVec2>) = points.iter().copied().unzip();
        // A marker's pose puts its own frame (at its centre) where the board's lies.
        let starts = used.iter().take(2).filter_map(|(m, corners)| {
            let found = estimate(&m.corners_f64(), self.marker_m(), camera)?;
            let centre = (corners[0] + corners[2]) * 0.5;
            Some([found.pose, found.alternative].map(|marker| {
                let rotation = marker.rotation * MARKER_AXES;
                Pose { rotation, translation: marker.translation - rotation * centre }
            }))
        });
        starts
            .flatten()
            .map(|start| {
                let pose = refine(start, &object, &pixels, camera);
                (pose, reprojection_error(&pose, &object, &pixels, camera))
            })
            .filter(|(_, error)| error.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(pose, error_px)| BoardPose { pose, error_px, markers: used.len() })
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::{Scratch, Settings, detect};
    use crate::synth::photograph_print;

    /// The board photographed tilted 35 degrees about x and turned 20 about y, 45 cm away,
    /// its middle near the image's centre: the pose found, and the truth.
    fn photographed(board: Board, dictionary: &Dictionary) -> (Option<BoardPose>, Pose, Vec<Marker>, Gray) {
        let (pixels_per_metre, margin_m) = (4000.0, 0.01);
        let image = board.image(dictionary, pixels_per_metre, margin_m).unwrap();
        let camera = Intrinsics::pinhole([640, 480], 50.0);
        let rotation = DMat3::from_rotation_y(0.35) * DMat3::from_rotation_x(-0.6);
        let translation = DVec3::new(0.0, 0.0, 0.45) - rotation * (board.size_m() * 0.5).extend(0.0);
        let truth = Pose { rotation, translation };
        let frame = photograph_print(&image, pixels_per_metre, margin_m, &truth, &camera);
        let markers = detect(&frame, dictionary, &Settings::default(), Some(&camera), &mut Scratch::default());
        let points = board.points(&frame, &markers);
        (board.pose(&points, &markers, &camera), truth, markers, frame)
    }

    #[test]
    fn a_photographed_board_gives_its_pose_from_all_of_it() {
        let dictionary = Dictionary::named("6x6_250").unwrap();
        let grid = Board::Grid(GridBoard::new([4, 3], 0.04, 0.01, 10, &dictionary).unwrap());
        let charuco = Board::Charuco(CharucoBoard::new([5, 4], 0.035, 0.025, 0, false, &dictionary).unwrap());
        for (board, markers, degrees) in [(grid, 12, 0.2), (charuco, 10, 0.1)] {
            let (found, truth, seen, frame) = photographed(board, &dictionary);
            let found = found.unwrap();
            assert_eq!(found.markers, markers, "every marker of {board:?}");
            assert!(found.error_px < 0.3, "{} px", found.error_px);
            let angle = found.pose.angle_to(&truth).to_degrees();
            assert!(angle < degrees, "{board:?}: {angle} degrees");
            let centre = (board.size_m() * 0.5).extend(0.0);
            assert!(found.pose.apply(centre).distance(truth.apply(centre)) < 1e-3);
            // Markers of another board: no pose.
            let other = match board {
                Board::Grid(grid) => Board::Grid(GridBoard { first_id: 100, ..grid }),
                Board::Charuco(charuco) => Board::Charuco(CharucoBoard { first_id: 100, ..charuco }),
            };
            let camera = Intrinsics::pinhole([640, 480], 50.0);
            assert!(other.pose(&other.points(&frame, &seen), &seen, &camera).is_none());
        }
    }
}
