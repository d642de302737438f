//! The colour and depth targets the rasterizer draws into.

use bevy_math::{Vec2, Vec3};
use std::path::Path;

/// Depth of an empty pixel: the far plane. Depth values are normalized device depth in
/// `[0, 1]` (0 at the near plane, 1 at the far plane); a fragment wins only if it is strictly
/// nearer than what the pixel holds, so nothing beyond the far plane is ever drawn.
pub const FAR_DEPTH: f32 = 1.0;

/// An RGBA8 colour buffer and an `f32` depth buffer of the same size, stored row by row from the
/// top-left pixel.
///
/// Colours are stored as sRGB-encoded bytes: the window shows them unchanged
/// ([`write_window`](Self::write_window)) and so do PNG files, so both show the same pixels.
#[derive(Debug, Clone, Default)]
pub struct Framebuffer {
    width: u32,
    height: u32,
    /// Four bytes per pixel, `width * height * 4` in all.
    color: Vec<u8>,
    depth: Vec<f32>,
}

impl Framebuffer {
    /// A framebuffer of `width` x `height` pixels, cleared to opaque black and the far depth.
    pub fn new(width: u32, height: u32) -> Self {
        let mut framebuffer = Self::default();
        framebuffer.resize(width, height);
        framebuffer
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Changes the size; the contents are cleared. Keeps the allocation when shrinking, so
    /// resizing back and forth does not allocate.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        let pixels = width as usize * height as usize;
        self.color.clear();
        self.color.resize(pixels * 4, 0);
        self.depth.clear();
        self.depth.resize(pixels, FAR_DEPTH);
    }

    /// Fills every pixel with `rgba` and every depth with [`FAR_DEPTH`].
    pub fn clear(&mut self, rgba: [u8; 4]) {
        for pixel in self.color.chunks_exact_mut(4) {
            pixel.copy_from_slice(&rgba);
        }
        self.depth.fill(FAR_DEPTH);
    }

    /// Gives every pixel no surface was drawn at (its depth still [`FAR_DEPTH`]) the colour
    /// of the same pixel of `backdrop` (RGBA8, row by row, this framebuffer's size): a frame
    /// drawn over a photograph. A backdrop of another size leaves the frame as it is.
    pub fn fill_empty(&mut self, backdrop: &[u8]) {
        if backdrop.len() != self.color.len() {
            return;
        }
        let pixels = self.color.chunks_exact_mut(4).zip(backdrop.chunks_exact(4));
        for ((pixel, behind), depth) in pixels.zip(&self.depth) {
            if *depth == FAR_DEPTH {
                pixel.copy_from_slice(behind);
            }
        }
    }

