//! The `tree` entity kind: trunks and branches as chains of tapered segments, drawn as smooth
//! tubes with rounded tips, and the geometry queries the sloth and the editor need.
//!
//! | module | what it holds |
//! |---|---|
//! | [`model`] | supports from their descriptions (polylines or forks), trunk or branch |
//! | [`geometry`] | one tapered segment: signed distance, closest surface point, ray hit |
//! | [`bvh`] | a bounding volume hierarchy over all segments: ray cast, nearest, within a radius |
//! | [`mesh`] | the render mesh: tubes with parallel-transported rings and rounded tips |
//! | [`generate`] | the seeded tree and forest generator |
//! | [`edit`] | checked edits of a written-out tree |
//!
//! All six are pure and tested (the queries against brute force); this module adds the scene
//! format, spawning and the state dump.

pub mod bvh;
pub mod edit;
pub mod generate;
pub mod geometry;
pub mod mesh;
pub mod model;

pub use bvh::{Nearest, RayHit, SegmentBvh};
pub use generate::GeneratorSettings;
pub use geometry::{SegmentHit, SurfacePoint, TaperedSegment};
pub use model::{Shape, Support, SupportKind, SupportSpec, Tree, TreeError};

use crate::controls::{SelectEntity, ViewClicked};
use crate::dump::{DumpState, RegisterDump};
use crate::raster::{MeshData, RasterMesh};
use crate::scene::SceneEntity;
use crate::scene::values::{Color, Degrees, Length, Point, Radius, UnitInterval};
use crate::schedule::ControlSystems;
use crate::shape::TextureDef;
use crate::ui::RegisterPanel;
use crate::view::CameraParams;
use bevy::color::Srgba;
use bevy::prelude::*;
use bevy_egui::egui;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};
use std::sync::Arc;

/// A `tree` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TreeDef {
    /// Bark colour; brown by default.
    #[serde(default = "bark")]
    pub color: Color,
    /// Bark image (PNG or BMP in the scene's folder), wrapped once around each support (u) and
    /// repeating every metre along it (v), times `repeat`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureDef>,
    /// Vertices around each ring of the tubes (3 to 64; 12 by default).
    #[serde(deserialize_with = "sides")]
    #[serde(default = "default_sides")]
    pub sides: usize,
    /// The trunks and branches, written out.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub supports: Vec<SupportDef>,
    /// Or: generated from these settings (see `canopy tree generate`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generate: Option<GeneratorSettings>,
}

fn bark() -> Color {
    Color(Srgba::rgb(0.42, 0.3, 0.2))
}

fn default_sides() -> usize {
    12
}

/// Reads `sides`: a whole number from 3 to 64.
fn sides<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<usize, D::Error> {
    let sides = u64::deserialize(deserializer)?;
    if (3..=64).contains(&sides) {
        Ok(sides as usize)
    } else {
        Err(serde::de::Error::custom(format_args!("expected 3 to 64 sides, found {sides}")))
    }
}

/// One support in a scene file: a polyline (`points`, `radii`) or a fork from a parent
/// (`parent`, `at`, `yaw_deg`, `pitch_deg`, `length`, `radius`, optionally `bend_deg` and
/// `sections`).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SupportDef {
    /// Unique within the tree.
    pub name: String,
    /// `trunk` or `branch`; by default a support tilted more than 70 degrees from horizontal is
    /// a trunk.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<SupportKind>,
    /// Axis points in metres (a polyline).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<Point>>,
    /// A radius in metres at each point (a polyline).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radii: Option<Vec<Radius>>,
    /// The support this one forks from (a fork).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<String>,
    /// Where along the parent it starts, 0 to 1 of its length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<UnitInterval>,
    /// Initial heading about +y, degrees (0 towards +z, 90 towards +x); 0 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw_deg: Option<Degrees>,
    /// Initial angle above the horizontal, degrees; 0 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pitch_deg: Option<Degrees>,
    /// Length in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<Length>,
    /// Radius at the start and at the tip, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<[Radius; 2]>,
    /// Total change of heading and pitch along the branch, degrees; none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bend_deg: Option<[Degrees; 2]>,
    /// Straight sections of a fork (1 to 64; 4 by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sections: Option<u32>,
}

