//! A heightmap's recipe, as a scene file's `height:` (a terrain's) or a world's holds it, and
//! its checks: a size, a seed and a list of [`Layer`]s. Each layer is one generator (fBm
//! Perlin noise, the source's choice; diamond-square and the hill algorithm, the alternatives
//! it analysed), then its own functions ([`Function`]), then a weight; the first layer starts
//! the map and each later one is combined into it by its [`Op`]; the recipe's own functions
//! come last. Plains, hills and mountains are mixed this way: broad low-octave noise, finer
//! noise added at a small weight, the sum raised to a power to flatten the valleys. The
//! generators themselves are in [`super::generate`].

use super::heightmap::{Heightmap, MAX_SIDE, check_size};
use super::noise::MAX_OCTAVES;
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

impl Default for DiamondSquareLayer {
    fn default() -> Self {
        Self { roughness: half() }
    }
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
    /// Where the hills' centres may fall; inside the map by default.
    #[serde(default, skip_serializing_if = "HillCentres::is_inside")]
    pub centres: HillCentres,
    /// Hills dug down instead of raised: a plateau with flat-bottomed lakes; no by default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub lakes: bool,
}

impl Default for HillsLayer {
    fn default() -> Self {
        Self { count: default_hills(), radius: default_radius(), centres: HillCentres::Inside, lakes: false }
    }
}

/// Where the hill algorithm's centres fall (the variants the source analysed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HillCentres {
    /// Anywhere on the map: its edges are lower, the hills cut off there.
    #[default]
    Inside,
    /// Up to the largest radius beyond the map's edges too, so the edges are not flat.
    BeyondEdges,
    /// Each hill wholly within the circle inscribed in the map: an island, its edges at 0.
    Island,
}

impl HillCentres {
    /// Every variant, in the panel's order.
    pub const ALL: [HillCentres; 3] = [HillCentres::Inside, HillCentres::BeyondEdges, HillCentres::Island];

    fn is_inside(&self) -> bool {
        *self == HillCentres::Inside
    }

    /// Its name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            HillCentres::Inside => "inside",
            HillCentres::BeyondEdges => "beyond_edges",
            HillCentres::Island => "island",
        }
    }
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
    /// Every operation, in the panel's order.
    pub const ALL: [Op; 5] = [Op::Add, Op::Subtract, Op::Multiply, Op::Min, Op::Max];

    /// Its name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Op::Add => "add",
            Op::Subtract => "subtract",
            Op::Multiply => "multiply",
            Op::Min => "min",
            Op::Max => "max",
        }
    }

    /// `a` combined with `b` by this operation.
    pub fn apply(self, a: f32, b: f32) -> f32 {
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
    /// Every function's name in scene files, in the panel's order.
    pub const NAMES: [&'static str; 8] =
        ["normalize", "invert", "abs", "power", "terraces", "clamp", "scale", "offset"];

    /// The function of that name with its numbers at their starting values (a square, four
    /// terraces, `[0, 1]`, a scale of 1, an offset of 0).
    pub fn named(name: &str) -> Option<Function> {
        Some(match name {
            "normalize" => Function::Normalize,
            "invert" => Function::Invert,
            "abs" => Function::Abs,
            "power" => Function::Power(2.0),
            "terraces" => Function::Terraces(4),
            "clamp" => Function::Clamp([0.0, 1.0]),
            "scale" => Function::Scale(1.0),
            "offset" => Function::Offset(0.0),
            _ => return None,
        })
    }

    /// Its name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Function::Normalize => "normalize",
            Function::Invert => "invert",
            Function::Abs => "abs",
            Function::Power(_) => "power",
            Function::Terraces(_) => "terraces",
            Function::Clamp(_) => "clamp",
            Function::Scale(_) => "scale",
            Function::Offset(_) => "offset",
        }
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_panels_names_are_the_scene_files() {
        for name in Function::NAMES {
            let function = Function::named(name).unwrap();
            assert_eq!(function.name(), name);
            function.check().unwrap();
            let written = serde_yaml::to_string(
                &serde_yaml::with::singleton_map_recursive::serialize(&vec![function], serde_yaml::value::Serializer)
                    .unwrap(),
            )
            .unwrap();
            assert!(written.trim_start_matches("- ").starts_with(name), "{written}");
        }
        assert_eq!(Function::named("sqrt"), None);
        for op in Op::ALL {
            assert_eq!(serde_yaml::to_string(&op).unwrap().trim(), op.name());
        }
        for centres in HillCentres::ALL {
            assert_eq!(serde_yaml::to_string(&centres).unwrap().trim(), centres.name());
        }
        // A generator's defaults are the file's: an empty entry reads as them.
        assert_eq!(serde_yaml::from_str::<HillsLayer>("{}").unwrap(), HillsLayer::default());
        assert_eq!(serde_yaml::from_str::<DiamondSquareLayer>("{}").unwrap(), DiamondSquareLayer::default());
    }
}
