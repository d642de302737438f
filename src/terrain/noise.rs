//! Perlin gradient noise in two dimensions and its fractal sum (fBm), seeded and the same on
//! every machine.
//!
//! The noise is the source's: a seeded permutation of 256 entries hashes each lattice point to
//! one of 256 pseudo-random unit gradients; a sample is the dot products of its cell's four
//! corner gradients with the offsets from those corners, blended with the quintic fade
//! `6t^5 - 15t^4 + 10t^3`, first along x, then along z. It is zero at every lattice point and
//! its magnitude is at most `sqrt(2) / 2`.
//!
//! Two ways compute it. [`Perlin::sample`] is the reference: one point, the formula as written.
//! [`Fbm::fill_row`] is the fast path for a row of a grid: along a row `z` is fixed, so the
//! blend along z folds into two coefficients per lattice column, computed once per row and
//! octave; each sample then costs a fade and two multiply-adds, eight samples at a time in SIMD
//! lanes. Tests hold it to the reference within `1e-5`.
//!
//! Every number comes from integer hashing and `f32` additions and multiplications (the
//! gradients are normalised with `sqrt`, which IEEE 754 rounds exactly), so a seed gives the
//! same bits on every machine.

use crate::foundation::random::Random;
use wide::{f32x8, i32x8};

/// The lattice repeats every this many units.
const PERIOD: usize = 256;

/// One octave's tables: the permutation and the gradients.
#[derive(Debug, Clone)]
pub struct Perlin {
    /// A permutation of `0..256`, twice, so that a hash of two indices never wraps.
    permutation: [u8; 2 * PERIOD],
    /// Gradient x components, indexed by hash.
    gradient_x: [f32; PERIOD],
    /// Gradient z components, indexed by hash.
    gradient_z: [f32; PERIOD],
}

/// The quintic fade `6t^5 - 15t^4 + 10t^3`: 0 at 0, 1 at 1, flat to the second derivative at
/// both ends.
#[inline(always)]
pub fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline(always)]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + t * (b - a)
}

impl Perlin {
    /// The tables of `seed`: a Fisher-Yates shuffle of `0..256` and 256 unit vectors drawn
    /// uniformly in direction (points drawn in the unit disc, normalised).
    pub fn new(seed: u64) -> Self {
        let mut random = Random::new(seed);
        let mut order: [u8; PERIOD] = std::array::from_fn(|i| i as u8);
        for i in (1..PERIOD).rev() {
            order.swap(i, random.below(i as u32 + 1) as usize);
        }
        let mut permutation = [0; 2 * PERIOD];
        permutation[..PERIOD].copy_from_slice(&order);
        permutation[PERIOD..].copy_from_slice(&order);
        let (mut gradient_x, mut gradient_z) = ([0.0; PERIOD], [0.0; PERIOD]);
        for i in 0..PERIOD {
            let (x, z) = loop {
                let (x, z) = (random.between(-1.0, 1.0), random.between(-1.0, 1.0));
                let length_squared = x * x + z * z;
                if (1e-4..=1.0).contains(&length_squared) {
                    let length = length_squared.sqrt();
                    break (x / length, z / length);
                }
            };
            (gradient_x[i], gradient_z[i]) = (x, z);
        }
        Self { permutation, gradient_x, gradient_z }
    }

    /// The gradient index of lattice point `(x, z)`.
    #[inline(always)]
    fn hash(&self, x: i32, z: i32) -> usize {
        let column = self.permutation[(x & 255) as usize] as usize;
        self.permutation[column + (z & 255) as usize] as usize
    }

    /// The gradient at lattice point `(x, z)`.
    #[inline(always)]
    fn gradient(&self, x: i32, z: i32) -> (f32, f32) {
        let h = self.hash(x, z);
        (self.gradient_x[h], self.gradient_z[h])
    }

    /// The noise at `(x, z)` in lattice units: the reference formula.
    pub fn sample(&self, x: f32, z: f32) -> f32 {
        self.sample_wrapped(x, z, |xi, zi| (xi, zi))
    }

    /// The noise at `(x, z)` with the lattice repeating every `period_x` units along x and
    /// `period_z` along z (both > 0), for images that tile.
    pub fn sample_periodic(&self, x: f32, z: f32, period_x: i32, period_z: i32) -> f32 {
        self.sample_wrapped(x, z, |xi, zi| (xi.rem_euclid(period_x), zi.rem_euclid(period_z)))
    }

