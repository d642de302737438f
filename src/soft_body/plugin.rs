//! The soft body kind's plugin: marks picked on the surface in the view, the deformer settings
//! as parameters, actions and keys that mark, apply and switch models, the write-back of the
//! surface, its marks and the original beside it, and the dump.

use super::def::{DecodedMesh, SoftBodyBuilt, SoftBodyDef};
use super::deform::{Deformer, Method, Settings, Variant};
use super::draw::{marker_mesh, region_tints, shift_tints, surface_mesh};
use super::measure::Distances;
use super::region::{Mark, RegionError};
use super::workbench::{ShrinkError, ShrinkJob, Shrunk, Workbench};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::entity::SceneEntity;
use crate::foundation::messages::SelectEntity;
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, LongWorkArrival, WriteBackSystems};
use crate::foundation::values::{Point, first_free_path, srgb_channels};
use crate::raster::RasterMesh;
use crate::spatial::SpatialSystems;
use crate::spatial::mesh_io::{self, MeshReport};
use crate::spatial::pick::{Pickable, Picked, Pointer};
use crate::spatial::surface_bvh::SurfaceBvh;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on};
use serde::Deserialize;
use serde_json::{Map, Value, json};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How the model shown is set against the original.
#[derive(Reflect, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compare {
    /// The model alone, its region tinted.
    #[default]
    Alone,
    /// The model over the original: each vertex tinted by how far it moved from it.
    Overlay,
    /// The original beside the model, to its left.
    SideBySide,
}

impl Compare {
    /// Every way, in the panel's order, with its label.
    pub const ALL: [(Compare, &'static str); 3] =
        [(Compare::Alone, "alone"), (Compare::Overlay, "overlay"), (Compare::SideBySide, "side by side")];
}

/// What a click on the surface does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tool {
    /// Adds a mark to the region's outline.
    #[default]
    Outline,
    /// Measures between two points: the first click, the second, then again from the first.
    Measure,
}

/// The deformer, its settings and the comparison, as parameters (`torso.k`, ...).
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct ShrinkParams {
    /// The deformer.
    pub method: Deformer,
    /// How the edge sum and the area are stepped.
    pub variant: Variant,
    /// The coefficient, in `(0, 1]` (below 1 for the area).
    pub k: f32,
    /// The convergence threshold.
    pub eps: f64,
    /// The iteration cap (rounded, at least 1).
    pub max_iterations: f64,
    /// How the model shown is set against the original.
    pub compare: Compare,
}

/// Most iterations a shrink may be given.
const MAX_ITERATIONS: f64 = 1e6;

impl ShrinkParams {
    /// The method and settings these parameters describe.
    pub fn deformer(&self) -> (Method, Settings) {
        let max_iterations = self.max_iterations.round().clamp(1.0, MAX_ITERATIONS) as u32;
        (self.method.method(self.variant), Settings { k: self.k, eps: self.eps, max_iterations })
    }
}

/// The region the marks outline on the surface shown, by the whole surface's vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionShown {
    /// The vertices that move.
    pub inside: Vec<u32>,
    /// The outline, held.
    pub outline: Vec<u32>,
}

/// A live soft body: the workflow's state on its surface, the region of its marks, and the
/// hierarchy clicks are cast against.
#[derive(Component, Debug, Clone)]
pub struct SoftBody {
    /// The original, the collection, the marks.
    pub bench: Workbench,
    /// What welding its mesh file found.
    pub read: MeshReport,
    /// The mesh file it was read from, which models in its format are written back over.
    file: Option<Arc<DecodedMesh>>,
    /// The region of the marks on the surface shown, or why there is none.
    pub region: Result<RegionShown, RegionError>,
    /// What the last action said: why it was refused, or where a model was saved.
    pub message: Option<String>,
    /// A shrink is under way off the main thread.
    pub shrinking: bool,
    /// What a click on the surface does.
    pub tool: Tool,
    /// The measured points' distances on the surface shown, once two are measured: found when
    /// the points or the surface shown change, not every frame.
    pub distances: Option<Distances>,
    /// The triangles of a surface for picking, and which surface (0 the original).
    picking: (Arc<SurfaceBvh>, usize),
}

