//! Heightmap generators and the recipe that combines them: fBm Perlin noise (the source's
//! choice), diamond-square and the hill algorithm (the alternatives it analysed), layered with
//! the map algebra.
//!
//! A [`Recipe`] is what a scene file's `height:` holds when the heights are generated: a size,
//! a seed and a list of [`Layer`]s. Each layer is one generator, then its own functions
//! ([`Function`]), then a weight; the first layer starts the map and each later one is
//! combined into it by its [`Op`]; the recipe's own functions come last. Plains, hills and
//! mountains are mixed this way: broad low-octave noise, finer noise added at a small weight,
//! the sum raised to a power to flatten the valleys.

use super::heightmap::{Heightmap, MAX_SIDE, SizeError, check_size};
use super::noise::{Fbm, FbmSettings, MAX_OCTAVES};
use crate::foundation::random::Random;
use serde::{Deserialize, Serialize};

/// Fractal Perlin noise: the libnoise-style parameters with the source's defaults.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PerlinLayer {
    /// Map samples per lattice unit of the first octave; 64 by default.
    #[serde(default = "default_scale")]
    pub scale: f32,
    /// Octaves summed, 1 to 16; 1 by default.
    #[serde(default = "one_octave")]
    pub octaves: u32,
    /// Frequency multiplier per octave; 2 by default.
    #[serde(default = "two")]
    pub lacunarity: f32,
    /// Amplitude multiplier per octave; 0.5 by default.
    #[serde(default = "half")]
    pub persistence: f32,
}

impl Default for PerlinLayer {
    fn default() -> Self {
        Self { scale: default_scale(), octaves: one_octave(), lacunarity: two(), persistence: half() }
    }
}

/// Midpoint displacement on the smallest `2^n + 1` square grid that holds the map, cropped.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiamondSquareLayer {
    /// How much of the displacement each finer level keeps, in `(0, 1]`: small values give
    /// smooth ground, 1 gives rough; 0.5 by default.
    #[serde(default = "half")]
    pub roughness: f32,
}

/// Random paraboloids `R^2 - d^2` (negative parts ignored), summed, normalised, squared.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HillsLayer {
    /// Hills raised, 1 to 100000; 200 by default.
    #[serde(default = "default_hills")]
    pub count: u32,
    /// Smallest and largest radius, in samples; `[4, 32]` by default.
    #[serde(default = "default_radius")]
    pub radius: [f32; 2],
}

fn default_scale() -> f32 {
    64.0
}
fn one_octave() -> u32 {
    1
}
fn two() -> f32 {
    2.0
}
fn half() -> f32 {
    0.5
}
fn one() -> f32 {
    1.0
}
fn default_hills() -> u32 {
    200
}
fn default_radius() -> [f32; 2] {
    [4.0, 32.0]
}

/// How a layer is combined into the map made by the layers before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Op {
    /// The sum.
    #[default]
    Add,
    /// The map minus the layer.
    Subtract,
    /// The product.
    Multiply,
    /// The lower of the two.
    Min,
    /// The higher of the two.
    Max,
}

impl Op {
    fn apply(self, a: f32, b: f32) -> f32 {
        match self {
            Op::Add => a + b,
            Op::Subtract => a - b,
            Op::Multiply => a * b,
            Op::Min => a.min(b),
            Op::Max => a.max(b),
        }
    }
}

/// A function applied to every height.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Function {
    /// Stretch linearly onto `[0, 1]`.
    Normalize,
    /// `1 - h`.
    Invert,
    /// `|h|`.
    Abs,
    /// `h^p` of `max(h, 0)` (squaring flattens valleys and sharpens peaks).
    Power(f32),
    /// `n` flat steps with steep rises between them: `(floor(h n) + frac(h n)^4) / n`.
    Terraces(u32),
    /// Clamp into `[low, high]`.
    Clamp([f32; 2]),
    /// Multiply by a number.
    Scale(f32),
    /// Add a number.
    Offset(f32),
}

impl Function {
    /// Applies the function to every height of `map`.
    pub fn apply(self, map: &mut Heightmap) {
        match self {
            Function::Normalize => map.normalize(),
            function => map.apply(|h| function.of_height(h).unwrap_or(h)),
        }
    }

