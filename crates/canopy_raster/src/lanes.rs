//! SIMD lanes: how many values a run of pixels holds, and the conversions between glam's
//! vectors and `wide`'s lanes that the passes share.

use bevy_math::Vec4;
use wide::{f32x4, i32x4, u32x4};

/// Values interpolated together, one per SIMD lane; also the pixels of a run.
pub(crate) const LANES: usize = 4;

/// Each lane's offset from a run's first pixel.
pub(crate) const LANE_OFFSETS: Vec4 = Vec4::new(0.0, 1.0, 2.0, 3.0);

/// Pixels one coverage mask holds.
pub(crate) const MASK_PIXELS: u32 = 8;

/// The four lanes of a [`Vec4`] as a [`f32x4`], for the mask operations glam lacks.
#[inline(always)]
pub(crate) fn lanes_of(v: Vec4) -> f32x4 {
    f32x4::new(v.to_array())
}

/// Each lane of `v` as a float.
#[inline(always)]
pub(crate) fn floats_of(v: i32x4) -> Vec4 {
    Vec4::from_array(v.round_float().to_array())
}

/// What one step of an eight-bit channel is worth in `[0, 1]`.
pub(crate) const BYTE_TO_UNIT: f32 = 1.0 / 255.0;

/// The byte `shift` bits up in each of `words` (0 to 255), as floats: a channel of RGBA8 words.
#[inline(always)]
pub(crate) fn bytes_of(words: u32x4, shift: u32) -> Vec4 {
    floats_of(bytemuck::cast((words >> shift) & u32x4::splat(0xff)))
}

/// The largest whole number not above each lane of `v`, for values well within `i32` (the
/// baseline x86-64 target has no rounding instruction).
#[inline(always)]
pub(crate) fn floor_lanes(v: Vec4) -> i32x4 {
    let v = lanes_of(v);
    let truncated = v.fast_trunc_int();
    // Truncation moves negative fractions up; the lanes it moved step back down (a true
    // comparison is all ones, minus one as an integer).
    let moved_up: i32x4 = bytemuck::cast(v.simd_lt(truncated.round_float()));
    truncated + moved_up
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_floor_like_whole_numbers() {
        let floor = |v: Vec4| floor_lanes(v).to_array();
        assert_eq!(floor(Vec4::new(-1.5, -1.0, 0.25, 2.0)), [-2, -1, 0, 2]);
        assert_eq!(floor(Vec4::new(-0.0, -0.75, 1e6 + 0.5, -1e6 - 0.5)), [0, -1, 1_000_000, -1_000_001]);
    }
}