impl SoftBody {
    /// A soft body on `built`'s surface.
    pub fn new(built: &SoftBodyBuilt) -> Self {
        let bench = Workbench::new(built.surface.clone());
        let picking = (Arc::new(SurfaceBvh::new(bench.shown_positions(), &bench.original().triangles)), bench.shown());
        Self {
            region: Err(RegionError::TooFewMarks(0)),
            bench,
            read: built.read,
            file: built.file.clone(),
            message: None,
            shrinking: false,
            tool: Tool::Outline,
            distances: None,
            picking,
        }
    }

    /// The triangles of the surface shown, for picking, in the body's own coordinates.
    pub fn picking(&self) -> Arc<SurfaceBvh> {
        self.picking.0.clone()
    }

    /// Does `action` with the deformer `params` name; for [`SoftBodyAction::Apply`], returns
    /// the shrink to start (the plugin starts it on the async compute pool).
    #[must_use = "a shrink to apply is to be started"]
    pub fn perform(&mut self, action: SoftBodyAction, params: &ShrinkParams) -> Option<ShrinkJob> {
        self.message = None;
        let mut job = None;
        match action {
            SoftBodyAction::Mark(point) => self.bench.mark(Mark::Point(point.0)),
            SoftBodyAction::MarkVertex(vertex) => self.bench.mark(Mark::Vertex(vertex)),
            SoftBodyAction::UndoMark => {
                self.bench.undo_mark();
            }
            SoftBodyAction::ClearMarks => self.bench.clear_marks(),
            SoftBodyAction::Measure(point) => self.measure_at(Mark::Point(point.0)),
            SoftBodyAction::MeasureVertex(vertex) => self.measure_at(Mark::Vertex(vertex)),
            SoftBodyAction::ClearMeasure => self.bench.clear_measure(),
            SoftBodyAction::UseTool(tool) => self.tool = tool,
            SoftBodyAction::Apply if self.shrinking => {
                self.message = Some("not applied: a shrink is under way".into());
            }
            SoftBodyAction::Apply => {
                let (method, settings) = params.deformer();
                match self.bench.job(method, settings) {
                    Ok(started) => {
                        self.shrinking = true;
                        job = Some(started);
                    }
                    Err(error) => self.message = Some(format!("not applied: {error}")),
                }
            }
            SoftBodyAction::Show(which) => {
                if !self.bench.show(which) {
                    let count = self.bench.models().len();
                    self.message =
                        Some(format!("there is no model {which}: 0 is the original, 1 to {count} the collection"));
                }
            }
        }
        self.follow_shown();
        job
    }

    /// Measures from or to `mark`; a point off the surface is refused with why.
    fn measure_at(&mut self, mark: Mark) {
        if let Err(error) = self.bench.measure_at(mark) {
            self.message = Some(format!("not measured: {error}"));
        }
    }

    /// The picking hierarchy, the region and the measured distances again for the surface
    /// shown, after the marks, the measured points or the surface shown changed. Models never
    /// change once made: the hierarchy is stale only when another is shown.
    fn follow_shown(&mut self) {
        if self.picking.1 != self.bench.shown() {
            let bvh = SurfaceBvh::new(self.bench.shown_positions(), &self.bench.original().triangles);
            self.picking = (Arc::new(bvh), self.bench.shown());
        }
        self.distances = self.bench.distances(self.bench.shown());
        self.region = self.bench.region().map(|region| RegionShown {
            inside: region.source.iter().zip(&region.surface.movable).filter(|(_, m)| **m).map(|(&v, _)| v).collect(),
            outline: region.outline,
        });
    }

    /// Takes in the result of `job`: a new model, shown, or why there is none.
    fn finish(&mut self, job: &ShrinkJob, result: Result<Shrunk, ShrinkError>) {
        self.shrinking = false;
        match result {
            Ok(shrunk) => {
                self.bench.add(job, shrunk);
                self.follow_shown();
            }
            Err(error) => self.message = Some(format!("not applied: {error}")),
        }
    }