/// Fields only forks take.
const FORK_FIELDS: [&str; 8] = ["parent", "at", "yaw_deg", "pitch_deg", "length", "radius", "bend_deg", "sections"];

impl SupportDef {
    /// The support's description, or the field at fault and why.
    fn spec(&self) -> Result<SupportSpec, (&'static str, String)> {
        let polyline = self.points.is_some() || self.radii.is_some();
        let fork = self.parent.is_some();
        let shape = match (polyline, fork) {
            (true, true) => {
                return Err((
                    "parent",
                    "a support is either a polyline (points, radii) or a fork (parent, ...), not both".into(),
                ));
            }
            (false, false) => {
                return Err((
                    "name",
                    format!("support \"{}\" needs points and radii, or a parent to fork from", self.name),
                ));
            }
            (true, false) => {
                if let Some(field) = self.fork_field() {
                    return Err((field, format!("`{field}` belongs to forks; this support is a polyline")));
                }
                let points = self.points.as_ref().ok_or(("radii", "a polyline needs points too".to_string()))?;
                let radii = self.radii.as_ref().ok_or(("points", "a polyline needs radii too".to_string()))?;
                Shape::Polyline {
                    points: points.iter().map(|p| p.0).collect(),
                    radii: radii.iter().map(|r| r.0).collect(),
                }
            }
            (false, true) => {
                let missing = |field: &'static str| ("parent", format!("a fork needs `{field}`"));
                let sections = self.sections.unwrap_or(4);
                if !(1..=64).contains(&sections) {
                    return Err(("sections", format!("expected 1 to 64 sections, found {sections}")));
                }
                Shape::Fork {
                    parent: self.parent.clone().unwrap_or_default(),
                    at: self.at.ok_or_else(|| missing("at"))?.0,
                    yaw_deg: self.yaw_deg.map_or(0.0, |d| d.0),
                    pitch_deg: self.pitch_deg.map_or(0.0, |d| d.0),
                    length: self.length.ok_or_else(|| missing("length"))?.0,
                    radius: self.radius.ok_or_else(|| missing("radius"))?.map(|r| r.0),
                    bend_deg: self.bend_deg.map_or([0.0; 2], |b| b.map(|d| d.0)),
                    sections,
                }
            }
        };
        Ok(SupportSpec { name: self.name.clone(), shape, kind: self.kind })
    }

    /// Every optional field and whether it is given, in file-format order.
    fn given(&self) -> [(&'static str, bool); 11] {
        [
            ("kind", self.kind.is_some()),
            ("points", self.points.is_some()),
            ("radii", self.radii.is_some()),
            ("parent", self.parent.is_some()),
            ("at", self.at.is_some()),
            ("yaw_deg", self.yaw_deg.is_some()),
            ("pitch_deg", self.pitch_deg.is_some()),
            ("length", self.length.is_some()),
            ("radius", self.radius.is_some()),
            ("bend_deg", self.bend_deg.is_some()),
            ("sections", self.sections.is_some()),
        ]
    }

    /// The first fork-only field given, if any.
    fn fork_field(&self) -> Option<&'static str> {
        self.given().into_iter().find_map(|(field, given)| (given && FORK_FIELDS.contains(&field)).then_some(field))
    }

    /// Whether this support's mapping holds `field`, for locating errors in the file.
    pub fn has_field(&self, field: &str) -> bool {
        field == "name" || self.given().into_iter().any(|(name, given)| given && name == field)
    }
}

