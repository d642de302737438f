//! Scenes: YAML files loaded through Bevy's asset system (so they hot-reload), checked with
//! errors that name the file, line, column and field, spawned as ECS entities and saved
//! back, all through the [`KindRegistry`] of entity kinds.
//!
//! | module | what it holds |
//! |---|---|
//! | [`schema`] | the file format: camera, light, background, render settings, the entity list |
//! | [`kinds`] | the registry of entity kinds: reading, checking, building, spawning, saving |
//! | [`kind_list`] | the registry's kinds as a list of types, for serde to read and write each definition |
//!
//! The scene file is served by its own asset source, [`SCENE_SOURCE`], rooted at the file's
//! folder, so any file on disk can be played and watched. A (re)load that fails keeps the
//! last good scene running and records the error in [`ActiveScene`].

pub mod kind_list;
pub mod kinds;
pub mod schema;

use crate::foundation::entity::SceneEntity;
use crate::foundation::messages::ReloadScene;
use crate::foundation::schedule::{ControlSystems, SimClock, SimControl};
use crate::foundation::values::first_free_path;
use crate::foundation::yaml::FileError;
use bevy::asset::io::{AssetSourceBuilder, Reader};
use bevy::asset::{AssetLoadFailedEvent, AssetLoader, LoadContext};
use bevy::prelude::*;
use kinds::{KindRegistry, LoadedScene, ReadFile};
use schema::Background;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The asset source that serves the folder of the scene being played.
pub const SCENE_SOURCE: &str = "scene";

/// The [`SceneEntity::index`] of the file's first entity: the camera, the light and the render
/// settings come before it.
pub const FIRST_FILE_ENTITY: usize = 3;

/// Registers [`SCENE_SOURCE`] at the folder of `scene_file`. Must be called before Bevy's
/// `AssetPlugin` is added.
pub fn register_scene_source(app: &mut App, scene_file: &Path) -> std::io::Result<()> {
    let folder = std::fs::canonicalize(scene_file)?
        .parent()
        .map(Path::to_path_buf)
        .ok_or_else(|| std::io::Error::other("the scene file has no folder"))?;
    app.register_asset_source(SCENE_SOURCE, AssetSourceBuilder::platform_default(&folder.to_string_lossy(), None));
    Ok(())
}

/// A loaded and checked scene file.
#[derive(Asset, TypePath, Debug, Clone)]
pub struct SceneAsset(pub Arc<LoadedScene>);

/// The kinds the app knows, shared by the loader and the systems.
#[derive(Resource, Debug, Clone)]
pub struct SceneKinds(pub Arc<KindRegistry>);

/// Loads `.yaml` / `.yml` scene files.
#[derive(TypePath)]
pub struct SceneLoader {
    kinds: Arc<KindRegistry>,
    /// The played scene's folder as the user named it: the scene is checked and built under
    /// its path there, so that messages show that path and kinds that read folders (camera
    /// frames) find them.
    folder: PathBuf,
}

impl AssetLoader for SceneLoader {
    type Asset = SceneAsset;
    type Settings = ();
    type Error = FileError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<SceneAsset, FileError> {
        let path = load_context.path().path().to_path_buf();
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await.map_err(|error| FileError::unreadable(&path, error))?;
        let kinds = &self.kinds;
        let scene = kinds.parse_unresolved(&path, &bytes)?;
        let folder = path.parent().unwrap_or(Path::new(""));
        let mut files = Vec::new();
        for file in kinds.references(&scene) {
            let referenced = folder.join(&file);
            // Read through the asset server, so that editing the referenced file reloads too.
            let asset_path = format!("{SCENE_SOURCE}://{}", referenced.to_string_lossy());
            let contents = load_context
                .read_asset_bytes(asset_path)
                .await
                .map_err(|error| FileError::unreadable(&self.folder.join(&referenced), error))?;
            // Its path as the user would name it, for messages and for the files it refers to
            // in turn (a glTF file's buffers and images).
            files.push(ReadFile { file, path: self.folder.join(&referenced), contents });
        }
        Ok(SceneAsset(Arc::new(kinds.finish(scene, &self.folder.join(&path), &bytes, &files)?)))
    }

    fn extensions(&self) -> &[&str] {
        &["yaml", "yml"]
    }
}

/// Where the played scene is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneStatus {
    /// The first load has not finished.
    Loading,
    /// A scene is spawned and running.
    Live,
    /// The first load failed; nothing is spawned.
    Failed,
}

/// The scene being played.
#[derive(Resource, Debug)]
pub struct ActiveScene {
    /// The file as the user named it.
    pub path: PathBuf,
    /// Where the scene is in its life.
    pub status: SceneStatus,
    /// The last load error; while the status is [`SceneStatus::Live`] this is a failed
    /// reload and the previous scene keeps running.
    pub error: Option<String>,
    /// How many times the scene has been spawned.
    pub generation: u32,
    /// The entity kinds in the scene, for the key help.
    pub kinds: Vec<&'static str>,
    handle: Handle<SceneAsset>,
}

impl ActiveScene {
    fn asset_path(&self) -> String {
        let file = self.path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
        format!("{SCENE_SOURCE}://{file}")
    }
}

/// Loads, watches and spawns the scene file at `path` with the entity kinds of `kinds`.
pub struct ScenePlugin {
    /// The scene file.
    pub path: PathBuf,
    /// The entity kinds.
    pub kinds: Arc<KindRegistry>,
}

