//! The tree kind's plugin: the live tree and its queries, picking a support in the view,
//! checked edits with undo, the write-back of its mesh, and its dump.

use super::bvh::SegmentBvh;
use super::def::{TreeDef, prefixed};
use super::generate::{ScatterSettings, scatter};
use super::geometry::TaperedSegment;
use super::model::{Shape, SupportSpec, Tree};
use super::{edit, mesh};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::entity::SceneEntity;
use crate::foundation::messages::{SelectEntity, ViewClicked};
use crate::foundation::schedule::{ControlSystems, WriteBackSystems};
use crate::foundation::values::srgb_channels;
use crate::raster::RasterMesh;
use crate::raster::texture::material;
use crate::view::CameraParams;
use crate::world::{WorldBody, WorldChunk, WorldSystems};
use bevy::ecs::world::EntityWorldMut;
use bevy::prelude::*;
use serde_json::{Map, Value, json};
use std::sync::Arc;

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
                support: body.segment_supports[hit.index],
                distance: hit.hit.distance,
                point: hit.hit.surface.point,
                normal: hit.hit.surface.normal,
                fraction: body.fraction_along(hit.index, hit.hit.surface.along),
            })
        })
        .min_by(|a, b| a.distance.total_cmp(&b.distance))
}

/// Spawns a tree entity of `def`, whose supports are `tree`; its mesh is written back with
/// the frame.
pub(super) fn spawn_tree(entity: &mut EntityWorldMut, def: &TreeDef, tree: Tree) {
    let material = material(srgb_channels(def.color.0), def.texture.as_ref());
    if let (Some(settings), Some(world)) = (def.scatter, &def.ground) {
        entity.insert(ScatteredTrees { world: world.clone(), settings });
    }
    entity.insert((
        Transform::IDENTITY,
        RasterMesh { mesh: Arc::default(), material },
        TreeBody::new(tree),
        TreeSource { def: def.clone(), undo: Vec::new() },
    ));
}

impl TreeBody {
    /// The body of a built tree: its supports and the hierarchy over their segments.
    pub fn new(tree: Tree) -> Self {
        let (segment_supports, segments): (Vec<usize>, Vec<TaperedSegment>) = tree.segments().unzip();
        TreeBody { tree, bvh: SegmentBvh::new(segments), segment_supports }
    }
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
/// rebuilds its body; the mesh follows in the write-back. `def` builds: edits are checked
/// first.
fn replace_tree(world: &mut World, entity: Entity, def: TreeDef, remember: bool) {
    let Ok(tree) = def.build() else { return };
    let body = TreeBody::new(tree);
    let Ok(mut entity_mut) = world.get_entity_mut(entity) else { return };
    if let Some(mut source) = entity_mut.get_mut::<TreeSource>() {
        let old = std::mem::replace(&mut source.def, def);
        if remember {
            source.undo.push(old);
        }
    }
    let supports = body.tree.supports.len();
    entity_mut.insert(body);
    if entity_mut.get::<SelectedSupport>().is_some_and(|s| s.0 >= supports) {
        entity_mut.remove::<SelectedSupport>();
    }
}

/// The support of a tree entity last picked in the view.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct SelectedSupport(pub usize);

/// Every system of the tree kind, in whichever phase it runs: a handle for ordering other
/// plugins' systems before or after the trees'.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TreeSystems;

/// Runs trees: their dump fields, picking supports in the view, the panel section, and the
/// write-back of their meshes.
#[derive(Default)]
pub struct TreePlugin;

impl Plugin for TreePlugin {
    fn build(&self, app: &mut App) {
        app.register_dump::<TreeBody>()
            .add_systems(RunFixedMainLoop, select_clicked_support.in_set(ControlSystems::Input).in_set(TreeSystems))
            .add_systems(Update, grow_on_new_chunks.after(WorldSystems).in_set(TreeSystems))
            .add_systems(PostUpdate, write_back_trees.in_set(WriteBackSystems).in_set(TreeSystems));
    }
}

/// Trees scattered over a streamed world's chunks: the world, by entity name, and how they
/// grow.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct ScatteredTrees {
    /// The world whose chunks they grow on.
    pub world: String,
    /// How many grow on a chunk, and how.
    pub settings: ScatterSettings,
}

/// The trees grown on one chunk: a child of the chunk, so that they stream out with it.
#[derive(Component, Debug, Clone)]
pub struct ChunkTrees {
    /// Their supports, trunks standing on the ground.
    pub tree: Tree,
}

/// Grows the scattered trees of each chunk that came in at the finest level of detail, as a
/// child of the chunk.
fn grow_on_new_chunks(
    chunks: Query<(Entity, &WorldChunk, &ChildOf), Added<WorldChunk>>,
    worlds: Query<(&WorldBody, &SceneEntity)>,
    forests: Query<(&ScatteredTrees, &TreeSource, &RasterMesh)>,
    mut commands: Commands,
) {
    for (chunk_entity, chunk, child_of) in &chunks {
        let Ok((world, world_entity)) = worlds.get(child_of.parent()) else { continue };
        if chunk.level != 0 {
            continue;
        }
        let (corner, side) = world.chunk_square(chunk.key);
        let (heights, geometry) = world.ground();
        for (forest, source, raster) in forests.iter().filter(|(forest, ..)| forest.world == world_entity.name) {
            let specs: Vec<SupportSpec> = scatter(&forest.settings, (chunk.key.x, chunk.key.z), corner, side)
                .into_iter()
                .map(|mut supports| {
                    if let Shape::Polyline { points, .. } = &mut supports[0].shape {
                        let lift = heights.ground_height(points[0].x, points[0].z, geometry);
                        points.iter_mut().for_each(|point| point.y += lift);
                    }
                    supports
                })
                .enumerate()
                .flat_map(prefixed)
                .collect();
            match Tree::build(&specs) {
                Ok(tree) => {
                    let mesh = Arc::new(mesh::tree_mesh(&tree, source.def.sides));
                    commands.spawn((
                        ChunkTrees { tree },
                        RasterMesh { mesh, material: raster.material.clone() },
                        ChildOf(chunk_entity),
                    ));
                }
                Err(error) => warn!("trees of chunk {:?}: {}", chunk.key, error.message),
            }
        }
    }
}

/// Meshes trees whose supports were built or edited.
fn write_back_trees(mut trees: Query<(&TreeBody, &TreeSource, &mut RasterMesh), Changed<TreeBody>>) {
    for (body, source, mut raster) in &mut trees {
        raster.mesh = Arc::new(mesh::tree_mesh(&body.tree, source.def.sides));
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
