//! The `tree:` entry of a scene file (supports written out, or generator settings), its
//! checks, and the kind that reads, builds, spawns and saves it.

use super::generate::{self, GeneratorSettings, ScatterSettings};
use super::model::{Shape, SupportKind, SupportSpec, Tree, TreeError};
use super::qsm::build::ImportOptions;
use super::qsm::{Qsm, QsmFormat};
use crate::foundation::values::{Color, Degrees, Length, Point, Radius, UnitInterval};
use crate::raster::texture::TextureDef;
use bevy::color::Srgba;
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A `tree` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TreeDef {
    /// Bark colour; brown by default.
    #[serde(default = "bark")]
    pub color: Color,
    /// Bark image (PNG or BMP in the scene's folder), wrapped once around each support (u) and
    /// repeating every metre along it (v), times `repeat`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureDef>,
    /// Vertices around each ring of the tubes (3 to 64; 12 by default).
    #[serde(deserialize_with = "sides")]
    #[serde(default = "default_sides")]
    pub sides: usize,
    /// The trunks and branches, written out.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub supports: Vec<SupportDef>,
    /// Or: generated from these settings (see `canopy tree generate`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generate: Option<GeneratorSettings>,
    /// Or: a scanned tree's model (a QSM) read from a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub import: Option<ImportDef>,
    /// Or: trees grown on each chunk of the streamed world named in `ground` as the chunk
    /// streams in at the finest level of detail, and gone with it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scatter: Option<ScatterSettings>,
    /// The terrain it stands on, by entity name: every support that forks from no other (a
    /// written-out polyline, a generated trunk) is raised by the ground's height under its
    /// first point when the scene loads, so that its heights count from the ground.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<String>,
    /// Supports whose every radius is below this, metres, are drawn but never gripped: the
    /// sloth neither walks on them nor meets them (twigs that would bend under it); 0, the
    /// default, offers every support.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub grip_min_radius_m: f32,
    /// How far each such support was raised, by name: found when the scene is built, and kept
    /// through edits in the window.
    #[serde(skip)]
    pub lifts: Vec<(String, f32)>,
}

fn bark() -> Color {
    Color(Srgba::rgb(0.42, 0.3, 0.2))
}

fn default_sides() -> usize {
    12
}

/// A tree read from a scanned tree's quantitative structure model (see
/// [`qsm`](super::qsm)).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ImportDef {
    /// The model's file, relative to the scene's folder: TreeQSM's `.mat` or text export,
    /// SimpleForest's or aRchi's CSV.
    pub file: String,
    /// `treeqsm_mat`, `treeqsm_text`, `simpleforest_csv` or `archi_csv`; found from the file
    /// when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<QsmFormat>,
    /// Cylinders thinner than this, metres of radius, are dropped with what grows from them
    /// (or drawn, as `thin_twigs` says).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub min_radius_m: f32,
    /// What becomes of the cylinders thinner than `min_radius_m`: `drop` (the default), or
    /// `draw`: supports of their own, drawn but never gripped.
    #[serde(default, skip_serializing_if = "ThinTwigs::is_drop")]
    pub thin_twigs: ThinTwigs,
    /// Points of a support within this many metres of the line through their neighbours are
    /// dropped.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub simplify_m: f32,
    /// Keep the model's coordinates (turned y up) instead of standing the tree on the origin.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub keep_base: bool,
    /// The model, read from `file` when the scene loads.
    #[serde(skip)]
    pub model: Option<Arc<Qsm>>,
}

fn is_zero(value: &f32) -> bool {
    *value == 0.0
}

/// What an imported tree does with the cylinders thinner than its least radius.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ThinTwigs {
    /// Left out, with everything growing from them.
    #[default]
    Drop,
    /// Drawn, but never gripped.
    Draw,
}

impl ThinTwigs {
    fn is_drop(&self) -> bool {
        *self == Self::Drop
    }
}

impl ImportDef {
    /// What to keep and how to place it, or the field at fault and why.
    pub fn options(&self) -> Result<ImportOptions, String> {
        for (field, value) in [("min_radius_m", self.min_radius_m), ("simplify_m", self.simplify_m)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(format!("import.{field}: expected metres from 0 to 1, found {value}"));
            }
        }
        Ok(ImportOptions {
            min_radius_m: self.min_radius_m,
            draw_thin: self.thin_twigs == ThinTwigs::Draw,
            simplify_m: self.simplify_m,
            keep_base: self.keep_base,
        })
    }

    /// The least radius gripped on the imported tree: the least radius kept, where thinner
    /// twigs are drawn.
    fn grip_min_radius_m(&self) -> f32 {
        match self.thin_twigs {
            ThinTwigs::Draw => self.min_radius_m,
            ThinTwigs::Drop => 0.0,
        }
    }
}

/// Reads `sides`: a whole number from 3 to 64.
fn sides<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<usize, D::Error> {
    let sides = u64::deserialize(deserializer)?;
    if (3..=64).contains(&sides) {
        Ok(sides as usize)
    } else {
        Err(serde::de::Error::custom(format_args!("expected 3 to 64 sides, found {sides}")))
    }
}

