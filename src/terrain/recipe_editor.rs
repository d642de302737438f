//! The whole generator in the window's panel: the map's size and seed, every layer of the
//! recipe (added, removed, moved; its generator and all of its parameters, its operation,
//! weight and functions) and the recipe's own functions. Edits go to a draft; each draft that
//! passes the scene file's checks makes the map again off the main thread, and one that does
//! not says why and waits for the next edit. Rows wrap, so that the panel keeps its width.

use super::heightmap::MAX_SIDE;
use super::noise::MAX_OCTAVES;
use super::recipe::{DiamondSquareLayer, Function, HillCentres, HillsLayer, Layer, Op, PerlinLayer, Recipe};
use bevy::prelude::*;
use bevy_egui::egui;

/// The panel's draft of a terrain's recipe, and the recipe it was last set from or asked for:
/// when the map is made from another (a new seed by key, a timeline), the draft starts again
/// from that.
#[derive(Component, Debug, Clone)]
pub struct GeneratorDraft {
    /// What the panel shows and edits.
    pub draft: Recipe,
    /// The recipe the draft followed last.
    pub based_on: Recipe,
}

/// Draws the editor of `draft`; true when something changed.
pub fn edit_recipe(ui: &mut egui::Ui, draft: &mut Recipe) -> bool {
    let mut changed = false;
    ui.horizontal_wrapped(|ui| {
        ui.label("size");
        changed |= ui.add(egui::DragValue::new(&mut draft.size[0]).range(1..=MAX_SIDE)).changed();
        ui.label("x");
        changed |= ui.add(egui::DragValue::new(&mut draft.size[1]).range(1..=MAX_SIDE)).changed();
        ui.label("seed");
        changed |= ui.add(egui::DragValue::new(&mut draft.seed).range(0..=i64::MAX)).changed();
    });
    let mut moved = None;
    let count = draft.layers.len();
    for (index, layer) in draft.layers.iter_mut().enumerate() {
        ui.push_id(("layer", index), |ui| {
            ui.group(|ui| {
                ui.horizontal_wrapped(|ui| {
                    ui.strong(format!("layer {}", index + 1));
                    changed |= generator_choice(ui, layer);
                    if ui.add_enabled(index > 0, egui::Button::new("up")).clicked() {
                        moved = Some(LayerEdit::Swap(index - 1));
                    }
                    if ui.add_enabled(index + 1 < count, egui::Button::new("down")).clicked() {
                        moved = Some(LayerEdit::Swap(index));
                    }
                    if ui.add_enabled(count > 1, egui::Button::new("remove")).clicked() {
                        moved = Some(LayerEdit::Remove(index));
                    }
                });
                changed |= generator_parameters(ui, layer);
                ui.horizontal_wrapped(|ui| {
                    if index > 0 {
                        ui.label("joined by");
                        changed |= op_choice(ui, &mut layer.op);
                    }
                    ui.label("weight");
                    changed |= ui.add(egui::DragValue::new(&mut layer.weight).speed(0.01)).changed();
                });
                changed |= functions(ui, "then", &mut layer.apply);
            });
        });
    }
    match moved {
        Some(LayerEdit::Swap(index)) => draft.layers.swap(index, index + 1),
        Some(LayerEdit::Remove(index)) => {
            draft.layers.remove(index);
        }
        None => {}
    }
    if moved.is_some() {
        // The first layer starts the map: it is joined to nothing.
        if let Some(first) = draft.layers.first_mut() {
            first.op = Op::Add;
        }
        changed = true;
    }
    if ui.button("Add layer").on_hover_text("Perlin noise added at weight 1").clicked() {
        draft.layers.push(Layer { perlin: Some(PerlinLayer::default()), ..Layer::default() });
        changed = true;
    }
    changed | functions(ui, "the map, then", &mut draft.apply)
}

/// A change to the list of layers asked for by a layer's buttons.
#[derive(Debug, Clone, Copy)]
enum LayerEdit {
    /// Swaps the layer with the one after it.
    Swap(usize),
    /// Removes the layer.
    Remove(usize),
}

/// The generators a layer may have, by their names in scene files.
const GENERATORS: [&str; 3] = ["perlin", "diamond_square", "hills"];

/// The layer's generator chosen by name; another generator starts from its defaults.
fn generator_choice(ui: &mut egui::Ui, layer: &mut Layer) -> bool {
    let current = layer.generator().map(|generator| generator.key()).unwrap_or("none");
    let mut chosen = current;
    egui::ComboBox::from_id_salt("generator").selected_text(current).show_ui(ui, |ui| {
        for name in GENERATORS {
            ui.selectable_value(&mut chosen, name, name);
        }
    });
    if chosen == current {
        return false;
    }
    (layer.perlin, layer.diamond_square, layer.hills) = (None, None, None);
    match chosen {
        "perlin" => layer.perlin = Some(PerlinLayer::default()),
        "diamond_square" => layer.diamond_square = Some(DiamondSquareLayer::default()),
        _ => layer.hills = Some(HillsLayer::default()),
    }
    true
}

