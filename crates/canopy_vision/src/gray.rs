//! Grey images: what the detector reads, made from RGB or RGBA pixels, sampled between pixel
//! centres.
//!
//! Coordinates follow OpenCV: pixel `(x, y)`'s centre is at `(x, y)`, so the image covers
//! `[-0.5, width - 0.5] x [-0.5, height - 0.5]`.

use bevy_math::Vec2;

/// An 8-bit grey image, row by row from the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Gray {
    /// Pixels a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width * height` intensities, 0 black to 255 white.
    pub pixels: Vec<u8>,
}

impl Gray {
    /// A uniform image.
    pub fn filled(width: u32, height: u32, value: u8) -> Self {
        Self { width, height, pixels: vec![value; width as usize * height as usize] }
    }

    /// The luma of 8-bit RGB pixels (ITU-R BT.601 weights, as OpenCV's conversion).
    pub fn from_rgb(width: u32, height: u32, rgb: &[u8]) -> Self {
        Self::from_channels(width, height, rgb, 3)
    }

    /// The luma of 8-bit RGBA pixels; alpha is ignored.
    pub fn from_rgba(width: u32, height: u32, rgba: &[u8]) -> Self {
        Self::from_channels(width, height, rgba, 4)
    }

    fn from_channels(width: u32, height: u32, bytes: &[u8], channels: usize) -> Self {
        let pixels = bytes
            .chunks_exact(channels)
            .take(width as usize * height as usize)
            .map(|p| ((u32::from(p[0]) * 4899 + u32::from(p[1]) * 9617 + u32::from(p[2]) * 1868 + 8192) >> 14) as u8)
            .collect();
        Self { width, height, pixels }
    }

    /// The intensity of pixel `(x, y)`.
    #[inline]
    pub fn at(&self, x: u32, y: u32) -> u8 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Whether `point` lies at least `margin` pixels inside the centres of the outermost
    /// pixels.
    pub fn contains(&self, point: Vec2, margin: f32) -> bool {
        point.x >= margin
            && point.y >= margin
            && point.x <= self.width as f32 - 1.0 - margin
            && point.y <= self.height as f32 - 1.0 - margin
    }

    /// The intensity at `point`, interpolated bilinearly between the four nearest pixel
    /// centres; points outside take the nearest edge pixel's value.
    #[inline]
    pub fn sample(&self, point: Vec2) -> f32 {
        let max = Vec2::new(self.width as f32 - 1.0, self.height as f32 - 1.0);
        let p = point.clamp(Vec2::ZERO, max);
        let (x0, y0) = (p.x.floor(), p.y.floor());
        let (fx, fy) = (p.x - x0, p.y - y0);
        let (x0, y0) = (x0 as u32, y0 as u32);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let top = f32::from(self.at(x0, y0)) * (1.0 - fx) + f32::from(self.at(x1, y0)) * fx;
        let bottom = f32::from(self.at(x0, y1)) * (1.0 - fx) + f32::from(self.at(x1, y1)) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luma_weighs_green_most_and_keeps_greys() {
        let gray = Gray::from_rgb(4, 1, &[255, 0, 0, 0, 255, 0, 0, 0, 255, 90, 90, 90]);
        assert_eq!(gray.pixels, vec![76, 150, 29, 90]);
    }

    #[test]
    fn samples_interpolate_between_centres_and_clamp_outside() {
        let gray = Gray { width: 2, height: 2, pixels: vec![0, 100, 200, 100] };
        assert_eq!(gray.sample(Vec2::new(0.0, 0.0)), 0.0);
        assert_eq!(gray.sample(Vec2::new(0.5, 0.0)), 50.0);
        assert_eq!(gray.sample(Vec2::new(0.0, 0.5)), 100.0);
        assert_eq!(gray.sample(Vec2::new(-3.0, 9.0)), 200.0);
        assert!(gray.contains(Vec2::new(0.5, 0.5), 0.5) && !gray.contains(Vec2::new(0.5, 0.5), 0.6));
    }
}