    /// The function of one height `h`; `None` for `normalize`, which needs the whole map.
    pub fn of_height(self, h: f32) -> Option<f32> {
        Some(match self {
            Function::Normalize => return None,
            Function::Invert => 1.0 - h,
            Function::Abs => h.abs(),
            Function::Power(p) => h.max(0.0).powf(p),
            Function::Terraces(n) => {
                let (n, t) = (n as f32, h * n as f32);
                (t.floor() + t.fract().powi(4)) / n
            }
            Function::Clamp([low, high]) => h.clamp(low, high),
            Function::Scale(k) => h * k,
            Function::Offset(c) => h + c,
        })
    }

    /// Why the function's number makes no sense, if it does not.
    pub fn check(self) -> Result<(), String> {
        let finite = |v: f32| v.is_finite() && v.abs() <= 1e6;
        match self {
            Function::Power(p) if !(finite(p) && p > 0.0 && p <= 64.0) => {
                Err(format!("power: expected an exponent greater than 0 and at most 64, found {p}"))
            }
            Function::Terraces(n) if !(1..=1000).contains(&n) => {
                Err(format!("terraces: expected 1 to 1000 steps, found {n}"))
            }
            Function::Clamp([low, high]) if !(finite(low) && finite(high) && low <= high) => {
                Err(format!("clamp: expected [low, high] with low <= high, found [{low}, {high}]"))
            }
            Function::Scale(v) | Function::Offset(v) if !finite(v) => {
                Err(format!("expected a number between -1e6 and 1e6, found {v}"))
            }
            _ => Ok(()),
        }
    }
}

/// One generator, exactly one of the three fields.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Layer {
    /// Fractal Perlin noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perlin: Option<PerlinLayer>,
    /// Diamond-square midpoint displacement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diamond_square: Option<DiamondSquareLayer>,
    /// The hill algorithm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hills: Option<HillsLayer>,
    /// How the layer joins the map so far (`add` by default; the first layer starts it).
    #[serde(default)]
    pub op: Op,
    /// The layer's heights are multiplied by this before they are combined; 1 by default.
    #[serde(default = "one")]
    pub weight: f32,
    /// Functions applied to the layer alone, in order, before its weight.
    #[serde(default, with = "serde_yaml::with::singleton_map_recursive", skip_serializing_if = "Vec::is_empty")]
    pub apply: Vec<Function>,
}

impl Default for Layer {
    /// No generator yet, added at weight 1 with no functions.
    fn default() -> Self {
        Self { perlin: None, diamond_square: None, hills: None, op: Op::Add, weight: 1.0, apply: Vec::new() }
    }
}

/// The generator of a [`Layer`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Generator {
    /// Fractal Perlin noise.
    Perlin(PerlinLayer),
    /// Diamond-square.
    DiamondSquare(DiamondSquareLayer),
    /// The hill algorithm.
    Hills(HillsLayer),
}

impl Generator {
    /// The generator's name in scene files.
    pub fn key(self) -> &'static str {
        match self {
            Generator::Perlin(_) => "perlin",
            Generator::DiamondSquare(_) => "diamond_square",
            Generator::Hills(_) => "hills",
        }
    }
}

/// A generated heightmap: its size, seed and layers.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    /// Samples along x and z, each 1 to 4096.
    pub size: [u32; 2],
    /// The seed; -1 (the default) draws one, which is printed and dumped so that the map can
    /// be made again.
    #[serde(default = "random_seed")]
    pub seed: i64,
    /// The layers, at least one.
    pub layers: Vec<Layer>,
    /// Functions applied to the combined map, in order.
    #[serde(default, with = "serde_yaml::with::singleton_map_recursive", skip_serializing_if = "Vec::is_empty")]
    pub apply: Vec<Function>,
}

fn random_seed() -> i64 {
    -1
}

