//! The source's experiment, repeated: the time to produce the final image of the visible
//! section against the section's size, with and without shadows.
//!
//! One measurement is what a user waits for after changing the section: meshing it from the
//! map, then drawing the frame (shadow map included when shadows are on) at the frame size.
//! Each size is framed alike (the camera backs off with the section) and every configuration
//! runs the same number of times, interleaved (all sizes and both modes in each round), so that
//! a slow spell of the machine spreads over all of them instead of one.

use crate::raster::{Camera, Frame, Framebuffer, Instance, Lens, Light, Material, RenderSettings, Renderer};
use crate::terrain::bands::{Band, BandRule, band_texture};
use crate::terrain::generate::perlin;
use crate::terrain::recipe::PerlinLayer;
use crate::terrain::section::{Geometry, Section, mesh_section};
use crate::ui::plot::save_egui_png;
use bevy::math::{Mat4, UVec2, Vec3};
use bevy::tasks::TaskPool;
use bevy_egui::egui;
use egui_plot::{GridMark, Legend, Line, Plot, PlotPoints, Points};
use std::ops::RangeInclusive;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The source's section sizes and the larger ones.
pub const SIZES: [u32; 7] = [8, 16, 32, 64, 128, 256, 512];

/// One configuration's figures, in milliseconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Vertices a side.
    pub size: u32,
    /// Whether shadows were drawn.
    pub shadows: bool,
    /// The median time.
    pub median_ms: f64,
    /// The fastest run.
    pub min_ms: f64,
    /// The slowest run.
    pub max_ms: f64,
}

/// Runs the experiment on `sizes` (each at most 512), `runs` times each, drawing frames of
/// `frame` pixels on `pool`.
pub fn run(sizes: &[u32], runs: usize, frame: UVec2, pool: &TaskPool) -> Vec<Timing> {
    let side = sizes.iter().copied().max().unwrap_or(2).max(2);
    let layer = PerlinLayer { scale: 48.0, octaves: 5, ..PerlinLayer::default() };
    let map = match perlin(layer, 1, side, side) {
        Ok(map) => map,
        Err(_) => return Vec::new(),
    };
    let textures: Vec<Arc<_>> = Band::ALL.iter().map(|&band| Arc::new(band_texture(band))).collect();
    let rule = BandRule::default();
    let mut renderer = Renderer::default();
    let mut framebuffer = Framebuffer::new(frame.x, frame.y);
    let configurations: Vec<(u32, bool)> = sizes.iter().flat_map(|&size| [(size, false), (size, true)]).collect();
    let mut times = vec![Vec::with_capacity(runs); configurations.len()];
    for _ in 0..runs {
        for (slot, &(size, shadows)) in configurations.iter().enumerate() {
            // A section a metre across whatever its size, so that every size fills the view
            // alike; heights keep their proportion to the width.
            let cell_m = 1.0 / (size - 1).max(1) as f32;
            let geometry = Geometry { cell_m, height_m: 0.35, texture_cells: 8.0 };
            let started = Instant::now();
            let mesh = mesh_section(&map, Section { origin: [0, 0], size: [size, size] }, geometry, &rule);
            let instances: Vec<Instance> = mesh
                .bands
                .into_iter()
                .zip(&textures)
                .map(|(band, texture)| Instance {
                    mesh: Arc::new(band),
                    model: Mat4::IDENTITY,
                    material: Material { texture: Some(texture.clone()), ..Material::colored(Vec3::ONE) },
                })
                .collect();
            let camera = Camera {
                eye: Vec3::new(0.0, 0.8, 0.9),
                target: Vec3::ZERO,
                lens: Lens::FieldOfView(90f32.to_radians()),
                near: 0.05,
                far: 10.0,
            };
            let light =
                Light { direction: Vec3::new(-0.5, -1.0, -0.3).normalize(), diffuse: 1.0, fill: 0.0, ambient: 0.175 };
            let frame = Frame {
                camera,
                light,
                background: [40, 40, 48, 255],
                instances: &instances,
                settings: RenderSettings { shadows, ..RenderSettings::default() },
            };
            renderer.render(&mut framebuffer, pool, &frame);
            times[slot].push(started.elapsed());
        }
    }
    configurations.iter().zip(times).map(|(&(size, shadows), runs)| summary(size, shadows, runs)).collect()
}

fn summary(size: u32, shadows: bool, mut runs: Vec<Duration>) -> Timing {
    runs.sort_unstable();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let median = match runs.len() {
        0 => 0.0,
        n if n % 2 == 1 => ms(runs[n / 2]),
        n => (ms(runs[n / 2 - 1]) + ms(runs[n / 2])) / 2.0,
    };
    Timing {
        size,
        shadows,
        median_ms: median,
        min_ms: runs.first().copied().map_or(0.0, ms),
        max_ms: runs.last().copied().map_or(0.0, ms),
    }
}

/// The experiment's table as text: per size, the medians and spreads with and without
/// shadows and their ratio.
pub fn table(timings: &[Timing]) -> String {
    let mut out = String::from(
        "| size | no shadows, median (min-max) ms | shadows, median (min-max) ms | shadows / none |\n|---|---|---|---|\n",
    );
    let mut sizes: Vec<u32> = timings.iter().map(|t| t.size).collect();
    sizes.dedup();
    for size in sizes {
        let find = |shadows| timings.iter().find(|t| t.size == size && t.shadows == shadows);
        if let (Some(plain), Some(shadowed)) = (find(false), find(true)) {
            out.push_str(&format!(
                "| {size} x {size} | {:.2} ({:.2}-{:.2}) | {:.2} ({:.2}-{:.2}) | {:.2} |\n",
                plain.median_ms,
                plain.min_ms,
                plain.max_ms,
                shadowed.median_ms,
                shadowed.min_ms,
                shadowed.max_ms,
                shadowed.median_ms / plain.median_ms.max(1e-9)
            ));
        }
    }
    out
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
    fn every_configuration_is_timed_and_summarised() {
        let pool = TaskPool::new();
        let timings = run(&[8, 16], 3, UVec2::new(64, 48), &pool);
        assert_eq!(timings.len(), 4);
        for t in &timings {
            assert!(t.min_ms <= t.median_ms && t.median_ms <= t.max_ms && t.min_ms > 0.0, "{t:?}");
        }
        let text = table(&timings);
        assert!(text.contains("| 8 x 8 |") && text.contains("| 16 x 16 |"), "{text}");
        let even = summary(8, false, [3, 1, 4, 2].map(Duration::from_millis).to_vec());
        assert_eq!((even.median_ms, even.min_ms, even.max_ms), (2.5, 1.0, 4.0));
    }

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
