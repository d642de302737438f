//! The world's section of the window's panel: the resident chunks per level of detail, the
//! chunks being made, how many arrive a second and what making one takes.

use super::plugin::WorldBody;
use bevy::prelude::*;
use bevy_egui::egui;

/// Draws the world section for `entity`.
pub fn world_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Some(body) = world.get::<WorldBody>(entity) else { return };
    egui::Grid::new("world-figures").num_columns(2).show(ui, |ui| {
        if let Some(seed) = body.seed() {
            ui.label("seed");
            ui.label(seed.to_string());
            ui.end_row();
        }
        if let Some([x, z]) = body.stream().bounds {
            ui.label("bounds");
            ui.label(format!("{x} x {z} chunks"));
            ui.end_row();
        }
        for (level, count) in body.per_level().iter().enumerate() {
            ui.label(format!("level {level}"));
            ui.label(format!("{count} chunks"));
            ui.end_row();
        }
        ui.label("being made");
        ui.label(format!("{} chunks", body.pending()));
        ui.end_row();
        ui.label("arriving");
        ui.label(format!("{} chunks a second", body.per_second()));
        ui.end_row();
        ui.label("making one");
        ui.label(format!("{:.2} ms (off the main thread)", body.mean_making_time().as_secs_f64() * 1e3));
        ui.end_row();
    });
}
