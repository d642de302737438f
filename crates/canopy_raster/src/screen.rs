//! The screen in fixed point: tile and target sizes, sub-pixel positions, projected vertices,
//! pixel bounds and the exact integer edge functions.

use crate::clip::{ClipLanes, outside};
use crate::lanes::floor_lanes;
use bevy_math::Vec4;

/// Tile width in pixels.
pub const TILE_WIDTH: u32 = 64;

/// Tile height in pixels; a row of tiles is one unit of parallel work.
pub const TILE_HEIGHT: u32 = 64;

/// Sub-pixel positions per pixel along each axis (8 bits of sub-pixel precision).
pub const SUBPIXEL_STEPS: i64 = 256;

/// The largest framebuffer or shadow-map side, in pixels, for which the fixed-point edge
/// functions are exact.
pub const MAX_TARGET_SIZE: u32 = 4096;

/// A vertex projected to the screen: which planes it is outside of and (when it needs no
/// clipping) its fixed-point screen position, depth and `1/w`. The rare triangle that needs
/// clipping computes its clip positions again from the world positions.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ScreenVertex {
    /// [`outside`] bits.
    pub code: u8,
    /// Screen x in sub-pixel units.
    pub x: i32,
    /// Screen y (downwards) in sub-pixel units.
    pub y: i32,
    /// Normalized device depth.
    pub z: f32,
    /// `1/w`.
    pub inv_w: f32,
}

impl ScreenVertex {
    /// Projects four clip-space positions onto a `width` x `height` target.
    #[inline(always)]
    pub(crate) fn lanes(clip: &ClipLanes, width: u32, height: u32) -> [Self; 4] {
        let codes = clip.outcodes();
        let projected = Self::project(clip, width, height);
        std::array::from_fn(|k| {
            let code = codes[k];
            let kept = if code & outside::CLIPPED == 0 { projected[k] } else { Self::default() };
            Self { code, ..kept }
        })
    }

    /// Projects a clip-space position known to be inside the near plane and the guard band
    /// (up to rounding).
    pub(crate) fn projected(clip: Vec4, width: u32, height: u32) -> Self {
        Self::project(&ClipLanes::splat(clip), width, height)[0]
    }

    /// Projects four clip-space positions, each inside the near plane and the guard band up
    /// to rounding.
    #[inline(always)]
    fn project(clip: &ClipLanes, width: u32, height: u32) -> [Self; 4] {
        let inv_w = Vec4::ONE / clip.w;
        let steps = SUBPIXEL_STEPS as f32;
        // The limits only guard against rounding past the guard band after clipping; `max`
        // comes first so that a position without a direction (on the eye point) lands on one.
        let limit = Vec4::splat(3.0 * MAX_TARGET_SIZE as f32 * steps);
        let fixed = |v: Vec4| floor_lanes(v.max(-limit).min(limit) + 0.5).to_array();
        let x = fixed((clip.x * inv_w + 1.0) * 0.5 * width as f32 * steps);
        let y = fixed((1.0 - clip.y * inv_w) * 0.5 * height as f32 * steps);
        let (z, inv_w) = ((clip.z * inv_w).max(Vec4::ZERO).to_array(), inv_w.to_array());
        std::array::from_fn(|k| Self { code: 0, x: x[k], y: y[k], z: z[k], inv_w: inv_w[k] })
    }
}

/// Inclusive pixel bounds of a triangle, within its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PixelBounds {
    pub min_x: u32,
    pub max_x: u32,
    pub min_y: u32,
    pub max_y: u32,
}

/// Twice the signed area of the triangle `a b p` in sub-pixel units squared; positive when `p`
/// lies to the right of `a -> b` on a y-down screen.
#[inline(always)]
pub(crate) fn edge(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> i64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// The least and the greatest of three coordinates.
#[inline(always)]
pub(crate) fn range_of([a, b, c]: [i64; 3]) -> (i64, i64) {
    (a.min(b).min(c), a.max(b).max(c))
}

/// The first and last of `size` pixel columns (or rows) whose centres lie between `least` and
/// `greatest` (sub-pixel units); `None` when there is none.
#[inline(always)]
pub(crate) fn pixel_span((least, greatest): (i64, i64), size: u32) -> Option<(u32, u32)> {
    // Pixel p is sampled at its centre, p + 1/2.
    let half = SUBPIXEL_STEPS / 2;
    let first = (least - half + SUBPIXEL_STEPS - 1).div_euclid(SUBPIXEL_STEPS).max(0);
    let last = (greatest - half).div_euclid(SUBPIXEL_STEPS).min(i64::from(size) - 1);
    (first <= last).then_some((first as u32, last as u32))
}

/// The pixel rectangle of tile column `tx` in a band.
pub(crate) fn tile_rect(tx: u32, y0: u32, width: u32, rows: u32) -> PixelBounds {
    PixelBounds {
        min_x: tx * TILE_WIDTH,
        max_x: ((tx + 1) * TILE_WIDTH).min(width) - 1,
        min_y: y0,
        max_y: y0 + rows - 1,
    }
}