/// A recipe's mistake: the field at fault (a path below the recipe, as `layers[1].hills`) and
/// why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct RecipeError {
    /// The field's path below the recipe.
    pub field: String,
    /// The key naming that field in the file, to find its line.
    pub key: &'static str,
    /// Which occurrence of `key` within the recipe, from 0.
    pub nth: usize,
    /// What is wrong.
    pub message: String,
}

/// The most work the hill algorithm may be asked for: hills times the samples each touches.
const MAX_HILL_WORK: f64 = 4.0e8;

impl Layer {
    /// The layer's generator, or why it has none or several.
    pub fn generator(&self) -> Result<Generator, String> {
        let given: Vec<Generator> = [
            self.perlin.map(Generator::Perlin),
            self.diamond_square.map(Generator::DiamondSquare),
            self.hills.map(Generator::Hills),
        ]
        .into_iter()
        .flatten()
        .collect();
        match given[..] {
            [one] => Ok(one),
            [] => Err("a layer needs a generator: perlin, diamond_square or hills".into()),
            _ => Err(format!(
                "a layer has one generator, this one has {}",
                given.iter().map(|g| g.key()).collect::<Vec<_>>().join(" and ")
            )),
        }
    }
}

/// Bits of a drawn seed: few enough that the seed, as a parameter (a double), stays exact and
/// one more is another seed.
pub const DRAWN_SEED_BITS: u32 = 52;

impl Recipe {
    /// Every check of the recipe, with the field at fault. `seed` is checked too: -1 or a
    /// non-negative number.
    pub fn check(&self) -> Result<(), RecipeError> {
        let error =
            |field: String, key: &'static str, nth: usize, message: String| RecipeError { field, key, nth, message };
        let [width, height] = self.size;
        check_size(width, height).map_err(|e| error("size".into(), "size", 0, e.to_string()))?;
        if self.seed < -1 {
            return Err(error(
                "seed".into(),
                "seed",
                0,
                format!("expected -1 (a random seed) or a seed of 0 or more, found {}", self.seed),
            ));
        }
        if self.layers.is_empty() {
            return Err(error("layers".into(), "layers", 0, "a recipe needs at least one layer".into()));
        }
        let (mut perlins, mut squares, mut hills, mut applies) = (0, 0, 0, 0);
        for (index, layer) in self.layers.iter().enumerate() {
            let field = |name: &str| format!("layers[{index}].{name}");
            let generator = layer.generator().map_err(|m| error(format!("layers[{index}]"), "layers", 0, m))?;
            let checked = match generator {
                Generator::Perlin(p) => {
                    perlins += 1;
                    check_perlin(p).map_err(|m| error(field("perlin"), "perlin", perlins - 1, m))
                }
                Generator::DiamondSquare(d) => {
                    squares += 1;
                    let valid = d.roughness.is_finite() && d.roughness > 0.0 && d.roughness <= 1.0;
                    (if valid {
                        Ok(())
                    } else {
                        Err(format!("roughness: expected a number greater than 0 and at most 1, found {}", d.roughness))
                    })
                    .map_err(|m| error(field("diamond_square"), "diamond_square", squares - 1, m))
                }
                Generator::Hills(h) => {
                    hills += 1;
                    check_hills(h, width, height).map_err(|m| error(field("hills"), "hills", hills - 1, m))
                }
            };
            checked?;
            if index == 0 && layer.op != Op::Add {
                return Err(error(field("op"), "op", 0, "the first layer starts the map: it takes no `op`".into()));
            }
            if !(layer.weight.is_finite() && layer.weight.abs() <= 1e6) {
                // The layers before that give a weight (one of 1, the default, is not told
                // from none).
                let written = self.layers[..index].iter().filter(|l| l.weight != 1.0).count();
                return Err(error(
                    field("weight"),
                    "weight",
                    written,
                    format!("expected a number between -1e6 and 1e6, found {}", layer.weight),
                ));
            }
            for function in &layer.apply {
                function.check().map_err(|m| error(field("apply"), "apply", applies, m))?;
            }
            applies += usize::from(!layer.apply.is_empty());
        }
        for function in &self.apply {
            function.check().map_err(|m| error("apply".into(), "apply", applies, m))?;
        }
        Ok(())
    }

