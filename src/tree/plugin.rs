//! The tree kind's plugin: the live tree and its queries, picking a support in the view,
//! checked edits with undo, the write-back of its mesh, and its dump.

use super::body::TreeBody;
use super::def::{TreeDef, prefixed};
use super::generate::{ScatterSettings, scatter};
use super::model::{Shape, SupportSpec, Tree};
use super::{edit, mesh};
use crate::foundation::dump::RegisterDump;
use crate::foundation::entity::SceneEntity;
use crate::foundation::messages::SelectEntity;
use crate::foundation::schedule::{ControlSystems, WriteBackSystems};
use crate::foundation::values::srgb_channels;
use crate::raster::texture::material;
use crate::raster::{Material, RasterMesh};
use crate::spatial::SpatialSystems;
use crate::spatial::ground::GroundPatch;
use crate::spatial::pick::{Pickable, Picked, Pointer};
use crate::spatial::solid::{Collider, Solid};
use bevy::ecs::world::EntityWorldMut;
use bevy::prelude::*;
use std::sync::Arc;

/// Spawns a tree entity of `def`, whose supports are `tree`; its meshes are written back with
/// the frame.
pub(super) fn spawn_tree(entity: &mut EntityWorldMut, def: &TreeDef, tree: Tree) {
    if let (Some(settings), Some(world)) = (def.scatter, &def.ground) {
        entity.insert(ScatteredTrees { world: world.clone(), settings });
    }
    entity.insert((
        Transform::IDENTITY,
        Visibility::default(),
        TreeBody::new(tree),
        TreeSource { def: def.clone(), undo: Vec::new() },
    ));
}

/// The bark a tree of `def` is drawn with.
fn bark(def: &TreeDef) -> Material {
    material(srgb_channels(def.color.0), def.texture.as_ref())
}

/// One cluster of a tree's supports as drawn: a child of the tree's entity (or of a chunk's
/// trees), its mesh and coarser levels beside it.
#[derive(Component, Debug, Clone, Copy)]
pub struct TreeMesh;

/// Spawns the clusters of `tree` as children of `parent`, drawn with `bark`.
fn spawn_clusters(commands: &mut Commands, parent: Entity, tree: &Tree, sides: usize, bark: &Material) {
    for cluster in mesh::tree_clusters(tree, sides) {
        let mesh = RasterMesh { mesh: Arc::new(cluster.mesh), material: bark.clone() };
        commands.spawn((TreeMesh, mesh, cluster.levels, Transform::IDENTITY, ChildOf(parent)));
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
            .add_systems(Update, grow_on_new_ground.after(SpatialSystems::Ground).in_set(TreeSystems))
            .add_systems(PostUpdate, write_back_trees.in_set(WriteBackSystems).in_set(TreeSystems))
            .add_systems(PostUpdate, publish_supports.in_set(SpatialSystems::Publish).in_set(TreeSystems));
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

/// Grows the scattered trees of each patch of ground that came in at the finest level of
/// detail, as a child of the patch, standing on the ground of the world it belongs to.
fn grow_on_new_ground(
    patches: Query<(Entity, &GroundPatch, &ChildOf), Added<GroundPatch>>,
    grounds: Query<(&Solid, &SceneEntity)>,
    forests: Query<(&ScatteredTrees, &TreeSource)>,
    mut commands: Commands,
) {
    for (patch_entity, patch, child_of) in &patches {
        let Ok((Solid(Collider::Ground(ground)), world_entity)) = grounds.get(child_of.parent()) else { continue };
        if patch.level != 0 {
            continue;
        }
        for (forest, source) in forests.iter().filter(|(forest, ..)| forest.world == world_entity.name) {
            let specs: Vec<SupportSpec> =
                scatter(&forest.settings, (patch.key.x, patch.key.y), (patch.corner.x, patch.corner.y), patch.side)
                    .into_iter()
                    .map(|mut supports| {
                        if let Shape::Polyline { points, .. } = &mut supports[0].shape {
                            let lift = ground.height(points[0].x, points[0].z).unwrap_or(0.0);
                            points.iter_mut().for_each(|point| point.y += lift);
                        }
                        supports
                    })
                    .enumerate()
                    .flat_map(prefixed)
                    .collect();
            match Tree::build(&specs) {
                Ok(tree) => {
                    let trees =
                        commands.spawn((Transform::IDENTITY, Visibility::default(), ChildOf(patch_entity))).id();
                    spawn_clusters(&mut commands, trees, &tree, source.def.sides, &bark(&source.def));
                    commands.entity(trees).insert(ChunkTrees { tree });
                }
                Err(error) => warn!("trees of the ground at {}: {}", patch.key, error.message),
            }
        }
    }
}

/// Meshes trees whose supports were built or edited: their clusters made anew.
fn write_back_trees(
    trees: Query<(Entity, &TreeBody, &TreeSource, Option<&Children>), Changed<TreeBody>>,
    meshes: Query<(), With<TreeMesh>>,
    mut commands: Commands,
) {
    for (entity, body, source, children) in &trees {
        for child in children.into_iter().flatten().filter(|&&child| meshes.contains(child)) {
            commands.entity(*child).despawn();
        }
        spawn_clusters(&mut commands, entity, &body.tree, source.def.sides, &bark(&source.def));
    }
}

/// Selects the support a click in the view picked, and its tree in the panel.
fn select_clicked_support(
    mut picks: MessageReader<Picked>,
    trees: Query<(&TreeBody, &SceneEntity)>,
    mut selections: MessageWriter<SelectEntity>,
    mut commands: Commands,
) {
    for picked in picks.read().filter(|picked| picked.pointer == Pointer::Click) {
        let Ok((body, scene_entity)) = trees.get(picked.hit.entity) else { continue };
        commands.entity(picked.hit.entity).insert(SelectedSupport(body.segment_supports[picked.hit.part]));
        selections.write(SelectEntity(scene_entity.name.clone()));
    }
}

/// A tree whose supports were built or edited is a solid and can be picked, segment by segment.
fn publish_supports(trees: Query<(Entity, &TreeBody), Changed<TreeBody>>, mut commands: Commands) {
    for (entity, body) in &trees {
        let bvh = Arc::new(body.bvh.clone());
        commands.entity(entity).insert((Solid(Collider::Supports(bvh.clone())), Pickable::Segments(bvh)));
    }
}
