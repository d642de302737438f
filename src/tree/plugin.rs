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
use crate::raster::RasterMesh;
use crate::raster::levels::MeshLevels;
use crate::raster::texture::material;
use crate::spatial::SpatialSystems;
use crate::spatial::ground::GroundPatch;
use crate::spatial::pick::{Pickable, Picked, Pointer};
use crate::spatial::solid::{Collider, Solid};
use bevy::ecs::world::EntityWorldMut;
use bevy::prelude::*;
use std::sync::Arc;

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
        MeshLevels::default(),
        TreeBody::new(tree),
        TreeSource { def: def.clone(), undo: Vec::new() },
    ));
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
    forests: Query<(&ScatteredTrees, &TreeSource, &RasterMesh)>,
    mut commands: Commands,
) {
    for (patch_entity, patch, child_of) in &patches {
        let Ok((Solid(Collider::Ground(ground)), world_entity)) = grounds.get(child_of.parent()) else { continue };
        if patch.level != 0 {
            continue;
        }
        for (forest, source, raster) in forests.iter().filter(|(forest, ..)| forest.world == world_entity.name) {
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
                    let mesh = Arc::new(mesh::tree_mesh(&tree, source.def.sides));
                    let levels = mesh::tree_levels(&tree, source.def.sides);
                    commands.spawn((
                        ChunkTrees { tree },
                        RasterMesh { mesh, material: raster.material.clone() },
                        levels,
                        ChildOf(patch_entity),
                    ));
                }
                Err(error) => warn!("trees of the ground at {}: {}", patch.key, error.message),
            }
        }
    }
}

/// Meshes trees whose supports were built or edited, with their coarser levels.
fn write_back_trees(mut trees: Query<(&TreeBody, &TreeSource, &mut RasterMesh, &mut MeshLevels), Changed<TreeBody>>) {
    for (body, source, mut raster, mut levels) in &mut trees {
        raster.mesh = Arc::new(mesh::tree_mesh(&body.tree, source.def.sides));
        *levels = mesh::tree_levels(&body.tree, source.def.sides);
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
