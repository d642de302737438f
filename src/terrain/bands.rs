//! Height bands: WATER, SAND, GRASS, ROCK and SNOW, chosen per triangle by its mean height (the
//! source's rule) and, beyond the source, by its slope (steep faces are rock); optionally
//! blended smoothly across their borders by per-vertex weights; and the band textures the
//! project makes itself.

use super::noise::{FbmSettings, Perlin};
use bevy::math::Vec3;
use canopy_raster::Texture;
use serde::{Deserialize, Serialize};

/// A height band.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Band {
    /// Below the first threshold.
    Water,
    /// Beaches.
    Sand,
    /// Plains and hills.
    Grass,
    /// Mountains, and every face steeper than the rock slope.
    Rock,
    /// Above the last threshold.
    Snow,
}

impl Band {
    /// Every band, from the lowest.
    pub const ALL: [Band; 5] = [Band::Water, Band::Sand, Band::Grass, Band::Rock, Band::Snow];

    /// The band's name in scene files and dumps.
    pub fn key(self) -> &'static str {
        match self {
            Band::Water => "water",
            Band::Sand => "sand",
            Band::Grass => "grass",
            Band::Rock => "rock",
            Band::Snow => "snow",
        }
    }

    /// The band's place in [`Band::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// Where the bands meet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandRule {
    /// The heights (in map units) where sand, grass, rock and snow begin, rising.
    pub thresholds: [f32; 4],
    /// Faces steeper than this many degrees from horizontal are rock (sand and grass only:
    /// water stays flat, snow stays snow); `None` keeps the source's heights-only rule.
    pub rock_slope_deg: Option<f32>,
    /// How bands fade into each other; `None` for the source's hard borders along triangle
    /// edges.
    pub blend: Option<BandBlend>,
}

impl Default for BandRule {
    fn default() -> Self {
        Self { thresholds: [0.3, 0.36, 0.62, 0.8], rock_slope_deg: None, blend: None }
    }
}

/// How far on either side of a border two bands are mixed.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BandBlend {
    /// Half the height range, in map units, over which the bands on either side of a
    /// threshold are mixed.
    pub height: f32,
    /// Half the range of slopes, in degrees, over which sand and grass turn to rock (with a
    /// rock slope); 5 by default.
    #[serde(default = "default_slope_blend")]
    pub slope_deg: f32,
}

fn default_slope_blend() -> f32 {
    5.0
}

/// `3t^2 - 2t^3` of `t` clamped to `[0, 1]`: a ramp with level ends.
fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl BandRule {
    /// The band of a triangle of mean map height `height` whose unit normal has vertical
    /// component `up` (the cosine of its slope). A height exactly at a threshold is in the
    /// band above it.
    pub fn band(&self, height: f32, up: f32) -> Band {
        let by_height = Band::ALL[self.thresholds.iter().take_while(|&&t| height >= t).count()];
        match (by_height, self.rock_slope_deg) {
            (Band::Sand | Band::Grass, Some(slope)) if up < slope.to_radians().cos() => Band::Rock,
            _ => by_height,
        }
    }

    /// How much of each band (in [`Band::ALL`] order) shows at a vertex of map height
    /// `height` whose unit normal has vertical component `up`, with blending: weights that sum
    /// to one and change smoothly with height and slope. Across each threshold the band above
    /// rises from 0 to 1 over `blend.height` on either side; with a rock slope, sand and grass
    /// give way to rock likewise over `blend.slope_deg` on either side of it. Without blending,
    /// all of the vertex's band by [`BandRule::band`].
    pub fn weights(&self, height: f32, up: f32) -> [f32; 5] {
        let Some(blend) = self.blend else {
            let mut weights = [0.0; 5];
            weights[self.band(height, up).index()] = 1.0;
            return weights;
        };
        // How far past each threshold the vertex is: falling from threshold to threshold.
        let past = self.thresholds.map(|t| smoothstep((height - t + blend.height) / (2.0 * blend.height)));
        let mut weights: [f32; 5] = std::array::from_fn(|k| {
            let above_lower = if k == 0 { 1.0 } else { past[k - 1] };
            let above_upper = past.get(k).copied().unwrap_or(0.0);
            (above_lower - above_upper).max(0.0)
        });
        if let Some(slope) = self.rock_slope_deg {
            let steepness = up.clamp(-1.0, 1.0).acos().to_degrees();
            let rock = smoothstep((steepness - slope + blend.slope_deg) / (2.0 * blend.slope_deg));
            for band in [Band::Sand, Band::Grass] {
                let moved = weights[band.index()] * rock;
                weights[band.index()] -= moved;
                weights[Band::Rock.index()] += moved;
            }
        }
        weights
    }

    /// Why the thresholds or the slope make no sense, if they do not.
    pub fn check(&self) -> Result<(), String> {
        let rising = self.thresholds.windows(2).all(|w| w[0] <= w[1]);
        if !(self.thresholds.iter().all(|t| t.is_finite()) && rising) {
            return Err(format!("thresholds: expected four rising heights, found {:?}", self.thresholds));
        }
        if let Some(slope) = self.rock_slope_deg
            && !(slope.is_finite() && slope > 0.0 && slope < 90.0)
        {
            return Err(format!("rock_slope_deg: expected an angle greater than 0 and less than 90, found {slope}"));
        }
        match self.blend {
            Some(BandBlend { height, .. }) if !(height.is_finite() && height > 0.0 && height <= 0.5) => {
                Err(format!("blend.height: expected a height greater than 0 and at most 0.5, found {height}"))
            }
            Some(BandBlend { slope_deg, .. }) if !(slope_deg.is_finite() && slope_deg > 0.0 && slope_deg <= 45.0) => {
                Err(format!("blend.slope_deg: expected an angle greater than 0 and at most 45, found {slope_deg}"))
            }
            _ => Ok(()),
        }
    }
}

