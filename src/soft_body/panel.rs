//! The soft body's section of the window's panel: the surface's figures, the marks and the
//! region, the deformer with its `k` slider, threshold and cap, Apply, the collection with
//! each model's report, the comparison, and saving a model.

use super::deform::{Deformer, Variant};
use super::plugin::{Compare, ShrinkParams, SoftBody, SoftBodyAction, Tool, perform_on};
use super::workbench::ShrinkReport;
use crate::foundation::entity::SceneEntity;
use bevy::prelude::*;
use bevy_egui::egui;
use std::path::Path;

/// Where the panel saves models, relative to the working folder.
const SAVE_FOLDER: &str = "meshes";

/// Draws the soft body section for `entity`.
pub(super) fn soft_body_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    let name = entity_mut.get::<SceneEntity>().map_or("soft_body".to_string(), |s| s.name.clone());
    let (Some(mut params), Some(body)) = (entity_mut.get::<ShrinkParams>().cloned(), entity_mut.get::<SoftBody>())
    else {
        return;
    };
    let mut action = None;
    let mut save = None;
    figures(ui, body);
    ui.separator();
    ui.label(format!("{} marks: click points on the surface to outline a region", body.bench.marks().len()));
    match &body.region {
        Ok(region) => ui.label(format!(
            "region: {} vertices move, {} hold its outline",
            region.inside.len(),
            region.outline.len()
        )),
        Err(error) => ui.colored_label(egui::Color32::GRAY, error.to_string()),
    };
    ui.horizontal(|ui| {
        if ui.add_enabled(!body.bench.marks().is_empty(), egui::Button::new("Undo mark")).clicked() {
            action = Some(SoftBodyAction::UndoMark);
        }
        if ui.add_enabled(!body.bench.marks().is_empty(), egui::Button::new("Clear marks")).clicked() {
            action = Some(SoftBodyAction::ClearMarks);
        }
    });
    measure(ui, body, &mut action);
    ui.separator();
    settings(ui, &mut params);
    ui.horizontal(|ui| {
        let apply = ui.add_enabled(body.region.is_ok() && !body.shrinking, egui::Button::new("Apply"));
        if apply.on_hover_text("shrink the region of the surface shown into a new model").clicked() {
            action = Some(SoftBodyAction::Apply);
        }
        if body.shrinking {
            ui.spinner();
            ui.label("shrinking...");
        }
    });
    if let Some(message) = &body.message {
        ui.colored_label(egui::Color32::LIGHT_RED, message);
    }
    ui.separator();
    ui.label("collection");
    let shown = body.bench.shown();
    if ui.selectable_label(shown == 0, "original").clicked() {
        action = Some(SoftBodyAction::Show(0));
    }
    for (index, model) in body.bench.models().iter().enumerate() {
        if ui.selectable_label(shown == index + 1, &model.name).clicked() {
            action = Some(SoftBodyAction::Show(index + 1));
        }
    }
    if let Some(model) = shown.checked_sub(1).and_then(|i| body.bench.models().get(i)) {
        let base = if model.base == 0 { "the original".to_string() } else { format!("model {}", model.base) };
        ui.label(format!("made from {base}"));
        report(ui, &model.report);
    }
    ui.horizontal(|ui| {
        ui.label("compare");
        for (compare, label) in Compare::ALL {
            ui.radio_value(&mut params.compare, compare, label);
        }
    });
    ui.horizontal(|ui| {
        for extension in body.save_extensions() {
            let label = format!("Save {}", extension.to_uppercase());
            if ui.button(label).on_hover_text("the surface shown, in meshes/").clicked() {
                save = Some(extension);
            }
        }
    });
    let saved = save.map(|extension| body.save(Path::new(SAVE_FOLDER), &name, shown, extension));
    if entity_mut.get::<ShrinkParams>() != Some(&params) {
        entity_mut.insert(params.clone());
    }
    if let Some(action) = action {
        perform_on(&mut entity_mut, action);
    }
    let message = match saved {
        Some(Ok(path)) => format!("saved {}", path.display()),
        Some(Err(error)) => format!("not saved: {error}"),
        None => return,
    };
    if let Some(mut body) = entity_mut.get_mut::<SoftBody>() {
        body.message = Some(message);
    }
}

