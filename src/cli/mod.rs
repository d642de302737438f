//! The `canopy` command line: the clap tree of its commands and their dispatch. Each command
//! group is a file of its own with its arguments and handlers, and the tool code that only a
//! command uses lives beside it.
//!
//! | module | commands |
//! |---|---|
//! | [`play`] | `play` (the default), `run`, `check` |
//! | [`test`] | `test`: scene tests |
//! | [`tree`] | `tree generate` |
//! | [`sloth`] | `sloth gait` |
//! | [`terrain`] | `terrain generate`, `terrain stats`, `terrain textures` |
//! | [`muscle`] | `muscle table`: the source's tables of radii and growth, and the fitted growth |
//! | [`mesh`] | `mesh sample`, `deform`, with [`deform_batch`] |
//! | [`ar`] | `ar marker`, `ar board`, `ar sequence`, `ar detect`, with [`ar_calibrate`] (`ar calibrate`), [`ar_sweep`] (`ar sweep`) and [`board_layout`] |
//! | [`bench`] | `bench terrain`, with [`section_timing`] |
//!
//! Handlers print what they made and exit 0; bad input is 1 (a file that cannot be read or
//! written) or 2 (settings that make no sense), with a message naming what is wrong.

pub mod ar;
pub mod ar_calibrate;
pub mod ar_sweep;
pub mod bench;
pub mod board_layout;
pub mod deform_batch;
pub mod mesh;
pub mod muscle;
pub mod play;
pub mod section_timing;
pub mod sloth;
pub mod terrain;
pub mod test;
pub mod tree;

use crate::raster::MAX_TARGET_SIZE;
use bevy::math::UVec2;
use clap::{Parser, Subcommand};
use std::path::Path;
use std::process::ExitCode;

/// Canopy plays interactive 3D scenes described in YAML files, drawn by a CPU rasterizer.
#[derive(Parser, Debug)]
#[command(name = "canopy", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Play a scene in a window with keyboard controls (the default). Without a display,
    /// render it headless to a PNG and print where.
    Play(play::PlayArgs),
    /// Run a scene headless at a fixed 60 Hz step and write its state and last frame.
    Run(play::RunArgs),
    /// Check scene files without running them; exit 0 only if all are valid.
    Check(play::CheckArgs),
    /// Run scene tests (`*.test.yaml`): exit 0 if all pass, 1 if one fails, 2 if one cannot
    /// run as written.
    Test(test::TestArgs),
    /// Tree tools.
    Tree {
        #[command(subcommand)]
        action: tree::TreeCommand,
    },
    /// Muscle tools: the model beside the real biceps.
    Muscle {
        #[command(subcommand)]
        action: muscle::MuscleCommand,
    },
    /// Sloth tools: the gait measured beside the study's.
    Sloth {
        #[command(subcommand)]
        action: sloth::SlothCommand,
    },
    /// Heightmap tools.
    Terrain {
        #[command(subcommand)]
        action: terrain::TerrainCommand,
    },
    /// Shrink a region of a mesh file with a surface deformer and print the report as JSON.
    Deform(mesh::DeformArgs),
    /// Mesh tools.
    Mesh {
        #[command(subcommand)]
        action: mesh::MeshCommand,
    },
    /// Augmented-reality tools: printable markers, sample camera sequences, and the marker
    /// detector on images.
    Ar {
        #[command(subcommand)]
        action: ar::ArCommand,
    },
    /// Measurements.
    Bench {
        #[command(subcommand)]
        action: bench::BenchCommand,
    },
}

/// Reads the command line and runs the command it names (`play` without one).
pub fn main() -> ExitCode {
    match Cli::parse().command.unwrap_or_else(|| Command::Play(play::PlayArgs::default())) {
        Command::Play(args) => args.play(),
        Command::Run(args) => args.run(),
        Command::Check(args) => args.check(),
        Command::Test(args) => args.test(),
        Command::Tree { action } => action.run(),
        Command::Muscle { action } => action.run(),
        Command::Sloth { action } => action.run(),
        Command::Terrain { action } => action.run(),
        Command::Deform(args) => args.deform(),
        Command::Mesh { action } => action.run(),
        Command::Ar { action } => action.run(),
        Command::Bench { action } => action.run(),
    }
}

/// Exit 1, saying why, if `out` exists and `force` does not say to replace it: nothing the
/// user made is replaced unasked.
fn refuse_to_replace(out: &Path, force: bool) -> Option<ExitCode> {
    (out.exists() && !force).then(|| {
        eprintln!("{}: already exists; choose another --out, or add --force to replace it", out.display());
        ExitCode::from(1)
    })
}

/// A frame size written `WIDTHxHEIGHT`, each side from 1 to [`MAX_TARGET_SIZE`].
fn parse_size(text: &str) -> Result<UVec2, String> {
    let error =
        || format!("expected WIDTHxHEIGHT with each from 1 to {MAX_TARGET_SIZE}, e.g. 1280x720; found `{text}`");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(error)?;
    let (w, h) = (w.parse::<u32>().map_err(|_| error())?, h.parse::<u32>().map_err(|_| error())?);
    let valid = 1..=MAX_TARGET_SIZE;
    if valid.contains(&w) && valid.contains(&h) { Ok(UVec2::new(w, h)) } else { Err(error()) }
}

/// Markers across and down a board, `XxY`.
fn parse_markers(text: &str) -> Result<[u32; 2], String> {
    let size = parse_size(text)?;
    Ok([size.x, size.y])
}

/// A marker dictionary given on the command line: OpenCV's name of a predefined one, or a
/// dictionary file (`.yml`, `.yaml` or `.json`, as OpenCV's `writeDictionary` writes it).
fn dictionary_of(text: &str) -> Result<canopy_vision::Dictionary, String> {
    let lower = text.to_ascii_lowercase();
    if [".yml", ".yaml", ".json"].iter().any(|extension| lower.ends_with(extension)) {
        crate::ar::dictionary_file::read(Path::new(text)).map_err(|error| error.to_string())
    } else {
        canopy_vision::Dictionary::named(text).map_err(|error| error.to_string())
    }
}

/// Simulated seconds, from 0 to `max`.
fn parse_seconds(text: &str, max: f64) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(seconds) if seconds.is_finite() && (0.0..=max).contains(&seconds) => Ok(seconds),
        _ => Err(format!("expected seconds from 0 to {max}, found `{text}`")),
    }
}
