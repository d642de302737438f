//! `canopy ar calibrate`: a camera calibrated from photographs of a printed board (grid or
//! ChArUco), without OpenCV, written as the calibration file Canopy and OpenCV both read.

use super::board_layout::BoardLayout;
use super::refuse_to_replace;
use crate::ar::calibration::to_yaml;
use crate::ar::frames::load_image;
use canopy_vision::calibrate::{View, calibrate};
use canopy_vision::{Gray, Scratch, Settings, detect};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

/// `canopy ar calibrate`.
#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Photographs of the board from different sides (PNG or JPEG, all one size), at least
    /// three.
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// The board photographed.
    #[command(flatten)]
    layout: BoardLayout,
    /// The calibration file to write (OpenCV's YAML layout).
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
}

/// The fewest corners a photograph must show of the board to count as a view.
const MIN_CORNERS: usize = 8;

impl CalibrateArgs {
    /// Finds the board in each photograph, calibrates, prints the reprojection error of each
    /// view and overall, and writes the file: exit 0, 1 if it could not be written or the
    /// photographs do not determine the camera, 2 for bad settings or unreadable images.
    pub fn run(&self) -> ExitCode {
        let usage = |error: String| {
            eprintln!("canopy ar calibrate: {error}");
            ExitCode::from(2)
        };
        let (board, dictionary) = match self.layout.board() {
            Ok(found) => found,
            Err(error) => return usage(error),
        };
        let mut scratch = Scratch::default();
        let (mut views, mut used, mut size) = (Vec::new(), Vec::new(), None);
        for path in &self.images {
            let image = match load_image(path, size) {
                Ok(image) => image,
                Err(error) => return usage(error),
            };
            size = Some([image.width(), image.height()]);
            let gray = Gray::from_rgba(image.width(), image.height(), image.as_raw());
            let markers = detect(&gray, &dictionary, &Settings::default(), None, &mut scratch);
            let (object, pixels): (Vec<_>, Vec<_>) =
                board.points(&gray, &markers).into_iter().map(|(object, pixel)| (object.truncate(), pixel)).unzip();
            if object.len() < MIN_CORNERS {
                println!("{}: {} corners of the board, left out", path.display(), object.len());
                continue;
            }
            views.push(View { object, pixels });
            used.push(path);
        }
        let Some(size) = size else { return usage("no photographs".into()) };
        let found = match calibrate(&views, size) {
            Ok(found) => found,
            Err(error) => {
                eprintln!("canopy ar calibrate: {error}");
                return ExitCode::from(1);
            }
        };
        for ((path, view), error) in used.iter().zip(&views).zip(&found.view_errors_px) {
            println!("{}: {} corners, {error:.3} px", path.display(), view.object.len());
        }
        let camera = &found.camera;
        println!(
            "{} views, {:.3} px overall: fx {:.2}, fy {:.2}, cx {:.2}, cy {:.2}, distortion {:?}",
            views.len(),
            found.error_px,
            camera.fx,
            camera.fy,
            camera.cx,
            camera.cy,
            &camera.distortion.0[..5]
        );
        if let Some(refused) = refuse_to_replace(&self.out, self.force) {
            return refused;
        }
        match std::fs::write(&self.out, to_yaml(camera)) {
            Ok(()) => ExitCode::SUCCESS,
            Err(error) => {
                eprintln!("{}: {error}", self.out.display());
                ExitCode::from(1)
            }
        }
    }
}
