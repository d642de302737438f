//! Marker dictionaries: OpenCV's predefined ArUco and AprilTag sets by name, each marker's
//! cells, and the match of a read grid of cells against a dictionary in its four rotations
//! with error correction.

use super::dictionaries as tables;
use std::borrow::Cow;
use std::fmt;

/// The most markers a dictionary read from a file may hold.
pub const MAX_CUSTOM_MARKERS: usize = 100_000;

/// A set of markers of `n x n` inner cells: OpenCV's predefined dictionary of the same name,
/// or one of the user's (OpenCV's `extendDictionary`, say).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Dictionary {
    /// The name as OpenCV writes it without `DICT_`, lower case: `4x4_50`, `aruco_original`;
    /// for a dictionary of the user's, the name it was given.
    pub name: Cow<'static, str>,
    /// Inner cells a side.
    pub cells: u32,
    /// Each marker's cells, unrotated, row by row from the top-left (the first cell in the
    /// highest of the `cells * cells` low bits, 1 = white).
    codes: Cow<'static, [u64]>,
    /// The most wrong cells that can be corrected without confusing two markers (OpenCV's
    /// `maxCorrectionBits`).
    pub max_correction_bits: u32,
}

/// A name that is not one of [`Dictionary::ALL`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown dictionary `{0}`: expected one of {names}", names = Dictionary::names().join(", "))]
pub struct UnknownDictionary(pub String);

/// How a grid of cells matched a dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Match {
    /// The marker's index in its dictionary.
    pub id: u32,
    /// Quarter turns clockwise that take the marker as printed to the grid as read.
    pub rotation: u32,
    /// Cells that differed from the marker (corrected).
    pub wrong_cells: u32,
}

macro_rules! dictionary {
    ($name:literal, $cells:literal, $table:ident, $count:literal, $correction:literal) => {
        Dictionary {
            name: Cow::Borrowed($name),
            cells: $cells,
            codes: Cow::Borrowed(tables::$table.split_at($count).0),
            max_correction_bits: $correction,
        }
    };
}

impl Dictionary {
    /// Every dictionary, with OpenCV's correction bounds.
    pub const ALL: [Dictionary; 22] = [
        dictionary!("4x4_50", 4, ARUCO_4X4, 50, 1),
        dictionary!("4x4_100", 4, ARUCO_4X4, 100, 1),
        dictionary!("4x4_250", 4, ARUCO_4X4, 250, 1),
        dictionary!("4x4_1000", 4, ARUCO_4X4, 1000, 0),
        dictionary!("5x5_50", 5, ARUCO_5X5, 50, 3),
        dictionary!("5x5_100", 5, ARUCO_5X5, 100, 3),
        dictionary!("5x5_250", 5, ARUCO_5X5, 250, 2),
        dictionary!("5x5_1000", 5, ARUCO_5X5, 1000, 2),
        dictionary!("6x6_50", 6, ARUCO_6X6, 50, 6),
        dictionary!("6x6_100", 6, ARUCO_6X6, 100, 5),
        dictionary!("6x6_250", 6, ARUCO_6X6, 250, 5),
        dictionary!("6x6_1000", 6, ARUCO_6X6, 1000, 4),
        dictionary!("7x7_50", 7, ARUCO_7X7, 50, 9),
        dictionary!("7x7_100", 7, ARUCO_7X7, 100, 8),
        dictionary!("7x7_250", 7, ARUCO_7X7, 250, 8),
        dictionary!("7x7_1000", 7, ARUCO_7X7, 1000, 6),
        dictionary!("aruco_original", 5, ARUCO_ORIGINAL, 1024, 0),
        dictionary!("aruco_mip_36h12", 6, ARUCO_MIP_36H12, 250, 12),
        dictionary!("apriltag_16h5", 4, APRILTAG_16H5, 30, 0),
        dictionary!("apriltag_25h9", 5, APRILTAG_25H9, 35, 0),
        dictionary!("apriltag_36h10", 6, APRILTAG_36H10, 2320, 0),
        dictionary!("apriltag_36h11", 6, APRILTAG_36H11, 587, 0),
    ];

