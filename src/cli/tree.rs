//! `canopy tree`: tree scenes written from a seed, or from a scanned tree's model.

use super::refuse_to_replace;
use crate::sloth::Supports;
use crate::sloth::gait::FREE_SPEED;
use crate::sloth::rig::Proportions;
use crate::sloth::survey::{BoughWalk, Outcome, survey};
use crate::tree::GeneratorSettings;
use crate::tree::generate::{generate, scene_text, support_yaml};
use crate::tree::qsm::build::{ImportOptions, supports};
use crate::tree::qsm::{self, QsmFormat};
use crate::tree::{Shape, SupportSpec, Tree};
use bevy::math::Vec3;
use clap::{Args, Subcommand};
use std::fmt::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// `canopy tree ...`.
#[derive(Subcommand, Debug)]
pub enum TreeCommand {
    /// Write a scene of seeded, generated trees: an ordinary scene file to play and edit.
    Generate(GenerateArgs),
    /// Write a scene of a scanned tree's quantitative structure model (TreeQSM's .mat or text
    /// export, SimpleForest's or aRchi's CSV), its supports written out to play and edit.
    Import(ImportArgs),
}

/// `canopy tree import`.
#[derive(Args, Debug)]
pub struct ImportArgs {
    /// The model's file.
    file: PathBuf,
    /// Its format (treeqsm-mat, treeqsm-text, simpleforest-csv, archi-csv); found from the
    /// file when not given.
    #[arg(long, value_parser = parse_format)]
    format: Option<QsmFormat>,
    /// Drop cylinders thinner than this radius in metres, and what grows from them.
    #[arg(long, default_value_t = 0.0)]
    min_radius_m: f32,
    /// Keep the cylinders thinner than `--min-radius-m` instead, as supports drawn but never
    /// gripped (the tree's `grip_min_radius_m`).
    #[arg(long)]
    draw_thin: bool,
    /// Drop a support's points within this many metres of the line through their neighbours.
    #[arg(long, default_value_t = 0.0)]
    simplify_m: f32,
    /// Keep the model's coordinates (turned y up) instead of standing the tree on the origin.
    #[arg(long)]
    keep_base: bool,
    /// Put a sloth on autorun on the longest bough it walks along (found as `canopy sloth
    /// survey` finds them).
    #[arg(long)]
    sloth: bool,
    /// The scene file to write.
    #[arg(long, value_name = "SCENE.yaml")]
    out: PathBuf,
    /// Replace `--out` if it exists (otherwise an existing file is never overwritten).
    #[arg(long)]
    force: bool,
}

/// The name of an imported tree's entity.
const TREE_NAME: &str = "scan";

/// The longest bough of `supports` (an imported tree's) that a sloth walks along, and where on
/// it to place the sloth, 0 to 1 of its length.
fn walked_bough(supports: &[SupportSpec], grip_min_radius_m: f32) -> Option<(String, f32)> {
    let tree = Tree { grip_min_radius_m, ..Tree::build(supports).ok()? };
    let paths = Supports::new([(TREE_NAME, &tree)]);
    let walks = survey(&paths, Proportions::default(), FREE_SPEED, 1.0, 60.0);
    let walked = |walk: &&BoughWalk| {
        matches!(walk.outcome, Outcome::ReachedEnd | Outcome::WentOn(_) | Outcome::StillWalking { .. })
    };
    let longest = walks.iter().filter(walked).max_by(|a, b| a.length.total_cmp(&b.length))?;
    Some((longest.label.clone(), longest.fraction))
}

/// A format's name on the command line: its scene-file name with dashes or underscores.
fn parse_format(name: &str) -> Result<QsmFormat, String> {
    serde_yaml::from_str(&name.replace('-', "_"))
        .map_err(|_| "expected treeqsm-mat, treeqsm-text, simpleforest-csv or archi-csv".to_string())
}

/// `canopy tree generate`.
#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// The seed: the same seed and settings always give the same trees.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Trees, on a jittered grid.
    #[arg(long, default_value_t = 1)]
    trunks: u32,
    /// Trunk height in metres.
    #[arg(long, default_value_t = 6.0)]
    height: f32,
    /// Forks per support.
    #[arg(long, default_value_t = 5)]
    branches: u32,
    /// Levels of forks below the trunk (at most 4).
    #[arg(long, default_value_t = 2)]
    depth: u32,
    /// Distance between neighbouring trees in metres.
    #[arg(long, default_value_t = 6.0)]
    spacing: f32,
    /// The scene file to write.
    #[arg(long, value_name = "SCENE.yaml")]
    out: PathBuf,
    /// Replace `--out` if it exists (otherwise an existing file is never overwritten).
    #[arg(long)]
    force: bool,
}

impl TreeCommand {
    /// Runs the tree command.
    pub fn run(self) -> ExitCode {
        match self {
            TreeCommand::Generate(args) => args.generate(),
            TreeCommand::Import(args) => args.import(),
        }
    }
}