    /// The seed the map is made with: the recipe's, or one drawn from `draw` for -1 (kept to
    /// [`DRAWN_SEED_BITS`] bits).
    pub fn seed_used(&self, draw: impl FnOnce() -> u64) -> u64 {
        u64::try_from(self.seed).unwrap_or_else(|_| draw() >> (64 - DRAWN_SEED_BITS))
    }

    /// Why this recipe cannot make an unbounded world, if it cannot: every height must follow
    /// from its own position alone, so the layers are Perlin noise (diamond-square and the
    /// hills are made for a whole finite map) and no function is `normalize` (which needs the
    /// whole map's range).
    pub fn check_unbounded(&self) -> Result<(), RecipeError> {
        let error = |field: String, key: &'static str, nth: usize, message: &str| RecipeError {
            field,
            key,
            nth,
            message: format!(
                "{message}: an unbounded world is made piece by piece, each height from its position alone \
                 (a finite world's `map` may use it)"
            ),
        };
        let mut applies = 0;
        for (index, layer) in self.layers.iter().enumerate() {
            // The first such layer is the first of its key in the recipe.
            let field = format!("layers[{index}]");
            match layer.generator() {
                Ok(Generator::DiamondSquare(_)) => {
                    return Err(error(field, "diamond_square", 0, "diamond-square needs a whole map"));
                }
                Ok(Generator::Hills(_)) => {
                    return Err(error(field, "hills", 0, "the hill algorithm needs a whole map"));
                }
                _ => {}
            }
            if layer.apply.contains(&Function::Normalize) {
                return Err(error(format!("layers[{index}].apply"), "apply", applies, "normalize needs a whole map"));
            }
            applies += usize::from(!layer.apply.is_empty());
        }
        if self.apply.contains(&Function::Normalize) {
            return Err(error("apply".into(), "apply", applies, "normalize needs a whole map"));
        }
        Ok(())
    }

    /// The heights of this recipe (checked, and unbounded by [`Recipe::check_unbounded`]) with
    /// `seed` at the world samples `(x0 + i * step, z0 + j * step)` for `i < width`,
    /// `j < depth`, row by row. A sample's height depends on its position alone: grids that
    /// share a sample give it bit for bit.
    pub fn sample_grid(&self, seed: u64, origin: [i32; 2], step: i32, size: [usize; 2]) -> Vec<f32> {
        self.sample_grid_with(&self.noises(seed), origin, step, size)
    }

    /// Each layer's fractal sum for `seed` (none for a layer without Perlin noise): what
    /// [`sample_grid_with`](Self::sample_grid_with) samples, made once for many small grids
    /// (making them costs far more than sampling a few points).
    pub fn noises(&self, seed: u64) -> Vec<Option<Fbm>> {
        let noise =
            |(index, layer): (usize, &Layer)| layer.perlin.map(|p| Fbm::new(fbm_settings(p, layer_seed(seed, index))));
        self.layers.iter().enumerate().map(noise).collect()
    }

    /// [`sample_grid`](Self::sample_grid) with the layers' `noises` made already.
    pub fn sample_grid_with(
        &self,
        noises: &[Option<Fbm>],
        [x0, z0]: [i32; 2],
        step: i32,
        [width, depth]: [usize; 2],
    ) -> Vec<f32> {
        let step = step.max(1);
        let mut grid = vec![0.0; width * depth];
        let mut layer_heights = vec![0.0; width * depth];
        for ((index, layer), fbm) in self.layers.iter().enumerate().zip(noises) {
            let Some(fbm) = fbm else { continue };
            for (j, row) in layer_heights.chunks_exact_mut(width.max(1)).enumerate() {
                fbm.fill_row_every(x0, step, z0 + j as i32 * step, row);
            }
            for (sum, &h) in grid.iter_mut().zip(&layer_heights) {
                let h = layer.apply.iter().fold(h, |h, f| f.of_height(h).unwrap_or(h)) * layer.weight;
                *sum = if index == 0 { h } else { layer.op.apply(*sum, h) };
            }
        }
        for h in &mut grid {
            *h = self.apply.iter().fold(*h, |h, f| f.of_height(h).unwrap_or(h));
        }
        grid
    }

    /// The map of this (checked) recipe with `seed`.
    pub fn generate(&self, seed: u64) -> Result<Heightmap, SizeError> {
        let [width, height] = self.size;
        let mut map: Option<Heightmap> = None;
        for (index, layer) in self.layers.iter().enumerate() {
            let layer_seed = layer_seed(seed, index);
            let mut heights = match layer.generator() {
                Ok(Generator::Perlin(p)) => perlin(p, layer_seed, width, height)?,
                Ok(Generator::DiamondSquare(d)) => diamond_square(d, layer_seed, width, height)?,
                Ok(Generator::Hills(h)) => hills(h, layer_seed, width, height)?,
                Err(_) => Heightmap::filled(width, height, 0.0)?,
            };
            layer.apply.iter().for_each(|f| f.apply(&mut heights));
            if layer.weight != 1.0 {
                let weight = layer.weight;
                heights.apply(|h| h * weight);
            }
            match &mut map {
                None => map = Some(heights),
                Some(map) => map.combine(&heights, |a, b| layer.op.apply(a, b))?,
            }
        }
        let mut map = match map {
            Some(map) => map,
            None => Heightmap::filled(width, height, 0.0)?,
        };
        self.apply.iter().for_each(|f| f.apply(&mut map));
        Ok(map)
    }
}

