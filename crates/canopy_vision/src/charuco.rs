//! ChArUco boards, laid out as OpenCV's `CharucoBoard` lays them out (4.7 and later): a
//! chessboard whose white squares hold markers. The markers say which part of the board is
//! seen; the chessboard's corners, where two black squares touch, are what a pose or a
//! calibration is fitted to: a saddle of intensity is placed far more precisely than a marker's
//! corner, which is a dark square's corner on white.
//!
//! The board frame: origin at the top-left corner of the board, x right, y down the printed
//! board, z into it. The top-left square is black (OpenCV's `legacyPattern` of boards made
//! before 4.6 turns boards of an even number of rows: their bottom-left square is black). The
//! markers fill the white squares row by row, their ids counting up from the first; the inner
//! chessboard corners are numbered row by row too.

use crate::calibrate::homography;
use crate::detect::Marker;
use crate::dictionary::Dictionary;
use crate::gray::Gray;
use crate::grid::{ids_fit, marker_cells, marker_white, print_board};
use crate::saddle;
use bevy_math::{DMat3, DVec2, DVec3};

/// The most squares along either side of a board.
pub const MAX_SQUARES_A_SIDE: u32 = 64;

/// A chessboard with markers in its white squares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CharucoBoard {
    /// Squares across and down.
    pub squares: [u32; 2],
    /// Each square's side, metres.
    pub square_m: f64,
    /// Each marker's side, metres (less than a square's).
    pub marker_m: f64,
    /// The first marker's id; the others count up along the rows.
    pub first_id: u32,
    /// OpenCV's layout before 4.6 (it differs for an even number of rows).
    pub legacy: bool,
}

impl CharucoBoard {
    /// A board of `squares` across and down, or what is wrong with it for `dictionary`.
    pub fn new(
        squares: [u32; 2],
        square_m: f64,
        marker_m: f64,
        first_id: u32,
        legacy: bool,
        dictionary: &Dictionary,
    ) -> Result<Self, String> {
        if squares.iter().any(|&n| !(2..=MAX_SQUARES_A_SIDE).contains(&n)) {
            return Err(format!(
                "expected 2 to {MAX_SQUARES_A_SIDE} squares a side, found {}x{}",
                squares[0], squares[1]
            ));
        }
        if !(square_m.is_finite() && square_m > 0.0 && square_m <= 10.0) {
            return Err(format!("expected a square side greater than 0 and at most 10 m, found {square_m}"));
        }
        if !(marker_m.is_finite() && marker_m > 0.0 && marker_m < square_m) {
            return Err(format!(
                "expected a marker side greater than 0 and less than the square's {square_m} m, found {marker_m}"
            ));
        }
        let board = Self { squares, square_m, marker_m, first_id, legacy };
        ids_fit(first_id, board.marker_count(), dictionary)?;
        Ok(board)
    }

    /// Whether square `[x, y]` (from the top-left) is white and holds a marker.
    pub fn holds_marker(&self, [x, y]: [u32; 2]) -> bool {
        if self.legacy && self.squares[1].is_multiple_of(2) { y % 2 == x % 2 } else { y % 2 != x % 2 }
    }

    /// The markers on the board.
    pub fn marker_count(&self) -> u32 {
        (0..self.squares[1]).map(|y| self.row_markers(y)).sum()
    }

    /// The markers in row `y`: every other square, from the first or the second.
    fn row_markers(&self, y: u32) -> u32 {
        let across = self.squares[0];
        if self.holds_marker([0, y]) { across.div_ceil(2) } else { across / 2 }
    }

    /// The board's width and height, metres.
    pub fn size_m(&self) -> DVec2 {
        DVec2::new(f64::from(self.squares[0]), f64::from(self.squares[1])) * self.square_m
    }

