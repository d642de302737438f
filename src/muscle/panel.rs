//! The muscle's section of the window's panel: volume and its error, the radii, a node
//! editor, a plot of the model's radii against the real biceps measurements, and the source's
//! Table 4.3 of their growth.

use super::comparison::{REAL_BICEPS_RADII, growth_table, model_radii};
use super::fit::fit_growth;
use super::plugin::{MuscleBody, MuscleParams};
use bevy::prelude::*;
use bevy_egui::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints, Points};

/// Colours of the four flexion angles in the plot.
const ANGLE_COLORS: [egui::Color32; 4] = [
    egui::Color32::from_rgb(90, 160, 255),
    egui::Color32::from_rgb(90, 210, 120),
    egui::Color32::from_rgb(240, 190, 60),
    egui::Color32::from_rgb(240, 90, 80),
];

/// Which node the editor shows, per muscle entity.
#[derive(Component, Default)]
pub(super) struct SelectedNode(pub usize);

/// Draws the muscle section for `entity`; edits go straight to the model.
pub fn muscle_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    let node = entity_mut.get::<SelectedNode>().map_or(0, |n| n.0);
    let Some(mut body) = entity_mut.get_mut::<MuscleBody>() else { return };
    let model = &body.model;
    let (volume, rest) = (model.volume(), model.rest_volume());
    egui::Grid::new("muscle-figures").num_columns(2).show(ui, |ui| {
        ui.label("length");
        ui.label(format!("{:.3}", model.length()));
        ui.end_row();
        ui.label("flexion");
        ui.label(format!("{:.2} deg", body.carcass.flexion_from_length(model.length()).value.to_degrees()));
        ui.end_row();
        ui.label("volume");
        ui.label(format!("{volume:.3}"));
        ui.end_row();
        ui.label("relative error");
        ui.label(format!("{:.2e}", ((volume - rest) / rest).abs()));
        ui.end_row();
    });
    if let Some(message) = &body.message {
        ui.colored_label(egui::Color32::LIGHT_RED, message);
    }
    let radii: Vec<String> = model.radii().iter().map(|r| format!("{r:.2}")).collect();
    ui.label(format!("radii: {}", radii.join(", ")));

    ui.separator();
    let nodes = model.nodes();
    let mut node = node.min(nodes - 1);
    let (mut radius, mut mult) = (model.rest_radii()[node], model.mults()[node]);
    let mut edited = false;
    ui.horizontal(|ui| {
        ui.label("node");
        ui.add(egui::DragValue::new(&mut node).range(0..=nodes - 1));
    });
    ui.horizontal(|ui| {
        ui.label("rest radius");
        edited |= ui.add(egui::DragValue::new(&mut radius).speed(0.1).range(0.01..=1e6)).changed();
        ui.label("multiplier");
        edited |= ui.add(egui::DragValue::new(&mut mult).speed(0.05)).changed();
    });
    if edited {
        match body.model.edit_node(node, radius, mult) {
            // The edited multipliers are the ones a fit starts from now.
            Ok(()) => (body.fit, body.fitted) = (fit_growth(&body.model, &body.carcass), false),
            Err(error) => body.message = Some(error.to_string()),
        }
    }
    if let Some(fit) = &body.fit {
        let mut fitted = body.fitted;
        ui.checkbox(&mut fitted, "growth fitted to the real biceps")
            .on_hover_text("multipliers chosen to bring the radii at 0, 30, 60 and 90 degrees nearest the measurements; the volume stays exact");
        ui.label(format!(
            "radii from the real: {:.2} rms with the configured multipliers, {:.2} fitted ({:.0} % of the gap closed)",
            fit.rms_before,
            fit.rms_after,
            fit.gap_closed() * 100.0
        ));
        if fitted != body.fitted {
            body.use_fit(fitted);
            edited = true;
        }
    }
    let curves = model_radii(&body.model, &body.carcass);
    let table = growth_table(&body.model, &body.carcass);
    entity_mut.insert(SelectedNode(node));
    if edited && let Some(mut params) = entity_mut.get_mut::<MuscleParams>() {
        // Re-applies the current flexion to the edited rest state.
        params.set_changed();
    }

    ui.label("radii by node: model (lines) and real biceps (dots)");
    Plot::new("muscle-radii")
        // The wheel scrolls the panel, not the plot.
        .allow_scroll(false)
        .allow_zoom(false)
        .legend(Legend::default().position(egui_plot::Corner::LeftTop))
        .height(180.0)
        .x_axis_label("node")
        .y_axis_label("radius")
        .show(ui, |plot| {
            for (((angle, real), model), color) in REAL_BICEPS_RADII.iter().zip(&curves).zip(ANGLE_COLORS) {
                // Model (line) and measurement (dots) of one angle share a legend entry.
                let name = format!("{angle:.0} deg");
                if let Some(model) = model {
                    let points: PlotPoints = model.iter().enumerate().map(|(i, r)| [i as f64, *r]).collect();
                    plot.line(Line::new(name.clone(), points).color(color));
                }
                let points: PlotPoints = real.iter().enumerate().map(|(i, r)| [i as f64 + 1.0, *r]).collect();
                plot.points(Points::new(name, points).color(color).radius(3.0));
            }
        });
    if let Some(table) = table {
        ui.label("growth from 0 to 90 degrees (the source's Table 4.3)");
        egui::Grid::new("muscle-growth").num_columns(4).striped(true).show(ui, |ui| {
            for heading in ["node", "real", "model", "real / model"] {
                ui.strong(heading);
            }
            ui.end_row();
            for row in table {
                ui.label(row.node.to_string());
                ui.label(format!("{:.1}", row.real));
                ui.label(format!("{:.2}", row.model));
                ui.label(row.ratio.map_or("-".to_string(), |ratio| format!("{ratio:.2}")));
                ui.end_row();
            }
        });
    }
}
