//! The command-line options that describe a printed board, grid or ChArUco, shared by the
//! commands that print one and that photograph one.

use canopy_vision::Dictionary;
use canopy_vision::board::{Board, CharucoBoard, GridBoard};
use clap::{Args, ValueEnum};

/// The kinds of board.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoardKind {
    /// An ArUco grid board: markers with gaps between them (OpenCV's `GridBoard`).
    Grid,
    /// A ChArUco board: a chessboard with markers in its white squares (OpenCV's
    /// `CharucoBoard`).
    Charuco,
}

/// A board's layout on the command line.
#[derive(Args, Debug)]
pub struct BoardLayout {
    /// The kind of board.
    #[arg(long, value_enum, default_value = "grid")]
    pub board: BoardKind,
    /// A grid board's markers across and down, e.g. 4x3.
    #[arg(long, value_name = "XxY", value_parser = super::parse_markers)]
    pub markers: Option<[u32; 2]>,
    /// A grid board's gap between neighbouring markers as printed, metres.
    #[arg(long)]
    pub separation_m: Option<f64>,
    /// A ChArUco board's squares across and down, e.g. 5x7.
    #[arg(long, value_name = "XxY", value_parser = super::parse_markers)]
    pub squares: Option<[u32; 2]>,
    /// A ChArUco board's square side as printed, metres.
    #[arg(long)]
    pub square_m: Option<f64>,
    /// Each marker's side as printed, metres.
    #[arg(long)]
    pub marker_m: f64,
    /// A ChArUco board of an even number of rows made by OpenCV before 4.6 (its top-left
    /// square is white).
    #[arg(long)]
    pub legacy: bool,
    /// The first marker's id; the others count up along the rows.
    #[arg(long, default_value_t = 0)]
    pub first_id: u32,
    /// The dictionary, by OpenCV's name or a dictionary file as OpenCV writes it.
    #[arg(long, default_value = "6x6_250")]
    pub dictionary: String,
}

impl BoardLayout {
    /// The board and its dictionary, or what is wrong with them.
    pub fn board(&self) -> Result<(Board, Dictionary), String> {
        let dictionary = super::dictionary_of(&self.dictionary)?;
        let board = match (self.board, self.markers, self.separation_m, self.squares, self.square_m) {
            (BoardKind::Grid, Some(markers), Some(separation_m), None, None) => {
                Board::Grid(GridBoard::new(markers, self.marker_m, separation_m, self.first_id, &dictionary)?)
            }
            (BoardKind::Grid, ..) => return Err("a grid board takes --markers and --separation-m".into()),
            (BoardKind::Charuco, None, None, Some(squares), Some(square_m)) => Board::Charuco(CharucoBoard::new(
                squares,
                square_m,
                self.marker_m,
                self.first_id,
                self.legacy,
                &dictionary,
            )?),
            (BoardKind::Charuco, ..) => return Err("a ChArUco board takes --squares and --square-m".into()),
        };
        Ok((board, dictionary))
    }
}
