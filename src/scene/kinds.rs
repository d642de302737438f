//! The registry of entity kinds, through which a scene is read, checked, spawned and saved
//! without naming any kind.
//!
//! Kinds are listed once, with [`Kinds::with`], in the order their keys appear in messages
//! and in which they are built: a kind's checks see what the kinds before it built (the sloth
//! comes after the trees it hangs from).

use super::kind_list::{KindList, Then};
use super::schema::{EntityDef, SceneDef, SceneFile, WriteScene};
use crate::foundation::kind::{
    BuildContext, Built, EntityContext, EntityKind, EntityRecord, KindDef, ReferencedFile, SharedBuilds, Standalone,
};
use crate::foundation::yaml::{FileError, parse_yaml};
use bevy::app::{App, Plugin, PluginGroupBuilder};
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What [`EntityKind::register`] adds for kind `K`, as a plugin that follows the kind's own.
struct KindRegistration<K>(PhantomData<fn() -> K>);

impl<K: EntityKind> Plugin for KindRegistration<K> {
    fn build(&self, app: &mut App) {
        K::register(app);
    }
}

/// A kind's hooks behind one object-safe face.
trait ErasedKind: Send + Sync {
    fn key(&self) -> &'static str;
    fn add_plugin(&self, group: PluginGroupBuilder) -> PluginGroupBuilder;
    fn standalone(&self, path: &Path, bytes: &[u8]) -> Option<Result<Standalone<Box<dyn KindDef>>, FileError>>;
    fn validate(&self, def: &dyn KindDef, cx: &EntityContext) -> Result<(), FileError>;
    fn references(&self, def: &dyn KindDef) -> Vec<String>;
    fn resolve(&self, def: &mut dyn KindDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError>;
    fn build(&self, def: &dyn KindDef, cx: &BuildContext) -> Result<Built, FileError>;
    fn spawn(&self, def: &dyn KindDef, built: &Built, entity: &mut EntityWorldMut);
    fn saved(&self, def: &dyn KindDef) -> Box<dyn KindDef>;
    fn save_live(&self, def: &mut dyn KindDef, entity: EntityRef);
}

struct Erased<K>(PhantomData<fn() -> K>);

impl<K: EntityKind> Erased<K> {
    fn def(def: &dyn KindDef) -> &K::Def {
        def.as_any().downcast_ref().expect("the registry holds each definition with its own kind")
    }
}

impl<K: EntityKind> ErasedKind for Erased<K> {
    fn key(&self) -> &'static str {
        K::KEY
    }

    fn add_plugin(&self, group: PluginGroupBuilder) -> PluginGroupBuilder {
        group.add(K::Plugin::default()).add(KindRegistration::<K>(PhantomData))
    }

    fn standalone(&self, path: &Path, bytes: &[u8]) -> Option<Result<Standalone<Box<dyn KindDef>>, FileError>> {
        let read = K::standalone(path, bytes)?;
        Some(read.map(|Standalone { def, view }| Standalone { def: Box::new(def) as Box<dyn KindDef>, view }))
    }

    fn validate(&self, def: &dyn KindDef, cx: &EntityContext) -> Result<(), FileError> {
        K::validate(Self::def(def), cx)
    }

    fn references(&self, def: &dyn KindDef) -> Vec<String> {
        K::references(Self::def(def))
    }

    fn resolve(&self, def: &mut dyn KindDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        let def = def.as_any_mut().downcast_mut().expect("the registry holds each definition with its own kind");
        K::resolve(def, file, cx)
    }

    fn build(&self, def: &dyn KindDef, cx: &BuildContext) -> Result<Built, FileError> {
        K::build(Self::def(def), cx).map(|built| Arc::new(built) as Built)
    }

    fn spawn(&self, def: &dyn KindDef, built: &Built, entity: &mut EntityWorldMut) {
        let built = built.downcast_ref().expect("a kind's build is spawned by the same kind");
        K::spawn(Self::def(def), built, entity);
    }

    fn saved(&self, def: &dyn KindDef) -> Box<dyn KindDef> {
        Box::new(K::saved(Self::def(def)))
    }

    fn save_live(&self, def: &mut dyn KindDef, entity: EntityRef) {
        let def = def.as_any_mut().downcast_mut().expect("the registry holds each definition with its own kind");
        K::save_live(def, entity);
    }
}

/// The kinds being listed, before [`Kinds::build`] makes them a [`KindRegistry`].
pub struct Kinds<L> {
    kinds: Vec<Box<dyn ErasedKind>>,
    list: PhantomData<L>,
}

impl Kinds<()> {
    /// No kinds yet.
    pub fn new() -> Self {
        Self { kinds: Vec::new(), list: PhantomData }
    }
}

impl Default for Kinds<()> {
    fn default() -> Self {
        Self::new()
    }
}

