//! `canopy tree`: tree scenes written from a seed.

use super::refuse_to_replace;
use crate::tree::GeneratorSettings;
use crate::tree::generate::{generate, scene_text};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// `canopy tree ...`.
#[derive(Subcommand, Debug)]
pub enum TreeCommand {
    /// Write a scene of seeded, generated trees: an ordinary scene file to play and edit.
    Generate(GenerateArgs),
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
