//! The window's pixels, composed on the CPU: the rasterizer's frame where the panel leaves room
//! for the 3D view, the background around it, and egui's tessellated panel painted over both.
//! Pure: it knows neither the window system nor the ECS, so tests compose windows in memory.
//!
//! Window buffers are `0RGB` (one `u32` a pixel, red in bits 16-23, blue in 0-7), the layout
//! `softbuffer` hands out; on a little-endian machine its bytes are B, G, R, X, the order the
//! egui painter is told to write.

use crate::raster::Framebuffer;
use bevy::math::UVec2;
use bevy_egui::egui;
use egui_software_backend::{BufferMutRef, ColorFieldOrder, EguiSoftwareRender};
use std::path::Path;

/// What egui asks to be painted this frame.
#[derive(Clone, Copy)]
pub struct PanelPaint<'a> {
    /// The tessellated shapes, in painting order, each with its clip rectangle.
    pub primitives: &'a [egui::ClippedPrimitive],
    /// Physical pixels per egui point.
    pub pixels_per_point: f32,
}

/// Paints windows frame after frame; keeps egui's textures (the font atlas above all).
pub struct WindowPainter {
    egui: EguiSoftwareRender,
    /// Texture changes not yet taken in: egui sends each change once, so none may be lost
    /// while the window has no area to paint (minimized).
    textures: egui::TexturesDelta,
}

impl Default for WindowPainter {
    /// Paints straight into the window buffer. The painter's cache of rasterized primitives
    /// redraws its whole canvas whenever one primitive changes, and the panel's timings change
    /// every frame: painting directly took a quarter of the time (0.5 ms against 2 ms a frame
    /// for the panel of an empty scene).
    fn default() -> Self {
        Self {
            egui: EguiSoftwareRender::new(ColorFieldOrder::Bgra).with_caching(false),
            textures: egui::TexturesDelta::default(),
        }
    }
}

impl WindowPainter {
    /// Takes in egui's texture changes of a frame; they are applied with the next painting.
    pub fn take_textures(&mut self, delta: egui::TexturesDelta) {
        self.textures.append(delta);
    }

    /// Composes one window of `size` pixels into `window`: `frame` with its top-left pixel at
    /// `view_origin`, `background` (RGB) wherever the frame does not reach, and the panel over
    /// both. Returns the time the panel's painting took, apart from the frame's copy.
    ///
    /// # Panics
    /// If `window` does not hold `size.x * size.y` pixels.
    pub fn paint(
        &mut self,
        window: &mut [u32],
        size: UVec2,
        frame: &Framebuffer,
        view_origin: UVec2,
        background: [u8; 3],
        panel: PanelPaint,
    ) -> std::time::Duration {
        assert_eq!(window.len(), size.x as usize * size.y as usize, "window buffer of the wrong size");
        frame.write_window(window, size.x, view_origin.to_array(), background);
        let started = std::time::Instant::now();
        if size.min_element() > 0 && panel.pixels_per_point > 0.0 {
            let pixels: &mut [[u8; 4]] = bytemuck::cast_slice_mut(window);
            let mut buffer = BufferMutRef::new(pixels, size.x as usize, size.y as usize);
            let textures = std::mem::take(&mut self.textures);
            self.egui.render(&mut buffer, panel.primitives, &textures, panel.pixels_per_point);
        }
        started.elapsed()
    }
}

/// The RGBA8 bytes of a window buffer, row by row, for image files.
pub fn window_rgba(window: &[u32]) -> Vec<u8> {
    window
        .iter()
        .flat_map(|&pixel| {
            let [_, r, g, b] = pixel.to_be_bytes();
            [r, g, b, 255]
        })
        .collect()
}

/// Writes a window buffer of `size` pixels to a PNG file.
pub fn save_window_png(window: &[u32], size: UVec2, path: &Path) -> image::ImageResult<()> {
    image::save_buffer(path, &window_rgba(window), size.x, size.y, image::ExtendedColorType::Rgba8)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One frame of a panel of `width` points on the right of a `size` window, a filled
    /// rectangle with a label on it, tessellated as the app's egui context does it.
    fn panel_frame(ctx: &egui::Context, size: UVec2, width: f32) -> (Vec<egui::ClippedPrimitive>, egui::TexturesDelta) {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(size.x as f32, size.y as f32))),
            ..Default::default()
        };
        let output = ctx.run_ui(input, |ui| {
            egui::Panel::right("panel").exact_size(width).show_inside(ui, |ui| {
                ui.label("Canopy");
            });
        });
        (ctx.tessellate(output.shapes, output.pixels_per_point), output.textures_delta)
    }

    #[test]
    fn the_view_shows_the_frame_and_the_panel_covers_its_side() {
        let size = UVec2::new(200, 100);
        let mut frame = Framebuffer::new(120, 100);
        frame.clear([200, 40, 30, 255]);
        let ctx = egui::Context::default();
        let (primitives, textures) = panel_frame(&ctx, size, 60.0);
        let mut painter = WindowPainter::default();
        painter.take_textures(textures);
        let mut window = vec![0; 200 * 100];
        let panel = PanelPaint { primitives: &primitives, pixels_per_point: 1.0 };
        painter.paint(&mut window, size, &frame, UVec2::ZERO, [0, 0, 255], panel);

        let at = |x: usize, y: usize| window[y * 200 + x] & 0xff_ffff;
        // The view: the frame's red, unchanged, up to its right edge.
        assert_eq!(at(0, 0), 0xc8_281e);
        assert_eq!(at(119, 99), 0xc8_281e);
        // Between the frame and the panel: the background.
        assert_eq!(at(130, 50), 0x00_00ff);
        // The panel: egui's panel fill, grey, over everything else.
        let fill = ctx.global_style().visuals.panel_fill;
        assert_eq!(at(195, 90), u32::from_be_bytes([0, fill.r(), fill.g(), fill.b()]));
        // Its label: text pixels lighter than the fill somewhere in the top rows.
        let lighter = (0..20).flat_map(|y| (145..200).map(move |x| (x, y))).filter(|&(x, y)| at(x, y) > at(195, 90));
        assert!(lighter.count() > 10, "no text painted in the panel");
    }

    #[test]
    fn texture_changes_wait_for_a_window_with_area() {
        let ctx = egui::Context::default();
        let (_, textures) = panel_frame(&ctx, UVec2::new(100, 100), 50.0);
        assert!(!textures.set.is_empty(), "the first frame sets the font atlas");
        let mut painter = WindowPainter::default();
        painter.take_textures(textures);
        let (_, later) = panel_frame(&ctx, UVec2::new(100, 100), 50.0);
        painter.take_textures(later);
        // A minimized window paints nothing and keeps the atlas for later.
        painter.paint(
            &mut [],
            UVec2::ZERO,
            &Framebuffer::default(),
            UVec2::ZERO,
            [0; 3],
            PanelPaint { primitives: &[], pixels_per_point: 1.0 },
        );
        assert!(!painter.textures.set.is_empty());
    }

    #[test]
    fn png_bytes_are_rgba() {
        assert_eq!(window_rgba(&[0x00_10_20_30, 0xff_01_02_03]), [0x10, 0x20, 0x30, 255, 1, 2, 3, 255]);
    }
}
