//! The heightmap: a `width x height` grid of `f32` heights, and the map algebra that combines
//! maps (add, subtract, scale, min, max, functions of every value, normalising).
//!
//! Index `(x, z)` is a position on the ground, the value there its height. Generated maps hold
//! heights in `[0, 1]`; the terrain's height scale turns them into metres.

use std::fmt;

/// The longest side a heightmap may have, in samples: a map read from a file or asked for in a
/// scene is refused beyond it, so that no file can exhaust memory (4096 x 4096 heights are
/// 64 MiB).
pub const MAX_SIDE: u32 = 4096;

/// A grid of heights, stored row by row (`z` major).
#[derive(Clone, PartialEq)]
pub struct Heightmap {
    width: u32,
    height: u32,
    values: Vec<f32>,
}

impl fmt::Debug for Heightmap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Heightmap({} x {}, checksum {:016x})", self.width, self.height, self.checksum())
    }
}

/// Why a heightmap of some size cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SizeError {
    /// A side is zero or longer than [`MAX_SIDE`].
    #[error("a heightmap of {0} x {1} samples: each side must be from 1 to {MAX_SIDE}")]
    OutOfRange(u32, u32),
    /// Two maps combined have different sizes.
    #[error("maps of {0} x {1} and {2} x {3} samples cannot be combined: their sizes differ")]
    Mismatch(u32, u32, u32, u32),
}

/// A map's figures: its extremes, mean and a checksum of every height's bits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    /// Width in samples.
    pub width: u32,
    /// Height (depth along z) in samples.
    pub height: u32,
    /// The lowest height.
    pub min: f32,
    /// The highest height.
    pub max: f32,
    /// The mean height.
    pub mean: f32,
    /// FNV-1a over the heights' bits, row by row.
    pub checksum: u64,
}

impl Heightmap {
    /// A map of `width x height` samples, each `value`.
    pub fn filled(width: u32, height: u32, value: f32) -> Result<Self, SizeError> {
        check_size(width, height)?;
        Ok(Self { width, height, values: vec![value; width as usize * height as usize] })
    }

    /// A map of `width x height` samples from a function of the position.
    pub fn from_fn(width: u32, height: u32, mut value: impl FnMut(u32, u32) -> f32) -> Result<Self, SizeError> {
        check_size(width, height)?;
        let values = (0..height).flat_map(|z| (0..width).map(move |x| (x, z))).map(|(x, z)| value(x, z)).collect();
        Ok(Self { width, height, values })
    }

    /// A map holding `values`, row by row; `None` when their count is not `width * height` or
    /// the size is out of range.
    pub fn from_values(width: u32, height: u32, values: Vec<f32>) -> Option<Self> {
        (check_size(width, height).is_ok() && values.len() == width as usize * height as usize).then_some(Self {
            width,
            height,
            values,
        })
    }

    /// Width in samples (along x).
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in samples (along z).
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Every height, row by row.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Every height, row by row, to change in place.
    pub fn values_mut(&mut self) -> &mut [f32] {
        &mut self.values
    }

    /// The height at `(x, z)`, which must lie inside the map.
    #[inline]
    pub fn at(&self, x: u32, z: u32) -> f32 {
        self.values[z as usize * self.width as usize + x as usize]
    }

    /// The height at `(x, z)`, or `None` outside the map.
    #[inline]
    pub fn get(&self, x: i64, z: i64) -> Option<f32> {
        let inside = (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&z);
        inside.then(|| self.values[z as usize * self.width as usize + x as usize])
    }

    /// One row of heights.
    pub fn row(&self, z: u32) -> &[f32] {
        let start = z as usize * self.width as usize;
        &self.values[start..start + self.width as usize]
    }

    /// The map's figures.
    pub fn stats(&self) -> Stats {
        let (min, max) =
            self.values.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let sum: f64 = self.values.iter().map(|&v| f64::from(v)).sum();
        Stats {
            width: self.width,
            height: self.height,
            min,
            max,
            mean: (sum / self.values.len() as f64) as f32,
            checksum: self.checksum(),
        }
    }

