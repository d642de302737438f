//! The terrain's section of the window's panel: the map's figures, the section's triangles
//! per band, the time meshing and generating took, and buttons to make the map again and to
//! save it. The parameters themselves (section, turn, scale, noise) are edited in the panel's
//! parameter list like every entity's.

use super::bands::Band;
use super::plugin::{TerrainBody, TerrainParams, save_heightmap};
use super::recipe_editor::{GeneratorDraft, edit_recipe};
use bevy::prelude::*;
use bevy_egui::egui;

/// Draws the terrain section for `entity`.
pub fn terrain_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    let Some(body) = entity_mut.get::<TerrainBody>() else { return };
    let stats = body.map.stats();
    let generated = body.recipe.is_some();
    let mut save = false;
    egui::Grid::new("terrain-figures").num_columns(2).show(ui, |ui| {
        ui.label("map");
        ui.label(format!("{} x {} samples", stats.width, stats.height));
        ui.end_row();
        ui.label("heights");
        ui.label(format!("{:.3} to {:.3}, mean {:.3}", stats.min, stats.max, stats.mean));
        ui.end_row();
        ui.label("seed");
        ui.label(body.seed.map_or("from an image".to_string(), |seed| seed.to_string()));
        ui.end_row();
        for (band, count) in Band::ALL.iter().zip(body.counts) {
            ui.label(band.key());
            ui.label(format!("{count} triangles"));
            ui.end_row();
        }
        ui.label("meshing");
        ui.label(format!("{:.2} ms", body.mesh_time.as_secs_f64() * 1e3));
        ui.end_row();
        if generated {
            ui.label("generation");
            ui.label(format!("{:.2} ms (off the main thread)", body.generation_time.as_secs_f64() * 1e3));
            ui.end_row();
        }
    });
    if let Some(message) = &body.message {
        ui.colored_label(egui::Color32::LIGHT_RED, message);
    }
    let mut next_seed = false;
    ui.horizontal(|ui| {
        next_seed = generated && ui.button("New seed").on_hover_text("make the map again with the next seed").clicked();
        save = ui.button("Save heightmap").on_hover_text("a 16-bit PNG in heightmaps/").clicked();
    });
    if save {
        save_heightmap(&body.map);
    }
    if next_seed && let Some(mut params) = entity_mut.get_mut::<TerrainParams>() {
        params.noise.seed += 1.0;
    }
    generator(ui, &mut entity_mut);
}

/// The generator's whole recipe, for a generated map: edits that pass the file's checks make
/// the map again.
fn generator(ui: &mut egui::Ui, entity_mut: &mut EntityWorldMut) {
    let Some(body) = entity_mut.get::<TerrainBody>() else { return };
    let Some(mut recipe) = body.recipe.clone() else { return };
    recipe.seed = body.seed.map_or(recipe.seed, |seed| seed as i64);
    let mut draft = match entity_mut.get::<GeneratorDraft>() {
        // Kept while it follows the map's recipe or a map is being made; started again from
        // a map made from another recipe.
        Some(draft) if draft.based_on == recipe || body.remaking() => draft.clone(),
        _ => GeneratorDraft { draft: recipe.clone(), based_on: recipe },
    };
    let changed = egui::CollapsingHeader::new("generator")
        .show(ui, |ui| edit_recipe(ui, &mut draft.draft))
        .body_returned
        .unwrap_or(false);
    if changed && let Some(mut body) = entity_mut.get_mut::<TerrainBody>() {
        body.remake(draft.draft.clone());
        if body.message.is_none() {
            draft.based_on = draft.draft.clone();
        }
    }
    entity_mut.insert(draft);
}
