//! The `terrain:` entry of a scene file, and the kind that reads, builds, spawns and saves it.

use super::bands::{Band, BandBlend, BandRule};
use super::ground::Ground;
use super::heightmap::Heightmap;
use super::image_io;
use super::recipe::{Function, Layer, Recipe};
use crate::foundation::kind::{BuildContext, EntityContext, ReferencedFile};
use crate::foundation::values::{Degrees, FolderFile, Point, PositiveMetres, checked_number};
use crate::foundation::yaml::FileError;
use crate::raster::texture::{ImageFile, TextureDef};
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

checked_number!(
    /// A scale factor: positive and at most 1000.
    Factor(f32),
    "a factor greater than 0 and at most 1000",
    |v| v > 0.0 && v <= 1000.0
);

/// Where the heights come from: an image file, or a generator recipe; functions of the map
/// algebra apply to either.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HeightDef {
    /// A grayscale PNG (8 or 16 bit) or BMP in the scene's folder: brightness is height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<FolderFile<ImageFile>>,
    /// Samples along x and z of a generated map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[u32; 2]>,
    /// The generator's seed; -1 (the default) draws one, which is printed and dumped.
    #[serde(default = "random_seed")]
    pub seed: i64,
    /// The generator layers of a generated map.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<Layer>,
    /// Functions applied to the map, in order.
    #[serde(default, with = "serde_yaml::with::singleton_map_recursive", skip_serializing_if = "Vec::is_empty")]
    pub apply: Vec<Function>,
    /// The decoded image, filled in when the scene is resolved.
    #[serde(skip)]
    pub decoded: Option<Arc<Heightmap>>,
}

fn random_seed() -> i64 {
    -1
}

impl HeightDef {
    /// The recipe of a generated map (whatever `image` says).
    pub fn recipe(&self) -> Recipe {
        Recipe {
            size: self.size.unwrap_or([0, 0]),
            seed: self.seed,
            layers: self.layers.clone(),
            apply: self.apply.clone(),
        }
    }

    /// Why the entry (field `key` of its entity) names no source of heights, or two.
    pub fn validate(&self, key: &str, cx: &EntityContext) -> Result<(), FileError> {
        match (&self.image, self.size.is_some() || !self.layers.is_empty()) {
            (Some(_), true) => {
                Err(cx.field_error("image", 0, key, "heights come from an image or from size and layers, not both"))
            }
            (None, false) => {
                Err(cx.field_error(key, 0, key, "expected `image: FILE`, or `size` and `layers` to generate the map"))
            }
            _ => Ok(()),
        }
    }

    /// The image file it reads, if any.
    pub fn references(&self) -> Option<String> {
        self.image.as_ref().map(|file| file.path.clone())
    }

    /// Decodes `file` if it is the image (the entry being field `key` of its entity).
    pub fn resolve(&mut self, key: &str, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        if self.image.as_ref().is_some_and(|image| image.path == file.file) {
            let field = format!("{key}.image");
            let map = file
                .decoded(|_, bytes| image_io::decode(bytes).map_err(|error| error.to_string()))
                .map_err(|error| cx.field_error("image", 0, &field, format!("{}: {error}", file.path.display())))?;
            self.decoded = Some(map);
        }
        Ok(())
    }