/// One support in a scene file: a polyline (`points`, `radii`), a fork from a parent
/// (`parent`, `at`, `yaw_deg`, `pitch_deg`, `length`, `radius`, optionally `bend_deg` and
/// `sections`), or a polyline growing out of a parent (`parent`, `points`, `radii`: a scanned
/// tree's branches, its first point on or in the parent's wood).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SupportDef {
    /// Unique within the tree.
    pub name: String,
    /// `trunk` or `branch`; by default a support tilted more than 70 degrees from horizontal is
    /// a trunk.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<SupportKind>,
    /// Axis points in metres (a polyline).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<Point>>,
    /// A radius in metres at each point (a polyline).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radii: Option<Vec<Radius>>,
    /// The support this one forks from (a fork), or grows out of (a polyline).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<String>,
    /// Where along the parent it starts, 0 to 1 of its length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<UnitInterval>,
    /// Initial heading about +y, degrees (0 towards +z, 90 towards +x); 0 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw_deg: Option<Degrees>,
    /// Initial angle above the horizontal, degrees; 0 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pitch_deg: Option<Degrees>,
    /// Length in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<Length>,
    /// Radius at the start and at the tip, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<[Radius; 2]>,
    /// Total change of heading and pitch along the branch, degrees; none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bend_deg: Option<[Degrees; 2]>,
    /// Straight sections of a fork (1 to 64; 4 by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sections: Option<u32>,
}

