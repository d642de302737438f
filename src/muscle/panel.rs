//! The muscle's section of the window's panel: volume and its error, the radii, a node
//! editor, and a plot of the model's radii against the real biceps measurements.

use super::plugin::{MuscleBody, MuscleParams};
use bevy::prelude::*;
use bevy_egui::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints, Points};

/// Node radii of a real biceps (ultrasound, OpenArm 2.0) at 0, 30, 60 and 90 degrees of
/// elbow flexion: the nine measured nodes, which are nodes 1 to 9 of the eleven-node config.
pub const REAL_BICEPS_RADII: [(f64, [f64; 9]); 4] = [
    (0.0, [7.6, 18.2, 20.7, 21.2, 21.7, 24.3, 25.7, 20.7, 13.2]),
    (30.0, [16.2, 18.7, 22.5, 26.2, 27.5, 31.3, 28.7, 26.6, 20.8]),
    (60.0, [7.8, 16.2, 24.9, 32.4, 32.4, 32.0, 29.8, 22.0, 12.7]),
    (90.0, [9.5, 15.2, 23.4, 27.7, 35.2, 35.8, 36.6, 24.2, 16.7]),
];

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
    if edited && let Err(error) = body.model.edit_node(node, radius, mult) {
        body.message = Some(error.to_string());
    }
    let curves = model_curves(&body);
    entity_mut.insert(SelectedNode(node));
    if edited && let Some(mut params) = entity_mut.get_mut::<MuscleParams>() {
        // Re-applies the current flexion to the edited rest state.
        params.set_changed();
    }

    ui.label("radii by node: model (lines) and real biceps (dots)");
    Plot::new("muscle-radii")
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
}

/// The model's radii at each flexion of [`REAL_BICEPS_RADII`], where the model can reach it.
fn model_curves(body: &MuscleBody) -> Vec<Option<Vec<f64>>> {
    REAL_BICEPS_RADII
        .iter()
        .map(|(angle, _)| {
            let length = body.carcass.length_from_flexion(angle.to_radians()).value;
            body.model.radii_at(length).ok()
        })
        .collect()
}
