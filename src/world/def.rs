//! The `world:` entry of a scene file: the heights (a recipe without bounds, or a finite map),
//! the chunks, the streaming radii and levels, and the bands.

use super::chunk::{LEVELS, WorldHeights};
use super::stream::StreamSettings;
use crate::foundation::kind::BuildContext;
use crate::foundation::values::PositiveMetres;
use crate::foundation::yaml::FileError;
use crate::terrain::def::{BandsDef, HeightDef, draw_seed};
use crate::terrain::recipe::{Function, Layer, Recipe};
use crate::terrain::section::Geometry;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A `world` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WorldDef {
    /// A finite world: its heights from an image or a generated map, as a terrain's
    /// `height` (any generator and function), its first sample at the origin. Without it the
    /// world has no bounds and its heights are `layers`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<HeightDef>,
    /// The seed of the layers; -1 (the default) draws one, which is printed and dumped.
    #[serde(default = "random_seed")]
    pub seed: i64,
    /// The height layers of a world without bounds: Perlin noise, combined by map algebra
    /// (heights of their position alone: no diamond-square, hills or `normalize`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<Layer>,
    /// Functions applied to the combined heights, in order.
    #[serde(default, with = "serde_yaml::with::singleton_map_recursive", skip_serializing_if = "Vec::is_empty")]
    pub apply: Vec<Function>,
    /// Cells a side of a chunk: 16 (the default), 32, 64 or 128.
    #[serde(default = "default_cells")]
    pub chunk_cells: u32,
    /// Metres between neighbouring samples; 1 by default.
    #[serde(default = "one_metre")]
    pub cell_m: PositiveMetres,
    /// Metres of height for a height of 1; 40 by default.
    #[serde(default = "default_height")]
    pub height_m: PositiveMetres,
    /// Chunks whose centre is nearer the camera than this are made; 160 m by default.
    #[serde(default = "default_load")]
    pub load_radius_m: PositiveMetres,
    /// Chunks farther than this are let go; more than the load radius, 200 m by default.
    #[serde(default = "default_unload")]
    pub unload_radius_m: PositiveMetres,
    /// From these distances on (rising) chunks take levels of detail 1, 2 and 3.
    #[serde(default = "default_levels")]
    pub level_distances_m: [f32; LEVELS as usize - 1],
    /// Finished chunks spawned a frame at most; 4 by default.
    #[serde(default = "default_budget")]
    pub spawn_budget: u32,
    /// How deep the skirts hang along the chunks' edges where levels meet, metres; 2 by default.
    #[serde(default = "default_skirt")]
    pub skirt_m: PositiveMetres,
    /// Height bands and their textures, as for `terrain`.
    #[serde(default)]
    pub bands: BandsDef,
}

fn random_seed() -> i64 {
    -1
}
fn default_cells() -> u32 {
    16
}
fn one_metre() -> PositiveMetres {
    PositiveMetres(1.0)
}
fn default_height() -> PositiveMetres {
    PositiveMetres(40.0)
}
fn default_load() -> PositiveMetres {
    PositiveMetres(160.0)
}
fn default_unload() -> PositiveMetres {
    PositiveMetres(200.0)
}
fn default_levels() -> [f32; LEVELS as usize - 1] {
    [48.0, 96.0, 144.0]
}
fn default_budget() -> u32 {
    4
}
fn default_skirt() -> PositiveMetres {
    PositiveMetres(2.0)
}

impl WorldDef {
    /// The recipe of the layers (its size unused: a world without bounds has none).
    pub fn recipe(&self) -> Recipe {
        Recipe { size: [1, 1], seed: self.seed, layers: self.layers.clone(), apply: self.apply.clone() }
    }

    /// The streaming settings, for a world of `bounds` chunks (`None` without bounds).
    pub fn stream(&self, bounds: Option<[u32; 2]>) -> StreamSettings {
        StreamSettings {
            chunk_m: self.chunk_cells as f32 * self.cell_m.0,
            load_radius_m: self.load_radius_m.0,
            unload_radius_m: self.unload_radius_m.0,
            level_distances_m: self.level_distances_m,
            bounds,
        }
    }

    /// The heights, and the seed they were made with (none for an image): the map's, or the
    /// recipe's, checked.
    pub(super) fn heights(&self, cx: &BuildContext) -> Result<(WorldHeights, Option<u64>), FileError> {
        if let Some(map) = &self.map {
            let (map, seed) = map.build("map", cx)?;
            return Ok((WorldHeights::Map(Arc::new(map)), seed));
        }
        let recipe = self.recipe();
        let located = |error: crate::terrain::recipe::RecipeError| {
            cx.entity.field_error(error.key, error.nth, &error.field, &error.message)
        };
        recipe.check().map_err(located)?;
        recipe.check_unbounded().map_err(located)?;
        let seed = recipe.seed_used(draw_seed);
        if recipe.seed == -1 {
            println!("{}: seed -1 drew seed {seed}", cx.entity.field("seed"));
        }
        Ok((WorldHeights::unbounded(Arc::new(recipe), seed), Some(seed)))
    }
}

/// What a world's build made: its heights, the seed used and the streaming settings.
#[derive(Debug, Clone)]
pub struct WorldBuilt {
    /// The heights.
    pub heights: WorldHeights,
    /// The seed the heights were made with (drawn when the file says -1); none for an image.
    pub seed: Option<u64>,
    /// Where chunks are wanted.
    pub stream: StreamSettings,
    /// Metres between samples and for a height of 1 (and the bands' texture repeat).
    pub geometry: Geometry,
}

impl WorldBuilt {
    /// The height of the ground under the world point `(x, z)`, metres, as the finest level
    /// of detail draws it.
    pub fn height_under(&self, x: f32, z: f32) -> f32 {
        self.heights.ground_height(x, z, self.geometry)
    }
}
