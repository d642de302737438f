//! `canopy mesh` and `canopy deform`: sample surfaces written as mesh files, and a region of a
//! mesh file shrunk by a surface deformer.

use super::deform_batch::{self, BatchError};
use super::refuse_to_replace;
use crate::soft_body::deform::Settings;
use crate::soft_body::sample::Shape;
use crate::spatial::mesh_io;
use clap::builder::PossibleValue;
use clap::{Args, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `canopy mesh ...`.
#[derive(Subcommand, Debug)]
pub enum MeshCommand {
    /// Write one of the project's sample surfaces as an .obj or .ply file.
    Sample {
        /// Which surface.
        #[arg(value_enum)]
        name: Shape,
        /// The file to write.
        #[arg(long)]
        out: PathBuf,
        /// Vertices along a side (the belly), around (the cap, the sphere and the torus) or
        /// rings from hips to chest (the torso), 3 to 1000.
        #[arg(long, default_value_t = 65, value_parser = clap::value_parser!(u32).range(3..=1000))]
        size: u32,
        /// Replace `--out` if it exists.
        #[arg(long)]
        force: bool,
    },
}

/// The sample surfaces by the names and descriptions they have in scene files.
impl ValueEnum for Shape {
    fn value_variants<'a>() -> &'a [Self] {
        &Shape::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()).help(self.about()))
    }
}

/// `canopy deform`.
#[derive(Args, Debug)]
pub struct DeformArgs {
    /// The mesh: an .obj, .ply, .stl, .gltf or .glb file.
    input: PathBuf,
    /// The outline: three or more points on the surface as x:y:z in metres
    /// (`0.1:0.05:0,-0.1:0.05:0,0:0.05:0.1`), or vertex indices of the mesh as read (welded;
    /// an OBJ's numbered by first use in its faces), joined along the surface.
    #[arg(long, allow_hyphen_values = true)]
    region: String,
    /// Two points to measure between before and after, along the surface and straight,
    /// written as the outline's (`0.1:0.05:0,-0.1:0.05:0` or `12,40`).
    #[arg(long, allow_hyphen_values = true)]
    measure: Option<String>,
    /// The deformer: edge (a length constraint per edge), edge-sum or area.
    #[arg(long, default_value = "edge")]
    method: String,
    /// For edge-sum and area: projection (the constraint's projection), source (the
    /// source's step), or a step rule of the source's theory: constant, decreasing, steepest
    /// or coordinate.
    #[arg(long, default_value = "projection")]
    variant: String,
    /// The coefficient, in (0, 1] (below 1 for area).
    #[arg(long)]
    k: f32,
    /// The convergence threshold: metres of shift for edge, a share of the target for
    /// edge-sum and area.
    #[arg(long, default_value_t = 1e-5)]
    eps: f64,
    /// Iterations at most.
    #[arg(long, default_value_t = 10_000)]
    max_iterations: u32,
    /// Where to write the whole deformed mesh: an .obj or .ply file.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
}

impl MeshCommand {
    /// Runs the mesh command.
    pub fn run(self) -> ExitCode {
        let MeshCommand::Sample { name, out, size, force } = self;
        write_sample(name, &out, size, force)
    }
}

/// `canopy mesh sample`: exit 0 with the file written, 1 if it could not be.
fn write_sample(shape: Shape, out: &Path, size: u32, force: bool) -> ExitCode {
    if let Some(refused) = refuse_to_replace(out, force) {
        return refused;
    }
    let surface = shape.make(size);
    let mesh = mesh_io::TriangleMesh { positions: surface.positions, triangles: surface.triangles };
    match mesh_io::write(&mesh, out) {
        Ok(()) => {
            println!("{}: {} vertices, {} triangles", out.display(), mesh.positions.len(), mesh.triangles.len());
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("canopy mesh sample: {}: {error}", out.display());
            ExitCode::from(1)
        }
    }
}

impl DeformArgs {
    /// `canopy deform`: exit 0 with the report printed, 1 for bad input, 2 for bad settings.
    pub fn deform(&self) -> ExitCode {
        if let Some(refused) = refuse_to_replace(&self.out, self.force) {
            return refused;
        }
        let settings = Settings { k: self.k, eps: self.eps, max_iterations: self.max_iterations };
        let measure = self.measure.as_deref().map(deform_batch::parse_measure).transpose();
        let result = deform_batch::method(&self.method, &self.variant)
            .and_then(|method| Ok((method, deform_batch::parse_marks(&self.region)?, measure?)))
            .and_then(|(method, marks, measure)| {
                deform_batch::run(&self.input, &marks, measure, method, settings, &self.out)
            });
        match result {
            Ok(report) => {
                println!("{}", serde_json::to_string_pretty(&report).unwrap_or_default());
                ExitCode::SUCCESS
            }
            Err(error @ BatchError::Settings(_)) => {
                eprintln!("canopy deform: {error}");
                ExitCode::from(2)
            }
            Err(error) => {
                eprintln!("canopy deform: {error}");
                ExitCode::from(1)
            }
        }
    }
}