    /// The names [`Dictionary::named`] accepts.
    pub fn names() -> Vec<&'static str> {
        Self::ALL
            .iter()
            .map(|d| match d.name {
                Cow::Borrowed(name) => name,
                Cow::Owned(_) => "",
            })
            .collect()
    }

    /// A dictionary of the user's: `codes` are its markers' cells (row by row from the
    /// top-left, the first cell in the highest of the `cells * cells` low bits, 1 = white), up
    /// to `max_correction_bits` of which are corrected; or what is wrong with it.
    pub fn custom(name: String, cells: u32, codes: Vec<u64>, max_correction_bits: u32) -> Result<Self, String> {
        if !(2..=8).contains(&cells) {
            return Err(format!("expected markers of 2 to 8 cells a side, found {cells}"));
        }
        if codes.is_empty() || codes.len() > MAX_CUSTOM_MARKERS {
            return Err(format!("expected 1 to {MAX_CUSTOM_MARKERS} markers, found {}", codes.len()));
        }
        let count = cells * cells;
        if let Some(id) = codes.iter().position(|&code| count < 64 && code >> count != 0) {
            return Err(format!("marker {id} has more than {count} cells"));
        }
        if max_correction_bits > count / 2 {
            return Err(format!(
                "expected at most {} correction bits for {count} cells, found {max_correction_bits}",
                count / 2
            ));
        }
        Ok(Self { name: Cow::Owned(name), cells, codes: Cow::Owned(codes), max_correction_bits })
    }

    /// The dictionary called `name`, case-insensitively, with or without OpenCV's `DICT_`
    /// prefix (`6x6_250`, `DICT_6X6_250`).
    pub fn named(name: &str) -> Result<Dictionary, UnknownDictionary> {
        let lower = name.trim().to_ascii_lowercase();
        let bare = lower.strip_prefix("dict_").unwrap_or(&lower);
        Self::ALL.iter().find(|d| d.name == bare).cloned().ok_or_else(|| UnknownDictionary(name.to_string()))
    }

    /// Markers in the dictionary.
    pub fn len(&self) -> u32 {
        self.codes.len() as u32
    }

    /// Whether the dictionary has no markers (never true of the predefined ones).
    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Marker `id`'s cells, row by row from the top-left (true = white); `None` past the end.
    pub fn cells_of(&self, id: u32) -> Option<Vec<bool>> {
        let code = *self.codes.get(id as usize)?;
        let count = self.cells * self.cells;
        Some((0..count).map(|i| code >> (count - 1 - i) & 1 == 1).collect())
    }

    /// The marker whose cells, in one of the four rotations, differ from `grid` (row by row,
    /// as [`Dictionary::cells_of`]) in at most `max_wrong` cells, the closest one; ties go to
    /// the lower id.
    pub fn identify(&self, grid: u64, max_wrong: u32) -> Option<Match> {
        let mut best: Option<Match> = None;
        let mut rotated = grid;
        for turns in 0..4 {
            // `rotated` is the grid turned back by `turns` quarter turns: the marker as printed
            // if the grid shows it turned by `turns`.
            for (id, &code) in self.codes.iter().enumerate() {
                let wrong = (code ^ rotated).count_ones();
                if wrong <= max_wrong && best.is_none_or(|b| wrong < b.wrong_cells) {
                    best = Some(Match { id: id as u32, rotation: turns, wrong_cells: wrong });
                }
            }
            rotated = rotate_counterclockwise(rotated, self.cells);
        }
        best
    }
}

impl fmt::Display for Dictionary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name)
    }
}

/// A grid of `n x n` cells (row by row, first cell in the highest bit) turned a quarter turn
/// counter-clockwise.
pub fn rotate_counterclockwise(grid: u64, n: u32) -> u64 {
    let count = n * n;
    let bit = |row: u32, col: u32| grid >> (count - 1 - (row * n + col)) & 1;
    let mut out = 0;
    for row in 0..n {
        for col in 0..n {
            // The cell at (row, col) after the turn was at (col, n - 1 - row) before it.
            out = out << 1 | bit(col, n - 1 - row);
        }
    }
    out
}

/// Packs cells (row by row, true = white) into a grid as [`Dictionary::identify`] reads it.
pub fn pack(cells: &[bool]) -> u64 {
    cells.iter().fold(0, |grid, &white| grid << 1 | u64::from(white))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_found_in_either_spelling_and_unknown_ones_are_listed() {
        assert_eq!(Dictionary::named("DICT_6X6_250").unwrap().len(), 250);
        assert_eq!(Dictionary::named("aruco_original").unwrap().cells, 5);
        let error = Dictionary::named("9x9_10").unwrap_err().to_string();
        assert!(error.contains("9x9_10") && error.contains("4x4_50") && error.contains("aruco_original"), "{error}");
    }

    #[test]
    fn every_marker_is_found_in_each_rotation_with_its_turns() {
        for dictionary in Dictionary::ALL {
            for id in (0..dictionary.len()).step_by(7) {
                let mut grid = pack(&dictionary.cells_of(id).unwrap());
                for turns in 0..4 {
                    let found = dictionary.identify(grid, 0).unwrap();
                    assert_eq!((found.id, found.rotation, found.wrong_cells), (id, turns, 0), "{dictionary} id {id}");
                    // A quarter turn clockwise: three counter-clockwise.
                    grid = (0..3).fold(grid, |g, _| rotate_counterclockwise(g, dictionary.cells));
                }
            }
        }
    }

    #[test]
    fn wrong_cells_are_corrected_up_to_the_bound_and_no_further_for_an_exact_match() {
        let dictionary = Dictionary::named("6x6_250").unwrap();
        let grid = pack(&dictionary.cells_of(17).unwrap());
        let flipped = grid ^ 0b1000_0000_0100_0010_0000_0001;
        let found = dictionary.identify(flipped, dictionary.max_correction_bits).unwrap();
        assert_eq!((found.id, found.wrong_cells), (17, 4));
        assert_eq!(dictionary.identify(flipped, 3), None);
    }

    #[test]
    fn four_quarter_turns_are_the_identity() {
        let grid = 0b1011_0101_0011_0010;
        let turned = rotate_counterclockwise(grid, 4);
        assert_ne!(turned, grid);
        assert_eq!((0..4).fold(grid, |g, _| rotate_counterclockwise(g, 4)), grid);
        // The top row 1011 becomes the left column read upwards.
        // The right column read downwards becomes the top row.
        assert_eq!(turned >> 12, 0b1110);
    }
}