/// The measure tool: what a click does, and the two points' distances on the surface shown.
fn measure(ui: &mut egui::Ui, body: &SoftBody, action: &mut Option<SoftBodyAction>) {
    ui.horizontal(|ui| {
        ui.label("a click");
        for (tool, label) in [(Tool::Outline, "marks the outline"), (Tool::Measure, "measures")] {
            if ui.radio(body.tool == tool, label).clicked() {
                *action = Some(SoftBodyAction::UseTool(tool));
            }
        }
    });
    let text = match (body.bench.measured().len(), body.distances) {
        (_, Some(distances)) => format!(
            "{} along the surface, {:.1} mm straight",
            distances.along_m.map_or("no way".to_string(), |m| format!("{:.1} mm", m * 1e3)),
            distances.straight_m * 1e3
        ),
        (1, None) => "one point measured from: click the second".to_string(),
        _ => "no points measured".to_string(),
    };
    // On a line of its own, so that it wraps rather than widens the panel.
    ui.label(text);
    if ui.add_enabled(!body.bench.measured().is_empty(), egui::Button::new("Clear measure")).clicked() {
        *action = Some(SoftBodyAction::ClearMeasure);
    }
}

/// The surface's counts and what reading its file found.
fn figures(ui: &mut egui::Ui, body: &SoftBody) {
    let surface = body.bench.original();
    egui::Grid::new("soft-body-figures").num_columns(2).show(ui, |ui| {
        let rows = [
            ("vertices", surface.positions.len()),
            ("triangles", surface.triangles.len()),
            ("welded", body.read.welded),
            ("collapsed faces", body.read.degenerate),
            ("non-manifold edges", body.read.non_manifold_edges),
        ];
        for (label, count) in rows {
            ui.label(label);
            ui.label(count.to_string());
            ui.end_row();
        }
    });
}

/// The deformer choice and its settings.
fn settings(ui: &mut egui::Ui, params: &mut ShrinkParams) {
    ui.horizontal(|ui| {
        for deformer in Deformer::ALL {
            ui.radio_value(&mut params.method, deformer, deformer.label());
        }
    });
    if params.method != Deformer::EdgeLengths {
        ui.horizontal_wrapped(|ui| {
            for variant in Variant::ALL {
                ui.radio_value(&mut params.variant, variant, variant.label());
            }
        });
    }
    // Values from the file or a timeline outside a slider's range stay as they are until the
    // slider is moved; the area's k must stay below 1, and Apply says so when it is not.
    let edits = egui::SliderClamping::Edits;
    ui.add(egui::Slider::new(&mut params.k, 0.05..=1.0).clamping(edits).text("k"));
    ui.add(egui::Slider::new(&mut params.eps, 1e-10..=1e-2).logarithmic(true).clamping(edits).text("threshold"));
    let cap = egui::Slider::new(&mut params.max_iterations, 1.0..=100_000.0).logarithmic(true).integer();
    ui.add(cap.clamping(edits).text("cap"));
}

/// A model's report.
fn report(ui: &mut egui::Ui, report: &ShrinkReport) {
    let facts = &report.facts;
    egui::Grid::new("soft-body-report").num_columns(2).show(ui, |ui| {
        let rows = [
            ("region", format!("{} moving, {} held", report.region_vertices, report.outline_vertices)),
            ("k", format!("{}", report.k)),
            ("stopped", format!("{:?} after {} iterations", report.stop, report.iterations).to_lowercase()),
            ("error", format!("{:.3e}", report.error)),
            ("time", format!("{:.1} ms", report.time_ms)),
            ("area ratio", format!("{:.5}", facts.area_ratio)),
            ("volume between", format!("{:.3} cm³", facts.volume_between_m3 * 1e6)),
            ("edge sum ratio", format!("{:.5}", facts.edge_sum_ratio)),
            ("edge error", format!("max {:.4}, mean {:.4}", facts.max_edge_error, facts.mean_edge_error)),
            ("inverted", facts.inverted.to_string()),
            ("outline held", if facts.fixed_unchanged { "bit for bit" } else { "NO" }.to_string()),
            ("NaN", if facts.has_nan { "YES" } else { "none" }.to_string()),
        ];
        let measured = report.measure.map(|measured| {
            let along = |m: Option<f64>| m.map_or("no way".to_string(), |m| format!("{:.1}", m * 1e3));
            let (before, after) = (measured.before, measured.after);
            [
                ("along the surface", format!("{} -> {} mm", along(before.along_m), along(after.along_m))),
                ("straight", format!("{:.1} -> {:.1} mm", before.straight_m * 1e3, after.straight_m * 1e3)),
            ]
        });
        for (label, value) in rows.into_iter().chain(measured.into_iter().flatten()) {
            ui.label(label);
            ui.label(value);
            ui.end_row();
        }
    });
}
