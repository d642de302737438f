//! The `tree` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::TreeDef;
use super::model::{Shape, Tree};
use super::panel;
use super::plugin::{self, TreePlugin, TreeSource};
use super::qsm;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use crate::raster::texture::TextureDef;
use crate::terrain::TerrainKind;
use crate::terrain::def::TerrainBuilt;
use crate::world::{WorldBuilt, WorldKind};
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};

/// The `tree` kind.
pub struct TreeKind;

impl EntityKind for TreeKind {
    const KEY: &'static str = "tree";
    type Def = TreeDef;
    type Built = Tree;
    type Plugin = TreePlugin;

    fn references(def: &TreeDef) -> Vec<String> {
        let mut files = TextureDef::reference(def.texture.as_ref());
        files.extend(def.import.as_ref().map(|import| import.file.clone()));
        files
    }

    /// Decodes the bark texture and reads the model of an imported tree; a bad model is an
    /// error at its own file's line and column.
    fn resolve(def: &mut TreeDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        if let Some(import) = def.import.as_mut().filter(|import| import.file == file.file) {
            let format = import.format;
            let model = file.decoded(|path, bytes| {
                qsm::read(bytes, format).map_err(|error| match error.location {
                    Some((line, column)) => FileError::at(path, line, column, error.message),
                    None => FileError::whole_file(path, format!("{}: {}", cx.field("import.file"), error.message)),
                })
            })?;
            import.model = Some(model);
        }
        def.texture.as_mut().map_or(Ok(()), |texture| texture.resolve(file, cx, "texture.file"))
    }

    /// Builds the tree; an error is located at its support's field, the nth occurrence of that
    /// key among the supports of the file's trees, or at the tree's `generate` or `tree` key.
    fn build(def: &TreeDef, cx: &BuildContext) -> Result<Tree, FileError> {
        if def.scatter.is_some() {
            scattered_on_a_world(def, cx)?;
        }
        let rooted;
        let def = match &def.ground {
            Some(ground) => {
                rooted = TreeDef { lifts: lifts_on(def, ground, cx)?, ..def.clone() };
                &rooted
            }
            None => def,
        };
        let error = match def.build() {
            Ok(tree) => return Ok(tree),
            Err(error) => error,
        };
        let entity = &cx.entity;
        let message = format!("entities[{}].tree.{error}", entity.index);
        let earlier: Vec<&TreeDef> = cx.earlier::<TreeKind>().collect();
        let Some(support) = error.support else {
            // About the tree as a whole: at its `generate` key, or else its `tree` key.
            return Err(match error.field {
                "generate" => {
                    let nth = earlier.iter().filter(|tree| tree.generate.is_some()).count();
                    entity.locate("generate", nth, message)
                }
                "scatter" => {
                    let nth = earlier.iter().filter(|tree| tree.scatter.is_some()).count();
                    entity.locate("scatter", nth, message)
                }
                "import" => {
                    let nth = earlier.iter().filter(|tree| tree.import.is_some()).count();
                    entity.locate("import", nth, message)
                }
                "grip_min_radius_m" => {
                    let nth = earlier.iter().filter(|tree| tree.grip_min_radius_m != 0.0).count();
                    entity.locate("grip_min_radius_m", nth, message)
                }
                _ => entity.locate("tree", earlier.len(), message),
            });
        };
        // Supports of earlier trees, and earlier supports of this one, holding the key.
        let before = earlier.iter().flat_map(|tree| &tree.supports).chain(&def.supports[..support]);
        let mut nth = before.filter(|s| s.has_field(error.field)).count();
        if error.field == "name" {
            // Entity names come before their kinds' supports in the file.
            nth += cx.names_through();
        }
        Err(entity.locate(error.field, nth, message))
    }

    fn spawn(def: &TreeDef, tree: &Tree, entity: &mut EntityWorldMut) {
        let def = TreeDef { lifts: tree.lifts.clone(), ..def.clone() };
        plugin::spawn_tree(entity, &def, tree.clone());
    }

    fn save_live(def: &mut TreeDef, entity: EntityRef) {
        if let Some(source) = entity.get::<TreeSource>() {
            *def = source.def.clone();
        }
    }

    fn register(app: &mut App) {
        app.register_panel_section::<Self>(panel::tree_section);
    }
}

/// How far each support that forks from no other must be raised to stand on the ground named
/// `ground` (a terrain or a streamed world): the ground's height under its first point. An
/// unknown ground, or a support standing off a terrain's section, is an error at the tree's
/// `ground`. (A tree whose supports do not build is left to the build to report.)
fn lifts_on(def: &TreeDef, ground: &str, cx: &BuildContext) -> Result<Vec<(String, f32)>, FileError> {
    let entity = &cx.entity;
    let nth = cx.earlier::<TreeKind>().filter(|tree| tree.ground.is_some()).count();
    let error =
        |message: String| entity.locate("ground", nth, format!("entities[{}].tree.ground: {message}", entity.index));
    let terrains: Vec<(&str, &TerrainBuilt)> = cx.built::<TerrainKind>().collect();
    let worlds: Vec<(&str, &WorldBuilt)> = cx.built::<WorldKind>().collect();
    let height_under: Box<dyn Fn(f32, f32) -> Option<f32>> =
        if let Some((_, terrain)) = terrains.iter().find(|(name, _)| *name == ground) {
            Box::new(|x, z| terrain.ground.height_under(x, z))
        } else if let Some((_, world)) = worlds.iter().find(|(name, _)| *name == ground) {
            Box::new(|x, z| Some(world.height_under(x, z)))
        } else {
            let names: Vec<&str> =
                terrains.iter().map(|(name, _)| *name).chain(worlds.iter().map(|(name, _)| *name)).collect();
            return Err(error(format!(
                "no terrain or world named `{ground}` (grounds: {})",
                if names.is_empty() { "none".into() } else { names.join(", ") }
            )));
        };
    let Ok(specs) = def.specs() else { return Ok(Vec::new()) };
    let mut lifts = Vec::new();
    for spec in &specs {
        if let Shape::Polyline { points, .. } = &spec.shape {
            let base = points[0];
            let height = height_under(base.x, base.z).ok_or_else(|| {
                error(format!(
                    "support `{}` starts at x {:.2}, z {:.2}, off the terrain `{ground}`'s section",
                    spec.name, base.x, base.z
                ))
            })?;
            lifts.push((spec.name.clone(), height));
        }
    }
    Ok(lifts)
}

/// Checks that a scattering tree's `ground` names a streamed world: its trees grow on chunks.
fn scattered_on_a_world(def: &TreeDef, cx: &BuildContext) -> Result<(), FileError> {
    let worlds: Vec<&str> = cx.built::<WorldKind>().map(|(name, _)| name).collect();
    if def.ground.as_deref().is_some_and(|ground| worlds.contains(&ground)) {
        return Ok(());
    }
    let entity = &cx.entity;
    let nth = cx.earlier::<TreeKind>().filter(|tree| tree.scatter.is_some()).count();
    let message = format!(
        "entities[{}].tree.scatter: trees are scattered over the chunks of a streamed world: name one in `ground` \
         (worlds: {})",
        entity.index,
        if worlds.is_empty() { "none".into() } else { worlds.join(", ") }
    );
    Err(entity.locate("scatter", nth, message))
}
