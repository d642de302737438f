//! The `muscle:` entry of a scene file (the source program's two configurations, inline or
//! from a file), its checks, and the kind that reads, builds, spawns and saves it.

use super::carcass::Carcass;
use super::comparison::MEASURED_NODES;
use super::fit::{GrowthFit, fit_growth};
use super::model::{self, Muscle};
use crate::foundation::values::{Angles, Color, FileType, FolderFile, Point, checked_number};
use crate::foundation::yaml::{FileError, locate_key, parse_yaml};
use bevy::color::Srgba;
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

checked_number!(
    /// A length or radius in config units, finite and greater than 0.
    ConfigLength(f64),
    "a number greater than 0",
    |v| v > 0.0 && v <= 1e9
);
checked_number!(
    /// A growth multiplier: any finite number.
    Multiplier(f64),
    "a finite number",
    |v| v.abs() <= 1e9
);
checked_number!(
    /// A scale factor from config units to metres, greater than 0.
    Scale(f32),
    "a scale greater than 0 and at most 1e6",
    |v| v > 0.0 && v <= 1e6
);
checked_number!(
    /// A bound on the node spacing relative to rest, greater than 0.
    Part(f64),
    "a fraction of the rest spacing greater than 0",
    |v| v > 0.0 && v <= 100.0
);
checked_number!(
    /// Vertices around each ring of the surface: a whole number from 3 to 256.
    Segments(u32),
    "a whole number of segments from 3 to 256",
    |v| v.fract() == 0.0 && (3.0..=256.0).contains(&v)
);

impl Segments {
    /// The count.
    pub fn count(self) -> usize {
        self.0 as usize
    }
}

/// The source program's `muscle_config`, verbatim. The source's listing of its second
/// configuration spells the first key `radiiuses:`; that spelling is read too.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MuscleConfig {
    /// Node radii (the source's spelling; `radiiuses` is read as well).
    #[serde(alias = "radiiuses")]
    pub radiuses: Vec<ConfigLength>,
    /// Growth multipliers, one per node.
    pub grow_mults: Vec<Multiplier>,
    /// Rest length.
    pub len: ConfigLength,
}

impl MuscleConfig {
    /// The node model at rest, with node spacing bounds relative to rest.
    pub fn model(&self, min_part: f64, max_part: f64) -> Result<Muscle, model::ConfigError> {
        let radii = self.radiuses.iter().map(|r| r.0).collect();
        let mults = self.grow_mults.iter().map(|m| m.0).collect();
        Muscle::new(radii, mults, self.len.0, min_part, max_part)
    }
}

/// The source program's `carcass_config`, verbatim.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CarcassConfig {
    /// `[[a1, b1], [a2, b2]]`: rod 1 split at its attachment, rod 2 split at its attachment.
    pub data: [[ConfigLength; 2]; 2],
    /// Rod thickness.
    pub thickness: ConfigLength,
}

impl CarcassConfig {
    /// The arm these values describe.
    pub fn carcass(&self) -> Carcass {
        let [[a1, b1], [a2, b2]] = self.data;
        Carcass { a1: a1.0, b1: b1.0, a2: a2.0, b2: b2.0, thickness: self.thickness.0 }
    }
}

fn default_min_part() -> Part {
    Part(0.5)
}

fn default_max_part() -> Part {
    Part(1.5)
}

fn default_segments() -> Segments {
    Segments(32)
}

fn default_scale() -> Scale {
    Scale(0.004)
}

fn default_muscle_color() -> Color {
    Color(Srgba::rgb(0.78, 0.25, 0.22))
}

fn origin() -> Point {
    Point(Vec3::ZERO)
}

fn no_rotation() -> Angles {
    Angles(Vec3::ZERO)
}

/// Configuration files: YAML files (`.yaml` or `.yml`, in any case).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigFileType;

impl FileType for ConfigFileType {
    const EXTENSIONS: &'static [&'static str] = &[".yaml", ".yml"];
    const EXPECTING: &'static str = "a .yaml file in the scene's folder, e.g. biceps_config.yaml";
    const FILES: &'static str = "a .yaml file";
}

/// A `muscle` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MuscleDef {
    /// A file holding `muscle_config` and `carcass_config`, relative to the scene's folder;
    /// instead of giving them inline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<FolderFile<ConfigFileType>>,
    /// The node model (not written back when it came from `file`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub muscle_config: Option<MuscleConfig>,
    /// The arm (not written back when it came from `file`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub carcass_config: Option<CarcassConfig>,
    /// Shortest node spacing, relative to rest (default 0.5).
    #[serde(default = "default_min_part")]
    pub min_part: Part,
    /// Longest node spacing, relative to rest (default 1.5).
    #[serde(default = "default_max_part")]
    pub max_part: Part,
    /// Vertices around each ring of the surface, 3 to 256 (default 32).
    #[serde(default = "default_segments")]
    pub segments: Segments,
    /// Muscle colour.
    #[serde(default = "default_muscle_color")]
    pub color: Color,
    /// Elbow position in metres.
    #[serde(default = "origin")]
    pub position: Point,
    /// Rotation of the arm in degrees (x, then y, then z).
    #[serde(default = "no_rotation")]
    pub rotation_deg: Angles,
    /// Metres per config unit (default 0.004: a 250-unit muscle is 1 m long).
    #[serde(default = "default_scale")]
    pub scale: Scale,
    /// Grows the muscle with multipliers fitted to the real biceps' radii at 0, 30, 60 and 90
    /// degrees rather than `grow_mults` (see [`super::fit`]); the model must have the
    /// measurements' eleven nodes. `grow_mults` is kept as written.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fit_growth: bool,
}

