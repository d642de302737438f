//! The window: the framebuffer shown in the space left of the egui side panel (and sized to
//! it), the panel with scene information, timings and the selected entity's parameters, the
//! key help and load errors. Dragging on the view orbits the camera, the wheel zooms; both
//! go through the camera's parameters like every other edit.

use crate::controls::HelpVisible;
use crate::foundation::entity::SceneEntity;
use crate::foundation::keys::KeyMap;
use crate::foundation::messages::{ReloadScene, SelectEntity, ViewClicked};
use crate::foundation::panel::{PanelSection, PanelSections};
use crate::foundation::params::{ParamEntry, ParamValue, list_params, set_param};
use crate::foundation::schedule::{FixedStepTime, RenderSystems, SimClock, SimControl};
use crate::raster::plugin::RasterTarget;
use crate::scene::{ActiveScene, FIRST_FILE_ENTITY, SceneStatus, save_live_scene};
use crate::view::CameraParams;
use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy_egui::egui;
use bevy_egui::{
    EguiContext, EguiGlobalSettings, EguiPrimaryContextPass, EguiTextureHandle, EguiUserTextures, PrimaryEguiContext,
};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What the Save button does, shown when hovering it.
const SAVE_HINT: &str = "Write the scene, with its trees as edited, to its file. The file is first copied to \
                         <file>.<n>.bak; comments are not kept in the new file.";

/// Degrees the camera turns per point of mouse drag.
const DRAG_DEG_PER_POINT: f32 = 0.3;
/// Factor the camera distance changes by per point of wheel scroll.
const WHEEL_ZOOM_PER_POINT: f32 = 0.998;

/// The window's view and panel.
pub struct UiPlugin;

impl Plugin for UiPlugin {
    fn build(&self, app: &mut App) {
        // While an egui field has the keyboard (typing a value), the scene's keys stay quiet.
        app.world_mut().get_resource_or_init::<EguiGlobalSettings>().enable_absorb_bevy_input_system = true;
        app.init_resource::<UiState>()
            .init_resource::<PresentTime>()
            .add_systems(Startup, setup_view)
            .add_systems(Update, capture_window.run_if(resource_exists::<WindowCapture>))
            .add_systems(EguiPrimaryContextPass, draw_ui)
            .add_systems(PostUpdate, present_framebuffer.in_set(RenderSystems::Present));
    }
}

/// Asks for a screenshot of the whole window (view and panel) once the scene has been shown
/// for some frames, after which the app exits: for smoke tests and documentation.
#[derive(Resource, Debug, Clone)]
pub struct WindowCapture {
    /// The PNG file to write.
    pub path: PathBuf,
    /// Frames to show after the scene has loaded (or failed to) before the capture.
    pub after_frames: u32,
}

fn capture_window(mut commands: Commands, capture: Res<WindowCapture>, scene: Res<ActiveScene>, mut shown: Local<u32>) {
    if scene.status == SceneStatus::Loading {
        return;
    }
    *shown += 1;
    if *shown == capture.after_frames.max(1) {
        commands.spawn(Screenshot::primary_window()).observe(save_to_disk(capture.path.clone())).observe(
            |_: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
                exit.write(AppExit::Success);
            },
        );
    }
}

/// The image the framebuffer is copied into for display.
#[derive(Resource)]
struct FramebufferImage(Handle<Image>);

/// What the panel remembers between frames.
#[derive(Resource, Default)]
struct UiState {
    /// Name of the entity whose parameters are shown.
    selected: Option<String>,
    /// Where the frame's time went, smoothed.
    times: PhaseTimes,
    /// Wall-clock time building the panel took last frame.
    panel: Duration,
    /// What the last save did.
    saved: Option<String>,
}

/// Wall-clock milliseconds of a frame and of its phases, each smoothed over about ten frames.
#[derive(Debug, Clone, Copy, Default)]
struct PhaseTimes {
    frame: f32,
    simulation: f32,
    raster: f32,
    panel: f32,
    present: f32,
}

impl PhaseTimes {
    /// Takes in the latest frame's times.
    fn update(&mut self, frame: Duration, simulation: Duration, raster: Duration, panel: Duration, present: Duration) {
        let smooth = |average: &mut f32, time: Duration| *average += (time.as_secs_f32() * 1000.0 - *average) * 0.1;
        smooth(&mut self.frame, frame);
        smooth(&mut self.simulation, simulation);
        smooth(&mut self.raster, raster);
        smooth(&mut self.panel, panel);
        smooth(&mut self.present, present);
    }

    /// What the phases do not account for: Bevy's renderer showing the image and the panel,
    /// and waiting for the display.
    fn rest(&self) -> f32 {
        (self.frame - self.simulation - self.raster - self.panel - self.present).max(0.0)
    }
}

/// Wall-clock time the last copy of the framebuffer into the displayed image took.
#[derive(Resource, Debug, Default)]
struct PresentTime(Duration);

