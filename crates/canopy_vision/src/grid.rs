//! ArUco grid boards, laid out as OpenCV's `GridBoard` lays them out.
//!
//! The board frame is OpenCV's (4.7 and later): origin at the top-left corner of the top-left
//! marker, x right, y down the printed board, z into it; markers in rows from the top-left,
//! their ids counting up from the first.

use crate::dictionary::Dictionary;
use crate::gray::Gray;
use bevy_math::{DVec2, DVec3};

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
        ids_fit(first_id, markers[0] * markers[1], dictionary)?;
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
        let cells = marker_cells(dictionary, self.first_id, self.markers[0] * self.markers[1]);
        let pitch = self.marker_m + self.separation_m;
        print_board(self.size_m(), pixels_per_metre, margin_m, |p| {
            let (column, row) = ((p.x / pitch).floor(), (p.y / pitch).floor());
            if column < 0.0 || row < 0.0 || column >= f64::from(self.markers[0]) || row >= f64::from(self.markers[1]) {
                return None;
            }
            let within = (p - DVec2::new(column, row) * pitch) / self.marker_m;
            if within.x >= 1.0 || within.y >= 1.0 {
                return None; // in the gap between markers
            }
            let marker = &cells[(row as u32 * self.markers[0] + column as u32) as usize];
            Some(marker_white(marker, dictionary.cells, within))
        })
    }
}

/// A board of `size_m` printed at `pixels_per_metre` with a white margin of `margin_m` round
/// it: each pixel black or white as `shade` says of the board point at its centre (metres
/// from the board's top-left corner; `None` leaves it white); `None` if the image would be
/// empty or larger than 16,384 pixels a side.
pub(crate) fn print_board(
    size_m: DVec2,
    pixels_per_metre: f64,
    margin_m: f64,
    shade: impl Fn(DVec2) -> Option<bool>,
) -> Option<Gray> {
    let extent = (size_m + DVec2::splat(2.0 * margin_m)) * pixels_per_metre;
    if !(extent.x >= 1.0 && extent.y >= 1.0 && extent.max_element() <= 16_384.0) {
        return None;
    }
    let (width, height) = (extent.x.round() as u32, extent.y.round() as u32);
    let mut image = Gray::filled(width, height, 255);
    for y in 0..height {
        for x in 0..width {
            let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5) / pixels_per_metre - DVec2::splat(margin_m);
            if let Some(white) = shade(p) {
                image.pixels[(y * width + x) as usize] = if white { 255 } else { 0 };
            }
        }
    }
    Some(image)
}

/// The inner cells of `count` markers from id `first_id` (empty for an id the dictionary
/// does not have).
pub(crate) fn marker_cells(dictionary: &Dictionary, first_id: u32, count: u32) -> Vec<Vec<bool>> {
    (0..count).map(|i| dictionary.cells_of(first_id + i).unwrap_or_default()).collect()
}

/// Whether `count` markers from id `first_id` are all in `dictionary`, or what is wrong.
pub(crate) fn ids_fit(first_id: u32, count: u32, dictionary: &Dictionary) -> Result<(), String> {
    let last = u64::from(first_id) + u64::from(count) - 1;
    if last >= u64::from(dictionary.len()) {
        return Err(format!(
            "{count} markers from id {first_id} need ids up to {last}, but {dictionary} has {}",
            dictionary.len()
        ));
    }
    Ok(())
}

/// Whether a marker of `cells` (its inner cells row by row, `bits` a side) is white at
/// `within` (0 to 1 across its black border, from its top-left corner).
pub(crate) fn marker_white(cells: &[bool], bits: u32, within: DVec2) -> bool {
    let n = f64::from(bits + 2);
    let (column, row) = ((within.x * n) as u32, (within.y * n) as u32);
    let inner = |k: u32| (1..=bits).contains(&k);
    inner(column) && inner(row) && cells.get(((row - 1) * bits + column - 1) as usize).copied().unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