    /// Draws a line two pixels wide from `from` to `to` (pixel centres at whole numbers) in
    /// `rgba` over the colours, leaving the depths: marks laid over a finished frame.
    pub fn draw_line(&mut self, from: Vec2, to: Vec2, rgba: [u8; 4]) {
        let steps = (to - from).abs().max_element().ceil().clamp(1.0, 16_384.0) as u32;
        for step in 0..=steps {
            let point = from.lerp(to, step as f32 / steps as f32);
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let (x, y) = ((point.x - 0.5 + dx).floor(), (point.y - 0.5 + dy).floor());
                if x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32 {
                    let i = (y as usize * self.width as usize + x as usize) * 4;
                    self.color[i..i + 4].copy_from_slice(&rgba);
                }
            }
        }
    }

    /// Draws a line two pixels wide between two points given as pixel coordinates and depth
    /// (`z`, normalized device depth), interpolating the depth along it: with `depth_tested`,
    /// a pixel is drawn only where the line is not behind what the frame holds there (a line
    /// lying on a surface shows). The depths are left as they are.
    pub fn draw_line_depth(&mut self, from: Vec3, to: Vec3, rgba: [u8; 4], depth_tested: bool) {
        /// Depth a line may lie behind a surface and still show: lines drawn on a surface.
        const ON_SURFACE: f32 = 2e-4;
        let steps = (to.truncate() - from.truncate()).abs().max_element().ceil().clamp(1.0, 16_384.0) as u32;
        for step in 0..=steps {
            let point = from.lerp(to, step as f32 / steps as f32);
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let (x, y) = ((point.x - 0.5 + dx).floor(), (point.y - 0.5 + dy).floor());
                if x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32 {
                    let i = y as usize * self.width as usize + x as usize;
                    if !depth_tested || point.z <= self.depth[i] + ON_SURFACE {
                        self.color[i * 4..i * 4 + 4].copy_from_slice(&rgba);
                    }
                }
            }
        }
    }

    /// The RGBA8 bytes, row by row.
    pub fn color(&self) -> &[u8] {
        &self.color
    }

    /// The depth values, row by row.
    pub fn depth(&self) -> &[f32] {
        &self.depth
    }

    /// The colour of pixel (`x`, `y`), counted from the top-left corner.
    ///
    /// # Panics
    /// If the pixel is outside the framebuffer.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside the framebuffer");
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [self.color[i], self.color[i + 1], self.color[i + 2], self.color[i + 3]]
    }

    /// Splits the targets into horizontal bands of `rows` rows each (the last may be shorter),
    /// so that bands can be drawn in parallel without sharing memory.
    pub(crate) fn bands_mut(&mut self, rows: u32) -> impl Iterator<Item = Band<'_>> {
        let row_pixels = self.width as usize;
        let band_pixels = row_pixels * rows as usize;
        let width = self.width;
        self.color
            .as_chunks_mut::<4>()
            .0
            .chunks_mut(band_pixels)
            .zip(self.depth.chunks_mut(band_pixels))
            .enumerate()
            .map(move |(index, (color, depth))| Band {
                y0: index as u32 * rows,
                rows: (depth.len() / row_pixels.max(1)) as u32,
                width,
                color,
                depth,
            })
    }

    /// Writes this frame into a window buffer and fills the rest of the window with
    /// `background` (RGB): the base layer a window's panel is then painted over.
    ///
    /// `window` holds `width` pixels a row in the `0RGB` layout display servers take (one `u32`
    /// per pixel, red in bits 16-23, green in 8-15, blue in 0-7, the top byte zero); the frame's
    /// top-left pixel goes to window pixel `at` = (column, row), and the frame is clipped to the
    /// window. A frame drawn at a size the window just left shows in part, never out of place.
    pub fn write_window(&self, window: &mut [u32], width: u32, at: [u32; 2], background: [u8; 3]) {
        let fill = xrgb(background);
        let width = width as usize;
        if width == 0 {
            return;
        }
        let [left, top] = at.map(|v| v as usize);
        let frame_width = self.width as usize;
        let shown = frame_width.min(width.saturating_sub(left));
        for (y, row) in window.chunks_exact_mut(width).enumerate() {
            let Some(source) = y.checked_sub(top).filter(|&fy| fy < self.height as usize) else {
                row.fill(fill);
                continue;
            };
            let source = &self.color.as_chunks::<4>().0[source * frame_width..][..shown];
            let (before, rest) = row.split_at_mut(left.min(width));
            let (view, after) = rest.split_at_mut(shown);
            before.fill(fill);
            for (pixel, &rgba) in view.iter_mut().zip(source) {
                // R, G, B, A in memory -> 0x00RRGGBB, in a form that compiles to byte shuffles.
                *pixel = u32::from_le_bytes(rgba).swap_bytes() >> 8;
            }
            after.fill(fill);
        }
    }

    /// Writes the colour buffer to a PNG file.
    pub fn save_png(&self, path: &Path) -> image::ImageResult<()> {
        image::save_buffer(path, &self.color, self.width, self.height, image::ExtendedColorType::Rgba8)
    }
}

/// One pixel in the `0RGB` layout of [`Framebuffer::write_window`].
fn xrgb([r, g, b]: [u8; 3]) -> u32 {
    u32::from(r) << 16 | u32::from(g) << 8 | u32::from(b)
}