/// Texels a side of the project's band textures.
pub const TEXTURE_SIDE: u32 = 128;

/// The project's texture of `band`: two colours mixed by tiling noise, `TEXTURE_SIDE` texels a
/// side, the same on every machine.
pub fn band_texture(band: Band) -> Texture {
    // (dark, light, lattice cells across the tile, octaves, stretch along v)
    let (dark, light, cells, octaves, stretch) = match band {
        Band::Water => (Vec3::new(0.05, 0.18, 0.38), Vec3::new(0.16, 0.42, 0.62), 4, 3, 3),
        Band::Sand => (Vec3::new(0.72, 0.63, 0.42), Vec3::new(0.9, 0.83, 0.62), 16, 3, 1),
        Band::Grass => (Vec3::new(0.15, 0.36, 0.09), Vec3::new(0.38, 0.6, 0.2), 8, 4, 1),
        Band::Rock => (Vec3::new(0.3, 0.28, 0.26), Vec3::new(0.6, 0.58, 0.55), 4, 5, 1),
        Band::Snow => (Vec3::new(0.8, 0.84, 0.9), Vec3::new(0.98, 0.98, 1.0), 4, 3, 1),
    };
    let octave_tables: Vec<Perlin> = (0..octaves).map(|o| Perlin::new(band.index() as u64 * 31 + o)).collect();
    let settings = FbmSettings::default();
    Texture::from_fn(TEXTURE_SIDE, TEXTURE_SIDE, |x, y| {
        let (mut sum, mut amplitude, mut total) = (0.0, 1.0, 0.0);
        for (octave, perlin) in octave_tables.iter().enumerate() {
            let period = cells << octave;
            let per_texel = period as f32 / TEXTURE_SIDE as f32;
            let (u, v) = (x as f32 * per_texel, y as f32 * per_texel);
            sum += amplitude * perlin.sample_periodic(u, v * stretch as f32, period, period * stretch);
            total += amplitude;
            amplitude *= settings.persistence;
        }
        let t = (0.5 + sum / total * std::f32::consts::SQRT_2).clamp(0.0, 1.0);
        dark.lerp(light, t)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::math::Vec2;
    use canopy_raster::{Address, Filter, Sampler};

    #[test]
    fn heights_at_a_threshold_belong_to_the_band_above() {
        let rule = BandRule::default();
        let [sand, grass, rock, snow] = rule.thresholds;
        assert_eq!(rule.band(sand - 1e-6, 1.0), Band::Water);
        assert_eq!(rule.band(sand, 1.0), Band::Sand);
        assert_eq!(rule.band(grass, 1.0), Band::Grass);
        assert_eq!(rule.band(rock - 1e-6, 1.0), Band::Grass);
        assert_eq!(rule.band(rock, 1.0), Band::Rock);
        assert_eq!(rule.band(snow, 1.0), Band::Snow);
        assert_eq!(rule.band(-5.0, 1.0), Band::Water);
        assert_eq!(rule.band(5.0, 1.0), Band::Snow);
    }

    #[test]
    fn steep_sand_and_grass_turn_to_rock() {
        let rule = BandRule { rock_slope_deg: Some(40.0), ..BandRule::default() };
        let steep = 50f32.to_radians().cos();
        let gentle = 30f32.to_radians().cos();
        assert_eq!(rule.band(0.5, steep), Band::Rock);
        assert_eq!(rule.band(0.5, gentle), Band::Grass);
        assert_eq!(rule.band(0.1, steep), Band::Water);
        assert_eq!(rule.band(0.9, steep), Band::Snow);
        assert_eq!(BandRule::default().band(0.5, steep), Band::Grass, "the source's rule: heights only");
        assert!(BandRule { thresholds: [0.5, 0.4, 0.6, 0.7], ..rule }.check().is_err());
        assert!(BandRule { rock_slope_deg: Some(90.0), ..rule }.check().is_err());
    }

    #[test]
    fn blend_weights_sum_to_one_and_ramp_across_each_border() {
        let blend = BandBlend { height: 0.02, slope_deg: 5.0 };
        let rule = BandRule { rock_slope_deg: Some(40.0), blend: Some(blend), ..BandRule::default() };
        let flat = 1.0;
        for k in 0..=200 {
            let height = k as f32 / 200.0;
            for up in [1.0, 0.8, 0.77, 0.7, 0.2] {
                let weights = rule.weights(height, up);
                assert!((weights.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{height} {up}: {weights:?}");
                assert!(weights.iter().all(|w| (0.0..=1.0).contains(w)));
            }
        }
        // Halfway at a threshold, the band alone beyond the blend.
        let [sand, grass, ..] = rule.thresholds;
        let at = rule.weights(grass, flat);
        assert!((at[Band::Sand.index()] - 0.5).abs() < 1e-6 && (at[Band::Grass.index()] - 0.5).abs() < 1e-6);
        assert_eq!(rule.weights(grass + 0.021, flat)[Band::Grass.index()], 1.0);
        assert_eq!(rule.weights(sand - 0.021, flat)[Band::Water.index()], 1.0);
        // Across the rock slope grass turns to rock by degrees; snow stays snow.
        let steep = |degrees: f32| rule.weights(0.5, degrees.to_radians().cos())[Band::Rock.index()];
        assert_eq!((steep(34.0), steep(46.0)), (0.0, 1.0));
        assert!((steep(40.0) - 0.5).abs() < 1e-4 && steep(38.0) < steep(42.0));
        assert_eq!(rule.weights(0.95, 0.2)[Band::Snow.index()], 1.0);
        // Without blending, a vertex is its band alone.
        let hard = BandRule { blend: None, ..rule };
        assert_eq!(hard.weights(0.5, flat), [0.0, 0.0, 1.0, 0.0, 0.0]);
        // Blends too wide or not positive are refused.
        assert!(BandRule { blend: Some(BandBlend { height: 0.0, ..blend }), ..rule }.check().is_err());
        assert!(BandRule { blend: Some(BandBlend { slope_deg: 60.0, ..blend }), ..rule }.check().is_err());
        assert!(rule.check().is_ok());
    }

    #[test]
    fn band_textures_tile_and_differ() {
        let sampler = Sampler { filter: Filter::Nearest, address: Address::Repeat };
        let mut means = Vec::new();
        for band in Band::ALL {
            let texture = band_texture(band);
            let texel = |x: u32, y: u32| {
                texture.sample(Vec2::new(x as f32 + 0.5, y as f32 + 0.5) / TEXTURE_SIDE as f32, sampler)
            };
            // Opposite edges continue each other: neighbours across the seam differ no more
            // than neighbours inside the tile do.
            let last = TEXTURE_SIDE - 1;
            let across: f32 = (0..TEXTURE_SIDE).map(|y| texel(last, y).distance(texel(0, y))).sum();
            let inside: f32 = (0..TEXTURE_SIDE).map(|y| texel(last - 1, y).distance(texel(last, y))).sum();
            assert!(across <= 2.0 * inside + 0.05, "{band:?}: across {across}, inside {inside}");
            let mean = (0..TEXTURE_SIDE)
                .flat_map(|y| (0..TEXTURE_SIDE).map(move |x| (x, y)))
                .map(|(x, y)| texel(x, y))
                .sum::<Vec3>();
            means.push(mean / (TEXTURE_SIDE * TEXTURE_SIDE) as f32);
        }
        for (i, a) in means.iter().enumerate() {
            for b in &means[i + 1..] {
                assert!(a.distance(*b) > 0.08, "bands look alike: {a} vs {b}");
            }
        }
    }
}