impl TreeDef {
    /// The tree this definition describes, or the support and field at fault and why.
    pub fn build(&self) -> Result<Tree, TreeError> {
        let tree_error = |field, message: String| TreeError { support: None, field, message };
        match (&self.generate, self.supports.is_empty()) {
            (Some(_), false) => Err(tree_error("generate", "give either supports or generate, not both".into())),
            (None, true) => Err(tree_error("supports", "a tree needs supports, or generate settings".into())),
            (Some(settings), true) => {
                settings.check().map_err(|message| tree_error("generate", message))?;
                Tree::build(
                    &generate::generate(settings).into_iter().enumerate().flat_map(prefixed).collect::<Vec<_>>(),
                )
            }
            (None, false) => {
                let specs = self
                    .supports
                    .iter()
                    .enumerate()
                    .map(|(support, def)| {
                        def.spec().map_err(|(field, message)| TreeError { support: Some(support), field, message })
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Tree::build(&specs)
            }
        }
    }
}

/// The supports of generated tree `index`, renamed `t<index + 1>-<name>` so that the supports of
/// all the trees generated into one entity have distinct names.
fn prefixed((index, supports): (usize, Vec<SupportSpec>)) -> Vec<SupportSpec> {
    let rename = |name: &str| format!("t{}-{name}", index + 1);
    supports
        .into_iter()
        .map(|mut spec| {
            spec.name = rename(&spec.name);
            if let Shape::Fork { parent, .. } = &mut spec.shape {
                *parent = rename(parent);
            }
            spec
        })
        .collect()
}

/// A live tree: its supports and the hierarchy over their segments.
#[derive(Component, Debug, Clone)]
pub struct TreeBody {
    /// The supports.
    pub tree: Tree,
    /// Every segment of every support, for queries.
    pub bvh: SegmentBvh,
    /// The support each segment of `bvh` belongs to.
    pub segment_supports: Vec<usize>,
}

impl TreeBody {
    /// Where a point `along` (0 to 1) segment `segment` lies on its support, as a fraction of
    /// the support's length.
    pub fn fraction_along(&self, segment: usize, along: f32) -> f32 {
        let index = self.segment_supports[segment];
        let first = self.segment_supports.iter().position(|&s| s == index).unwrap_or(segment);
        let support = &self.tree.supports[index];
        let lengths: Vec<f32> = support.points.windows(2).map(|p| p[0].distance(p[1])).collect();
        let local = segment - first;
        let before: f32 = lengths[..local].iter().sum();
        (before + along * lengths[local]) / lengths.iter().sum::<f32>().max(f32::MIN_POSITIVE)
    }
}

impl DumpState for TreeBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let supports: Vec<Value> = self
            .tree
            .supports
            .iter()
            .map(|s| {
                json!({
                    "name": s.name,
                    "kind": s.kind.key(),
                    "points": s.points.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
                    "radii": s.radii,
                })
            })
            .collect();
        out.insert("supports".into(), json!(supports));
    }
}

/// A support hit by a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pick {
    /// The tree entity.
    pub entity: Entity,
    /// The support's index in the tree.
    pub support: usize,
    /// Distance along the ray, metres.
    pub distance: f32,
    /// The point hit.
    pub point: Vec3,
    /// The surface normal there.
    pub normal: Vec3,
    /// Where along the support, as a fraction of its length (0 at its first point).
    pub fraction: f32,
}

/// The first support any tree shows along the ray from `origin` along the unit `direction`
/// (trees are placed in scene coordinates).
pub fn pick<'a>(
    trees: impl IntoIterator<Item = (Entity, &'a TreeBody)>,
    origin: Vec3,
    direction: Vec3,
) -> Option<Pick> {
    trees
        .into_iter()
        .filter_map(|(entity, body)| {
            let hit = body.bvh.ray_cast(origin, direction, f32::MAX)?;
            Some(Pick {
                entity,
                support: body.segment_supports[hit.segment],
                distance: hit.hit.distance,
                point: hit.hit.surface.point,
                normal: hit.hit.surface.normal,
                fraction: body.fraction_along(hit.segment, hit.hit.surface.along),
            })
        })
        .min_by(|a, b| a.distance.total_cmp(&b.distance))
}

/// Spawns the components of a tree entity onto `entity`.
pub fn spawn_tree(entity: &mut EntityCommands, def: &TreeDef) {
    let tree = match def.build() {
        Ok(tree) => tree,
        Err(error) => {
            // Scene files are checked before spawning; a definition built in code may not be.
            error!("tree not spawned: {error}");
            return;
        }
    };
    let (mesh, body) = body_of(def, tree);
    let color = def.color.0;
    let material = crate::shape::material(Vec3::new(color.red, color.green, color.blue), def.texture.as_ref());
    entity.insert((
        Transform::IDENTITY,
        RasterMesh { mesh: Arc::new(mesh), material },
        body,
        TreeSource { def: def.clone(), undo: Vec::new() },
    ));
}