impl<L: KindList> Kinds<L> {
    /// Adds kind `K` after the kinds listed so far.
    pub fn with<K: EntityKind>(mut self) -> Kinds<Then<L, K>> {
        assert!(self.kinds.iter().all(|kind| kind.key() != K::KEY), "two entity kinds have the key `{}`", K::KEY);
        self.kinds.push(Box::new(Erased::<K>(PhantomData)));
        Kinds { kinds: self.kinds, list: PhantomData }
    }

    /// The registry of the kinds listed.
    pub fn build(self) -> KindRegistry {
        KindRegistry {
            kinds: self.kinds,
            keys: L::keys(),
            read: |path, bytes| parse_yaml::<SceneFile<L>>(path, bytes, "a scene").map(SceneDef::from),
            write: |scene| serde_yaml::to_string(&WriteScene::<L>(scene, PhantomData)),
        }
    }
}

/// A file a scene refers to, as read from disk or through the asset server.
#[derive(Debug, Clone)]
pub struct ReadFile {
    /// The file as the scene names it, relative to its folder.
    pub file: String,
    /// Its path as messages show it.
    pub path: PathBuf,
    /// Its bytes.
    pub contents: Vec<u8>,
}

/// A checked scene: its definition, and what each entity's kind built from it.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// The scene as the file describes it, referenced files filled in.
    pub def: SceneDef,
    /// What each entity's kind built, in entity order.
    pub built: Vec<Built>,
}

/// Every entity kind the app knows; reading, checking, spawning and saving scenes go through
/// it.
pub struct KindRegistry {
    kinds: Vec<Box<dyn ErasedKind>>,
    keys: Vec<&'static str>,
    read: fn(&Path, &[u8]) -> Result<SceneDef, FileError>,
    write: fn(&SceneDef) -> Result<String, serde_yaml::Error>,
}

impl std::fmt::Debug for KindRegistry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KindRegistry").field("keys", &self.keys).finish()
    }
}

impl KindRegistry {
    /// Every kind's key, in registration order.
    pub fn keys(&self) -> &[&'static str] {
        &self.keys
    }

    /// `group` with every kind's plugin added, in registration order.
    pub fn add_plugins(&self, group: PluginGroupBuilder) -> PluginGroupBuilder {
        self.kinds.iter().fold(group, |group, kind| kind.add_plugin(group))
    }

    /// The kind with `key`; `None` for a definition made in code with a key no kind has.
    fn kind(&self, key: &str) -> Option<&dyn ErasedKind> {
        self.kinds.iter().find(|kind| kind.key() == key).map(Box::as_ref)
    }

    /// The kind of the file's entity `index`, or an error naming it.
    fn kind_of(&self, entity: &EntityDef, index: usize, path: &Path) -> Result<&dyn ErasedKind, FileError> {
        self.kind(entity.key).ok_or_else(|| {
            let message =
                format!("entities[{index}]: no entity kind `{}` (kinds: {})", entity.key, self.keys.join(", "));
            FileError::whole_file(path, message)
        })
    }

    /// Reads and checks a scene file, and the files it refers to.
    pub fn load(&self, path: &Path) -> Result<LoadedScene, FileError> {
        let bytes = std::fs::read(path).map_err(|error| FileError::unreadable(path, error))?;
        self.parse(path, &bytes)
    }

    /// Parses and checks scene text read from `path`, reading referenced files next to it.
    pub fn parse(&self, path: &Path, bytes: &[u8]) -> Result<LoadedScene, FileError> {
        let scene = self.parse_unresolved(path, bytes)?;
        let folder = path.parent().unwrap_or(Path::new(""));
        let files = self
            .references(&scene)
            .into_iter()
            .map(|file| {
                let path = folder.join(&file);
                let contents = std::fs::read(&path).map_err(|error| FileError::unreadable(&path, error))?;
                Ok(ReadFile { file, path, contents })
            })
            .collect::<Result<Vec<_>, FileError>>()?;
        self.finish(scene, path, bytes, &files)
    }

    /// Parses scene text read from `path`, leaving references to other files unread; the
    /// result still needs [`Self::finish`] with the files of [`Self::references`].
    ///
    /// A file a kind claims as its own configuration (see
    /// [`EntityKind::standalone`]) is a scene holding that one entity.
    pub fn parse_unresolved(&self, path: &Path, bytes: &[u8]) -> Result<SceneDef, FileError> {
        for kind in &self.kinds {
            if let Some(standalone) = kind.standalone(path, bytes) {
                return Ok(SceneDef::of_standalone(kind.key(), standalone?));
            }
        }
        let scene = (self.read)(path, bytes)?;
        let text = String::from_utf8_lossy(bytes);
        for ((index, entity), kind_index) in scene.entities.iter().enumerate().zip(scene.kind_indices()) {
            let cx = EntityContext { path, text: &text, index, kind_index, key: entity.key };
            self.kind_of(entity, index, path)?.validate(&*entity.def, &cx)?;
        }
        Ok(scene)
    }

    /// The files `scene` refers to, relative to its folder, each once, sorted.
    pub fn references(&self, scene: &SceneDef) -> Vec<String> {
        let mut files: Vec<String> = scene
            .entities
            .iter()
            .flat_map(|entity| self.kind(entity.key).map(|kind| kind.references(&*entity.def)))
            .flatten()
            .collect();
        files.sort();
        files.dedup();
        files
    }

