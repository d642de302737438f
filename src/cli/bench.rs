//! `canopy bench`: the source's measurements, repeated.

use super::section_timing::{self, SIZES, save_timing_plot};
use bevy::math::UVec2;
use clap::Subcommand;
use std::path::PathBuf;
use std::process::ExitCode;

/// `canopy bench ...`.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// The source's experiment: time to produce the image of the visible section against its
    /// size, with and without shadows; prints the table and draws the plot.
    Terrain {
        /// The plot to write (PNG).
        #[arg(long, value_name = "PLOT.png")]
        out: PathBuf,
        /// Runs of each configuration.
        #[arg(long, default_value_t = 10)]
        runs: usize,
        /// Section sizes (vertices a side, 2 to 512).
        #[arg(long, num_args = 1.., default_values_t = SIZES)]
        sizes: Vec<u32>,
    },
}

impl BenchCommand {
    /// Runs the measurement: exit 0 with the table printed and the plot written, 1 if the plot
    /// could not be written, 2 for bad settings.
    pub fn run(self) -> ExitCode {
        let BenchCommand::Terrain { out, runs, sizes } = self;
        if let Some(bad) = sizes.iter().find(|s| !(2..=512).contains(*s)) {
            eprintln!("canopy bench terrain: a section size is 2 to 512 vertices a side, not {bad}");
            return ExitCode::from(2);
        }
        let pool = bevy::tasks::TaskPool::new();
        let timings = section_timing::run(&sizes, runs.max(1), UVec2::new(1280, 720), &pool);
        print!("{}", section_timing::table(&timings));
        match save_timing_plot(&timings, &out) {
            Ok(()) => {
                println!("plot: {}", out.display());
                ExitCode::SUCCESS
            }
            Err(error) => {
                eprintln!("{}: cannot write the plot: {error}", out.display());
                ExitCode::from(1)
            }
        }
    }
}
