//! The tree's section of the window's panel: its supports, the one picked in the view and
//! its editor.

use super::body::TreeBody;
use super::edit;
use super::model::SupportKind;
use super::plugin::{SelectedSupport, TreeSource, edit_tree, undo_tree_edit};
use bevy::prelude::*;
use bevy_egui::egui;

/// Why the last edit of a tree in the panel was refused.
#[derive(Component, Debug, Clone)]
struct EditRefused(String);

/// The tree's section of the panel: its supports, the one picked in the view and its editor.
pub(super) fn tree_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Ok(entity_ref) = world.get_entity(entity) else { return };
    let (Some(body), Some(source)) = (entity_ref.get::<TreeBody>(), entity_ref.get::<TreeSource>()) else { return };
    let tree = &body.tree;
    let trunks = tree.supports.iter().filter(|s| s.kind == SupportKind::Trunk).count();
    egui::Grid::new("tree-counts").num_columns(2).show(ui, |ui| {
        let counts =
            [("trunks", trunks), ("branches", tree.supports.len() - trunks), ("segments", body.segment_supports.len())];
        for (label, count) in counts {
            ui.label(label);
            ui.label(count.to_string());
            ui.end_row();
        }
    });
    let can_undo = !source.undo.is_empty();
    let refused = entity_ref.get::<EditRefused>().map(|r| r.0.clone());
    let selected = entity_ref.get::<SelectedSupport>().map(|s| s.0).filter(|&i| i < tree.supports.len());
    let mut change = None;
    match selected {
        None => {
            ui.label("Click a support in the view to select it.");
        }
        Some(index) => {
            let support = &tree.supports[index];
            egui::Grid::new("tree-support").num_columns(2).show(ui, |ui| {
                let parent = support.parent.map_or("none", |p| tree.supports[p].name.as_str());
                let rows = [
                    ("support", support.name.clone()),
                    ("kind", support.kind.key().to_string()),
                    ("parent", parent.to_string()),
                    ("points", support.points.len().to_string()),
                    ("length", format!("{:.3} m", support.length())),
                ];
                for (label, value) in rows {
                    ui.label(label);
                    ui.label(value);
                    ui.end_row();
                }
                // Sliders for what the description holds: a fork's numbers, or a polyline's radii.
                match source.def.supports.get(index) {
                    Some(def) if def.parent.is_some() => {
                        for (field, label, low, high) in edit::ForkField::ALL {
                            let Some(mut value) = edit::fork_value(def, field) else { continue };
                            ui.label(label);
                            if ui.add(egui::Slider::new(&mut value, low..=high)).changed() {
                                change = Some(edit::Edit::Fork { support: index, field, value });
                            }
                            ui.end_row();
                        }
                    }
                    Some(_) => {
                        for (point, &radius) in support.radii.iter().enumerate() {
                            let mut value = radius;
                            ui.label(format!("radius {point}"));
                            if ui.add(egui::Slider::new(&mut value, 0.005..=2.0)).changed() {
                                change = Some(edit::Edit::Radius { support: index, point, value });
                            }
                            ui.end_row();
                        }
                    }
                    None => {}
                }
            });
            ui.horizontal(|ui| {
                if ui.button("Add branch").clicked() {
                    change = Some(edit::Edit::AddChild { parent: index });
                }
                if ui.button("Delete").clicked() {
                    change = Some(edit::Edit::Delete { support: index });
                }
            });
        }
    }
    let undo = ui.add_enabled(can_undo, egui::Button::new("Undo")).clicked();
    if let Some(reason) = &refused {
        ui.colored_label(egui::Color32::LIGHT_RED, reason);
    }
    if undo {
        undo_tree_edit(world, entity);
    }
    if let Some(change) = change {
        let result = edit_tree(world, entity, change);
        let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
        match result {
            Ok(()) => {
                entity_mut.remove::<EditRefused>();
            }
            Err(reason) => {
                entity_mut.insert(EditRefused(reason));
            }
        }
    }
}