    /// The extensions a surface can be saved with: OBJ and PLY, and the glTF file's own
    /// (`gltf` or `glb`) for a body read from one.
    pub fn save_extensions(&self) -> Vec<&'static str> {
        let own = self.file.as_ref().and_then(|file| match file.2.format {
            mesh_io::Format::Gltf => Some("gltf"),
            mesh_io::Format::Glb => Some("glb"),
            _ => None,
        });
        ["obj", "ply"].into_iter().chain(own).collect()
    }

    /// Writes surface `which` (0 the original) of the soft body named `entity` as OBJ, PLY or
    /// glTF (by `extension`, one of [`Self::save_extensions`]) in `folder` (made if needed),
    /// never over an earlier file; returns where, or why not. In the format of the mesh file
    /// it was read from, the file is written back with only the moved positions (and their
    /// normals, or bounds) changed.
    pub fn save(&self, folder: &Path, entity: &str, which: usize, extension: &str) -> Result<PathBuf, String> {
        let mesh = self.bench.mesh(which).ok_or_else(|| format!("there is no model {which}"))?;
        std::fs::create_dir_all(folder).map_err(|error| format!("{}: {error}", folder.display()))?;
        let stem = if which == 0 { format!("{entity}-original") } else { format!("{entity}-model{which}") };
        let path = first_free_path(|n| folder.join(format!("{stem}-{n:03}.{extension}")));
        let failed = |error: &dyn std::fmt::Display| format!("{}: {error}", path.display());
        let same_format = |source: &&Arc<DecodedMesh>| mesh_io::Format::of(&path).ok() == Some(source.2.format);
        match self.file.as_ref().filter(same_format) {
            Some(file) => {
                let bytes = file.2.written_back(&mesh.positions, &mesh.triangles, &path).map_err(|e| failed(&e))?;
                std::fs::write(&path, bytes).map_err(|e| failed(&e))?;
            }
            None => mesh_io::write(&mesh, &path).map_err(|e| failed(&e))?,
        }
        Ok(path)
    }
}

/// What a soft body can be told to do, by a timeline's `act` (see
/// [`crate::foundation::actions`]):
///
/// ```yaml
/// - { at: 0.1, act: { torso: [{ mark: [0.0, 0.2, 0.16] }, { mark_vertex: 1203 }, { mark_vertex: 1250 }] } }
/// - { at: 0.2, set: { torso.method: edge_sum, torso.k: 0.85 } }
/// - { at: 0.3, act: { torso: apply } }
/// - { at: 0.4, act: { torso: { show: 0 } } }
/// - { at: 0.5, act: { torso: [{ measure_vertex: 1203 }, { measure_vertex: 1250 }] } }
/// ```
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum SoftBodyAction {
    /// Marks a point on the surface, metres in the body's own coordinates.
    Mark(Point),
    /// Marks a vertex, by its index in the surface.
    MarkVertex(u32),
    /// Takes back the last mark.
    UndoMark,
    /// Takes back every mark.
    ClearMarks,
    /// Measures from or to a point on the surface, metres in the body's own coordinates: the
    /// first point, the second, then again from the first.
    Measure(Point),
    /// Measures from or to a vertex, by its index in the surface.
    MeasureVertex(u32),
    /// Takes back the measured points.
    ClearMeasure,
    /// Chooses what a click on the surface does.
    UseTool(Tool),
    /// Shrinks the marked region of the surface shown into a new model of the collection.
    Apply,
    /// Shows the original (0) or the collection's `n`-th model.
    Show(usize),
}

/// A shrink under way off the main thread.
#[derive(Component)]
pub struct PendingShrink {
    job: ShrinkJob,
    task: Option<Task<Result<Shrunk, ShrinkError>>>,
    /// Frames until a headless run takes the result in (see [`LongWorkArrival`]).
    frames_left: u32,
}

/// Frames after Apply at which a headless run takes the shrink in.
const SHRINK_FRAMES: u32 = 2;

/// Starts `job` on the async compute pool.
fn start_shrink(job: ShrinkJob) -> PendingShrink {
    let work = job.clone();
    let task = AsyncComputeTaskPool::get().spawn(async move { work.run() });
    PendingShrink { job, task: Some(task), frames_left: SHRINK_FRAMES }
}

