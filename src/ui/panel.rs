//! The panel: scene information, the frame's timings and the selected entity's parameters in
//! a side panel, the key help and load errors over the view. The 3D view fills the room the
//! panel leaves (the framebuffer is sized to it); dragging on it orbits the camera and the
//! wheel zooms, both through the camera's parameters like every other edit; a click is handed
//! to the scene's kinds (trees pick the support under it).

use super::{ViewArea, WindowCapture, WindowTimes};
use crate::controls::HelpVisible;
use crate::foundation::entity::SceneEntity;
use crate::foundation::frame_times::{FrameLog, Summary};
use crate::foundation::keys::KeyMap;
use crate::foundation::messages::{DragPhase, ReloadScene, SelectEntity, ViewClicked, ViewDragged, ViewGrab};
use crate::foundation::panel::{PanelSection, PanelSections};
use crate::foundation::params::{ParamEntry, ParamValue, list_params, set_param};
use crate::foundation::schedule::{FixedStepTime, SimClock, SimControl};
use crate::raster::plugin::RasterTarget;
use crate::scene::{ActiveScene, FIRST_FILE_ENTITY, SceneStatus, save_live_scene};
use crate::view::CameraParams;
use bevy::prelude::*;
use bevy_egui::egui;
use bevy_egui::{EguiContext, PrimaryEguiContext};
use std::time::{Duration, Instant};

/// What the Save button does, shown when hovering it.
const SAVE_HINT: &str = "Write the scene, with its trees as edited, to its file. The file is first copied to \
                         <file>.<n>.bak; comments are not kept in the new file.";

/// Degrees the camera turns per point of mouse drag.
const DRAG_DEG_PER_POINT: f32 = 0.3;
/// Factor the camera distance changes by per point of wheel scroll.
const WHEEL_ZOOM_PER_POINT: f32 = 0.998;

/// What the panel remembers between frames.
#[derive(Resource, Default)]
pub(super) struct UiState {
    /// Name of the entity whose parameters are shown.
    selected: Option<String>,
    /// The last frames' times by phase.
    times: FrameLog<7>,
    /// Wall-clock time building the panel took last frame.
    panel: Duration,
    /// What the last save did.
    saved: Option<String>,
}

/// The phases of a window frame the panel lists, in order; "other" is what they do not account
/// for: input, streaming, write-back, scene loading, Bevy's own systems.
const PHASES: [&str; 7] = ["simulation", "raster", "panel", "panel paint", "present", "frame cap wait", "other"];

/// The whole frame's and each phase's mean and 99th percentile, milliseconds, on one line:
/// what the panel shows, logged with a capture for measurements.
fn budget(times: &FrameLog<7>) -> String {
    let line = |name: &str, summary: Summary| format!("{name} {:.2} / {:.2} ms", summary.mean, summary.quantile);
    let phases = PHASES.iter().enumerate().map(|(phase, name)| line(name, times.phase(phase, 0.99)));
    std::iter::once(line("frame", times.frame(0.99))).chain(phases).collect::<Vec<_>>().join(", ")
}