    /// Fills `scene` from the referenced `files` (each shared by every entity naming it),
    /// then checks and builds every entity, kind by kind in registration order.
    pub fn finish(
        &self,
        mut scene: SceneDef,
        path: &Path,
        bytes: &[u8],
        files: &[ReadFile],
    ) -> Result<LoadedScene, FileError> {
        let text = String::from_utf8_lossy(bytes);
        let kinds = scene
            .entities
            .iter()
            .enumerate()
            .map(|(index, entity)| self.kind_of(entity, index, path))
            .collect::<Result<Vec<_>, _>>()?;
        let kind_indices = scene.kind_indices();
        for file in files {
            let mut decoded: HashMap<TypeId, Arc<dyn Any + Send + Sync>> = HashMap::new();
            for (index, entity) in scene.entities.iter_mut().enumerate() {
                let kind = kinds[index];
                if !kind.references(&*entity.def).contains(&file.file) {
                    continue;
                }
                let cx = EntityContext { path, text: &text, index, kind_index: kind_indices[index], key: entity.key };
                let mut referenced = ReferencedFile::new(&file.file, &file.path, &file.contents, &mut decoded);
                kind.resolve(&mut *entity.def, &mut referenced, &cx)?;
            }
        }
        scene.check_view(path, &text)?;
        let mut built: Vec<Option<Built>> = vec![None; scene.entities.len()];
        for kind in &self.kinds {
            // What the kinds before this one built, as every entity of this kind sees it.
            let records: Vec<EntityRecord> = scene
                .entities
                .iter()
                .zip(&built)
                .map(|(entity, built)| EntityRecord {
                    name: entity.name.as_deref(),
                    key: entity.key,
                    def: &*entity.def,
                    built: built.as_deref(),
                })
                .collect();
            let shared = SharedBuilds::default();
            let mut made = Vec::new();
            for (index, entity) in scene.entities.iter().enumerate().filter(|(_, e)| e.key == kind.key()) {
                let cx = BuildContext {
                    entity: EntityContext {
                        path,
                        text: &text,
                        index,
                        kind_index: kind_indices[index],
                        key: entity.key,
                    },
                    entities: &records,
                    shared: &shared,
                };
                made.push((index, kind.build(&*entity.def, &cx)?));
            }
            for (index, result) in made {
                built[index] = Some(result);
            }
        }
        scene.check_names(path, &text)?;
        let built = built.into_iter().map(|b| b.expect("every entity's kind is registered")).collect();
        Ok(LoadedScene { def: scene, built })
    }

    /// The scene as YAML text, as a file holds it: what came from referenced files stays a
    /// reference.
    pub fn to_yaml(&self, scene: &SceneDef) -> Result<String, serde_yaml::Error> {
        let mut scene = scene.clone();
        for entity in &mut scene.entities {
            if let Some(kind) = self.kind(entity.key) {
                entity.def = kind.saved(&*entity.def);
            }
        }
        let text = (self.write)(&scene)?;
        Ok(format!("# Saved by Canopy; the scene format is described in docs/scenes.md.\n{text}"))
    }

    /// Inserts the components of `entity`, a scene entity of `def`'s kind.
    pub fn spawn(&self, def: &EntityDef, built: &Built, entity: &mut EntityWorldMut) {
        match self.kind(def.key) {
            Some(kind) => kind.spawn(&*def.def, built, entity),
            None => bevy::log::error!("entity `{}` not spawned: no entity kind `{}`", def.display_name(), def.key),
        }
    }

    /// Brings `def` up to date with the live `entity` it was spawned as.
    pub fn save_live(&self, def: &mut EntityDef, entity: EntityRef) {
        if let Some(kind) = self.kind(def.key) {
            kind.save_live(&mut *def.def, entity);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_definition_of_no_registered_kind_is_an_error_not_a_panic() {
        let kinds = Kinds::new().build();
        let path = Path::new("code.yaml");
        let mut scene = kinds.parse_unresolved(path, b"entities: []\n").unwrap();
        scene.entities.push(EntityDef { name: None, key: "comet", def: Box::new(String::from("tail")) });
        let error = kinds.finish(scene.clone(), path, b"", &[]).unwrap_err();
        assert!(error.message.contains("entities[0]: no entity kind `comet`"), "{error}");
        assert!(kinds.to_yaml(&scene).is_err());
        assert!(kinds.references(&scene).is_empty());
    }

    #[test]
    fn an_empty_registry_reads_a_scene_without_entities_and_refuses_any_kind() {
        let kinds = Kinds::new().build();
        assert!(kinds.keys().is_empty());
        let error = kinds.parse(Path::new("s.yaml"), b"entities:\n  - shape: { primitive: box }\n").unwrap_err();
        assert!(error.message.contains("unknown field `shape`, expected `name`"), "{error}");
    }
}