impl Plugin for ScenePlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<SceneAsset>()
            .register_asset_loader(SceneLoader {
                kinds: self.kinds.clone(),
                folder: self.path.parent().map(Path::to_path_buf).unwrap_or_default(),
            })
            .insert_resource(SceneKinds(self.kinds.clone()))
            .init_resource::<Background>()
            .insert_resource(ActiveScene {
                path: self.path.clone(),
                status: SceneStatus::Loading,
                error: None,
                generation: 0,
                kinds: Vec::new(),
                handle: Handle::default(),
            })
            .add_systems(Startup, start_loading)
            .add_systems(Update, (reload_on_request, track_scene_asset).chain().in_set(ControlSystems::Load));
    }
}

fn start_loading(server: Res<AssetServer>, mut scene: ResMut<ActiveScene>) {
    scene.handle = server.load(scene.asset_path());
}

fn reload_on_request(mut requests: MessageReader<ReloadScene>, server: Res<AssetServer>, scene: Res<ActiveScene>) {
    if requests.read().count() > 0 {
        info!("reloading {}", scene.path.display());
        server.reload(scene.asset_path());
    }
}

/// Spawns the scene when its asset (re)loads, and records failures.
#[allow(clippy::too_many_arguments)]
fn track_scene_asset(
    mut commands: Commands,
    mut loaded: MessageReader<AssetEvent<SceneAsset>>,
    mut failed: MessageReader<AssetLoadFailedEvent<SceneAsset>>,
    assets: Res<Assets<SceneAsset>>,
    kinds: Res<SceneKinds>,
    mut scene: ResMut<ActiveScene>,
    mut control: ResMut<SimControl>,
    mut clock: ResMut<SimClock>,
) {
    let id = scene.handle.id();
    if failed.read().any(|event| event.id == id) {
        // Read the file again to report its error against the path the user gave.
        let message = match kinds.0.load(&scene.path) {
            Err(error) => error.to_string(),
            Ok(_) => format!("{}: the scene changed while it was loading; press F5 to reload", scene.path.display()),
        };
        error!("{message}");
        scene.error = Some(message);
        if scene.status == SceneStatus::Loading {
            scene.status = SceneStatus::Failed;
        }
    }
    // Sent once per successful load, the first and every reload alike.
    let changed = loaded.read().any(|event| event.is_loaded_with_dependencies(id));
    let Some(SceneAsset(loaded)) = changed.then(|| assets.get(id)).flatten() else {
        return;
    };
    let def = &loaded.def;
    scene.kinds = def.entities.iter().map(|e| e.key).collect();
    scene.kinds.dedup();
    scene.status = SceneStatus::Live;
    scene.error = None;
    scene.generation += 1;
    *clock = SimClock::default();
    control.live = true;
    info!("scene {} loaded ({} entities)", scene.path.display(), def.entities.len());
    let (loaded, kinds) = (loaded.clone(), kinds.0.clone());
    commands.queue(move |world: &mut World| respawn_scene(world, &loaded, &kinds));
}

/// Replaces every scene entity with those of `scene`: the camera, the light and the render
/// settings (their sections as components, which their plugins complete), then each entity
/// by its kind.
pub fn respawn_scene(world: &mut World, scene: &LoadedScene, kinds: &KindRegistry) {
    let existing: Vec<Entity> = world.query_filtered::<Entity, With<SceneEntity>>().iter(world).collect();
    for entity in existing {
        world.despawn(entity);
    }
    let def = &scene.def;
    let scene_entity = |index: usize, name: &str, kind: &'static str| {
        (SceneEntity { index, name: name.to_string(), kind }, Name::new(name.to_string()))
    };
    world.spawn((scene_entity(0, "camera", "camera"), def.camera));
    world.spawn((scene_entity(1, "light", "light"), def.light));
    world.spawn((scene_entity(2, "render", "render"), def.render));
    for (index, (entity_def, built)) in def.entities.iter().zip(&scene.built).enumerate() {
        let mut entity =
            world.spawn(scene_entity(FIRST_FILE_ENTITY + index, entity_def.display_name(), entity_def.key));
        kinds.spawn(entity_def, built, &mut entity);
    }
    world.insert_resource(Background(def.background.0));
}

/// Writes `scene` to `path`. An existing file there is first copied to the first free
/// `<path>.<n>.bak`, whose path is returned: nothing the user wrote is lost, comments included.
pub fn save_scene(kinds: &KindRegistry, scene: &schema::SceneDef, path: &Path) -> std::io::Result<Option<PathBuf>> {
    let text = kinds.to_yaml(scene).map_err(std::io::Error::other)?;
    let backup = if path.exists() {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let backup = first_free_path(|n| path.with_file_name(format!("{name}.{n}.bak")));
        std::fs::copy(path, &backup)?;
        Some(backup)
    } else {
        None
    };
    std::fs::write(path, text)?;
    Ok(backup)
}

/// Saves the playing scene to its file (see [`save_scene`]), with what the user changed in
/// its entities (the trees as edited in the window). Returns the file and the backup of its
/// previous contents.
pub fn save_live_scene(world: &mut World) -> Result<(PathBuf, Option<PathBuf>), String> {
    let active = world.resource::<ActiveScene>();
    let path = active.path.clone();
    let handle = active.handle.clone();
    let kinds = world.resource::<SceneKinds>().0.clone();
    let mut def = world.resource::<Assets<SceneAsset>>().get(&handle).ok_or("no scene is loaded")?.0.def.clone();
    let mut entities = world.query::<(EntityRef, &SceneEntity)>();
    for (entity, scene_entity) in entities.iter(world) {
        let index = scene_entity.index.checked_sub(FIRST_FILE_ENTITY);
        if let Some(entity_def) = index.and_then(|index| def.entities.get_mut(index))
            && entity_def.key == scene_entity.kind
        {
            kinds.save_live(entity_def, entity);
        }
    }
    let backup = save_scene(&kinds, &def, &path).map_err(|error| format!("{}: {error}", path.display()))?;
    Ok((path, backup))
}