/// A field at fault in a support and why.
type FieldError = (&'static str, String);

/// Fields only forks take.
const FORK_FIELDS: [&str; 8] = ["parent", "at", "yaw_deg", "pitch_deg", "length", "radius", "bend_deg", "sections"];

impl SupportDef {
    /// The support's description, or the field at fault and why.
    fn spec(&self) -> Result<SupportSpec, FieldError> {
        let polyline = self.points.is_some() || self.radii.is_some();
        let fork = self.parent.is_some();
        let shape = match (polyline, fork) {
            (true, true) => {
                // An attached polyline names its parent; nothing else of a fork's.
                if let Some(field) = self.fork_field("parent") {
                    return Err((field, format!("`{field}` belongs to forks; this support is a polyline")));
                }
                let (points, radii) = self.polyline()?;
                Shape::Attached { parent: self.parent.clone().unwrap_or_default(), points, radii }
            }
            (false, false) => {
                return Err((
                    "name",
                    format!("support \"{}\" needs points and radii, or a parent to fork from", self.name),
                ));
            }
            (true, false) => {
                if let Some(field) = self.fork_field("") {
                    return Err((field, format!("`{field}` belongs to forks; this support is a polyline")));
                }
                let (points, radii) = self.polyline()?;
                Shape::Polyline { points, radii }
            }
            (false, true) => {
                let missing = |field: &'static str| ("parent", format!("a fork needs `{field}`"));
                let sections = self.sections.unwrap_or(4);
                if !(1..=64).contains(&sections) {
                    return Err(("sections", format!("expected 1 to 64 sections, found {sections}")));
                }
                Shape::Fork {
                    parent: self.parent.clone().unwrap_or_default(),
                    at: self.at.ok_or_else(|| missing("at"))?.0,
                    yaw_deg: self.yaw_deg.map_or(0.0, |d| d.0),
                    pitch_deg: self.pitch_deg.map_or(0.0, |d| d.0),
                    length: self.length.ok_or_else(|| missing("length"))?.0,
                    radius: self.radius.ok_or_else(|| missing("radius"))?.map(|r| r.0),
                    bend_deg: self.bend_deg.map_or([0.0; 2], |b| b.map(|d| d.0)),
                    sections,
                }
            }
        };
        Ok(SupportSpec { name: self.name.clone(), shape, kind: self.kind })
    }

    /// A polyline's points and radii, or the one missing.
    fn polyline(&self) -> Result<(Vec<Vec3>, Vec<f32>), FieldError> {
        let points = self.points.as_ref().ok_or(("radii", "a polyline needs points too".to_string()))?;
        let radii = self.radii.as_ref().ok_or(("points", "a polyline needs radii too".to_string()))?;
        Ok((points.iter().map(|p| p.0).collect(), radii.iter().map(|r| r.0).collect()))
    }

    /// Every optional field and whether it is given, in file-format order.
    fn given(&self) -> [(&'static str, bool); 11] {
        [
            ("kind", self.kind.is_some()),
            ("points", self.points.is_some()),
            ("radii", self.radii.is_some()),
            ("parent", self.parent.is_some()),
            ("at", self.at.is_some()),
            ("yaw_deg", self.yaw_deg.is_some()),
            ("pitch_deg", self.pitch_deg.is_some()),
            ("length", self.length.is_some()),
            ("radius", self.radius.is_some()),
            ("bend_deg", self.bend_deg.is_some()),
            ("sections", self.sections.is_some()),
        ]
    }

    /// The first fork-only field given other than `allowed`, if any.
    fn fork_field(&self, allowed: &str) -> Option<&'static str> {
        self.given()
            .into_iter()
            .find_map(|(field, given)| (given && field != allowed && FORK_FIELDS.contains(&field)).then_some(field))
    }

    /// Whether this support's mapping holds `field`, for locating errors in the file.
    pub fn has_field(&self, field: &str) -> bool {
        field == "name" || self.given().into_iter().any(|(name, given)| given && name == field)
    }
}

impl TreeDef {
    /// The tree this definition describes, or the support and field at fault and why.
    pub fn build(&self) -> Result<Tree, TreeError> {
        if !(0.0..=1.0).contains(&self.grip_min_radius_m) {
            let message = format!("expected metres from 0 to 1, found {}", self.grip_min_radius_m);
            return Err(TreeError { support: None, field: "grip_min_radius_m", message });
        }
        let grip_min_radius_m =
            self.import.as_ref().map_or(0.0, ImportDef::grip_min_radius_m).max(self.grip_min_radius_m);
        let mut tree = self.lifted()?;
        tree.grip_min_radius_m = grip_min_radius_m;
        Ok(tree)
    }

    /// The tree described, each support that forks from no other raised by its lift.
    fn lifted(&self) -> Result<Tree, TreeError> {
        let mut specs = self.specs()?;
        if self.lifts.is_empty() {
            return Tree::build(&specs);
        }
        let lift_of = |name: &str| self.lifts.iter().find(|(lifted, _)| lifted == name).map_or(0.0, |(_, lift)| *lift);
        // An attached polyline rises with the support at the root of its parents.
        let lifts: Vec<f32> = specs
            .iter()
            .map(|spec| match &spec.shape {
                Shape::Polyline { .. } => lift_of(&spec.name),
                Shape::Attached { parent, .. } => lift_of(&root_of(&specs, parent)),
                Shape::Fork { .. } => 0.0,
            })
            .collect();
        for (spec, lift) in specs.iter_mut().zip(lifts) {
            if let Shape::Polyline { points, .. } | Shape::Attached { points, .. } = &mut spec.shape {
                points.iter_mut().for_each(|p| p.y += lift);
            }
        }
        let mut tree = Tree::build(&specs)?;
        tree.lifts = self.lifts.clone();
        Ok(tree)
    }

    /// The supports described, before any lift.
    pub(super) fn specs(&self) -> Result<Vec<SupportSpec>, TreeError> {
        let tree_error = |field, message: String| TreeError { support: None, field, message };
        if let Some(settings) = &self.scatter {
            if self.generate.is_some() || !self.supports.is_empty() {
                return Err(tree_error("scatter", "give scatter alone, without supports or generate".into()));
            }
            settings.check().map_err(|message| tree_error("scatter", message))?;
            // Its trees grow on the world's chunks as they stream in: the entity has none.
            return Ok(Vec::new());
        }
        if let Some(import) = &self.import {
            if self.generate.is_some() || !self.supports.is_empty() {
                return Err(tree_error("import", "give import alone, without supports or generate".into()));
            }
            let options = import.options().map_err(|message| tree_error("import", message))?;
            let model =
                import.model.as_ref().ok_or_else(|| tree_error("import", "the model file was not read".into()))?;
            let imported =
                super::qsm::build::supports(model, &options).map_err(|message| tree_error("import", message))?;
            return Ok(imported.supports);
        }
        match (&self.generate, self.supports.is_empty()) {
            (Some(_), false) => Err(tree_error("generate", "give either supports or generate, not both".into())),
            (None, true) => Err(tree_error("supports", "a tree needs supports, generate settings or an import".into())),
            (Some(settings), true) => {
                settings.check().map_err(|message| tree_error("generate", message))?;
                Ok(generate::generate(settings).into_iter().enumerate().flat_map(prefixed).collect())
            }
            (None, false) => self
                .supports
                .iter()
                .enumerate()
                .map(|(support, def)| {
                    def.spec().map_err(|(field, message)| TreeError { support: Some(support), field, message })
                })
                .collect(),
        }
    }
}

/// The name of the support at the root of `name`'s parents among `specs` (itself when it has
/// none; where the parents run out or loop, the last one reached).
fn root_of(specs: &[SupportSpec], name: &str) -> String {
    let mut at = name;
    for _ in 0..specs.len() {
        let parent = specs.iter().find(|s| s.name == at).and_then(|spec| match &spec.shape {
            Shape::Attached { parent, .. } | Shape::Fork { parent, .. } => Some(parent.as_str()),
            Shape::Polyline { .. } => None,
        });
        match parent {
            Some(parent) => at = parent,
            None => break,
        }
    }
    at.to_string()
}

/// The supports of generated tree `index`, renamed `t<index + 1>-<name>` so that the supports of
/// all the trees generated into one entity have distinct names.
pub(super) fn prefixed((index, supports): (usize, Vec<SupportSpec>)) -> Vec<SupportSpec> {
    let rename = |name: &str| format!("t{}-{name}", index + 1);
    supports
        .into_iter()
        .map(|mut spec| {
            spec.name = rename(&spec.name);
            if let Shape::Fork { parent, .. } = &mut spec.shape {
                *parent = rename(parent);
            }
            spec
        })
        .collect()
}