/// A horizontal band of a [`Framebuffer`]: rows `y0..y0 + rows` of both targets.
pub(crate) struct Band<'a> {
    /// First row of the band in framebuffer coordinates.
    pub y0: u32,
    /// Number of rows in the band (kept, not divided out of the buffer lengths for each
    /// triangle).
    pub rows: u32,
    /// Row length in pixels.
    pub width: u32,
    /// RGBA8 pixels of the band's rows (with shadows, a drawn pixel's alpha holds its diffuse
    /// term until the band's shadows are applied).
    pub color: &'a mut [[u8; 4]],
    /// Depth of the band's rows.
    pub depth: &'a mut [f32],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_empty_pixels_take_the_backdrop() {
        let mut framebuffer = Framebuffer::new(2, 1);
        framebuffer.clear([1, 2, 3, 255]);
        framebuffer.depth[1] = 0.5;
        framebuffer.fill_empty(&[9, 9, 9, 255, 7, 7, 7, 255]);
        assert_eq!((framebuffer.pixel(0, 0), framebuffer.pixel(1, 0)), ([9, 9, 9, 255], [1, 2, 3, 255]));
        framebuffer.fill_empty(&[0; 4]);
        assert_eq!(framebuffer.pixel(0, 0), [9, 9, 9, 255], "a backdrop of another size is ignored");
    }

    #[test]
    fn a_line_covers_the_pixels_between_its_ends_and_clips_at_the_edges() {
        let mut framebuffer = Framebuffer::new(8, 4);
        framebuffer.draw_line(Vec2::new(-3.0, 1.5), Vec2::new(20.0, 1.5), [9, 9, 9, 255]);
        for x in 0..8 {
            assert_eq!((framebuffer.pixel(x, 1), framebuffer.pixel(x, 2)), ([9, 9, 9, 255], [9, 9, 9, 255]));
            assert_eq!((framebuffer.pixel(x, 0), framebuffer.pixel(x, 3)), ([0, 0, 0, 0], [0, 0, 0, 0]));
        }
        assert!(framebuffer.depth().iter().all(|&d| d == FAR_DEPTH));
    }

    #[test]
    fn a_depth_tested_line_hides_behind_surfaces_and_shows_on_them() {
        let mut framebuffer = Framebuffer::new(8, 4);
        // A surface at depth 0.5 over the left half.
        for y in 0..4 {
            for x in 0..4 {
                framebuffer.depth[y * 8 + x] = 0.5;
            }
        }
        let (red, green) = ([255, 0, 0, 255], [0, 255, 0, 255]);
        framebuffer.draw_line_depth(Vec3::new(0.0, 1.5, 0.7), Vec3::new(8.0, 1.5, 0.7), red, true);
        assert_eq!((framebuffer.pixel(1, 1), framebuffer.pixel(6, 1)), ([0, 0, 0, 0], red), "behind, then in the open");
        framebuffer.draw_line_depth(Vec3::new(0.0, 1.5, 0.5), Vec3::new(8.0, 1.5, 0.5), green, true);
        assert_eq!(framebuffer.pixel(1, 1), green, "on the surface");
        framebuffer.draw_line_depth(Vec3::new(0.0, 1.5, 0.9), Vec3::new(8.0, 1.5, 0.9), red, false);
        assert_eq!(framebuffer.pixel(1, 1), red, "on top");
        assert_eq!(framebuffer.depth()[9], 0.5, "depths are left");
    }

    #[test]
    fn clear_sets_colour_and_far_depth() {
        let mut fb = Framebuffer::new(3, 2);
        fb.clear([1, 2, 3, 4]);
        assert_eq!(fb.pixel(2, 1), [1, 2, 3, 4]);
        assert!(fb.depth().iter().all(|&d| d == FAR_DEPTH));
        assert_eq!(fb.color().len(), 3 * 2 * 4);
    }

    #[test]
    fn window_gets_the_frame_at_its_place_and_the_background_around_it() {
        let mut fb = Framebuffer::new(2, 2);
        fb.clear([0x10, 0x20, 0x30, 255]);
        let mut window = vec![7; 4 * 3];
        fb.write_window(&mut window, 4, [1, 1], [1, 2, 3]);
        let (f, b) = (0x10_2030, 0x01_0203);
        assert_eq!(window, [b, b, b, b, b, f, f, b, b, f, f, b]);
    }

    #[test]
    fn window_clips_a_frame_larger_than_its_room() {
        let mut fb = Framebuffer::new(3, 3);
        fb.clear([0xff, 0, 0, 255]);
        let mut window = vec![7; 2 * 2];
        fb.write_window(&mut window, 2, [1, 0], [0, 0, 0]);
        assert_eq!(window, [0, 0xff_0000, 0, 0xff_0000]);
        // Placed entirely outside, the frame leaves only the background.
        fb.write_window(&mut window, 2, [5, 5], [0, 0, 9]);
        assert_eq!(window, [9; 4]);
    }

    #[test]
    fn bands_cover_every_row_once() {
        let mut fb = Framebuffer::new(5, 37);
        let bands: Vec<(u32, u32)> = fb.bands_mut(16).map(|b| (b.y0, b.rows)).collect();
        assert_eq!(bands, vec![(0, 16), (16, 16), (32, 5)]);
    }
}
