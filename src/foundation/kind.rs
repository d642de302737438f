//! Entity kinds: the one trait through which a kind of scene entity plugs into loading,
//! checking, spawning, saving and the app.
//!
//! A kind is a type implementing [`EntityKind`]: its key in the file, its definition (a serde
//! type whose values are checked as they are read), the files it refers to, its checks with
//! located errors, what checking it builds, how it spawns, and the plugin that runs it. The
//! scene layer keeps a registry of kinds and goes through it for every entity; nothing below
//! the domains names a kind.
//!
//! Loading runs these hooks, in this order:
//!
//! | step | hook | what it may see |
//! |---|---|---|
//! | parse | [`EntityKind::standalone`], then serde on [`EntityKind::Def`] | the file's bytes |
//! | validate | [`EntityKind::validate`] | the entity's own definition |
//! | read files | [`EntityKind::references`], [`EntityKind::resolve`] | each referenced file, read once |
//! | build | [`EntityKind::build`] | every definition, and what the kinds registered earlier built |
//! | spawn | [`EntityKind::spawn`] | its definition, what its build made, the world |
//! | save | [`EntityKind::saved`], [`EntityKind::save_live`] | the definition, the live entity |
//!
//! Beside its plugin, a kind registers its panel section, keys and actions under its own type
//! in [`EntityKind::register`].

use crate::foundation::yaml::{FileError, locate_key, locate_key_after};
use bevy::app::{App, Plugin};
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::math::Vec3;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::any::{Any, TypeId};
use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt::Debug;
use std::path::Path;
use std::sync::Arc;

/// A kind of scene entity: everything the scene layer needs to read, check, spawn and save
/// it, and the plugin that makes it live.
pub trait EntityKind: 'static {
    /// The key of an entity mapping that holds this kind; also the kind's name in dumps,
    /// parameters and key help.
    const KEY: &'static str;
    /// The kind's part of the scene file; values are checked while they are read, so that
    /// errors point at them.
    type Def: DeserializeOwned + Serialize + Clone + Debug + PartialEq + Send + Sync + 'static;
    /// What [`Self::build`] makes of a definition, kept with the loaded scene for
    /// [`Self::spawn`] and for the checks of kinds registered later.
    type Built: Send + Sync + 'static;
    /// The plugin that runs entities of this kind.
    type Plugin: Plugin + Default;

    /// A file that is this kind's own configuration and no scene: read as a scene holding one
    /// such entity, seen from `view`. `None` for a file this kind does not claim.
    fn standalone(_path: &Path, _bytes: &[u8]) -> Option<Result<Standalone<Self::Def>, FileError>> {
        None
    }

    /// Checks of the definition alone, before any referenced file is read.
    fn validate(_def: &Self::Def, _cx: &EntityContext) -> Result<(), FileError> {
        Ok(())
    }

    /// The files the definition refers to, relative to the scene's folder.
    fn references(_def: &Self::Def) -> Vec<String> {
        Vec::new()
    }

    /// Takes what the definition needs from `file`, one of its [`Self::references`].
    fn resolve(_def: &mut Self::Def, _file: &mut ReferencedFile, _cx: &EntityContext) -> Result<(), FileError> {
        Ok(())
    }

    /// Builds what the definition describes, with every check that spans several fields or
    /// entities; errors are located through `cx`.
    fn build(def: &Self::Def, cx: &BuildContext) -> Result<Self::Built, FileError>;

    /// Inserts the entity's components (it already holds its
    /// [`SceneEntity`](crate::foundation::entity::SceneEntity) and `Name`).
    fn spawn(def: &Self::Def, built: &Self::Built, entity: &mut EntityWorldMut);

    /// The definition as a saved file holds it: what was read from referenced files stays a
    /// reference.
    fn saved(def: &Self::Def) -> Self::Def {
        def.clone()
    }

    /// Brings the definition up to date with what the user changed in the live `entity`
    /// before the scene is saved.
    fn save_live(_def: &mut Self::Def, _entity: EntityRef) {}

    /// Registers what the app offers for this kind's entities under the kind itself, after
    /// [`Self::Plugin`] is added: its panel section, its keys, the actions timelines may ask of
    /// it. Done here rather than in the plugin so that the plugin never names its own kind.
    fn register(_app: &mut App) {}
}

