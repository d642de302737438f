//! Golden frames: a frame compared with a stored image within a tolerance, and a diff image
//! that shows where they differ.

use image::{Rgba, RgbaImage};
use serde::Deserialize;

/// How far a frame may stray from its golden image.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// Largest difference of any one channel (0-255) for a pixel to count as the same.
    #[serde(default = "Tolerance::default_channel")]
    pub channel: u8,
    /// Share of pixels (0-1) that may differ by more than `channel`.
    #[serde(default = "Tolerance::default_pixels")]
    pub pixels: f64,
}

impl Tolerance {
    fn default_channel() -> u8 {
        4
    }
    fn default_pixels() -> f64 {
        0.001
    }
}

impl Default for Tolerance {
    fn default() -> Self {
        Self { channel: Self::default_channel(), pixels: Self::default_pixels() }
    }
}

/// How a frame and its golden image differ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// Pixels differing by more than the tolerance's channel difference.
    pub pixels: usize,
    /// Pixels in the frame.
    pub total: usize,
    /// The largest channel difference anywhere.
    pub largest: u8,
}

impl Difference {
    /// The share of pixels that differ.
    pub fn share(&self) -> f64 {
        self.pixels as f64 / self.total.max(1) as f64
    }

    /// Whether the frame passes.
    pub fn within(&self, tolerance: Tolerance) -> bool {
        self.share() <= tolerance.pixels
    }
}

/// The largest channel difference of two pixels (colour and alpha).
fn pixel_difference(a: &Rgba<u8>, b: &Rgba<u8>) -> u8 {
    a.0.iter().zip(b.0).map(|(a, b)| a.abs_diff(b)).max().unwrap_or(0)
}

/// Compares two images of the same size.
pub fn compare(frame: &RgbaImage, golden: &RgbaImage, tolerance: Tolerance) -> Difference {
    debug_assert_eq!(frame.dimensions(), golden.dimensions());
    let mut difference = Difference { pixels: 0, total: (frame.width() * frame.height()) as usize, largest: 0 };
    for (a, b) in frame.pixels().zip(golden.pixels()) {
        let d = pixel_difference(a, b);
        difference.largest = difference.largest.max(d);
        if d > tolerance.channel {
            difference.pixels += 1;
        }
    }
    difference
}

/// The golden image faded to grey, with the pixels beyond the tolerance in red and those that
/// differ within it in yellow.
pub fn diff_image(frame: &RgbaImage, golden: &RgbaImage, tolerance: Tolerance) -> RgbaImage {
    RgbaImage::from_fn(golden.width(), golden.height(), |x, y| {
        let g = golden.get_pixel(x, y);
        let d = pixel_difference(frame.get_pixel(x, y), g);
        if d > tolerance.channel {
            Rgba([255, 0, 0, 255])
        } else if d > 0 {
            Rgba([255, 220, 0, 255])
        } else {
            let luma = (0.299 * g[0] as f32 + 0.587 * g[1] as f32 + 0.114 * g[2] as f32) as u8;
            let faded = 170 + luma / 3;
            Rgba([faded, faded, faded, 255])
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: &[[u8; 4]]) -> RgbaImage {
        RgbaImage::from_fn(pixels.len() as u32, 1, |x, _| Rgba(pixels[x as usize]))
    }

    #[test]
    fn counts_pixels_beyond_the_channel_tolerance() {
        let golden = image(&[[10, 10, 10, 255], [100, 100, 100, 255], [0, 0, 0, 255], [0, 0, 0, 255]]);
        let frame = image(&[[10, 10, 10, 255], [104, 100, 100, 255], [0, 9, 0, 255], [0, 0, 0, 255]]);
        let tolerance = Tolerance { channel: 4, pixels: 0.25 };
        let difference = compare(&frame, &golden, tolerance);
        assert_eq!(difference, Difference { pixels: 1, total: 4, largest: 9 });
        assert!(difference.within(tolerance));
        assert!(!difference.within(Tolerance { pixels: 0.2, ..tolerance }));
    }

    #[test]
    fn the_diff_marks_where_they_differ() {
        let golden = image(&[[10, 10, 10, 255], [100, 100, 100, 255], [0, 0, 0, 255]]);
        let frame = image(&[[10, 10, 10, 255], [102, 100, 100, 255], [0, 90, 0, 255]]);
        let diff = diff_image(&frame, &golden, Tolerance { channel: 4, pixels: 0.0 });
        assert_eq!(diff.get_pixel(1, 0), &Rgba([255, 220, 0, 255]));
        assert_eq!(diff.get_pixel(2, 0), &Rgba([255, 0, 0, 255]));
        let grey = diff.get_pixel(0, 0);
        assert_eq!((grey[0], grey[0]), (grey[1], grey[2]));
    }
}
