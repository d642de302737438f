//! `canopy ar sweep`: the marker detector on harder and harder synthetic frames, one condition
//! at a time (`canopy_vision::sweep`): a table of detection rates and pose errors, its JSON,
//! a plot, and optionally the frames themselves with their truth, for running another detector
//! on the same frames.

use super::refuse_to_replace;
use crate::ui::plot::save_egui_png;
use bevy::math::UVec2;
use bevy_egui::egui;
use canopy_vision::sweep::{Condition, Step, frame, sweep};
use clap::Args;
use egui_plot::{Line, Plot, PlotPoints};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `canopy ar sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    /// The folder to write `sweep.json` and `sweep.png` into (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// Frames at each step of each condition, 1 to 1000.
    #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u32).range(1..=1000))]
    frames: u32,
    /// Also write every frame as a PNG, with the marker's true corners in `frames.json`.
    #[arg(long)]
    write_frames: bool,
    /// Replace files in `--out`.
    #[arg(long)]
    force: bool,
}

impl SweepArgs {
    /// Sweeps every condition, prints the table and writes the files: exit 0, 1 if a file
    /// could not be written.
    pub fn run(&self) -> ExitCode {
        let failed = |error: String| {
            eprintln!("canopy ar sweep: {error}");
            ExitCode::from(1)
        };
        if let Err(error) = std::fs::create_dir_all(&self.out) {
            return failed(format!("{}: {error}", self.out.display()));
        }
        let (json_path, plot_path) = (self.out.join("sweep.json"), self.out.join("sweep.png"));
        for path in [&json_path, &plot_path] {
            if let Some(refused) = refuse_to_replace(path, self.force) {
                return refused;
            }
        }
        let steps: Vec<Step> = Condition::ALL.iter().flat_map(|&condition| sweep(condition, self.frames)).collect();
        println!("{}", table(&steps));
        let text = serde_json::to_string_pretty(&steps_json(&steps)).unwrap_or_default();
        if let Err(error) = std::fs::write(&json_path, text) {
            return failed(format!("{}: {error}", json_path.display()));
        }
        if let Err(error) = save_plot(&steps, &plot_path) {
            return failed(format!("{}: {error}", plot_path.display()));
        }
        if self.write_frames
            && let Err(error) = write_frames(&self.out.join("frames"), self.frames)
        {
            return failed(error);
        }
        ExitCode::SUCCESS
    }
}

/// The steps as a Markdown table.
pub fn table(steps: &[Step]) -> String {
    let mut out = String::from(
        "| condition | value | found | false detections | position error (median) | angle error (median) | ms a frame |\n|---|---|---|---|---|---|---|\n",
    );
    for step in steps {
        let error = |value: f64, text: String| if value.is_nan() { "-".to_string() } else { text };
        out += &format!(
            "| {} | {} | {}/{} | {} | {} | {} | {:.2} |\n",
            step.condition.name(),
            step.value,
            step.found,
            step.frames,
            step.false_detections,
            error(step.position_rel, format!("{:.3} %", step.position_rel * 100.0)),
            error(step.angle_deg, format!("{:.2} deg", step.angle_deg)),
            step.detect_ms
        );
    }
    out
}

fn steps_json(steps: &[Step]) -> Value {
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    Value::Array(
        steps
            .iter()
            .map(|s| {
                json!({
                    "condition": s.condition.name(), "value": s.value, "frames": s.frames, "found": s.found,
                    "false_detections": s.false_detections, "position_rel_median": finite(s.position_rel),
                    "angle_deg_median": finite(s.angle_deg), "detect_ms": s.detect_ms,
                })
            })
            .collect(),
    )
}

/// Every condition's detection rate and median angle error against its value: a row of two
/// plots each.
fn save_plot(steps: &[Step], path: &Path) -> image::ImageResult<()> {
    save_egui_png(UVec2::new(1200, 1210), path, |ui| {
        ui.heading("The marker detector on harder frames");
        ui.label(
            "a 10 cm 6x6_250 marker, 640 x 480 at 60 degrees; one condition worsened at a time from the \
             baseline (60 cm, 30 degrees, noise of 2 grey levels); left: frames in which it was found, per cent; \
             right: the median angle error of its pose, degrees",
        );
        egui::Grid::new("sweep").num_columns(2).show(ui, |ui| {
            for condition in Condition::ALL {
                let points: Vec<&Step> = steps.iter().filter(|s| s.condition == condition).collect();
                let found: Vec<[f64; 2]> =
                    points.iter().map(|s| [s.value, 100.0 * f64::from(s.found) / f64::from(s.frames)]).collect();
                let angle: Vec<[f64; 2]> =
                    points.iter().filter(|s| s.angle_deg.is_finite()).map(|s| [s.value, s.angle_deg]).collect();
                for (series, unit, color) in [
                    (found, "found, %", egui::Color32::from_rgb(90, 160, 255)),
                    (angle, "angle error, degrees", egui::Color32::from_rgb(240, 120, 70)),
                ] {
                    ui.vertical(|ui| {
                        ui.label(format!("{}: {unit}", condition.name()));
                        Plot::new((condition.name(), unit))
                            .width(570.0)
                            .height(140.0)
                            .include_y(0.0)
                            .show_background(false)
                            .allow_drag(false)
                            .allow_zoom(false)
                            .allow_scroll(false)
                            .show(ui, |plot| {
                                plot.line(Line::new(unit, PlotPoints::from(series)).color(color).width(2.0));
                            });
                    });
                }
                ui.end_row();
            }
        });
    })
}

/// Every frame of every step as `frames/<condition>/<value>-<k>.png`, with `frames.json`
/// listing each file and its marker's true corners.
fn write_frames(folder: &Path, frames: u32) -> Result<(), String> {
    let mut listed = Vec::new();
    for condition in Condition::ALL {
        let dir = folder.join(condition.name());
        std::fs::create_dir_all(&dir).map_err(|error| format!("{}: {error}", dir.display()))?;
        for &value in condition.steps() {
            for index in 0..frames {
                let made = frame(condition, value, index);
                let name = format!("{}/{value}-{index}.png", condition.name());
                let image = image::GrayImage::from_raw(made.image.width, made.image.height, made.image.pixels)
                    .ok_or_else(|| format!("{name}: the frame's pixels do not fill it"))?;
                image.save(folder.join(&name)).map_err(|error| format!("{name}: {error}"))?;
                let corners: Vec<[f64; 2]> = made.corners.iter().map(|c| [c.x, c.y]).collect();
                listed.push(json!({"file": name, "condition": condition.name(), "value": value, "corners": corners}));
            }
        }
    }
    let path = folder.join("frames.json");
    std::fs::write(&path, serde_json::to_string(&listed).unwrap_or_default())
        .map_err(|error| format!("{}: {error}", path.display()))
}