/// Performs a timeline's action on a soft body.
pub(super) fn perform_action(world: &mut World, entity: Entity, action: SoftBodyAction) {
    if let Ok(mut entity_mut) = world.get_entity_mut(entity) {
        perform_on(&mut entity_mut, action);
    }
}

/// Performs `action` on the soft body `entity` with its parameters, starting the shrink it
/// asks for; a refusal is logged and kept in the body's message.
pub(super) fn perform_on(entity: &mut EntityWorldMut, action: SoftBodyAction) {
    let Some(params) = entity.get::<ShrinkParams>().cloned() else { return };
    let Some(mut body) = entity.get_mut::<SoftBody>() else { return };
    let job = body.perform(action, &params);
    if let Some(message) = &body.message {
        warn!("soft body: {message}");
    }
    if let Some(job) = job {
        entity.insert(start_shrink(job));
    }
}

/// Takes finished shrinks in, when [`LongWorkArrival`] says.
fn take_shrinks(
    arrival: Res<LongWorkArrival>,
    mut bodies: Query<(Entity, &mut SoftBody, &mut PendingShrink)>,
    mut commands: Commands,
) {
    for (entity, mut body, mut pending) in &mut bodies {
        pending.frames_left = pending.frames_left.saturating_sub(1);
        let done = pending.task.as_ref().is_none_or(Task::is_finished);
        let due = match *arrival {
            LongWorkArrival::FixedFrames => pending.frames_left == 0,
            LongWorkArrival::WhenReady => done,
        };
        if !due {
            continue;
        }
        if let Some(task) = pending.task.take() {
            let result = block_on(task);
            body.finish(&pending.job, result);
            if let Some(message) = &body.message {
                warn!("soft body: {message}");
            }
        }
        commands.entity(entity).remove::<PendingShrink>();
    }
}

impl DumpState for SoftBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let original = self.bench.original();
        out.insert("vertices".into(), json!(original.positions.len()));
        out.insert("triangles".into(), json!(original.triangles.len()));
        out.insert("mesh".into(), json!(self.read));
        let marks: Vec<Value> = self
            .bench
            .marks()
            .iter()
            .map(|mark| match mark {
                Mark::Vertex(v) => json!({ "vertex": v }),
                Mark::Point(p) => json!({ "point": p.to_array() }),
            })
            .collect();
        out.insert("marks".into(), json!(marks));
        let region = match &self.region {
            Ok(region) => json!({ "inside": region.inside.len(), "outline": region.outline.len() }),
            Err(error) => json!({ "error": error.to_string() }),
        };
        out.insert("region".into(), region);
        let models: Vec<Value> = self
            .bench
            .models()
            .iter()
            .map(|model| json!({ "name": model.name, "base": model.base, "report": model.report }))
            .collect();
        out.insert("models".into(), json!(models));
        out.insert("shown".into(), json!(self.bench.shown()));
        out.insert("measure".into(), json!({ "vertices": self.bench.measured(), "distances": self.distances }));
        out.insert("message".into(), json!(self.message));
        out.insert("shrinking".into(), json!(self.shrinking));
    }
}

/// Marks the child entity drawing the marks.
#[derive(Component)]
struct Markers;

/// Marks the child entity drawing the measured points.
#[derive(Component)]
struct MeasureMarkers;

/// Marks the child entity drawing the original beside the model.
#[derive(Component)]
struct OriginalBeside;

/// Spawns a soft body entity of `def` on `built`'s surface, with its drawn parts.
pub(super) fn spawn_soft_body(entity: &mut EntityWorldMut, def: &SoftBodyDef, built: &SoftBodyBuilt) {
    let color = srgb_channels(def.color.0);
    let params = ShrinkParams {
        method: def.method,
        variant: def.variant,
        k: def.k.0,
        eps: def.eps.0,
        max_iterations: def.max_iterations.0 as f64,
        compare: Compare::Alone,
    };
    entity
        .insert((
            Transform::from_translation(def.position.0).with_scale(Vec3::splat(def.scale.0)),
            RasterMesh::colored(Arc::default(), color),
            SoftBody::new(built),
            params,
        ))
        .with_children(|children| {
            children.spawn((Markers, RasterMesh::colored(Arc::default(), Vec3::new(0.9, 0.1, 0.1))));
            children.spawn((MeasureMarkers, RasterMesh::colored(Arc::default(), Vec3::new(0.1, 0.35, 0.95))));
            children.spawn((OriginalBeside, Transform::IDENTITY, RasterMesh::colored(Arc::default(), color)));
        });
}