/// Every parameter of the layer's generator.
fn generator_parameters(ui: &mut egui::Ui, layer: &mut Layer) -> bool {
    let mut changed = false;
    ui.horizontal_wrapped(|ui| {
        if let Some(perlin) = &mut layer.perlin {
            ui.label("scale");
            changed |= ui.add(egui::DragValue::new(&mut perlin.scale).speed(0.5).range(0.01..=1e5)).changed();
            ui.label("octaves");
            changed |= ui.add(egui::DragValue::new(&mut perlin.octaves).range(1..=MAX_OCTAVES)).changed();
            ui.label("lacunarity");
            changed |= ui.add(egui::DragValue::new(&mut perlin.lacunarity).speed(0.01)).changed();
            ui.label("persistence");
            changed |= ui.add(egui::DragValue::new(&mut perlin.persistence).speed(0.01)).changed();
        }
        if let Some(diamond_square) = &mut layer.diamond_square {
            ui.label("roughness");
            let roughness = egui::DragValue::new(&mut diamond_square.roughness).speed(0.01).range(0.01..=1.0);
            changed |= ui.add(roughness).changed();
        }
        if let Some(hills) = &mut layer.hills {
            ui.label("hills");
            changed |= ui.add(egui::DragValue::new(&mut hills.count).range(1..=100_000)).changed();
            ui.label("radius");
            changed |= ui.add(egui::DragValue::new(&mut hills.radius[0]).speed(0.5)).changed();
            ui.label("to");
            changed |= ui.add(egui::DragValue::new(&mut hills.radius[1]).speed(0.5)).changed();
            let mut centres = hills.centres;
            egui::ComboBox::from_id_salt("centres").selected_text(centres.name()).show_ui(ui, |ui| {
                for choice in HillCentres::ALL {
                    ui.selectable_value(&mut centres, choice, choice.name());
                }
            });
            changed |= centres != hills.centres;
            hills.centres = centres;
            changed |= ui.checkbox(&mut hills.lakes, "lakes").changed();
        }
    });
    changed
}

/// How a layer joins the map so far.
fn op_choice(ui: &mut egui::Ui, op: &mut Op) -> bool {
    let before = *op;
    egui::ComboBox::from_id_salt("op").selected_text(op.name()).show_ui(ui, |ui| {
        for choice in Op::ALL {
            ui.selectable_value(op, choice, choice.name());
        }
    });
    *op != before
}

/// A list of functions: each chosen by name with its numbers, removable, and one to add.
fn functions(ui: &mut egui::Ui, label: &str, list: &mut Vec<Function>) -> bool {
    let mut changed = false;
    let mut removed = None;
    ui.horizontal_wrapped(|ui| {
        ui.label(label);
        for (index, function) in list.iter_mut().enumerate() {
            ui.push_id(("function", index), |ui| {
                let mut name = function.name();
                egui::ComboBox::from_id_salt("function").selected_text(name).show_ui(ui, |ui| {
                    for choice in Function::NAMES {
                        ui.selectable_value(&mut name, choice, choice);
                    }
                });
                if name != function.name() {
                    *function = Function::named(name).unwrap_or(*function);
                    changed = true;
                }
                changed |= function_numbers(ui, function);
                if ui.small_button("x").on_hover_text("remove the function").clicked() {
                    removed = Some(index);
                }
            });
        }
        if ui.small_button("+").on_hover_text("add a function").clicked() {
            list.push(Function::Normalize);
            changed = true;
        }
    });
    if let Some(index) = removed {
        list.remove(index);
        changed = true;
    }
    changed
}

/// The numbers of a function that has them.
fn function_numbers(ui: &mut egui::Ui, function: &mut Function) -> bool {
    match function {
        Function::Power(p) => ui.add(egui::DragValue::new(p).speed(0.05)).changed(),
        Function::Terraces(n) => ui.add(egui::DragValue::new(n).range(1..=1000)).changed(),
        Function::Clamp([low, high]) => {
            let low = ui.add(egui::DragValue::new(low).speed(0.01)).changed();
            low | ui.add(egui::DragValue::new(high).speed(0.01)).changed()
        }
        Function::Scale(v) | Function::Offset(v) => ui.add(egui::DragValue::new(v).speed(0.01)).changed(),
        Function::Normalize | Function::Invert | Function::Abs => false,
    }
}