    /// The map (the entry being field `key` of its entity): the image's with the functions
    /// applied, or generated, with the seed it was generated with (drawn, and printed, for -1).
    pub fn build(&self, key: &str, cx: &BuildContext) -> Result<(Heightmap, Option<u64>), FileError> {
        let (map, seed) = match &self.image {
            Some(_) => {
                let field = format!("{key}.image");
                let Some(map) = &self.decoded else {
                    return Err(cx.entity.field_error("image", 0, &field, "the image was not read"));
                };
                let mut map = (**map).clone();
                for function in &self.apply {
                    let field = format!("{key}.apply");
                    function.check().map_err(|message| cx.entity.field_error("apply", 0, &field, message))?;
                    function.apply(&mut map);
                }
                (map, None)
            }
            None => {
                let recipe = self.recipe();
                recipe.check().map_err(|error| {
                    let located = if error.key == "size" && self.size.is_none() { key } else { error.key };
                    cx.entity.field_error(located, error.nth, &format!("{key}.{}", error.field), &error.message)
                })?;
                let seed = recipe.seed_used(draw_seed);
                if recipe.seed == -1 {
                    println!("{}: seed -1 drew seed {seed}", cx.entity.field(&format!("{key}.seed")));
                }
                let map = recipe.generate(seed).map_err(|error| cx.entity.field_error(key, 0, key, error))?;
                (map, Some(seed))
            }
        };
        if map.values().iter().any(|h| !h.is_finite()) {
            return Err(cx.entity.field_error(key, 0, key, "the map algebra made heights that are not finite numbers"));
        }
        Ok((map, seed))
    }
}

/// The visible section: its first vertex in the map and its size in vertices.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionDef {
    /// The map sample `[x, z]` at the section's first vertex; `[0, 0]` by default.
    #[serde(default)]
    pub origin: [u32; 2],
    /// Vertices along x and z (2 up to the map's size); 64 x 64 by default (the source's
    /// demonstration), or the map if it is smaller.
    #[serde(default = "default_section_size")]
    pub size: [u32; 2],
}

pub(super) fn default_section_size() -> [u32; 2] {
    [64, 64]
}

impl Default for SectionDef {
    fn default() -> Self {
        Self { origin: [0, 0], size: default_section_size() }
    }
}

/// The height bands and their textures.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BandsDef {
    /// Map heights where sand, grass, rock and snow begin.
    #[serde(default = "default_thresholds")]
    pub thresholds: [f32; 4],
    /// Faces steeper than this (degrees from horizontal) are rock; off by default (the source
    /// banded by height alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rock_slope_deg: Option<f32>,
    /// How far bands fade into each other at their borders; off by default (the source's
    /// bands meet along triangle edges).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend: Option<BandBlend>,
    /// Cells one repetition of a band texture covers; 8 by default.
    #[serde(default = "default_texture_cells")]
    pub texture_cells: Factor,
    /// A texture per band; a band without one uses the project's own.
    #[serde(default, skip_serializing_if = "BandTextures::is_empty")]
    pub textures: BandTextures,
}

fn default_thresholds() -> [f32; 4] {
    BandRule::default().thresholds
}

fn default_texture_cells() -> Factor {
    Factor(8.0)
}

impl Default for BandsDef {
    fn default() -> Self {
        Self {
            thresholds: default_thresholds(),
            rock_slope_deg: None,
            blend: None,
            texture_cells: default_texture_cells(),
            textures: BandTextures::default(),
        }
    }
}

impl BandsDef {
    /// The texture files the bands read, for a kind's references.
    pub fn references(&self) -> Vec<String> {
        self.textures.all().into_iter().flat_map(|t| TextureDef::reference(t.as_ref())).collect()
    }

    /// Decodes `file` into every band texture that reads it; errors name the band's field.
    pub fn resolve(&mut self, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        for (band, texture) in Band::ALL.iter().zip(self.textures.all_mut()) {
            if let Some(texture) = texture {
                texture.resolve(file, cx, &format!("bands.textures.{}.file", band.key()))?;
            }
        }
        Ok(())
    }

    /// The banding rule.
    pub fn rule(&self) -> BandRule {
        BandRule { thresholds: self.thresholds, rock_slope_deg: self.rock_slope_deg, blend: self.blend }
    }
}

/// Texture files per band.
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BandTextures {
    /// Water.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water: Option<TextureDef>,
    /// Sand.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sand: Option<TextureDef>,
    /// Grass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grass: Option<TextureDef>,
    /// Rock.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rock: Option<TextureDef>,
    /// Snow.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub snow: Option<TextureDef>,
}

impl BandTextures {
    fn is_empty(&self) -> bool {
        self.all().iter().all(|texture| texture.is_none())
    }