/// Everything the panel shows, read from the world before drawing.
struct PanelData {
    scene: String,
    status: SceneStatus,
    error: Option<String>,
    clock: SimClock,
    control: SimControl,
    target_size: UVec2,
    stats: crate::raster::RenderStats,
    entities: Vec<(String, &'static str)>,
    /// The selected entity and its kind.
    selected: Option<(Entity, &'static str)>,
    params: Vec<ParamEntry>,
    keys: Vec<(String, &'static str)>,
    help: bool,
}

impl PanelData {
    fn gather(world: &mut World, selected: Option<&str>) -> Self {
        let mut entities: Vec<(usize, Entity, String, &'static str)> = world
            .query::<(Entity, &SceneEntity)>()
            .iter(world)
            .map(|(e, s)| (s.index, e, s.name.clone(), s.kind))
            .collect();
        entities.sort_by_key(|(index, ..)| *index);
        let selected =
            entities.iter().find(|(_, _, name, _)| Some(name.as_str()) == selected).map(|(_, e, _, kind)| (*e, *kind));
        let params = selected.map(|(entity, _)| list_params(world, entity)).unwrap_or_default();
        let scene = world.resource::<ActiveScene>();
        let target = world.resource::<RasterTarget>();
        let keys = world.resource::<KeyMap>().active(&scene.kinds).map(|help| (help.key_name(), help.action)).collect();
        Self {
            scene: scene.path.display().to_string(),
            status: scene.status,
            error: scene.error.clone(),
            clock: *world.resource::<SimClock>(),
            control: *world.resource::<SimControl>(),
            target_size: target.size,
            stats: target.stats,
            entities: entities.into_iter().map(|(_, _, name, kind)| (name, kind)).collect(),
            selected,
            params,
            keys,
            help: world.resource::<HelpVisible>().0,
        }
    }
}

/// What the user did in the panel this frame, applied to the world after drawing.
#[derive(Default)]
struct PanelActions {
    edits: Vec<(String, ParamValue)>,
    toggle_pause: bool,
    step: bool,
    reload: bool,
    save: bool,
    toggle_help: bool,
    /// The top-left corner of the room left for the 3D view, in points.
    view_min: egui::Pos2,
    /// The size of that room, in points.
    view_size: egui::Vec2,
}

pub(super) fn draw_ui(world: &mut World) {
    let Ok(mut context) = world.query_filtered::<&mut EguiContext, With<PrimaryEguiContext>>().single_mut(world) else {
        return;
    };
    let ctx = context.get_mut().clone();
    let started = Instant::now();
    let frame = world.resource::<Time<Real>>().delta();
    let mut state = world.remove_resource::<UiState>().unwrap_or_default();
    let simulation = world.resource::<FixedStepTime>().last;
    let raster = world.resource::<RasterTarget>().raster_time;
    let window = *world.resource::<WindowTimes>();
    let panel_time = state.panel;
    let phases = [simulation, raster, panel_time, window.paint, window.present, window.wait];
    let other = frame.saturating_sub(phases.iter().sum());
    state.times.push(frame, [simulation, raster, panel_time, window.paint, window.present, window.wait, other]);
    if world.get_resource::<WindowCapture>().is_some_and(|capture| capture.due()) {
        info!(
            "frame budget over the last {} frames, mean / 99th percentile: {}",
            state.times.len(),
            budget(&state.times)
        );
    }
    if let Some(SelectEntity(name)) = world.resource_mut::<Messages<SelectEntity>>().drain().last() {
        state.selected = Some(name);
    }
    if state.selected.is_none() {
        // Start with the first entity of the file selected.
        state.selected = world
            .query::<&SceneEntity>()
            .iter(world)
            .filter(|s| s.index == FIRST_FILE_ENTITY)
            .map(|s| s.name.clone())
            .next();
    }
    let data = PanelData::gather(world, state.selected.as_deref());
    let mut actions = PanelActions::default();

    let mut root = egui::Ui::new(
        ctx.clone(),
        "canopy-root".into(),
        egui::UiBuilder::new().layer_id(egui::LayerId::background()).max_rect(ctx.viewport_rect()),
    );
    let sections: Vec<PanelSection> = match (data.selected, world.get_resource::<PanelSections>()) {
        (Some((_, kind)), Some(sections)) => sections.of(kind).collect(),
        _ => Vec::new(),
    };
    egui::Panel::right("canopy-panel").default_size(300.0).show_inside(&mut root, |ui| {
        egui::ScrollArea::vertical().show(ui, |ui| {
            panel(ui, &data, &mut state, &mut actions);
            if let Some((entity, _)) = data.selected {
                for section in &sections {
                    ui.separator();
                    section(ui, world, entity);
                }
            }
        });
    });
    let view = egui::CentralPanel::no_frame()
        .show_inside(&mut root, |ui| {
            // The frame is copied in here when the window is composed; egui only takes the input.
            let (rect, response) = ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
            (actions.view_min, actions.view_size) = (rect.min, rect.size());
            let flying = ui.input(|input| input.modifiers.shift) || response.dragged_by(egui::PointerButton::Secondary);
            // egui turns the wheel into horizontal scrolling while Shift is held.
            let delta = ui.input(|input| input.smooth_scroll_delta);
            let scroll = if !response.hovered() {
                0.0
            } else if flying {
                delta.x + delta.y
            } else {
                delta.y
            };
            let ndc = |pos: egui::Pos2| {
                let at = (pos - rect.min) / rect.size();
                Vec2::new(at.x * 2.0 - 1.0, 1.0 - at.y * 2.0)
            };
            let aspect = rect.aspect_ratio();
            let click = response
                .clicked()
                .then(|| response.interact_pointer_pos())
                .flatten()
                .map(|pos| ViewClicked { ndc: ndc(pos), aspect });
            // A primary drag may grab something in the scene: it starts where the button went
            // down, and the camera does not turn in its first frame, before the scene answers.
            let primary = egui::PointerButton::Primary;
            let (phase, at) = if response.drag_started_by(primary) && !flying {
                (Some(DragPhase::Start), ui.input(|input| input.pointer.press_origin()))
            } else if response.drag_stopped_by(primary) {
                (Some(DragPhase::End), response.interact_pointer_pos())
            } else if response.dragged_by(primary) {
                (Some(DragPhase::Move), response.interact_pointer_pos())
            } else {
                (None, None)
            };
            let grab = phase.zip(at).map(|(phase, pos)| ViewDragged { phase, ndc: ndc(pos), aspect });
            let turning = response.dragged() && phase != Some(DragPhase::Start);
            (ViewPointer { drag: turning.then(|| response.drag_delta()), scroll, flying }, click, grab)
        })
        .inner;
    let (mut view, click, grab) = view;
    if world.resource::<ViewGrab>().held && !view.flying {
        view.drag = None;
    }
    if data.help {
        egui::Window::new("Keys").anchor(egui::Align2::LEFT_TOP, [8.0, 8.0]).show(&ctx, |ui| {
            egui::Grid::new("keys").striped(true).show(ui, |ui| {
                for (key, action) in &data.keys {
                    ui.monospace(key);
                    ui.label(*action);
                    ui.end_row();
                }
            });
        });
    }
    if let Some(error) = &data.error {
        egui::Window::new("Scene error").anchor(egui::Align2::LEFT_BOTTOM, [8.0, -8.0]).show(&ctx, |ui| {
            if data.status == SceneStatus::Live {
                ui.label("The last good scene keeps running. Fix the file and save it to reload.");
            }
            ui.colored_label(egui::Color32::LIGHT_RED, error);
        });
    }

    let pixels_per_point = ctx.pixels_per_point();
    let [x, y] = (actions.view_min.to_vec2() * pixels_per_point).round().max(egui::Vec2::ZERO).into();
    world.resource_mut::<ViewArea>().origin = UVec2::new(x as u32, y as u32);
    let pixels = (actions.view_size * pixels_per_point).round();
    world.resource_mut::<RasterTarget>().size = UVec2::new(pixels.x.max(1.0) as u32, pixels.y.max(1.0) as u32);
    camera_with_mouse(world, view, &mut actions.edits);
    for (name, value) in actions.edits {
        if let Err(error) = set_param(world, &name, value) {
            warn!("{error}");
        }
    }
    let mut control = world.resource_mut::<SimControl>();
    control.paused ^= actions.toggle_pause;
    control.step_once |= actions.step && control.paused;
    if actions.reload {
        world.write_message(ReloadScene);
    }
    world.resource_mut::<HelpVisible>().0 ^= actions.toggle_help;
    if actions.save {
        state.saved = Some(match save_live_scene(world) {
            Ok((path, Some(backup))) => format!("saved {}; the previous file is {}", path.display(), backup.display()),
            Ok((path, None)) => format!("saved {}", path.display()),
            Err(error) => format!("not saved: {error}"),
        });
    }
    if let Some(click) = click {
        world.write_message(click);
    }
    if let Some(grab) = grab {
        world.write_message(grab);
    }
    state.panel = started.elapsed();
    world.insert_resource(state);
}

/// What the pointer did over the 3D view this frame.
struct ViewPointer {
    /// The drag, in points.
    drag: Option<egui::Vec2>,
    /// The wheel, in points.
    scroll: f32,
    /// Shift held or the right button dragging: the fly camera's gestures.
    flying: bool,
}

/// Turns a drag on the view into camera edits: yaw and pitch about the target, or with
/// `flying` about the eye; and the wheel into the camera's distance, or with `flying` its fly
/// speed.
fn camera_with_mouse(world: &mut World, pointer: ViewPointer, edits: &mut Vec<(String, ParamValue)>) {
    let Some(camera) = world.query::<&CameraParams>().iter(world).next() else { return };
    let number = |name: &str, value: f32| (format!("camera.{name}"), ParamValue::Number(f64::from(value)));
    if let Some(drag) = pointer.drag {
        let (yaw, pitch) = (-drag.x * DRAG_DEG_PER_POINT, drag.y * DRAG_DEG_PER_POINT);
        let turned = match pointer.flying {
            true => camera.looked_around(yaw, pitch),
            false => camera.orbited(yaw, pitch),
        };
        edits.push(number("yaw_deg", turned.yaw_deg));
        edits.push(number("pitch_deg", turned.pitch_deg));
        if turned.target != camera.target {
            edits.extend(
                [("target.x", turned.target.x), ("target.y", turned.target.y), ("target.z", turned.target.z)]
                    .map(|(name, value)| number(name, value)),
            );
        }
    }
    if pointer.scroll != 0.0 {
        let factor = WHEEL_ZOOM_PER_POINT.powf(pointer.scroll);
        edits.push(match pointer.flying {
            // Scrolling up (away from the user) flies faster.
            true => number("fly_speed_m_s", (camera.fly_speed_m_s / factor).clamp(0.1, 10_000.0)),
            false => number("distance", (camera.distance * factor).max(camera.near * 2.0)),
        });
    }
}

/// A drop-down of a choice parameter's names; returns the name picked, if it changed.
fn choice_box(ui: &mut egui::Ui, id: &str, current: &str, choices: &[String]) -> Option<ParamValue> {
    let mut picked = None;
    egui::ComboBox::from_id_salt(id).selected_text(current).show_ui(ui, |ui| {
        for choice in choices {
            if ui.selectable_label(choice == current, choice).clicked() && choice != current {
                picked = Some(ParamValue::Choice(choice.clone()));
            }
        }
    });
    picked
}

fn panel(ui: &mut egui::Ui, data: &PanelData, state: &mut UiState, actions: &mut PanelActions) {
    ui.heading("Canopy");
    ui.label(&data.scene);
    let status = match data.status {
        SceneStatus::Loading => "loading",
        SceneStatus::Live if data.control.paused => "paused",
        SceneStatus::Live => "running",
        SceneStatus::Failed => "failed to load",
    };
    ui.label(format!("{status} - frame {} - {:.2} s", data.clock.frame, data.clock.elapsed.as_secs_f64()));
    ui.horizontal(|ui| {
        actions.toggle_pause = ui.button(if data.control.paused { "Resume" } else { "Pause" }).clicked();
        actions.step = ui.add_enabled(data.control.paused, egui::Button::new("Step")).clicked();
        actions.reload = ui.button("Reload").clicked();
        actions.save = ui.button("Save").on_hover_text(SAVE_HINT).clicked();
        let keys = egui::Button::new("Keys").selected(data.help);
        actions.toggle_help = ui.add(keys).on_hover_text("Show or hide the keys of this scene (F1)").clicked();
    });
    if let Some(saved) = &state.saved {
        ui.small(saved);
    }
    ui.separator();
    egui::Grid::new("figures").show(ui, |ui| {
        let times = &state.times;
        let shown = |ui: &mut egui::Ui, name: &str, summary: Summary| {
            ui.label(name);
            ui.label(format!("{:.2} ms", summary.mean));
            ui.label(format!("{:.2} ms", summary.quantile));
            ui.end_row();
        };
        ui.label(format!("last {} frames", times.len()));
        ui.label("mean");
        ui.label("99th pct");
        ui.end_row();
        shown(ui, "frame", times.frame(0.99));
        for (phase, name) in PHASES.iter().enumerate() {
            shown(ui, &format!("    {name}"), times.phase(phase, 0.99));
        }
        ui.label("triangles");
        ui.label(format!("{} ({} drawn)", data.stats.triangles_submitted, data.stats.triangles_rasterized));
        ui.end_row();
        ui.label("framebuffer");
        ui.label(format!("{} x {}", data.target_size.x, data.target_size.y));
        ui.end_row();
    });
    ui.separator();
    ui.label("Entities");
    egui::ScrollArea::vertical().id_salt("entities").max_height(180.0).show(ui, |ui| {
        for (name, kind) in &data.entities {
            let selected = state.selected.as_deref() == Some(name.as_str());
            if ui.selectable_label(selected, format!("{name}  ({kind})")).clicked() {
                state.selected = Some(name.clone());
            }
        }
    });
    if let Some(name) = &state.selected {
        ui.separator();
        ui.label(format!("Parameters of {name}"));
        egui::Grid::new("params").num_columns(2).show(ui, |ui| {
            for entry in &data.params {
                ui.label(&entry.path);
                let edited = match &entry.value {
                    &ParamValue::Number(mut v) if entry.whole => {
                        let drag = egui::DragValue::new(&mut v).speed(0.1).range(0.0..=f64::from(u32::MAX));
                        ui.add(drag.max_decimals(0)).changed().then_some(ParamValue::Number(v.round()))
                    }
                    &ParamValue::Number(mut v) => {
                        // A tiny value (a convergence threshold) is shown in exponent form and
                        // dragged in steps of its own size, not rounded to 0 and thrown far.
                        let tiny = v != 0.0 && v.abs() < 1e-3;
                        let speed = if tiny { v.abs() * 0.01 } else { (v.abs() * 0.01).max(0.01) };
                        let mut drag = egui::DragValue::new(&mut v).speed(speed);
                        if tiny {
                            drag = drag.custom_formatter(|v, _| format!("{v:.3e}"));
                        }
                        ui.add(drag).changed().then_some(ParamValue::Number(v))
                    }
                    &ParamValue::Bool(mut v) => ui.checkbox(&mut v, "").changed().then_some(ParamValue::Bool(v)),
                    ParamValue::Choice(current) => choice_box(ui, &entry.path, current, &entry.choices),
                };
                if let Some(value) = edited {
                    actions.edits.push((format!("{name}.{}", entry.path), value));
                }
                ui.end_row();
            }
        });
    }
}