fn check_perlin(p: PerlinLayer) -> Result<(), String> {
    if !(p.scale.is_finite() && p.scale > 0.0 && p.scale <= 1e6) {
        return Err(format!(
            "scale: expected samples per lattice unit greater than 0 and at most 1e6, found {}",
            p.scale
        ));
    }
    if !(1..=MAX_OCTAVES).contains(&p.octaves) {
        return Err(format!("octaves: expected 1 to {MAX_OCTAVES}, found {}", p.octaves));
    }
    if !(p.lacunarity.is_finite() && p.lacunarity > 0.0 && p.lacunarity <= 16.0) {
        return Err(format!("lacunarity: expected a number greater than 0 and at most 16, found {}", p.lacunarity));
    }
    if !(p.persistence.is_finite() && p.persistence > 0.0 && p.persistence <= 4.0) {
        return Err(format!("persistence: expected a number greater than 0 and at most 4, found {}", p.persistence));
    }
    Ok(())
}

fn check_hills(h: HillsLayer, width: u32, height: u32) -> Result<(), String> {
    if !(1..=100_000).contains(&h.count) {
        return Err(format!("count: expected 1 to 100000 hills, found {}", h.count));
    }
    let [low, high] = h.radius;
    let limit = MAX_SIDE as f32;
    if !(low.is_finite() && high.is_finite() && low > 0.0 && low <= high && high <= limit) {
        return Err(format!(
            "radius: expected [smallest, largest] with 0 < smallest <= largest <= {limit}, found [{low}, {high}]"
        ));
    }
    let touched = f64::from(2.0 * high + 1.0).powi(2).min(f64::from(width) * f64::from(height));
    if f64::from(h.count) * touched > MAX_HILL_WORK {
        return Err(format!(
            "{} hills of radius up to {high} are too much work for one map; use fewer or smaller hills",
            h.count
        ));
    }
    Ok(())
}

/// The seed of layer `index` of a recipe with `seed`: layers draw from streams far apart, so
/// that no two share an octave's tables.
fn layer_seed(seed: u64, index: usize) -> u64 {
    seed.wrapping_add((index as u64).wrapping_mul(0x1_0000))
}

/// The fractal sum of a Perlin layer with `seed`.
fn fbm_settings(layer: PerlinLayer, seed: u64) -> FbmSettings {
    FbmSettings {
        seed,
        scale: layer.scale,
        octaves: layer.octaves,
        lacunarity: layer.lacunarity,
        persistence: layer.persistence,
    }
}

/// Fractal Perlin noise of `width x height` samples, in `[0, 1]`.
pub fn perlin(layer: PerlinLayer, seed: u64, width: u32, height: u32) -> Result<Heightmap, SizeError> {
    let fbm = Fbm::new(fbm_settings(layer, seed));
    let mut map = Heightmap::filled(width, height, 0.0)?;
    for (z, row) in map.values_mut().chunks_exact_mut(width as usize).enumerate() {
        fbm.fill_row(0, z as i32, row);
    }
    Ok(map)
}

