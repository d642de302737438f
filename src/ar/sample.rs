//! Sample data for the overlay: synthetic frame sequences written as image files with their
//! calibration and their ground truth, and markers written for printing.

use super::calibration;
use canopy_vision::synth::{SequenceSettings, camera_pose, render_frame};
use image::codecs::jpeg::JpegEncoder;
use image::{ExtendedColorType, ImageEncoder, RgbImage};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// How frames are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFormat {
    /// Lossless PNG.
    Png,
    /// JPEG at this quality (1 to 100).
    Jpeg(u8),
}

/// Writes `settings`' frames into `folder` (`frame-0001.png`, ...), `calibration.yaml` and
/// `truth.json` (each frame's pose, corners and what it shows), rendering on `threads`
/// threads; returns the files written.
pub fn write_sequence(
    settings: &SequenceSettings,
    folder: &Path,
    format: FrameFormat,
    threads: usize,
) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(folder).map_err(|error| format!("{}: {error}", folder.display()))?;
    let extension = match format {
        FrameFormat::Png => "png",
        FrameFormat::Jpeg(_) => "jpg",
    };
    let names: Vec<PathBuf> = (1..=settings.frames).map(|i| folder.join(format!("frame-{i:04}.{extension}"))).collect();
    let threads = threads.clamp(1, 16);
    let truths: Vec<Result<Value, String>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|worker| {
                let names = &names;
                scope.spawn(move || {
                    (worker..settings.frames as usize)
                        .step_by(threads)
                        .map(|index| {
                            write_frame(settings, index as u32, &names[index], format).map(|truth| (index, truth))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        let mut all: Vec<(usize, Result<Value, String>)> = Vec::new();
        for worker in workers {
            for result in worker.join().unwrap_or_default() {
                match result {
                    Ok((index, truth)) => all.push((index, Ok(truth))),
                    Err(error) => all.push((usize::MAX, Err(error))),
                }
            }
        }
        all.sort_by_key(|(index, _)| *index);
        all.into_iter().map(|(_, truth)| truth).collect()
    });
    let truths = truths.into_iter().collect::<Result<Vec<_>, _>>()?;
    let camera = settings.camera;
    let truth = json!({
        "dictionary": settings.dictionary.name,
        "marker_id": settings.id,
        "marker_side_m": settings.side_m,
        "seed": settings.seed,
        "frames": truths,
    });
    let calibration_path = folder.join("calibration.yaml");
    std::fs::write(&calibration_path, calibration::to_yaml(&camera))
        .map_err(|error| format!("{}: {error}", calibration_path.display()))?;
    let truth_path = folder.join("truth.json");
    let text = serde_json::to_string_pretty(&truth).map_err(|error| error.to_string())?;
    std::fs::write(&truth_path, text + "\n").map_err(|error| format!("{}: {error}", truth_path.display()))?;
    let mut written = names;
    written.extend([calibration_path, truth_path]);
    Ok(written)
}

/// Renders and writes one frame; returns its ground truth.
fn write_frame(settings: &SequenceSettings, index: u32, path: &Path, format: FrameFormat) -> Result<Value, String> {
    let frame = render_frame(settings, index);
    let [width, height] = settings.camera.size;
    let error = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    match format {
        FrameFormat::Png => {
            let image = RgbImage::from_raw(width, height, frame.rgb).ok_or_else(|| error(&"wrong pixel count"))?;
            image.save(path).map_err(|e| error(&e))?;
        }
        FrameFormat::Jpeg(quality) => {
            let file = std::fs::File::create(path).map_err(|e| error(&e))?;
            JpegEncoder::new_with_quality(std::io::BufWriter::new(file), quality)
                .write_image(&frame.rgb, width, height, ExtendedColorType::Rgb8)
                .map_err(|e| error(&e))?;
        }
    }
    let (_, looking_away) = camera_pose(settings, index);
    Ok(json!({
        "file": path.file_name().map(|n| n.to_string_lossy().into_owned()),
        "view": frame.view.key(),
        "looking_away": looking_away,
        "rvec": frame.pose.rvec().to_array(),
        "tvec": frame.pose.translation.to_array(),
        "corners": frame.corners.map(|c| c.to_array()),
        "blur_px": frame.blur_px,
    }))
}