    /// Each square's marker's index on the board (row by row), `None` for black squares.
    fn marker_indices(&self) -> Vec<Option<u32>> {
        let mut next = 0;
        (0..self.squares[1])
            .flat_map(|y| (0..self.squares[0]).map(move |x| [x, y]))
            .map(|square| {
                self.holds_marker(square).then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect()
    }

    /// The square marker `id` is in; `None` for an id not on the board.
    fn square_of(&self, id: u32) -> Option<[u32; 2]> {
        let mut index = id.checked_sub(self.first_id)?;
        for y in 0..self.squares[1] {
            let in_row = self.row_markers(y);
            if index < in_row {
                let first = u32::from(!self.holds_marker([0, y]));
                return Some([first + 2 * index, y]);
            }
            index -= in_row;
        }
        None
    }

    /// The corners of marker `id` in the board frame, in OpenCV's order; `None` for an id not
    /// on the board.
    pub fn corners(&self, id: u32) -> Option<[DVec3; 4]> {
        self.square_of(id).map(|square| self.marker_corners(square))
    }

    /// The corners of the marker in `square`, in the board frame, in OpenCV's order.
    fn marker_corners(&self, [x, y]: [u32; 2]) -> [DVec3; 4] {
        let inset = (self.square_m - self.marker_m) * 0.5;
        let top_left = DVec3::new(f64::from(x) * self.square_m + inset, f64::from(y) * self.square_m + inset, 0.0);
        let l = self.marker_m;
        [top_left, top_left + DVec3::X * l, top_left + DVec3::new(l, l, 0.0), top_left + DVec3::Y * l]
    }

    /// The inner chessboard corners: `(squares across - 1) x (squares down - 1)`.
    pub fn corner_count(&self) -> u32 {
        (self.squares[0] - 1) * (self.squares[1] - 1)
    }

    /// Chessboard corner `index` in the board frame.
    pub fn chessboard_corner(&self, index: u32) -> DVec3 {
        let across = self.squares[0] - 1;
        DVec3::new(f64::from(index % across + 1), f64::from(index / across + 1), 0.0) * self.square_m
    }

    /// The printable board: `pixels_per_metre` of the printed size, a white margin of
    /// `margin_m` round it; `None` if the image would be empty or larger than 16,384 pixels a
    /// side.
    pub fn image(&self, dictionary: &Dictionary, pixels_per_metre: f64, margin_m: f64) -> Option<Gray> {
        let indices = self.marker_indices();
        let cells = marker_cells(dictionary, self.first_id, self.marker_count());
        let inset = (self.square_m - self.marker_m) * 0.5;
        print_board(self.size_m(), pixels_per_metre, margin_m, |p| {
            let square = (p / self.square_m).floor();
            if square.x < 0.0
                || square.y < 0.0
                || square.x >= f64::from(self.squares[0])
                || square.y >= f64::from(self.squares[1])
            {
                return None;
            }
            let (sx, sy) = (square.x as u32, square.y as u32);
            Some(match indices[(sy * self.squares[0] + sx) as usize] {
                None => false,
                Some(marker) => {
                    let within = (p - square * self.square_m - DVec2::splat(inset)) / self.marker_m;
                    let in_marker = within.min_element() >= 0.0 && within.max_element() < 1.0;
                    !in_marker || marker_white(&cells[marker as usize], dictionary.cells, within)
                }
            })
        })
    }

    /// The chessboard corners between the board's `markers` found in `image`, each placed to
    /// a fraction of a pixel: its place foretold by the homography of each marker beside it
    /// that was found, then refined as a saddle of intensity within a window that keeps out
    /// the markers' own edges. Where two markers foretell places further apart than that
    /// window, the corner is left out: one of them is not where it seems. Returns each
    /// corner's index and place, in index order.
    pub fn find_corners(&self, image: &Gray, markers: &[Marker]) -> Vec<(u32, DVec2)> {
        let indices = self.marker_indices();
        let seen_once = |id: u32| markers.iter().filter(|m| m.id == id).count() == 1;
        // Each square's marker found, with the homography from the board's plane to the image.
        let across = self.squares[0];
        let found: Vec<Option<(&Marker, DMat3)>> = indices
            .iter()
            .enumerate()
            .map(|(square, index)| {
                let id = self.first_id + (*index)?;
                let marker = markers.iter().find(|m| m.id == id && seen_once(id))?;
                let square = [square as u32 % across, square as u32 / across];
                let object: Vec<DVec2> = self.marker_corners(square).iter().map(|c| c.truncate()).collect();
                Some((marker, homography(&object, &marker.corners_f64())?))
            })
            .collect();
        let mut corners = Vec::new();
        for index in 0..self.corner_count() {
            let (x, y) = (index % (across - 1), index / (across - 1));
            let point = self.chessboard_corner(index).truncate();
            // The squares meeting at the corner: the two white ones hold markers.
            let beside: Vec<&(&Marker, DMat3)> = [[x, y], [x + 1, y], [x, y + 1], [x + 1, y + 1]]
                .iter()
                .filter_map(|[sx, sy]| found[(sy * across + sx) as usize].as_ref())
                .collect();
            if beside.is_empty() {
                continue;
            }
            let foretold: Vec<DVec2> = beside.iter().map(|(_, h)| project(h, point)).collect();
            let guess = foretold.iter().copied().sum::<DVec2>() / foretold.len() as f64;
            // The window reaches towards the nearest marker corner no further than most of the
            // way to its edges.
            let nearest = beside
                .iter()
                .flat_map(|(marker, _)| marker.corners_f64())
                .map(|corner| corner.distance(guess))
                .fold(f64::INFINITY, f64::min);
            let half = (0.7 * nearest / std::f64::consts::SQRT_2).floor().clamp(2.0, 12.0);
            let spread = foretold.iter().map(|p| p.distance(guess)).fold(0.0, f64::max);
            if spread > half {
                continue;
            }
            if let Some(refined) = saddle::refine(image, guess, half as u32) {
                corners.push((index, refined));
            }
        }
        corners
    }
}

/// `point` of the board's plane through homography `h`.
fn project(h: &DMat3, point: DVec2) -> DVec2 {
    let p = *h * point.extend(1.0);
    p.truncate() / p.z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Distortion, Intrinsics};
    use crate::detect::{Scratch, Settings, detect};
    use crate::pose::Pose;
    use crate::synth::photograph_print;

    fn board(legacy: bool) -> (CharucoBoard, Dictionary) {
        let dictionary = Dictionary::named("6x6_250").unwrap();
        (CharucoBoard::new([5, 7], 0.04, 0.02, 0, legacy, &dictionary).unwrap(), dictionary)
    }

    #[test]
    fn layout_follows_opencv_and_bad_boards_are_refused() {
        let (board, dictionary) = board(false);
        assert_eq!((board.marker_count(), board.corner_count()), (17, 24));
        // The top-left square is black; marker 0 is in the second square of the first row.
        assert!(!board.holds_marker([0, 0]) && board.holds_marker([1, 0]));
        let corners = board.corners(0).unwrap();
        assert!((corners[0] - DVec3::new(0.05, 0.01, 0.0)).length() < 1e-12, "{corners:?}");
        assert!((corners[2] - DVec3::new(0.07, 0.03, 0.0)).length() < 1e-12);
        // Marker 2 starts the second row, in its first square.
        assert!((board.corners(2).unwrap()[0] - DVec3::new(0.01, 0.05, 0.0)).length() < 1e-12);
        assert_eq!(board.corners(17), None);
        assert!((board.chessboard_corner(5) - DVec3::new(0.08, 0.08, 0.0)).length() < 1e-12);
        // The legacy layout of a board of an even number of rows starts with a white square.
        let legacy = CharucoBoard { squares: [5, 6], legacy: true, ..board };
        assert!(legacy.holds_marker([0, 0]) && !legacy.holds_marker([1, 0]));
        assert!(CharucoBoard { squares: [5, 7], ..legacy }.holds_marker([1, 0]), "odd rows: no change");
        // Every id's square, counted along the rows, for either layout and width.
        for (squares, legacy) in [([5, 7], false), ([6, 4], false), ([5, 6], true), ([4, 6], true)] {
            let board = CharucoBoard { squares, legacy, ..board };
            let holding = (0..squares[1]).flat_map(|y| (0..squares[0]).map(move |x| [x, y]));
            let holding: Vec<[u32; 2]> = holding.filter(|&square| board.holds_marker(square)).collect();
            assert_eq!(holding.len() as u32, board.marker_count(), "{squares:?}");
            for (id, &square) in holding.iter().enumerate() {
                assert_eq!(board.square_of(id as u32), Some(square), "{squares:?}, legacy {legacy}");
            }
            assert_eq!(board.square_of(holding.len() as u32), None);
        }
        assert!(CharucoBoard::new([1, 7], 0.04, 0.02, 0, false, &dictionary).unwrap_err().contains("2 to 64"));
        assert!(CharucoBoard::new([5, 7], 0.04, 0.04, 0, false, &dictionary).unwrap_err().contains("less than"));
        assert!(CharucoBoard::new([30, 30], 0.04, 0.02, 0, false, &dictionary).unwrap_err().contains("has 250"));
    }

    #[test]
    fn the_printed_board_has_black_squares_and_markers_in_the_white_ones() {
        let (board, dictionary) = board(false);
        let image = board.image(&dictionary, 1000.0, 0.0).unwrap();
        assert_eq!((image.width, image.height), (200, 280));
        // The middle of the top-left square is black; the top-left corner of the next square,
        // outside its marker, white; its marker's border black.
        assert_eq!((image.at(20, 20), image.at(42, 2), image.at(51, 11)), (0, 255, 0));
    }

    #[test]
    fn corners_found_through_a_lens_lie_within_a_tenth_of_a_pixel_of_the_truth() {
        let (board, dictionary) = board(false);
        let (pixels_per_metre, margin_m) = (5000.0, 0.01);
        let print = board.image(&dictionary, pixels_per_metre, margin_m).unwrap();
        let camera = Intrinsics {
            distortion: Distortion([-0.2, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            ..Intrinsics::pinhole([640, 480], 55.0)
        };
        let rotation = DMat3::from_rotation_y(0.4) * DMat3::from_rotation_x(-0.5);
        let translation = DVec3::new(0.0, 0.0, 0.42) - rotation * (board.size_m() * 0.5).extend(0.0);
        let truth = Pose { rotation, translation };
        let frame = photograph_print(&print, pixels_per_metre, margin_m, &truth, &camera);
        let markers = detect(&frame, &dictionary, &Settings::default(), None, &mut Scratch::default());
        let corners = board.find_corners(&frame, &markers);
        assert_eq!(corners.len(), 24, "every corner of the board");
        let mut worst: f64 = 0.0;
        for (index, found) in corners {
            let expected = camera.project(truth.apply(board.chessboard_corner(index))).unwrap();
            worst = worst.max(found.distance(expected));
        }
        assert!(worst < 0.1, "the worst corner is {worst} px off");
        // Markers of another board: no corners.
        let other = CharucoBoard { first_id: 100, ..board };
        assert!(other.find_corners(&frame, &markers).is_empty());
    }
}
