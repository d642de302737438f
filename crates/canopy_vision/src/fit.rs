//! A camera frame fitted into a view of another size (scaled as large as fits, centred) and
//! its lens distortion removed: the photograph behind an augmented-reality render.

use crate::camera::Intrinsics;
use bevy_math::DVec2;

/// Where the camera frame sits in a view of `target` pixels: scaled by `scale` (as large as
/// fits, the shape kept) with its top-left corner at `offset` pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// View pixels per frame pixel.
    pub scale: f64,
    /// The frame's top-left corner in the view, pixels.
    pub offset: DVec2,
}

impl Fit {
    /// The frame of `frame` pixels as large as fits in a view of `target` pixels, centred.
    pub fn new(frame: [u32; 2], target: [u32; 2]) -> Self {
        let [w, h] = frame.map(f64::from);
        let [tw, th] = target.map(f64::from);
        let scale = (tw / w).min(th / h);
        Self { scale, offset: DVec2::new(0.5 * (tw - w * scale), 0.5 * (th - h * scale)) }
    }

    /// A frame pixel position (OpenCV's convention) in the view, same convention.
    pub fn to_view(&self, pixel: DVec2) -> DVec2 {
        (pixel + 0.5) * self.scale + self.offset - 0.5
    }

    /// A view pixel position in the frame.
    pub fn to_frame(&self, pixel: DVec2) -> DVec2 {
        (pixel + 0.5 - self.offset) / self.scale - 0.5
    }
}

/// For each view pixel, where in the camera frame its colour comes from (frame pixels), or
/// none outside the fitted frame: the frame as a pinhole camera would have taken it (its
/// distortion removed), so that a pinhole render lines up with it.
#[derive(Debug, Clone, PartialEq)]
pub struct Remap {
    /// The view's size, pixels.
    pub target: [u32; 2],
    /// The camera it was made for.
    pub camera: Intrinsics,
    /// Row by row over the view: the taps to blend, or none outside the frame.
    taps: Vec<Option<Tap>>,
}

/// A bilinear read of the frame: the top-left texel's byte offset and the weights of the
/// right and lower neighbours in 256ths (the neighbours always inside the frame).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tap {
    offset: u32,
    fx: u16,
    fy: u16,
}

impl Remap {
    /// The map for a view of `target` pixels.
    pub fn new(camera: &Intrinsics, target: [u32; 2]) -> Self {
        let fit = Fit::new(camera.size, target);
        let [w, h] = camera.size;
        let (right, bottom) = (f64::from(w) - 0.5, f64::from(h) - 0.5);
        let inside = |p: DVec2| p.x >= -0.5 && p.y >= -0.5 && p.x <= right && p.y <= bottom;
        // The texel left of (or above) a position and the weight of the next, kept so that
        // the next is inside the frame.
        let axis = |v: f64, size: u32| -> (u32, u16) {
            if size < 2 {
                return (0, 0);
            }
            let v = v.clamp(0.0, f64::from(size - 1));
            let base = (v.floor() as u32).min(size - 2);
            (base, ((v - f64::from(base)) * 256.0).round() as u16)
        };
        let mut taps = Vec::with_capacity(target[0] as usize * target[1] as usize);
        for y in 0..target[1] {
            for x in 0..target[0] {
                let ideal = fit.to_frame(DVec2::new(f64::from(x), f64::from(y)));
                let source = inside(ideal).then(|| camera.bent(ideal));
                taps.push(source.filter(|&p| inside(p)).map(|p| {
                    let ((x0, fx), (y0, fy)) = (axis(p.x, w), axis(p.y, h));
                    Tap { offset: (y0 * w + x0) * 4, fx, fy }
                }));
            }
        }
        Self { target, camera: *camera, taps }
    }

    /// The view of `frame` (RGBA8, the camera's size): RGBA8 row by row, `background`
    /// outside the frame.
    pub fn apply(&self, frame: &[u8], background: [u8; 4], out: &mut Vec<u8>) {
        let [w, h] = self.camera.size;
        let (dx, dy) = (if w > 1 { 4 } else { 0 }, if h > 1 { 4 * w as usize } else { 0 });
        out.clear();
        out.resize(self.taps.len() * 4, 0);
        if frame.len() < w as usize * h as usize * 4 {
            return;
        }
        for (tap, pixel) in self.taps.iter().zip(out.chunks_exact_mut(4)) {
            let Some(Tap { offset, fx, fy }) = *tap else {
                pixel.copy_from_slice(&background);
                continue;
            };
            let (fx, fy) = (u32::from(fx), u32::from(fy));
            let i = offset as usize;
            for c in 0..3 {
                let texel = |at: usize| u32::from(frame[at + c]);
                let top = texel(i) * (256 - fx) + texel(i + dx) * fx;
                let low = texel(i + dy) * (256 - fx) + texel(i + dy + dx) * fx;
                pixel[c] = ((top * (256 - fy) + low * fy + 32768) >> 16) as u8;
            }
            pixel[3] = 255;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_is_the_frame_fitted_and_bordered() {
        let camera = Intrinsics::pinhole([4, 2], 60.0);
        let frame: Vec<u8> = (0..8u8).flat_map(|i| [i * 30, 0, 0, 255]).collect();
        let map = Remap::new(&camera, [8, 8]);
        let mut out = Vec::new();
        map.apply(&frame, [1, 2, 3, 255], &mut out);
        // Scaled twice: rows 2 to 5 hold the frame, the rest is background.
        assert_eq!(&out[..4], &[1, 2, 3, 255]);
        let at = |x: usize, y: usize| out[(y * 8 + x) * 4];
        assert_eq!((at(0, 2), at(7, 5)), (0, 210));
        assert!(at(1, 2) > 0 && at(1, 2) < 30, "between the first two pixels");
    }

    #[test]
    fn a_distorted_frame_is_straightened() {
        let camera = Intrinsics {
            distortion: crate::camera::Distortion([-0.3, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            ..Intrinsics::pinhole([64, 48], 70.0)
        };
        let map = Remap::new(&camera, [64, 48]);
        // A view pixel near the corner reads the frame where the lens put that direction:
        // nearer the centre for barrel distortion.
        let corner = map.taps[0].unwrap();
        let (x, y) = ((corner.offset / 4) % 64, (corner.offset / 4) / 64);
        assert!(x >= 1 && y >= 1, "({x}, {y})");
        // The centre, where the lens bends nothing, reads its own place.
        let centre = map.taps[24 * 64 + 32].unwrap();
        let x = f32::from(centre.fx) / 256.0 + ((centre.offset / 4) % 64) as f32;
        let y = f32::from(centre.fy) / 256.0 + ((centre.offset / 4) / 64) as f32;
        assert!((x - 32.0).abs() < 0.01 && (y - 24.0).abs() < 0.01, "({x}, {y})");
    }
}