    /// The reference formula, with lattice points mapped by `wrap` before they are hashed.
    #[inline(always)]
    fn sample_wrapped(&self, x: f32, z: f32, wrap: impl Fn(i32, i32) -> (i32, i32)) -> f32 {
        let (x0, z0) = (x.floor(), z.floor());
        let (fx, fz) = (x - x0, z - z0);
        let (xi, zi) = (x0 as i32, z0 as i32);
        let gradient = |dx: i32, dz: i32| {
            let (x, z) = wrap(xi + dx, zi + dz);
            self.gradient(x, z)
        };
        let dot = |(gx, gz): (f32, f32), ox: f32, oz: f32| gx * ox + gz * oz;
        let n00 = dot(gradient(0, 0), fx, fz);
        let n10 = dot(gradient(1, 0), fx - 1.0, fz);
        let n01 = dot(gradient(0, 1), fx, fz - 1.0);
        let n11 = dot(gradient(1, 1), fx - 1.0, fz - 1.0);
        let (u, w) = (fade(fx), fade(fz));
        lerp(lerp(n00, n10, u), lerp(n01, n11, u), w)
    }
}

/// The libnoise-style fractal sum's parameters, with the source's defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FbmSettings {
    /// The seed of the first octave; octave `i` uses `seed + i`.
    pub seed: u64,
    /// Map samples per lattice unit of the first octave (> 0).
    pub scale: f32,
    /// Octaves summed (at least 1).
    pub octaves: u32,
    /// Frequency multiplier from one octave to the next.
    pub lacunarity: f32,
    /// Amplitude multiplier from one octave to the next.
    pub persistence: f32,
}

impl Default for FbmSettings {
    fn default() -> Self {
        Self { seed: 0, scale: 64.0, octaves: 1, lacunarity: 2.0, persistence: 0.5 }
    }
}

/// The most octaves a fractal sum takes: beyond this many, the finest octave is far below one
/// sample for any scale a map can use.
pub const MAX_OCTAVES: u32 = 16;

/// A fractal sum of Perlin octaves, mapped onto `[0, 1]`.
#[derive(Debug, Clone)]
pub struct Fbm {
    settings: FbmSettings,
    /// Each octave's tables, frequency (lattice units per sample) and amplitude.
    octaves: Vec<(Perlin, f32, f32)>,
    /// Turns the sum into `[0, 1]`: `sqrt(2) / 2` over the sum of the amplitudes.
    normalisation: f32,
}

impl Fbm {
    /// The fractal sum of `settings` (octaves are clamped to `1..=MAX_OCTAVES`).
    pub fn new(settings: FbmSettings) -> Self {
        let count = settings.octaves.clamp(1, MAX_OCTAVES);
        let (mut frequency, mut amplitude) = (1.0 / settings.scale, 1.0);
        let mut octaves = Vec::with_capacity(count as usize);
        for i in 0..count {
            octaves.push((Perlin::new(settings.seed.wrapping_add(u64::from(i))), frequency, amplitude));
            frequency *= settings.lacunarity;
            amplitude *= settings.persistence;
        }
        let total: f32 = octaves.iter().map(|o| o.2.abs()).sum();
        Self { settings, octaves, normalisation: std::f32::consts::SQRT_2 / total.max(f32::MIN_POSITIVE) }
    }

    /// The settings this sum was made with.
    pub fn settings(&self) -> FbmSettings {
        self.settings
    }

    /// The raw sum at map position `(x, z)`, by the reference formula.
    fn sum(&self, x: f32, z: f32) -> f32 {
        self.octaves
            .iter()
            .map(|(perlin, frequency, amplitude)| amplitude * perlin.sample(x * frequency, z * frequency))
            .sum()
    }

    /// The height at map position `(x, z)` (in samples) by the reference formula, in `[0, 1]`.
    pub fn sample(&self, x: f32, z: f32) -> f32 {
        self.to_unit(self.sum(x, z))
    }

    #[inline(always)]
    fn to_unit(&self, sum: f32) -> f32 {
        0.5 + 0.5 * self.normalisation * sum
    }

    /// The heights of samples `x0, x0 + 1, ...` of row `z` (map positions in samples) into
    /// `out`, the fast way: the same values as [`Fbm::sample`] within `1e-5`.
    pub fn fill_row(&self, x0: i32, z: i32, out: &mut [f32]) {
        self.fill_row_every(x0, 1, z, out);
    }