/// Brings the definition's deformer settings up to date with the live parameters.
pub(super) fn save_live(def: &mut SoftBodyDef, entity: EntityRef) {
    use super::def::{Coefficient, IterationCap, Threshold};
    let Some(params) = entity.get::<ShrinkParams>() else { return };
    let (method, settings) = params.deformer();
    // Only settings a scene file may hold are kept: the file's own stay otherwise.
    if settings.check(method).is_ok() && settings.eps <= 1.0 {
        def.method = params.method;
        def.variant = params.variant;
        def.k = Coefficient(settings.k);
        def.eps = Threshold(settings.eps);
        def.max_iterations = IterationCap(settings.max_iterations);
    }
}

/// Every system of the soft body kind, in whichever phase it runs: a handle for ordering
/// other plugins' systems before or after the soft bodies'.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SoftBodySystems;

/// Soft body keys: (key, action).
pub(super) const SOFT_BODY_KEYS: [(KeyCode, &str); 6] = [
    (KeyCode::Backspace, "take back the last mark on the soft body"),
    (KeyCode::Delete, "take back every mark"),
    (KeyCode::Enter, "shrink the marked region into a new model"),
    (KeyCode::BracketLeft, "show the previous model (the original before the first)"),
    (KeyCode::BracketRight, "show the next model"),
    (KeyCode::KeyC, "compare: alone, overlay, side by side"),
];

/// Runs soft bodies: parameters, actions, keys, picking marks in the view, the write-back of
/// their meshes, the dump and the panel section.
#[derive(Default)]
pub struct SoftBodyPlugin;

impl Plugin for SoftBodyPlugin {
    fn build(&self, app: &mut App) {
        app.register_params::<ShrinkParams>()
            .register_dump::<SoftBody>()
            .add_systems(
                RunFixedMainLoop,
                (mark_clicked_points, act_on_keys).in_set(ControlSystems::Input).in_set(SoftBodySystems),
            )
            .add_systems(RunFixedMainLoop, take_shrinks.in_set(ControlSystems::Apply).in_set(SoftBodySystems))
            .add_systems(PostUpdate, write_back_soft_bodies.in_set(WriteBackSystems).in_set(SoftBodySystems))
            .add_systems(PostUpdate, publish_surfaces.in_set(SpatialSystems::Publish).in_set(SoftBodySystems));
    }
}

/// Marks (or measures from) the vertex nearest a click that picked a soft body, and selects
/// the body.
fn mark_clicked_points(
    mut picks: MessageReader<Picked>,
    mut bodies: Query<(&mut SoftBody, &ShrinkParams, &SceneEntity)>,
    mut selections: MessageWriter<SelectEntity>,
) {
    for picked in picks.read().filter(|picked| picked.pointer == Pointer::Click) {
        let (Ok((mut body, params, scene)), Some(vertex)) = (bodies.get_mut(picked.hit.entity), picked.hit.vertex)
        else {
            continue;
        };
        let action = match body.tool {
            Tool::Outline => SoftBodyAction::MarkVertex(vertex),
            Tool::Measure => SoftBodyAction::MeasureVertex(vertex),
        };
        // A mark or a measure starts no shrink.
        let _ = body.perform(action, params);
        selections.write(SelectEntity(scene.name.clone()));
    }
}

/// A soft body can be picked on the surface it shows, where it stands now.
fn publish_surfaces(bodies: Query<(Entity, Ref<SoftBody>, Ref<GlobalTransform>)>, mut commands: Commands) {
    for (entity, body, placed) in &bodies {
        if body.is_changed() || placed.is_changed() {
            commands.entity(entity).insert(Pickable::Surface { bvh: body.picking(), to_world: placed.affine() });
        }
    }
}

