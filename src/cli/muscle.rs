//! `canopy muscle table`: a scene's muscles beside the real biceps, as the source's tables
//! have them: the real radii (its Table 4.1), the model's radii (Table 4.2) at 0, 30, 60 and
//! 90 degrees of elbow flexion, the growth from 0 to 90 degrees (Table 4.3), and the model
//! with its growth fitted to the measurements.

use crate::foundation::entity::SceneEntity;
use crate::muscle::MuscleBody;
use crate::muscle::comparison::{REAL_BICEPS_RADII, growth_table, model_radii};
use crate::run::live_app;
use bevy::math::UVec2;
use clap::Subcommand;
use std::fmt::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// Muscle tools.
#[derive(Subcommand, Debug)]
pub enum MuscleCommand {
    /// Print a scene's muscles beside the real biceps: the radii node by node at 0, 30, 60 and
    /// 90 degrees of flexion (real, model, fitted), the growth from 0 to 90 degrees, and how
    /// much of the model's difference from the measurements the fitted growth removes.
    Table {
        /// The scene file.
        scene: PathBuf,
        /// Only the muscle of this name (default: every muscle).
        #[arg(long)]
        muscle: Option<String>,
    },
}

impl MuscleCommand {
    /// Runs the command.
    pub fn run(self) -> ExitCode {
        let MuscleCommand::Table { scene, muscle } = self;
        match tables(&scene, muscle.as_deref()) {
            Ok(text) => {
                print!("{text}");
                ExitCode::SUCCESS
            }
            Err(message) => {
                eprintln!("{message}");
                ExitCode::from(1)
            }
        }
    }
}

/// The tables of `scene`'s muscles (of the one named `wanted`, if given).
fn tables(scene: &std::path::Path, wanted: Option<&str>) -> Result<String, String> {
    let mut app = live_app(scene, UVec2::new(64, 36), None, false).map_err(|error| error.to_string())?;
    let world = app.world_mut();
    let mut muscles: Vec<(usize, String, MuscleBody)> = world
        .query::<(&SceneEntity, &MuscleBody)>()
        .iter(world)
        .map(|(entity, body)| (entity.index, entity.name.clone(), body.clone()))
        .collect();
    muscles.sort_by_key(|(index, ..)| *index);
    let names: Vec<String> = muscles.iter().map(|(_, name, _)| name.clone()).collect();
    if let Some(wanted) = wanted {
        muscles.retain(|(_, name, _)| name == wanted);
        if muscles.is_empty() {
            return Err(format!("{}: no muscle is named `{wanted}` (muscles: {})", scene.display(), names.join(", ")));
        }
    }
    if muscles.is_empty() {
        return Err(format!("{}: the scene has no muscle", scene.display()));
    }
    Ok(muscles.iter().map(|(_, name, body)| muscle_tables(name, body)).collect::<Vec<_>>().join("\n"))
}

/// One muscle's tables. The configured model is the one the scene's `grow_mults` give; the
/// fitted one, where the model is laid out as the measurements are, is beside it.
fn muscle_tables(name: &str, body: &MuscleBody) -> String {
    let configured = match &body.fit {
        Some(fit) => body.model.with_mults(fit.configured.clone()).unwrap_or_else(|_| body.model.clone()),
        None => body.model.clone(),
    };
    let fitted = body.fit.as_ref().and_then(|fit| body.model.with_mults(fit.mults.clone()).ok());
    let model_columns = model_radii(&configured, &body.carcass);
    let fitted_columns = fitted.as_ref().map(|fitted| model_radii(fitted, &body.carcass));
    let mut out = String::new();
    let grows = if body.fitted { "the fitted multipliers" } else { "its grow_mults" };
    let _ = writeln!(out, "{name}: {} nodes, growing with {grows}", body.model.nodes());
    // A model laid out otherwise than the measurements has only its own column.
    let measured = fitted_columns.is_some();
    let columns: &[&str] = if measured { &["real", "model", "fitted"] } else { &["model"] };
    let title = if measured { "real (Table 4.1), model (Table 4.2) and fitted" } else { "the model's (Table 4.2)" };
    let _ = writeln!(out, "\nRadii by node: {title}, at each flexion");
    let width = columns.len() * 7 - 1;
    let mut header = String::from("node");
    for (flexion, _) in REAL_BICEPS_RADII {
        let _ = write!(header, " | {:>width$}", format!("{flexion:.0} deg"));
    }
    let _ = writeln!(out, "{header}");
    let mut header = String::from("    ");
    for _ in REAL_BICEPS_RADII {
        let names: Vec<String> = columns.iter().map(|name| format!("{name:>6}")).collect();
        let _ = write!(header, " | {}", names.join(" "));
    }
    let _ = writeln!(out, "{header}");
    let cell = |value: Option<f64>| value.map_or(format!("{:>6}", "-"), |v| format!("{v:>6.2}"));
    for node in 0..body.model.nodes() {
        let mut row = format!("{node:>4}");
        for (k, (_, real)) in REAL_BICEPS_RADII.iter().enumerate() {
            let model = cell(model_columns[k].as_ref().map(|radii| radii[node]));
            match &fitted_columns {
                Some(fitted) => {
                    let real = cell(node.checked_sub(1).and_then(|i| real.get(i).copied()));
                    let fit = cell(fitted[k].as_ref().map(|radii| radii[node]));
                    let _ = write!(row, " | {real} {model} {fit}");
                }
                None => {
                    let _ = write!(row, " | {model}");
                }
            }
        }
        let _ = writeln!(out, "{row}");
    }
    if let Some(table) = growth_table(&configured, &body.carcass) {
        let fitted_table = fitted.as_ref().and_then(|fitted| growth_table(fitted, &body.carcass));
        let _ = writeln!(out, "\nGrowth from 0 to 90 degrees (Table 4.3)");
        let _ = writeln!(
            out,
            "node | {:>6} {:>6} {:>12} | {:>6} {:>12}",
            "real", "model", "real / model", "fitted", "real / fitted"
        );
        for (k, row) in table.iter().enumerate() {
            let ratio = |ratio: Option<f64>| ratio.map_or(format!("{:>12}", "-"), |r| format!("{r:>12.2}"));
            let fitted_row = fitted_table.as_ref().map(|table| table[k]);
            let _ = writeln!(
                out,
                "{:>4} | {:>6.1} {:>6.2} {} | {} {}",
                row.node,
                row.real,
                row.model,
                ratio(row.ratio),
                cell(fitted_row.map(|row| row.model)),
                ratio(fitted_row.and_then(|row| row.ratio)),
            );
        }
    }
    if let Some(fit) = &body.fit {
        let mults: Vec<String> = fit.mults.iter().map(|m| format!("{m:.2}")).collect();
        let _ = writeln!(out, "\nFitted grow_mults: [{}]", mults.join(", "));
        let _ = writeln!(
            out,
            "Root-mean-square difference from the real radii: {:.2} with grow_mults, {:.2} fitted: the fit closes {:.0} % of the gap",
            fit.rms_before,
            fit.rms_after,
            fit.gap_closed() * 100.0
        );
    }
    out
}
