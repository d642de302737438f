//! The command-line options that describe a printed grid board, shared by the commands that
//! print one and that photograph one.

use canopy_vision::Dictionary;
use canopy_vision::board::GridBoard;
use clap::Args;

/// A grid board's layout on the command line.
#[derive(Args, Debug)]
pub struct BoardLayout {
    /// Markers across and down, e.g. 5x7.
    #[arg(long, value_name = "XxY", value_parser = super::parse_markers)]
    pub markers: [u32; 2],
    /// Each marker's side as printed, metres.
    #[arg(long)]
    pub marker_m: f64,
    /// The gap between neighbouring markers as printed, metres.
    #[arg(long)]
    pub separation_m: f64,
    /// The top-left marker's id; the others count up along the rows.
    #[arg(long, default_value_t = 0)]
    pub first_id: u32,
    /// The dictionary, by OpenCV's name.
    #[arg(long, default_value = "6x6_250")]
    pub dictionary: String,
}

impl BoardLayout {
    /// The board and its dictionary, or what is wrong with them.
    pub fn board(&self) -> Result<(GridBoard, Dictionary), String> {
        let dictionary = Dictionary::named(&self.dictionary).map_err(|error| error.to_string())?;
        let board = GridBoard::new(self.markers, self.marker_m, self.separation_m, self.first_id, &dictionary)?;
        Ok((board, dictionary))
    }
}