impl MuscleDef {
    /// The model and carcass this definition describes, with the growth fitted to the
    /// measurements when it asks for that, or why it describes none.
    pub fn build(&self) -> Result<BuiltMuscle, model::ConfigError> {
        let (Some(config), Some(arm)) = (&self.muscle_config, &self.carcass_config) else {
            return Err(model::ConfigError::Missing);
        };
        let (model, carcass) = (config.model(self.min_part.0, self.max_part.0)?, arm.carcass());
        let fit = fit_growth(&model, &carcass);
        if self.fit_growth && fit.is_none() {
            return Err(match model.nodes() {
                nodes if nodes == MEASURED_NODES + 2 => model::ConfigError::NoFitFrom,
                nodes => model::ConfigError::NotMeasuredLayout(nodes),
            });
        }
        Ok(BuiltMuscle { model, carcass, fit })
    }

    /// Takes the configurations from a referenced file's contents.
    pub fn fill_from(&mut self, file: ConfigFile) {
        self.muscle_config = Some(file.muscle_config);
        self.carcass_config = Some(file.carcass_config);
    }
}

/// A muscle as its definition describes it, before it is spawned.
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltMuscle {
    /// The node model with its configured multipliers, at rest.
    pub model: Muscle,
    /// The arm.
    pub carcass: Carcass,
    /// Its growth fitted to the measurements, for a model laid out as they are.
    pub fit: Option<GrowthFit>,
}

/// A file holding exactly the source program's configuration.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigFile {
    /// The node model.
    pub muscle_config: MuscleConfig,
    /// The arm.
    pub carcass_config: CarcassConfig,
}

impl ConfigFile {
    /// The source program's first configuration: a ten-node biceps of rest length 250 on rods
    /// of 260 and 150 units (`scenes/biceps_config.yaml` holds the same).
    pub fn source_first() -> Self {
        let lengths = |values: &[f64]| values.iter().map(|&v| ConfigLength(v)).collect();
        Self {
            muscle_config: MuscleConfig {
                radiuses: lengths(&[5.0, 5.0, 10.0, 15.0, 18.0, 18.0, 15.0, 10.0, 5.0, 5.0]),
                grow_mults: [0.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 1.0, 1.0, 0.0].map(Multiplier).to_vec(),
                len: ConfigLength(250.0),
            },
            carcass_config: CarcassConfig {
                data: [[ConfigLength(30.0), ConfigLength(230.0)], [ConfigLength(30.0), ConfigLength(120.0)]],
                thickness: ConfigLength(5.0),
            },
        }
    }

    /// Reads a configuration file, its node model checked so that its errors point into it.
    pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<Self, FileError> {
        let config: ConfigFile = parse_yaml(path, bytes, "a muscle configuration")?;
        if let Err(error) = config.muscle_config.model(1.0, 1.0) {
            let text = String::from_utf8_lossy(bytes);
            return Err(locate_key(path, &text, "muscle_config", 0, format!("muscle_config: {error}")));
        }
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_out_of_range_are_errors_not_clamped() {
        let base = "muscle_config: {radiuses: [1, 2], grow_mults: [1, 1], len: 10}\n\
                    carcass_config: {data: [[1, 1], [1, 1]], thickness: 1}\n";
        for (segments, ok) in [("3", true), ("256", true), ("2", false), ("257", false), ("12.5", false)] {
            let text = format!("{base}segments: {segments}\n");
            let result = serde_yaml::from_str::<MuscleDef>(&text);
            assert_eq!(result.is_ok(), ok, "{segments}: {result:?}");
            if let Err(error) = result {
                assert!(error.to_string().contains("a whole number of segments from 3 to 256"), "{error}");
            }
        }
    }

    #[test]
    fn the_source_first_configuration_is_the_one_in_the_sample_file() {
        let text = std::fs::read_to_string("scenes/biceps_config.yaml").unwrap();
        let file: ConfigFile = serde_yaml::from_str(&text).unwrap();
        assert_eq!(file, ConfigFile::source_first());
    }

    #[test]
    fn the_source_misspelling_of_radiuses_is_read() {
        let config: MuscleConfig = serde_yaml::from_str("radiiuses: [5, 7.6]\ngrow_mults: [1, 2]\nlen: 250\n").unwrap();
        assert_eq!(config.radiuses.iter().map(|r| r.0).collect::<Vec<_>>(), [5.0, 7.6]);
    }
}