    /// [`Fbm::fill_row`] of every `step`-th sample (`step` > 0): `x0, x0 + step, ...`.
    ///
    /// A sample's value depends only on its position, never on the row it is part of: rows
    /// that share a position give it bit for bit, whatever their start, step or length, so
    /// that pieces of a world made apart meet exactly.
    pub fn fill_row_every(&self, x0: i32, step: i32, z: i32, out: &mut [f32]) {
        out.fill(0.0);
        let mut columns = Vec::new();
        for (perlin, frequency, amplitude) in &self.octaves {
            row_octave(perlin, *frequency, *amplitude, (x0, step.max(1)), z, out, &mut columns);
        }
        out.iter_mut().for_each(|v| *v = self.to_unit(*v));
    }
}

/// Adds one octave of noise along a row to `out`, at samples `x0 + k * step` of `(x0, step)`.
///
/// With `z` fixed, the blend along z of the two gradients of lattice column `j` is a linear
/// function of the offset along x, `slope_j * fx + offset_j`; a sample in cell `i` is then
/// `p + fade(fx) * (q - p)` with `p` from column `i` at `fx` and `q` from column `i + 1` at
/// `fx - 1`.
fn row_octave(
    perlin: &Perlin,
    frequency: f32,
    amplitude: f32,
    (x0, step): (i32, i32),
    z: i32,
    out: &mut [f32],
    columns: &mut Vec<[f32; 2]>,
) {
    let Some(last) = out.len().checked_sub(1) else { return };
    let nz = z as f32 * frequency;
    let z_floor = nz.floor();
    let (fz, zi) = (nz - z_floor, z_floor as i32);
    let w = fade(fz);
    // Whole sample positions are exact in `f32` (below 2^24): the lanes and the tail turn the
    // same number into the same float.
    let position = |k: usize| (x0 + k as i32 * step) as f32 * frequency;
    let first = position(0).floor() as i32;
    let end = position(last).floor() as i32 + 1;
    columns.clear();
    columns.extend((first..=end).map(|j| {
        let (gx0, gz0) = perlin.gradient(j, zi);
        let (gx1, gz1) = perlin.gradient(j, zi + 1);
        [lerp(gx0, gx1, w), lerp(gz0 * fz, gz1 * (fz - 1.0), w)]
    }));
    let columns = &columns[..];
    let column = |index: i32| columns[(index - first) as usize];

    let lanes = out.len() / 8 * 8;
    let lane_offsets = i32x8::from(std::array::from_fn::<i32, 8, _>(|k| k as i32 * step));
    for start in (0..lanes).step_by(8) {
        let x = (i32x8::splat(x0 + start as i32 * step) + lane_offsets).round_float() * f32x8::splat(frequency);
        // The baseline x86-64 target has no rounding instruction (and `floor` would call the C
        // library lane by lane): truncate, then step back down the lanes that truncation moved
        // up, the negative fractions (a true comparison is all ones, minus one as an integer).
        let truncated = x.fast_trunc_int();
        let moved_up: i32x8 = bytemuck::cast(x.simd_lt(truncated.round_float()));
        let whole = truncated + moved_up;
        let fx = x - whole.round_float();
        let cells = whole.to_array();
        let (mut slope0, mut offset0, mut slope1, mut offset1) = ([0.0; 8], [0.0; 8], [0.0; 8], [0.0; 8]);
        for lane in 0..8 {
            [slope0[lane], offset0[lane]] = column(cells[lane]);
            [slope1[lane], offset1[lane]] = column(cells[lane] + 1);
        }
        let p = f32x8::from(slope0) * fx + f32x8::from(offset0);
        let q = f32x8::from(slope1) * (fx - f32x8::ONE) + f32x8::from(offset1);
        let u = fx * fx * fx * (fx * (fx * f32x8::splat(6.0) - f32x8::splat(15.0)) + f32x8::splat(10.0));
        let noise = p + u * (q - p);
        let sums = f32x8::from(<[f32; 8]>::try_from(&out[start..start + 8]).unwrap_or_default());
        out[start..start + 8].copy_from_slice(&(sums + noise * f32x8::splat(amplitude)).to_array());
    }
    for (k, sum) in out.iter_mut().enumerate().skip(lanes) {
        let x = position(k);
        let floor = x.floor();
        let fx = x - floor;
        let cell = floor as i32;
        let ([slope0, offset0], [slope1, offset1]) = (column(cell), column(cell + 1));
        let (p, q) = (slope0 * fx + offset0, slope1 * (fx - 1.0) + offset1);
        *sum += amplitude * lerp(p, q, fade(fx));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn noise_is_zero_at_lattice_points_and_bounded() {
        let perlin = Perlin::new(7);
        for (x, z) in [(0, 0), (3, 9), (-4, 17), (255, 256), (-1000, 1000)] {
            assert_eq!(perlin.sample(x as f32, z as f32), 0.0, "({x}, {z})");
        }
        let bound = std::f32::consts::SQRT_2 / 2.0 + 1e-6;
        let mut largest = 0.0f32;
        for i in 0..200 {
            for j in 0..200 {
                let v = perlin.sample(i as f32 * 0.137, j as f32 * 0.091);
                assert!(v.abs() <= bound, "{v}");
                largest = largest.max(v.abs());
            }
        }
        assert!(largest > 0.3, "noise that varies: {largest}");
    }

    #[test]
    fn noise_is_continuous_across_cells() {
        let perlin = Perlin::new(3);
        for z in [0.25f32, 1.5, 7.75] {
            for x in [1.0f32, 2.0, 13.0] {
                let (left, right) = (perlin.sample(x - 1e-4, z), perlin.sample(x + 1e-4, z));
                assert!((left - right).abs() < 1e-3, "across x = {x}: {left} vs {right}");
                let (below, above) = (perlin.sample(z, x - 1e-4), perlin.sample(z, x + 1e-4));
                assert!((below - above).abs() < 1e-3, "across z = {x}: {below} vs {above}");
            }
        }
    }

    #[test]
    fn gradients_are_unit_vectors_and_tables_follow_the_seed() {
        let perlin = Perlin::new(11);
        for (x, z) in perlin.gradient_x.iter().zip(&perlin.gradient_z) {
            assert!((x * x + z * z - 1.0).abs() < 1e-6);
        }
        let mut sorted = perlin.permutation[..PERIOD].to_vec();
        sorted.sort_unstable();
        assert!(sorted.iter().enumerate().all(|(i, &v)| v as usize == i), "a permutation");
        assert_eq!(Perlin::new(11).permutation, perlin.permutation);
        assert_ne!(Perlin::new(12).permutation, perlin.permutation);
        // The value at a fixed point, from these tables: the same on every machine.
        let value = Perlin::new(11).sample(3.3, 4.6).to_bits();
        assert_eq!(value, Perlin::new(11).sample(3.3, 4.6).to_bits());
    }

    #[test]
    fn fade_has_its_endpoints_and_midpoint() {
        assert_eq!((fade(0.0), fade(0.5), fade(1.0)), (0.0, 0.5, 1.0));
    }

    proptest! {
        /// The fast row path gives the reference values within 1e-5, for any octaves, scales
        /// and positions, and rows of any length (lanes and the tail).
        #[test]
        fn rows_match_the_reference(
            seed in 0u64..1000,
            scale in 0.5f32..300.0,
            octaves in 1u32..7,
            lacunarity in 1.5f32..3.0,
            persistence in 0.2f32..0.9,
            x0 in -5000i32..5000,
            z in -5000i32..5000,
            length in 1usize..70,
        ) {
            let fbm = Fbm::new(FbmSettings { seed, scale, octaves, lacunarity, persistence });
            let mut row = vec![0.0; length];
            fbm.fill_row(x0, z, &mut row);
            for (k, &fast) in row.iter().enumerate() {
                let reference = fbm.sample((x0 + k as i32) as f32, z as f32);
                prop_assert!((fast - reference).abs() <= 1e-5, "sample {k}: {fast} vs {reference}");
                prop_assert!((-1e-5..=1.0 + 1e-5).contains(&fast));
            }
        }

        /// Rows give every sample they share bit for bit: rows starting elsewhere, of other
        /// lengths (a sample in the lanes of one and the tail of another) and every `step`-th
        /// sample of a row.
        #[test]
        fn a_sample_is_the_same_in_every_row(
            seed in 0u64..1000,
            scale in 0.5f32..300.0,
            octaves in 1u32..7,
            x0 in -5000i32..5000,
            z in -5000i32..5000,
            shift in 1usize..20,
            step in 2i32..9,
        ) {
            let fbm = Fbm::new(FbmSettings { seed, scale, octaves, ..FbmSettings::default() });
            let mut row = vec![0.0; 67];
            fbm.fill_row(x0, z, &mut row);
            let mut later = vec![0.0; 67 - shift];
            fbm.fill_row(x0 + shift as i32, z, &mut later);
            for (k, value) in later.iter().enumerate() {
                prop_assert_eq!(value.to_bits(), row[k + shift].to_bits(), "sample {}", k + shift);
            }
            let mut every = vec![0.0; 66 / step as usize + 1];
            fbm.fill_row_every(x0, step, z, &mut every);
            for (k, value) in every.iter().enumerate() {
                prop_assert_eq!(value.to_bits(), row[k * step as usize].to_bits(), "sample {}", k * step as usize);
            }
        }
    }
}