impl GenerateArgs {
    /// Writes the scene: exit 0 with it written, 1 if it could not be, 2 for bad settings.
    fn generate(&self) -> ExitCode {
        let settings = GeneratorSettings {
            seed: self.seed,
            trunks: self.trunks,
            height: self.height,
            branches: self.branches,
            depth: self.depth,
            spacing: self.spacing,
        };
        if let Err(error) = settings.check() {
            eprintln!("canopy tree generate: {error}");
            return ExitCode::from(2);
        }
        if let Some(refused) = refuse_to_replace(&self.out, self.force) {
            return refused;
        }
        let trees = generate(&settings);
        let supports: usize = trees.iter().map(Vec::len).sum();
        match std::fs::write(&self.out, scene_text(&settings, &trees)) {
            Ok(()) => {
                println!("{}: {} trees, {supports} supports", self.out.display(), trees.len());
                ExitCode::SUCCESS
            }
            Err(error) => {
                eprintln!("{}: cannot write the scene: {error}", self.out.display());
                ExitCode::from(1)
            }
        }
    }
}

impl ImportArgs {
    /// Writes the scene: exit 0 with it written, 1 if it could not be, 2 for a bad model or
    /// bad settings.
    fn import(&self) -> ExitCode {
        let path = self.file.display();
        let bytes = match std::fs::read(&self.file) {
            Ok(bytes) => bytes,
            Err(error) => {
                eprintln!("{path}: cannot read the file: {error}");
                return ExitCode::from(2);
            }
        };
        let model = match qsm::read(&bytes, self.format) {
            Ok(model) => model,
            Err(error) => {
                match error.location {
                    Some((line, column)) => eprintln!("{path}:{line}:{column}: {}", error.message),
                    None => eprintln!("{path}: {}", error.message),
                }
                return ExitCode::from(2);
            }
        };
        let options = ImportOptions {
            min_radius_m: self.min_radius_m,
            draw_thin: self.draw_thin,
            simplify_m: self.simplify_m,
            keep_base: self.keep_base,
        };
        let grip_min_radius_m = if self.draw_thin { self.min_radius_m } else { 0.0 };
        let imported = match supports(&model, &options) {
            Ok(imported) => imported,
            Err(error) => {
                eprintln!("{path}: {error}");
                return ExitCode::from(2);
            }
        };
        if let Some(refused) = refuse_to_replace(&self.out, self.force) {
            return refused;
        }
        let sloth = if self.sloth {
            match walked_bough(&imported.supports, grip_min_radius_m) {
                Some(bough) => Some(bough),
                None => {
                    eprintln!("{path}: no bough of the tree that a sloth walks along");
                    return ExitCode::from(2);
                }
            }
        } else {
            None
        };
        let file = self.file.display().to_string();
        let text = imported_scene_text(&file, model.format, &imported.supports, grip_min_radius_m, sloth);
        match std::fs::write(&self.out, text) {
            Ok(()) => {
                println!(
                    "{}: {} supports from {} of the {} cylinders ({} thinner than {} m {}, {} in fragments \
                     connected to nothing)",
                    self.out.display(),
                    imported.supports.len(),
                    imported.cylinders,
                    model.cylinders.len(),
                    imported.thin,
                    self.min_radius_m,
                    if self.draw_thin { "drawn, never gripped" } else { "dropped" },
                    imported.fragments
                );
                ExitCode::SUCCESS
            }
            Err(error) => {
                eprintln!("{}: cannot write the scene: {error}", self.out.display());
                ExitCode::from(1)
            }
        }
    }
}

/// A scene holding the tree of `supports` (those thinner than `grip_min_radius_m` never
/// gripped), imported from `file`, with a camera that frames it, the ground under it, and a
/// sloth on autorun on the support and at the place `sloth` names.
fn imported_scene_text(
    file: &str,
    format: QsmFormat,
    supports: &[SupportSpec],
    grip_min_radius_m: f32,
    sloth: Option<(String, f32)>,
) -> String {
    let points = supports.iter().flat_map(|s| match &s.shape {
        Shape::Polyline { points, .. } | Shape::Attached { points, .. } => points.as_slice(),
        Shape::Fork { .. } => &[],
    });
    let (low, high) = points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(low, high), p| (low.min(*p), high.max(*p)));
    let centre = (low + high) * 0.5;
    let size = (high - low).max_element().max(1.0);
    let mut text = String::new();
    let _ = writeln!(
        text,
        "# Imported by `canopy tree import` from {file} ({format}).\n\
         # An ordinary scene: edit it freely (the format is described in docs/scenes.md).\n"
    );
    let _ = writeln!(
        text,
        "camera:\n  position: [{:.2}, {:.2}, {:.2}]\n  look_at: [{:.2}, {:.2}, {:.2}]\n  fov_deg: 50\n  far: {:.0}\n",
        centre.x,
        centre.y,
        centre.z + size * 1.4,
        centre.x,
        centre.y,
        centre.z,
        (size * 10.0).max(100.0)
    );
    let _ = writeln!(text, "entities:");
    if let Some((support, at)) = sloth {
        let _ = writeln!(text, "  - name: sloth\n    sloth: {{ support: {support}, at: {at:.4}, autorun: true }}\n");
    }
    let _ = writeln!(
        text,
        "  - name: ground\n    shape: {{ primitive: plane, size: [{0:.1}, 1, {0:.1}], position: [{1:.2}, {2:.2}, {3:.2}], \
         color: [0.42, 0.52, 0.33] }}\n",
        size * 2.0,
        centre.x,
        low.y,
        centre.z
    );
    let _ = writeln!(text, "  - name: {TREE_NAME}\n    tree:");
    if grip_min_radius_m > 0.0 {
        let _ = writeln!(text, "      grip_min_radius_m: {grip_min_radius_m}");
    }
    let _ = writeln!(text, "      supports:");
    for support in supports {
        let _ = writeln!(text, "        - {}", support_yaml(support, 4));
    }
    text
}