/// The soft body keys, acting on every soft body.
fn act_on_keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut bodies: Query<(Entity, &mut SoftBody, &mut ShrinkParams)>,
    mut commands: Commands,
) {
    for (entity, mut body, mut params) in &mut bodies {
        let shown = body.bench.shown();
        let count = body.bench.models().len();
        let action = if keys.just_pressed(KeyCode::Backspace) {
            Some(SoftBodyAction::UndoMark)
        } else if keys.just_pressed(KeyCode::Delete) {
            Some(SoftBodyAction::ClearMarks)
        } else if keys.just_pressed(KeyCode::Enter) {
            Some(SoftBodyAction::Apply)
        } else if keys.just_pressed(KeyCode::BracketLeft) {
            Some(SoftBodyAction::Show(shown.saturating_sub(1)))
        } else if keys.just_pressed(KeyCode::BracketRight) {
            Some(SoftBodyAction::Show((shown + 1).min(count)))
        } else {
            None
        };
        if let Some(job) = action.and_then(|action| body.perform(action, &params)) {
            commands.entity(entity).insert(start_shrink(job));
        }
        if keys.just_pressed(KeyCode::KeyC) {
            let next = Compare::ALL.iter().position(|(c, _)| *c == params.compare).map_or(0, |i| (i + 1) % 3);
            params.compare = Compare::ALL[next].0;
        }
    }
}

/// The drawn parts of a soft body.
type Parts<'w, 's> = Query<
    'w,
    's,
    (&'static mut RasterMesh, &'static mut Transform, Has<Markers>, Has<MeasureMarkers>),
    (Or<(With<Markers>, With<MeasureMarkers>, With<OriginalBeside>)>, Without<SoftBody>),
>;

/// Soft bodies whose state or parameters changed, with their drawn parts.
type ChangedBodies<'w, 's> = Query<
    'w,
    's,
    (&'static SoftBody, &'static ShrinkParams, &'static mut RasterMesh, &'static Children),
    (
        Or<(Changed<SoftBody>, Changed<ShrinkParams>)>,
        Without<Markers>,
        Without<MeasureMarkers>,
        Without<OriginalBeside>,
    ),
>;

/// Meshes soft bodies whose surface, marks or comparison changed: the surface shown (its
/// region tinted, or its shift from the original), the marks and the measured points as
/// balls, the original beside.
fn write_back_soft_bodies(mut bodies: ChangedBodies, mut parts: Parts) {
    for (body, params, mut raster, children) in &mut bodies {
        let bench = &body.bench;
        let (shown, original) = (bench.shown_positions(), &bench.original().positions);
        let triangles = &bench.original().triangles;
        let tints = match (params.compare, &body.region) {
            (Compare::Overlay, _) => shift_tints(original, shown).0,
            (_, Ok(region)) => region_tints(shown.len(), &region.inside, &region.outline),
            (_, Err(_)) => Vec::new(),
        };
        raster.mesh = Arc::new(surface_mesh(shown, triangles, tints));
        let (low, high) = bench.original().bounds();
        let marks: Vec<Vec3> = bench.marks().iter().filter_map(|&mark| bench.mark_position(mark)).collect();
        let measured: Vec<Vec3> = bench.measured().iter().filter_map(|&v| shown.get(v as usize).copied()).collect();
        let ball = MARKER_SHARE * (high - low).length();
        for &child in children {
            let Ok((mut part, mut transform, markers, measure_markers)) = parts.get_mut(child) else { continue };
            if markers {
                part.mesh = Arc::new(marker_mesh(&marks, ball));
            } else if measure_markers {
                part.mesh = Arc::new(marker_mesh(&measured, ball));
            } else if params.compare == Compare::SideBySide {
                // The original to the model's left, a fifth of its width apart. It never
                // changes: it is meshed when it is first shown, not with every mark.
                transform.translation = Vec3::X * -(high.x - low.x) * 1.2;
                if part.mesh.positions.is_empty() {
                    part.mesh = Arc::new(surface_mesh(original, triangles, Vec::new()));
                }
            } else if !part.mesh.positions.is_empty() {
                part.mesh = Arc::default();
            }
        }
    }
}

/// A mark's ball radius as a share of the surface's bounding diagonal.
const MARKER_SHARE: f32 = 0.006;
