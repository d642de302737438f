//! The elastic body's section of the window's panel: its figures as it moves, and buttons
//! for what its keys do.

use super::plugin::{ElasticAction, ElasticBody};
use bevy::prelude::*;
use bevy_egui::egui;

/// Draws the elastic body section for `entity`.
pub(super) fn elastic_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Some(mut elastic) = world.get_mut::<ElasticBody>(entity) else { return };
    let body = &elastic.body;
    let centre = body.centre_of_mass();
    let rows = [
        ("tetrahedra", body.tet_count().to_string()),
        ("particles", body.positions.len().to_string()),
        ("mass", format!("{:.3} kg", body.mass_kg())),
        ("centre of mass", format!("{:.3}, {:.3}, {:.3} m", centre.x, centre.y, centre.z)),
        ("volume / rest", format!("{:.4}", body.volume_ratio())),
        ("largest strain", format!("{:.1} %", 100.0 * body.max_strain())),
        ("kinetic energy", format!("{:.2e} J", body.kinetic_energy())),
        ("in contact", format!("{} particles", body.contacts().iter().sum::<u32>())),
        ("on its stem", if body.stems.is_empty() { "no" } else { "yes" }.to_string()),
    ];
    egui::Grid::new("elastic-figures").num_columns(2).show(ui, |ui| {
        for (label, value) in rows {
            ui.label(label);
            ui.label(value);
            ui.end_row();
        }
    });
    ui.label("drag it with the mouse");
    let mut action = None;
    ui.horizontal(|ui| {
        if ui.add_enabled(!body.stems.is_empty(), egui::Button::new("Drop")).clicked() {
            action = Some(ElasticAction::Drop);
        }
        if ui.button("Reset").clicked() {
            action = Some(ElasticAction::Reset);
        }
        let (label, toggle) =
            if elastic.paused { ("Resume", ElasticAction::Resume) } else { ("Pause", ElasticAction::Pause) };
        if ui.button(label).clicked() {
            action = Some(toggle);
        }
    });
    if let Some(action) = action {
        let _ = elastic.perform(&action);
    }
}
