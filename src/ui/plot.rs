//! Plots as image files, drawn without a window: an egui frame holding an `egui_plot` plot,
//! tessellated and painted on the CPU by the window's own painter, then written as PNG.

use super::compose::{PanelPaint, WindowPainter, save_window_png};
use crate::raster::Framebuffer;
use crate::terrain::experiment::Timing;
use bevy::math::UVec2;
use bevy_egui::egui;
use egui_plot::{GridMark, Legend, Line, Plot, PlotPoints, Points};
use std::ops::RangeInclusive;
use std::path::Path;

/// Draws `ui_fn` into an image of `size` pixels at `path`.
fn save_egui_png(size: UVec2, path: &Path, mut ui_fn: impl FnMut(&mut egui::Ui)) -> image::ImageResult<()> {
    let ctx = egui::Context::default();
    let input = || egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(size.x as f32, size.y as f32))),
        ..Default::default()
    };
    let mut painter = WindowPainter::default();
    // The first pass lays out and measures; the second draws with the sizes it found.
    let first = ctx.run_ui(input(), |ui| {
        egui::CentralPanel::default().show_inside(ui, &mut ui_fn);
    });
    painter.take_textures(first.textures_delta);
    let output = ctx.run_ui(input(), |ui| {
        egui::CentralPanel::default().show_inside(ui, &mut ui_fn);
    });
    painter.take_textures(output.textures_delta);
    let primitives = ctx.tessellate(output.shapes, output.pixels_per_point);
    let mut window = vec![0; size.x as usize * size.y as usize];
    let panel = PanelPaint { primitives: &primitives, pixels_per_point: output.pixels_per_point };
    painter.paint(&mut window, size, &Framebuffer::default(), UVec2::ZERO, [0; 3], panel);
    save_window_png(&window, size, path)
}

/// A whole power of two's exponent as the size it stands for on the log axis.
fn size_label(mark: GridMark, _: &RangeInclusive<f64>) -> String {
    let exponent = mark.value.round();
    if (mark.value - exponent).abs() < 1e-6 { format!("{0} x {0}", 2f64.powf(exponent)) } else { String::new() }
}

/// Marks at 1, 2 and 5 times a power of ten on the log axis as milliseconds; the grid lines
/// between them go unlabelled.
fn ms_label(mark: GridMark, _: &RangeInclusive<f64>) -> String {
    let ms = 10f64.powf(mark.value);
    let decade = 10f64.powf(mark.value.floor());
    let round = [1.0, 2.0, 5.0, 10.0].iter().any(|&step| (ms / (step * decade) - 1.0).abs() < 0.01);
    match round {
        false => String::new(),
        true if ms >= 1.0 => format!("{ms:.0} ms"),
        true => format!("{ms:.2} ms"),
    }
}

/// The timing experiment's plot: median time against section size, with and without shadows,
/// both axes logarithmic, the fastest and slowest runs as dots.
pub fn save_timing_plot(timings: &[Timing], path: &Path) -> image::ImageResult<()> {
    let series = |shadows: bool| -> Vec<&Timing> { timings.iter().filter(|t| t.shadows == shadows).collect() };
    let point = |t: &Timing, ms: f64| [f64::from(t.size).log2(), ms.max(1e-3).log10()];
    save_egui_png(UVec2::new(900, 560), path, |ui| {
        ui.heading("Time to produce the image of the visible section");
        ui.label(
            "meshing the section and drawing a 1280 x 720 frame, against the section's vertices a side; \
             median of the runs, dots at the fastest and slowest; both axes logarithmic",
        );
        Plot::new("terrain-timing")
            .legend(Legend::default().position(egui_plot::Corner::LeftTop))
            .x_grid_spacer(egui_plot::log_grid_spacer(2))
            .y_grid_spacer(egui_plot::log_grid_spacer(10))
            .x_axis_formatter(size_label)
            .y_axis_formatter(ms_label)
            .show_background(false)
            .allow_drag(false)
            .allow_zoom(false)
            .allow_scroll(false)
            .show(ui, |plot| {
                for (shadows, name, color) in [
                    (false, "without shadows", egui::Color32::from_rgb(90, 160, 255)),
                    (true, "with shadows", egui::Color32::from_rgb(240, 120, 70)),
                ] {
                    let runs = series(shadows);
                    let medians: PlotPoints = runs.iter().map(|t| point(t, t.median_ms)).collect();
                    plot.line(Line::new(name, medians).color(color).width(2.0));
                    let spread: PlotPoints =
                        runs.iter().flat_map(|t| [point(t, t.min_ms), point(t, t.max_ms)]).collect();
                    plot.points(Points::new(name, spread).color(color).radius(2.5));
                }
            });
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plot_is_an_image_with_both_curves() {
        let timings: Vec<Timing> = [8u32, 16, 32]
            .iter()
            .flat_map(|&size| {
                [false, true].map(|shadows| {
                    let base = f64::from(size * size) / 100.0 * if shadows { 2.0 } else { 1.0 };
                    Timing { size, shadows, median_ms: base, min_ms: base * 0.9, max_ms: base * 1.2 }
                })
            })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.png");
        save_timing_plot(&timings, &path).unwrap();
        let image = image::open(&path).unwrap().into_rgb8();
        assert_eq!(image.dimensions(), (900, 560));
        let near = |p: &image::Rgb<u8>, c: [u8; 3]| p.0.iter().zip(c).all(|(a, b)| a.abs_diff(b) < 40);
        let blue = image.pixels().filter(|p| near(p, [90, 160, 255])).count();
        let orange = image.pixels().filter(|p| near(p, [240, 120, 70])).count();
        assert!(blue > 100 && orange > 100, "curves drawn: {blue} blue, {orange} orange pixels");
    }
}