/// Diamond-square of `width x height` samples, normalised to `[0, 1]`.
pub fn diamond_square(layer: DiamondSquareLayer, seed: u64, width: u32, height: u32) -> Result<Heightmap, SizeError> {
    check_size(width, height)?;
    let side = (width.max(height) - 1).max(1).next_power_of_two() as usize + 1;
    let mut random = Random::new(seed);
    let mut grid = vec![0.0f32; side * side];
    let last = side - 1;
    for (x, z) in [(0, 0), (last, 0), (0, last), (last, last)] {
        grid[z * side + x] = random.between(-1.0, 1.0);
    }
    let mut amplitude = 1.0;
    let mut step = last;
    while step > 1 {
        let half = step / 2;
        // Diamond: the centre of each square from its four corners.
        for z in (half..side).step_by(step) {
            for x in (half..side).step_by(step) {
                let corners = grid[(z - half) * side + x - half]
                    + grid[(z - half) * side + x + half]
                    + grid[(z + half) * side + x - half]
                    + grid[(z + half) * side + x + half];
                grid[z * side + x] = corners / 4.0 + random.between(-amplitude, amplitude);
            }
        }
        // Square: the midpoint of each edge from its (three or four) neighbours.
        for z in (0..side).step_by(half) {
            let first = if (z / half).is_multiple_of(2) { half } else { 0 };
            for x in (first..side).step_by(step) {
                let neighbours = [
                    (x >= half).then(|| grid[z * side + x - half]),
                    (x + half < side).then(|| grid[z * side + x + half]),
                    (z >= half).then(|| grid[(z - half) * side + x]),
                    (z + half < side).then(|| grid[(z + half) * side + x]),
                ];
                let (sum, count) = neighbours.iter().flatten().fold((0.0, 0.0), |(s, c), v| (s + v, c + 1.0));
                grid[z * side + x] = sum / count + random.between(-amplitude, amplitude);
            }
        }
        amplitude *= layer.roughness;
        step = half;
    }
    let mut map = Heightmap::from_fn(width, height, |x, z| grid[z as usize * side + x as usize])?;
    map.normalize();
    Ok(map)
}