/// The mesh and the body of a built tree.
fn body_of(def: &TreeDef, tree: Tree) -> (MeshData, TreeBody) {
    let (segment_supports, segments): (Vec<usize>, Vec<TaperedSegment>) = tree.segments().unzip();
    let mesh = mesh::tree_mesh(&tree, def.sides.clamp(3, 64));
    (mesh, TreeBody { tree, bvh: SegmentBvh::new(segments), segment_supports })
}

/// A tree's description as edited in the window, and the descriptions before each edit.
#[derive(Component, Debug, Clone)]
pub struct TreeSource {
    /// The current description.
    pub def: TreeDef,
    /// Earlier descriptions, the latest last.
    pub undo: Vec<TreeDef>,
}

/// Applies `edit` to the tree `entity` and rebuilds it, or says why not (nothing changes).
pub fn edit_tree(world: &mut World, entity: Entity, change: edit::Edit) -> Result<(), String> {
    let source = world.get::<TreeSource>(entity).ok_or("not a tree")?;
    let def = edit::apply(&source.def, change)?;
    replace_tree(world, entity, def, true);
    Ok(())
}

/// Takes the tree `entity` back to its description before the last edit; false if there is none.
pub fn undo_tree_edit(world: &mut World, entity: Entity) -> bool {
    let Some(def) = world.get_mut::<TreeSource>(entity).and_then(|mut source| source.undo.pop()) else {
        return false;
    };
    replace_tree(world, entity, def, false);
    true
}

/// Makes `def` the tree's description (keeping the old one for undo when `remember`), and
/// rebuilds its body and mesh. `def` builds: edits are checked first.
fn replace_tree(world: &mut World, entity: Entity, def: TreeDef, remember: bool) {
    let Ok(tree) = def.build() else { return };
    let (mesh, body) = body_of(&def, tree);
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    if let Some(mut source) = entity_mut.get_mut::<TreeSource>() {
        let old = std::mem::replace(&mut source.def, def);
        if remember {
            source.undo.push(old);
        }
    }
    let supports = body.tree.supports.len();
    if let Some(mut raster) = entity_mut.get_mut::<RasterMesh>() {
        raster.mesh = Arc::new(mesh);
    }
    entity_mut.insert(body);
    if entity_mut.get::<SelectedSupport>().is_some_and(|s| s.0 >= supports) {
        entity_mut.remove::<SelectedSupport>();
    }
}

/// The support of a tree entity last picked in the view.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct SelectedSupport(pub usize);

/// Registers the tree kind: its dump fields, picking supports in the view, its panel section.
pub struct TreePlugin;

impl Plugin for TreePlugin {
    fn build(&self, app: &mut App) {
        app.register_dump::<TreeBody>()
            .register_panel_section("tree", tree_section)
            .add_systems(Update, select_clicked_support.in_set(ControlSystems::Input));
    }
}

/// Picks the support under a click in the view and selects its tree in the panel.
fn select_clicked_support(
    mut clicks: MessageReader<ViewClicked>,
    cameras: Query<&CameraParams>,
    trees: Query<(Entity, &TreeBody, &SceneEntity)>,
    mut selections: MessageWriter<SelectEntity>,
    mut commands: Commands,
) {
    let Some(camera) = cameras.iter().next().map(CameraParams::camera) else { return };
    for click in clicks.read() {
        let (origin, direction) = camera.ray(click.ndc, click.aspect);
        let Some(picked) = pick(trees.iter().map(|(entity, body, _)| (entity, body)), origin, direction) else {
            continue;
        };
        commands.entity(picked.entity).insert(SelectedSupport(picked.support));
        if let Ok((_, _, scene_entity)) = trees.get(picked.entity) {
            selections.write(SelectEntity(scene_entity.name.clone()));
        }
    }
}

/// Why the last edit of a tree in the panel was refused.
#[derive(Component, Debug, Clone)]
struct EditRefused(String);

/// The tree's section of the panel: its supports, the one picked in the view and its editor.
fn tree_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
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
