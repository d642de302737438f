//! Plots as image files, drawn without a window: an egui frame (an `egui_plot` plot, say),
//! tessellated and painted on the CPU by the window's own painter, then written as PNG.

use super::compose::{PanelPaint, WindowPainter, save_window_png};
use crate::raster::Framebuffer;
use bevy::math::UVec2;
use bevy_egui::egui;
use std::path::Path;

/// Draws `ui_fn` into an image of `size` pixels at `path`.
pub fn save_egui_png(size: UVec2, path: &Path, mut ui_fn: impl FnMut(&mut egui::Ui)) -> image::ImageResult<()> {
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