/// The hill algorithm on `width x height` samples: summed paraboloids, normalised, squared.
pub fn hills(layer: HillsLayer, seed: u64, width: u32, height: u32) -> Result<Heightmap, SizeError> {
    let mut map = Heightmap::filled(width, height, 0.0)?;
    let mut random = Random::new(seed);
    let [low, high] = layer.radius;
    for _ in 0..layer.count {
        let (cx, cz) = (random.between(0.0, width as f32), random.between(0.0, height as f32));
        let radius = random.between(low, high.max(low));
        let r2 = radius * radius;
        let span = |c: f32, size: u32| {
            let first = (c - radius).floor().max(0.0) as u32;
            let last = ((c + radius).ceil() as u32).min(size - 1);
            first..=last
        };
        for z in span(cz, height) {
            let dz = z as f32 - cz;
            let row = z as usize * width as usize;
            for x in span(cx, width) {
                let dx = x as f32 - cx;
                let raise = r2 - (dx * dx + dz * dz);
                if raise > 0.0 {
                    map.values_mut()[row + x as usize] += raise;
                }
            }
        }
    }
    map.normalize();
    map.apply(|h| h * h);
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recipe(yaml: &str) -> Recipe {
        serde_yaml::from_str(yaml).unwrap()
    }

    #[test]
    fn the_same_seed_makes_the_same_map() {
        for layer in ["{perlin: {scale: 16, octaves: 4}}", "{diamond_square: {roughness: 0.6}}", "{hills: {count: 30}}"]
        {
            let r = recipe(&format!("{{size: [65, 40], seed: 3, layers: [{layer}]}}"));
            r.check().unwrap();
            let (a, b, c) = (r.generate(3).unwrap(), r.generate(3).unwrap(), r.generate(4).unwrap());
            assert_eq!(a.checksum(), b.checksum(), "{layer}");
            assert_ne!(a.checksum(), c.checksum(), "{layer}");
            let stats = a.stats();
            assert!(stats.min >= 0.0 && stats.max <= 1.0 && stats.max > stats.min, "{layer}: {stats:?}");
        }
    }

    #[test]
    fn layers_combine_by_their_ops_weights_and_functions() {
        let base = recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}}]}");
        let single = base.generate(1).unwrap();
        let doubled =
            recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}, weight: 2}]}").generate(1).unwrap();
        for (a, b) in single.values().iter().zip(doubled.values()) {
            assert_eq!(a * 2.0, *b);
        }
        let squared =
            recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}}], apply: [{power: 2}, {offset: 1}]}")
                .generate(1)
                .unwrap();
        for (a, b) in single.values().iter().zip(squared.values()) {
            assert_eq!(a.powf(2.0) + 1.0, *b);
        }
        // A second layer equal to the first (same seed stream offset aside) subtracted: the
        // first layer minus another map.
        let two = recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}}, {hills: {count: 5}, op: max}]}");
        two.check().unwrap();
        let hills_alone = hills(HillsLayer { count: 5, radius: [4.0, 32.0] }, 1 + 0x1_0000, 32, 32).unwrap();
        let combined = two.generate(1).unwrap();
        for ((a, b), c) in single.values().iter().zip(hills_alone.values()).zip(combined.values()) {
            assert_eq!(a.max(*b), *c);
        }
    }

    #[test]
    fn functions_give_hand_computed_values() {
        let mut map = Heightmap::from_values(4, 1, vec![-0.5, 0.0, 0.3, 1.0]).unwrap();
        Function::Clamp([0.0, 0.5]).apply(&mut map);
        assert_eq!(map.values(), &[0.0, 0.0, 0.3, 0.5]);
        Function::Terraces(2).apply(&mut map);
        // 0.3 * 2 = 0.6: floor 0, fraction 0.6, 0.6^4 / 2 = 0.0648; 0.5 * 2 = 1: one step up.
        assert!((map.values()[2] - 0.0648).abs() < 1e-6);
        assert_eq!(map.values()[3], 0.5);
        Function::Invert.apply(&mut map);
        assert_eq!(map.values()[0], 1.0);
        Function::Scale(-2.0).apply(&mut map);
        Function::Abs.apply(&mut map);
        assert_eq!(map.values()[0], 2.0);
    }

    #[test]
    fn hills_are_paraboloids() {
        // One hill: the normalised, squared paraboloid peaks at 1 at its centre and is zero
        // beyond its radius.
        let map = hills(HillsLayer { count: 1, radius: [5.0, 5.0] }, 9, 64, 64).unwrap();
        let stats = map.stats();
        assert_eq!((stats.min, stats.max), (0.0, 1.0));
        let raised = map.values().iter().filter(|&&h| h > 0.0).count() as f32;
        // The disc of radius 5 holds about 78.5 samples (fewer when cut by the border).
        assert!(raised <= 90.0 && raised > 20.0, "{raised}");
    }

    #[test]
    fn mistakes_name_their_field() {
        let cases = [
            ("{size: [0, 5], layers: [{perlin: {}}]}", "size"),
            ("{size: [5000, 5], layers: [{perlin: {}}]}", "size"),
            ("{size: [5, 5], seed: -2, layers: [{perlin: {}}]}", "seed"),
            ("{size: [5, 5], layers: []}", "layers"),
            ("{size: [5, 5], layers: [{weight: 2}]}", "layers[0]"),
            ("{size: [5, 5], layers: [{perlin: {}, hills: {}}]}", "layers[0]"),
            ("{size: [5, 5], layers: [{perlin: {octaves: 40}}]}", "layers[0].perlin"),
            ("{size: [5, 5], layers: [{perlin: {scale: .nan}}]}", "layers[0].perlin"),
            ("{size: [5, 5], layers: [{perlin: {}}, {diamond_square: {roughness: 2}}]}", "layers[1].diamond_square"),
            ("{size: [5, 5], layers: [{hills: {radius: [3, 1]}}]}", "layers[0].hills"),
            ("{size: [5, 5], layers: [{perlin: {}, op: multiply}]}", "layers[0].op"),
            ("{size: [5, 5], layers: [{perlin: {}, weight: .inf}]}", "layers[0].weight"),
            ("{size: [5, 5], layers: [{perlin: {}}], apply: [{power: -1}]}", "apply"),
            ("{size: [5, 5], layers: [{perlin: {}, apply: [{terraces: 0}]}]}", "layers[0].apply"),
        ];
        for (yaml, field) in cases {
            let error = recipe(yaml).check().unwrap_err();
            assert_eq!(error.field, field, "{yaml}: {error}");
        }
        let error = serde_yaml::from_str::<Recipe>("{size: [5, 5], layers: [{ridged: {}}]}").unwrap_err();
        assert!(error.to_string().contains("unknown field `ridged`"), "{error}");
    }

    /// A recipe of two Perlin layers, a weight, an operation and pointwise functions.
    fn unbounded() -> Recipe {
        recipe(
            "{size: [40, 30], seed: 5, layers: [{perlin: {scale: 24, octaves: 4}}, \
             {perlin: {scale: 60, octaves: 2}, op: max, weight: 0.7, apply: [{power: 3}]}], apply: [{terraces: 4}]}",
        )
    }

    #[test]
    fn an_unbounded_grid_is_the_map_and_grids_agree_where_they_meet() {
        let recipe = unbounded();
        recipe.check().unwrap();
        recipe.check_unbounded().unwrap();
        // At the map's own samples, the grid is the map, bit for bit.
        let map = recipe.generate(5).unwrap();
        let grid = recipe.sample_grid(5, [0, 0], 1, [40, 30]);
        assert!(grid.iter().zip(map.values()).all(|(a, b)| a.to_bits() == b.to_bits()));
        // A grid elsewhere (negative positions too) and a coarser one give the samples they
        // share with it bit for bit.
        let shifted = recipe.sample_grid(5, [-13, 7], 1, [40, 30]);
        let wide = recipe.sample_grid(5, [-13, -1], 1, [60, 40]);
        for (j, row) in shifted.chunks_exact(40).enumerate() {
            assert_eq!(row, &wide[(j + 8) * 60..(j + 8) * 60 + 40]);
        }
        let coarse = recipe.sample_grid(5, [-13, -1], 4, [15, 10]);
        for (j, row) in coarse.chunks_exact(15).enumerate() {
            for (i, h) in row.iter().enumerate() {
                assert_eq!(h.to_bits(), wide[j * 4 * 60 + i * 4].to_bits(), "({i}, {j})");
            }
        }
    }

    #[test]
    fn only_heights_of_their_own_position_make_an_unbounded_world() {
        let refused = |yaml: &str| recipe(yaml).check_unbounded().unwrap_err();
        let hills = refused("{size: [8, 8], layers: [{perlin: {scale: 4}}, {hills: {count: 3}}]}");
        assert_eq!((hills.field.as_str(), hills.key), ("layers[1]", "hills"));
        let squares = refused("{size: [8, 8], layers: [{diamond_square: {roughness: 0.5}}]}");
        assert_eq!(squares.key, "diamond_square");
        let normalize =
            refused("{size: [8, 8], layers: [{perlin: {scale: 4}, apply: [{power: 2}]}], apply: [normalize]}");
        assert_eq!((normalize.field.as_str(), normalize.nth), ("apply", 1));
        assert!(normalize.message.contains("whole map"), "{}", normalize.message);
    }

    #[test]
    fn recipes_save_as_they_were_written() {
        let text = "size: [8, 8]\nseed: 4\nlayers:\n- perlin: {scale: 4}\n  apply: [{power: 2}, normalize]\napply: [{terraces: 3}]\n";
        let read = recipe(text);
        let saved = serde_yaml::to_string(&read).unwrap();
        assert!(saved.contains("power: 2.0") && !saved.contains('!'), "{saved}");
        assert_eq!(recipe(&saved), read);
    }
}