    /// FNV-1a over the bits of every height, row by row: equal maps give equal checksums on
    /// every machine.
    pub fn checksum(&self) -> u64 {
        self.values
            .iter()
            .flat_map(|v| v.to_bits().to_le_bytes())
            .fold(0xcbf2_9ce4_8422_2325, |hash, byte| (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3))
    }

    /// Combines every height with the other map's height at the same place.
    pub fn combine(&mut self, other: &Heightmap, op: impl Fn(f32, f32) -> f32) -> Result<(), SizeError> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(SizeError::Mismatch(self.width, self.height, other.width, other.height));
        }
        self.values.iter_mut().zip(&other.values).for_each(|(a, &b)| *a = op(*a, b));
        Ok(())
    }

    /// Applies `function` to every height.
    pub fn apply(&mut self, function: impl Fn(f32) -> f32) {
        self.values.iter_mut().for_each(|v| *v = function(*v));
    }

    /// Stretches the heights linearly onto `[0, 1]`; a flat map becomes all zeros.
    pub fn normalize(&mut self) {
        let Stats { min, max, .. } = self.stats();
        let span = max - min;
        if span > 0.0 && span.is_finite() {
            self.apply(|v| (v - min) / span);
        } else {
            self.apply(|_| 0.0);
        }
    }
}

/// Refuses sizes with a zero side or one beyond [`MAX_SIDE`].
pub fn check_size(width: u32, height: u32) -> Result<(), SizeError> {
    let valid = 1..=MAX_SIDE;
    if valid.contains(&width) && valid.contains(&height) { Ok(()) } else { Err(SizeError::OutOfRange(width, height)) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(values: &[f32]) -> Heightmap {
        Heightmap::from_values(2, 2, values.to_vec()).unwrap()
    }

    #[test]
    fn algebra_matches_hand_computed_values() {
        let mut a = map(&[0.0, 1.0, 2.0, 4.0]);
        let b = map(&[1.0, 1.0, 0.5, -1.0]);
        a.combine(&b, |x, y| x + y).unwrap();
        assert_eq!(a.values(), &[1.0, 2.0, 2.5, 3.0]);
        a.combine(&b, |x, y| x - y).unwrap();
        assert_eq!(a.values(), &[0.0, 1.0, 2.0, 4.0]);
        a.combine(&b, f32::min).unwrap();
        assert_eq!(a.values(), &[0.0, 1.0, 0.5, -1.0]);
        a.apply(|v| v * 2.0);
        assert_eq!(a.values(), &[0.0, 2.0, 1.0, -2.0]);
        a.normalize();
        assert_eq!(a.values(), &[0.5, 1.0, 0.75, 0.0]);
        let wide = Heightmap::filled(3, 2, 0.0).unwrap();
        assert_eq!(a.combine(&wide, |x, _| x), Err(SizeError::Mismatch(2, 2, 3, 2)));
    }

    #[test]
    fn figures_and_checksums() {
        let a = map(&[0.0, 1.0, 2.0, 5.0]);
        let stats = a.stats();
        assert_eq!((stats.min, stats.max, stats.mean), (0.0, 5.0, 2.0));
        assert_eq!(stats.checksum, map(&[0.0, 1.0, 2.0, 5.0]).checksum());
        assert_ne!(stats.checksum, map(&[0.0, 1.0, 2.0, 5.000001]).checksum());
        assert_ne!(stats.checksum, map(&[1.0, 0.0, 2.0, 5.0]).checksum());
        let mut flat = map(&[3.0; 4]);
        flat.normalize();
        assert_eq!(flat.values(), &[0.0; 4]);
    }

    #[test]
    fn sizes_are_bounded() {
        assert!(Heightmap::filled(0, 4, 0.0).is_err());
        assert!(Heightmap::filled(4, MAX_SIDE + 1, 0.0).is_err());
        assert!(Heightmap::filled(MAX_SIDE, 1, 0.0).is_ok());
        assert!(Heightmap::from_values(2, 2, vec![0.0; 3]).is_none());
        let m = Heightmap::from_fn(3, 2, |x, z| (x + 10 * z) as f32).unwrap();
        assert_eq!((m.at(2, 1), m.get(2, 1), m.get(3, 0), m.get(-1, 0)), (12.0, Some(12.0), None, None));
        assert_eq!(m.row(1), &[10.0, 11.0, 12.0]);
    }
}