/// A kind's configuration file read as a scene: the one entity and where to look at it from.
#[derive(Debug, Clone, PartialEq)]
pub struct Standalone<D> {
    /// The entity's definition.
    pub def: D,
    /// The camera that frames it.
    pub view: ViewPoint,
}

/// Where a camera stands and looks, in metres, and its vertical field of view in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewPoint {
    /// The eye, metres.
    pub position: Vec3,
    /// The point looked at, metres.
    pub look_at: Vec3,
    /// Vertical field of view, degrees.
    pub fov_deg: f32,
}

/// A kind's definition as the scene holds it, whatever its type.
pub trait KindDef: Any + Debug + Send + Sync {
    /// A boxed copy.
    fn clone_def(&self) -> Box<dyn KindDef>;
    /// Whether `other` is a definition of the same type and equal.
    fn eq_def(&self, other: &dyn KindDef) -> bool;
    /// For downcasting to the kind's definition type.
    fn as_any(&self) -> &dyn Any;
    /// For downcasting to the kind's definition type.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// Every kind's definition type is a [`KindDef`]; the `Serialize` bound keeps a boxed
/// definition from being one itself, so that method calls on a box reach the definition.
impl<T: Any + Debug + Clone + PartialEq + Serialize + Send + Sync> KindDef for T {
    fn clone_def(&self) -> Box<dyn KindDef> {
        Box::new(self.clone())
    }

    fn eq_def(&self, other: &dyn KindDef) -> bool {
        other.as_any().downcast_ref::<T>() == Some(self)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

impl Clone for Box<dyn KindDef> {
    fn clone(&self) -> Self {
        (**self).clone_def()
    }
}

/// What a kind's build made, whatever its type.
pub type Built = Arc<dyn Any + Send + Sync>;

/// Where an entity stands in its scene file, for locating its errors.
#[derive(Debug, Clone, Copy)]
pub struct EntityContext<'a> {
    /// The scene file, as the user named it.
    pub path: &'a Path,
    /// The scene file's text.
    pub text: &'a str,
    /// The entity's place among the file's entities, from 0.
    pub index: usize,
    /// The entity's place among the file's entities of its kind, from 0.
    pub kind_index: usize,
    /// The entity's kind key.
    pub key: &'static str,
}

impl EntityContext<'_> {
    /// The field path of this entity's `field` in messages: `entities[2].tree.sides`.
    pub fn field(&self, field: &str) -> String {
        format!("entities[{}].{}.{field}", self.index, self.key)
    }

    /// An error at the `nth` (from 0) occurrence of mapping key `key` in the scene file, or
    /// about the whole file when the key cannot be found.
    pub fn locate(&self, key: &str, nth: usize, message: String) -> FileError {
        locate_key(self.path, self.text, key, nth, message)
    }

    /// An error at the `nth` (from 0) occurrence of mapping key `key` from this entity's entry
    /// on (its kind key, the `kind_index`-th in the file).
    pub fn locate_within(&self, key: &str, nth: usize, message: String) -> FileError {
        locate_key_after(self.path, self.text, (self.key, self.kind_index), key, nth, message)
    }

    /// An error about `field` (a path below the entity's kind key) found at the `nth`
    /// occurrence of `key` within this entity's entry: `<field path>: <message>` at its line.
    pub fn field_error(&self, key: &str, nth: usize, field: &str, message: impl std::fmt::Display) -> FileError {
        self.locate_within(key, nth, format!("{}: {message}", self.field(field)))
    }

    /// An error about the scene file as a whole.
    pub fn whole_file(&self, message: String) -> FileError {
        FileError::whole_file(self.path, message)
    }
}

/// One entity of the scene as the build step sees it.
#[derive(Debug, Clone, Copy)]
pub struct EntityRecord<'a> {
    /// The name given in the file, if any.
    pub name: Option<&'a str>,
    /// The kind key.
    pub key: &'static str,
    /// The definition.
    pub def: &'a dyn KindDef,
    /// What its build made, once its kind has been built.
    pub built: Option<&'a (dyn Any + Send + Sync)>,
}

impl EntityRecord<'_> {
    /// The name parameters and dumps use: the given name, else the kind.
    pub fn display_name(&self) -> &str {
        self.name.unwrap_or(self.key)
    }
}

