//! The overlay's section of the window's panel: a live camera's device, size and rate, the
//! frame shown, what became of the marker in it, its pose and errors, the time a frame's
//! reading took, and a switch that outlines the marker found.

use super::camera;
use super::frames::MAX_FRAME_SIDE;
use super::plugin::{ArState, ArView, Finding, Target};
use super::source::{CameraSettings, Source};
use bevy::prelude::*;
use bevy_egui::egui;
use canopy_vision::board::Board;

/// The camera's controls: the device (from those found connected), the size and the rate,
/// opened again with `Open`; a calibration for another shape is refused in the panel.
fn camera_controls(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    let Some(Source::Camera(current)) = entity_mut.get::<ArView>().map(|view| view.source.clone()) else { return };
    let id = ui.id().with(("ar-camera", entity));
    let mut draft: CameraSettings = ui.data_mut(|data| data.get_temp(id)).unwrap_or_else(|| current.clone());
    let mut found: Option<Vec<(String, String)>> = ui.data_mut(|data| data.get_temp(id.with("found")));
    ui.horizontal(|ui| {
        ui.label("camera");
        egui::ComboBox::from_id_salt(id.with("device")).selected_text(draft.device.clone()).show_ui(ui, |ui| {
            for (path, name) in found.iter().flatten() {
                ui.selectable_value(&mut draft.device, path.clone(), format!("{path}  {name}"));
            }
        });
        if ui.button("Find").on_hover_text("list the cameras connected").clicked() {
            found = Some(camera::connected());
        }
    });
    if found.as_ref().is_some_and(Vec::is_empty) {
        ui.label("no cameras connected");
    }
    ui.horizontal(|ui| {
        ui.label("size");
        ui.add(egui::DragValue::new(&mut draft.size[0]).range(16..=MAX_FRAME_SIDE));
        ui.label("x");
        ui.add(egui::DragValue::new(&mut draft.size[1]).range(16..=MAX_FRAME_SIDE));
        ui.label("fps");
        ui.add(egui::DragValue::new(&mut draft.fps).range(1.0..=240.0));
        if ui.button("Open").on_hover_text("open the camera with these settings").clicked() {
            let opened = entity_mut.get_mut::<ArView>().map(|mut view| view.use_camera(draft.clone()));
            // A camera refused (a calibration of another shape) leaves the one playing alone.
            if let (Some(result), Some(mut state)) = (opened, entity_mut.get_mut::<ArState>()) {
                match result {
                    Ok(()) => state.restart(),
                    Err(why) => state.source_error = Some(format!("{}: {why}", draft.device)),
                }
            }
        }
    });
    ui.data_mut(|data| {
        data.insert_temp(id, draft);
        if let Some(found) = found {
            data.insert_temp(id.with("found"), found);
        }
    });
}

/// Draws the overlay section for `entity`.
pub fn overlay_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    camera_controls(ui, world, entity);
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    let Some(view) = entity_mut.get::<ArView>() else { return };
    let (source, dictionary, target) = (view.source.clone(), view.dictionary.name.clone(), view.target);
    let Some(mut state) = entity_mut.get_mut::<ArState>() else { return };
    let mut outline = state.outline;
    if ui.checkbox(&mut outline, "Outline the marker found").on_hover_text("its first side in red").changed() {
        state.outline = outline;
    }
    egui::Grid::new("ar-figures").num_columns(2).show(ui, |ui| {
        let row = |ui: &mut egui::Ui, label: &str, value: String| {
            ui.label(label);
            ui.label(value);
            ui.end_row();
        };
        let shown = state.records.back();
        match target {
            Target::Marker { id, .. } => row(ui, "marker", format!("{dictionary} #{id}")),
            Target::Board(Board::Grid(grid)) => row(
                ui,
                "board",
                format!("{dictionary}, {} x {} markers from #{}", grid.markers[0], grid.markers[1], grid.first_id),
            ),
            Target::Board(Board::Charuco(charuco)) => row(
                ui,
                "board",
                format!(
                    "ChArUco, {} x {} squares, {dictionary} from #{}",
                    charuco.squares[0], charuco.squares[1], charuco.first_id
                ),
            ),
        }
        if !source.live() {
            row(ui, source.kind(), source.location());
        }
        let of = source.frame_count().map_or(String::new(), |frames| format!(" of {frames}"));
        row(
            ui,
            "frame",
            shown.map_or("none yet".into(), |r| format!("{}{of} ({})", r.frame + 1, source.frame_name(r.frame))),
        );
        if let Some(error) = &state.source_error {
            row(ui, "source", error.clone());
        }
        match shown.map(|r| &r.finding) {
            Some(Finding::Found { estimate, kept_alternative, .. }) => {
                // The pose drawn: the better fit, or the other one where it continues the last.
                let (pose, error_px, other_px) = match kept_alternative {
                    true => (estimate.alternative, estimate.alternative_error_px, estimate.error_px),
                    false => (estimate.pose, estimate.error_px, estimate.alternative_error_px),
                };
                let (t, r) = (pose.translation, pose.rvec());
                row(ui, "found", format!("{:.3} m away", t.length()));
                row(ui, "tvec (m)", format!("{:.4} {:.4} {:.4}", t.x, t.y, t.z));
                row(ui, "rvec (rad)", format!("{:.4} {:.4} {:.4}", r.x, r.y, r.z));
                row(ui, "reprojection", format!("{error_px:.3} px (the other pose {other_px:.2} px)"));
            }
            Some(Finding::Board { pose, .. }) => {
                let (t, r) = (pose.pose.translation, pose.pose.rvec());
                row(ui, "found", format!("{:.3} m away, {} markers", t.length(), pose.markers));
                row(ui, "tvec (m)", format!("{:.4} {:.4} {:.4}", t.x, t.y, t.z));
                row(ui, "rvec (rad)", format!("{:.4} {:.4} {:.4}", r.x, r.y, r.z));
                row(ui, "reprojection", format!("{:.3} px", pose.error_px));
            }
            Some(Finding::Lost { held: true }) => row(ui, "lost", "its last pose held".into()),
            Some(Finding::Lost { held: false }) => row(ui, "lost", "only the photograph shows".into()),
            Some(Finding::Unreadable(message)) => row(ui, "unreadable", message.clone()),
            None => {}
        }
        let (flips, kept) = (state.follower_flips(), state.follower_kept());
        row(ui, "flips", format!("{flips} (the other pose kept {kept} times)"));
        if let Some(error) = state.overlay_error_px {
            row(ui, "drawn marker", format!("{error:.3} px from the found one"));
        }
        row(ui, "reading", format!("{:.2} ms (decoding, detection)", state.read_time.as_secs_f64() * 1e3));
    });
}