    /// Each band's texture, in [`Band::ALL`] order.
    pub fn all(&self) -> [&Option<TextureDef>; 5] {
        [&self.water, &self.sand, &self.grass, &self.rock, &self.snow]
    }

    fn all_mut(&mut self) -> [&mut Option<TextureDef>; 5] {
        [&mut self.water, &mut self.sand, &mut self.grass, &mut self.rock, &mut self.snow]
    }
}

/// A `terrain` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainDef {
    /// The heightmap.
    pub height: HeightDef,
    /// The visible section.
    #[serde(default)]
    pub section: SectionDef,
    /// Metres between neighbouring samples; 0.25 by default.
    #[serde(default = "default_cell")]
    pub cell_m: PositiveMetres,
    /// Metres of height for a map height of 1; 8 by default.
    #[serde(default = "default_height")]
    pub height_m: PositiveMetres,
    /// Where the section's centre stands, metres (its heights above this point's); the origin
    /// by default.
    #[serde(default = "origin")]
    pub position: Point,
    /// Turn about the vertical axis through the section's centre, degrees; 0 by default.
    #[serde(default = "no_turn")]
    pub rotation_deg: Degrees,
    /// Scale along x, y and z about the section's centre; 1 by default.
    #[serde(default = "unit_scale")]
    pub scale: [Factor; 3],
    /// Height bands and their textures.
    #[serde(default)]
    pub bands: BandsDef,
}

fn default_cell() -> PositiveMetres {
    PositiveMetres(0.25)
}

fn default_height() -> PositiveMetres {
    PositiveMetres(8.0)
}

pub(super) fn origin() -> Point {
    Point(Vec3::ZERO)
}

fn no_turn() -> Degrees {
    Degrees(0.0)
}

fn unit_scale() -> [Factor; 3] {
    [Factor(1.0); 3]
}

/// What a terrain's build made: its map and the seed it was made with.
#[derive(Debug, Clone)]
pub struct TerrainBuilt {
    /// The heightmap.
    pub map: Arc<Heightmap>,
    /// The seed a generated map was made with (drawn when the file says -1).
    pub seed: Option<u64>,
    /// The ground of the section as the scene places it when it loads: where trees are rooted.
    pub ground: Arc<Ground>,
}

/// A seed from the clock, for `seed: -1`.
pub fn draw_seed() -> u64 {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    crate::foundation::random::Random::new(nanos as u64).next_u64()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_sources() {
        let def: TerrainDef = serde_yaml::from_str("height: {size: [128, 128], layers: [{perlin: {}}]}").unwrap();
        assert_eq!(def.section, SectionDef { origin: [0, 0], size: [64, 64] });
        assert_eq!(def.height.seed, -1);
        let perlin = def.height.layers[0].perlin.unwrap();
        assert_eq!((perlin.octaves, perlin.lacunarity, perlin.persistence), (1, 2.0, 0.5));
        assert_eq!(def.bands.rule(), BandRule::default());
    }

    #[test]
    fn unknown_fields_and_bad_numbers_are_refused_where_they_are() {
        for (yaml, expected) in [
            ("height: {image: a.png}\nsection: {origin: [0, 0], sise: [3, 3]}", "unknown field `sise`"),
            ("height: {image: ../a.png}", "inside the scene's folder"),
            ("height: {image: a.jpg}", "a .png or .bmp file"),
            ("height: {image: a.png}\ncell_m: .nan", "greater than 0"),
            ("height: {image: a.png}\nscale: [1, 0, 1]", "a factor greater than 0"),
            ("height: {image: a.png}\nheight_m: -3", "greater than 0"),
            ("height: {image: a.png}\nsection: {size: [-3, 3]}", "expected u32"),
        ] {
            let error = serde_yaml::from_str::<TerrainDef>(yaml).unwrap_err().to_string();
            assert!(error.contains(expected), "{yaml}: {error}");
        }
    }
}