/// What the entities of one kind derive alike while they are built (the sloths' view of all
/// the trees, say), made for the first that asks and shared by the others of that load.
#[derive(Debug, Default)]
pub struct SharedBuilds(RefCell<HashMap<(&'static str, TypeId), Built>>);

/// What [`EntityKind::build`] may see: the entity's place in the file, and every entity of
/// the scene with what the kinds registered before this one built.
#[derive(Debug, Clone, Copy)]
pub struct BuildContext<'a> {
    /// The entity being built.
    pub entity: EntityContext<'a>,
    /// Every entity of the scene, in file order.
    pub entities: &'a [EntityRecord<'a>],
    /// What this load's entities of the kind share.
    pub shared: &'a SharedBuilds,
}

impl<'a> BuildContext<'a> {
    /// The definitions of kind `K` before this entity in the file, in file order.
    pub fn earlier<K: EntityKind>(&self) -> impl Iterator<Item = &'a K::Def> + 'a {
        self.entities[..self.entity.index].iter().filter_map(|record| record.def.as_any().downcast_ref::<K::Def>())
    }

    /// How many entities up to and including this one have a name in the file.
    pub fn names_through(&self) -> usize {
        self.entities[..=self.entity.index].iter().filter(|record| record.name.is_some()).count()
    }

    /// The value of type `T` that this kind's entities share in this load: made by `make`
    /// for the first entity that asks, the same for every later one.
    pub fn shared<T: Send + Sync + 'static>(&self, make: impl FnOnce() -> T) -> Arc<T> {
        let key = (self.entity.key, TypeId::of::<T>());
        if let Some(done) = self.shared.0.borrow().get(&key).and_then(|d| d.clone().downcast::<T>().ok()) {
            return done;
        }
        let value = Arc::new(make());
        self.shared.0.borrow_mut().insert(key, value.clone());
        value
    }

    /// The entities of kind `K` already built, with their display names, in file order.
    pub fn built<K: EntityKind>(&self) -> impl Iterator<Item = (&'a str, &'a K::Built)> + 'a {
        self.entities
            .iter()
            .filter(|record| record.key == K::KEY)
            .filter_map(|record| Some((record.display_name(), record.built?.downcast_ref::<K::Built>()?)))
    }
}

/// A file an entity refers to, read once for every entity that names it.
pub struct ReferencedFile<'a> {
    /// The file as the definition names it, relative to the scene's folder.
    pub file: &'a str,
    /// The file's path as messages show it.
    pub path: &'a Path,
    /// Its bytes.
    pub contents: &'a [u8],
    /// What earlier entities decoded from it.
    decoded: &'a mut HashMap<TypeId, Arc<dyn Any + Send + Sync>>,
}

impl<'a> ReferencedFile<'a> {
    /// A file and the store of what is decoded from it.
    pub fn new(
        file: &'a str,
        path: &'a Path,
        contents: &'a [u8],
        decoded: &'a mut HashMap<TypeId, Arc<dyn Any + Send + Sync>>,
    ) -> Self {
        Self { file, path, contents, decoded }
    }

    /// The file decoded as a `T`: decoded by `decode` for the first entity that asks, shared
    /// with every later one.
    pub fn decoded<T: Send + Sync + 'static, E>(
        &mut self,
        decode: impl FnOnce(&Path, &[u8]) -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        if let Some(done) = self.decoded.get(&TypeId::of::<T>()).and_then(|d| d.clone().downcast::<T>().ok()) {
            return Ok(done);
        }
        let value = Arc::new(decode(self.path, self.contents)?);
        self.decoded.insert(TypeId::of::<T>(), value.clone());
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_value_is_made_once_per_kind_and_type() {
        let shared = SharedBuilds::default();
        let entity = |key| EntityContext { path: Path::new("s.yaml"), text: "", index: 0, kind_index: 0, key };
        let cx = |key| BuildContext { entity: entity(key), entities: &[], shared: &shared };
        let mut made = 0;
        let first = cx("sloth").shared(|| {
            made += 1;
            7u32
        });
        let again = cx("sloth").shared(|| 8u32);
        assert!(Arc::ptr_eq(&first, &again));
        assert_eq!((*again, made), (7, 1));
        assert_eq!(*cx("tree").shared(|| 9u32), 9, "another kind has values of its own");
    }
}