fn image_of(size: UVec2, data: Vec<u8>) -> Image {
    Image::new(
        Extent3d { width: size.x, height: size.y, depth_or_array_layers: 1 },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::MAIN_WORLD | RenderAssetUsages::RENDER_WORLD,
    )
}

fn setup_view(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    commands.spawn(Camera2d);
    let image = images.add(image_of(UVec2::ONE, vec![0, 0, 0, 255]));
    commands.insert_resource(FramebufferImage(image));
}

/// Copies the last frame into the displayed image, replacing the image when the size changed.
fn present_framebuffer(
    target: Res<RasterTarget>,
    image: Res<FramebufferImage>,
    mut images: ResMut<Assets<Image>>,
    mut time: ResMut<PresentTime>,
) {
    let started = Instant::now();
    let framebuffer = &target.framebuffer;
    let size = UVec2::new(framebuffer.width(), framebuffer.height());
    if size.min_element() == 0 {
        return;
    }
    let Some(mut shown) = images.get_mut(&image.0) else { return };
    let same_size = shown.size() == size;
    match shown.data.as_mut() {
        Some(data) if same_size => data.copy_from_slice(framebuffer.color()),
        _ => *shown = image_of(size, framebuffer.color().to_vec()),
    }
    time.0 = started.elapsed();
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
    view_size: egui::Vec2,
}

fn draw_ui(world: &mut World) {
    let Ok(mut context) = world.query_filtered::<&mut EguiContext, With<PrimaryEguiContext>>().single_mut(world) else {
        return;
    };
    let ctx = context.get_mut().clone();
    let image = world.resource::<FramebufferImage>().0.id();
    let texture = world.resource_mut::<EguiUserTextures>().add_image(EguiTextureHandle::Weak(image));
    let started = Instant::now();
    let frame = world.resource::<Time<Real>>().delta();
    let mut state = world.remove_resource::<UiState>().unwrap_or_default();
    let simulation = world.resource::<FixedStepTime>().last;
    let raster = world.resource::<RasterTarget>().raster_time;
    let present = world.resource::<PresentTime>().0;
    let panel_time = state.panel;
    state.times.update(frame, simulation, raster, panel_time, present);
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
            let size = ui.available_size();
            actions.view_size = size;
            let picture =
                egui::Image::new(egui::load::SizedTexture::new(texture, size)).sense(egui::Sense::click_and_drag());
            let response = ui.add(picture);
            let scroll = if response.hovered() { ui.input(|input| input.smooth_scroll_delta.y) } else { 0.0 };
            let rect = response.rect;
            let click = response.clicked().then(|| response.interact_pointer_pos()).flatten().map(|pos| {
                let at = (pos - rect.min) / rect.size();
                ViewClicked { ndc: Vec2::new(at.x * 2.0 - 1.0, 1.0 - at.y * 2.0), aspect: rect.aspect_ratio() }
            });
            ((response.dragged().then(|| response.drag_delta()), scroll), click)
        })
        .inner;
    let (view, click) = view;
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

    let pixels = (actions.view_size * ctx.pixels_per_point()).round();
    world.resource_mut::<RasterTarget>().size = UVec2::new(pixels.x.max(1.0) as u32, pixels.y.max(1.0) as u32);
    orbit_with_mouse(world, view, &mut actions.edits);
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
    state.panel = started.elapsed();
    world.insert_resource(state);
}

/// Turns a drag on the view into camera yaw and pitch edits and the wheel into distance.
fn orbit_with_mouse(
    world: &mut World,
    (drag, scroll): (Option<egui::Vec2>, f32),
    edits: &mut Vec<(String, ParamValue)>,
) {
    let Some(camera) = world.query::<&CameraParams>().iter(world).next() else { return };
    if let Some(drag) = drag {
        let yaw = camera.yaw_deg - drag.x * DRAG_DEG_PER_POINT;
        let pitch = camera.pitch_deg + drag.y * DRAG_DEG_PER_POINT;
        edits.push(("camera.yaw_deg".into(), ParamValue::Number(yaw as f64)));
        edits.push(("camera.pitch_deg".into(), ParamValue::Number(pitch.clamp(-89.0, 89.0) as f64)));
    }
    if scroll != 0.0 {
        let distance = camera.distance * WHEEL_ZOOM_PER_POINT.powf(scroll);
        edits.push(("camera.distance".into(), ParamValue::Number(distance.max(camera.near * 2.0) as f64)));
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
        ui.label("frame time");
        ui.label(format!("{:.1} ms", times.frame));
        ui.end_row();
        let phases = [
            ("simulation", times.simulation),
            ("raster", times.raster),
            ("panel", times.panel),
            ("present", times.present),
            ("renderer, waiting", times.rest()),
        ];
        for (phase, ms) in phases {
            ui.label(format!("    {phase}"));
            ui.label(format!("{ms:.2} ms"));
            ui.end_row();
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
                    &ParamValue::Number(mut v) => {
                        let speed = (v.abs() * 0.01).max(0.01);
                        ui.add(egui::DragValue::new(&mut v).speed(speed)).changed().then_some(ParamValue::Number(v))
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
