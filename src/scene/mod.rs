//! Scenes: YAML files loaded through Bevy's asset system (so they hot-reload), checked with
//! errors that name the file, line, column and field, and spawned as ECS entities.
//!
//! | module | what it holds |
//! |---|---|
//! | [`schema`] | the file format: camera, light, background, entities and their kinds |
//! | [`values`] | checked numbers, points, sizes and colours |
//!
//! The scene file is served by its own asset source, [`SCENE_SOURCE`], rooted at the file's
//! folder, so any file on disk can be played and watched. A (re)load that fails keeps the
//! last good scene running and records the error in [`ActiveScene`].

pub mod schema;
pub mod values;

use crate::controls::ReloadScene;
use crate::muscle::spawn_muscle;
use crate::raster::RenderParams;
use crate::schedule::{ControlSystems, SimClock, SimControl};
use crate::shape::{PrimitiveMeshes, spawn_shape};
use crate::sloth::spawn_sloth;
use crate::tree::{TreeSource, spawn_tree};
use crate::view::{Background, CameraParams, LightParams};
use crate::yaml::FileError;
use bevy::asset::io::{AssetSourceBuilder, Reader};
use bevy::asset::{AssetLoadFailedEvent, AssetLoader, LoadContext};
use bevy::prelude::*;
use schema::{EntityKind, SceneDef};
use std::path::{Path, PathBuf};

pub use schema::EntityDef;

/// The asset source that serves the folder of the scene being played.
pub const SCENE_SOURCE: &str = "scene";

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

/// A loaded scene file.
#[derive(Asset, TypePath, Debug, Clone)]
pub struct SceneAsset(pub SceneDef);

/// Loads `.yaml` / `.yml` scene files.
#[derive(Default, TypePath)]
pub struct SceneLoader;

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
        let mut scene = SceneDef::parse_unresolved(&path, &bytes)?;
        let folder = path.parent().unwrap_or(Path::new(""));
        for file in scene.references() {
            let referenced = folder.join(&file);
            // Read through the asset server, so that editing the referenced file reloads too.
            let asset_path = format!("{SCENE_SOURCE}://{}", referenced.to_string_lossy());
            let contents = load_context
                .read_asset_bytes(asset_path)
                .await
                .map_err(|error| FileError::unreadable(&referenced, error))?;
            scene.resolve(&file, &referenced, &contents)?;
        }
        scene.check(&path, &String::from_utf8_lossy(&bytes))?;
        Ok(SceneAsset(scene))
    }

    fn extensions(&self) -> &[&str] {
        &["yaml", "yml"]
    }
}

/// Identifies a spawned scene entity: its place in the file, its name and its kind.
#[derive(Component, Debug, Clone, PartialEq, Eq)]
pub struct SceneEntity {
    /// Order in the scene: the camera, the light, the render settings, then the file's entities.
    pub index: usize,
    /// The name parameters and dumps use.
    pub name: String,
    /// The kind (`camera`, `light`, `shape`, ...).
    pub kind: &'static str,
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

/// Loads, watches and spawns the scene file at `path`.
pub struct ScenePlugin {
    /// The scene file.
    pub path: PathBuf,
}

impl Plugin for ScenePlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<SceneAsset>()
            .init_asset_loader::<SceneLoader>()
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
    meshes: Res<PrimitiveMeshes>,
    existing: Query<Entity, With<SceneEntity>>,
    mut scene: ResMut<ActiveScene>,
    mut control: ResMut<SimControl>,
    mut clock: ResMut<SimClock>,
) {
    let id = scene.handle.id();
    if failed.read().any(|event| event.id == id) {
        // Read the file again to report its error against the path the user gave.
        let message = match SceneDef::load(&scene.path) {
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
    let Some(SceneAsset(def)) = changed.then(|| assets.get(id)).flatten() else {
        return;
    };
    for entity in &existing {
        commands.entity(entity).despawn();
    }
    spawn_scene(&mut commands, def, &meshes);
    commands.insert_resource(Background(def.background.0));
    scene.kinds = def.entities.iter().map(|e| e.kind.key()).collect();
    scene.kinds.dedup();
    scene.status = SceneStatus::Live;
    scene.error = None;
    scene.generation += 1;
    *clock = SimClock::default();
    control.live = true;
    info!("scene {} loaded ({} entities)", scene.path.display(), def.entities.len());
}

/// Writes `scene` to `path`. An existing file there is first copied to the first free
/// `<path>.<n>.bak`, whose path is returned: nothing the user wrote is lost, comments included.
pub fn save_scene(scene: &SceneDef, path: &Path) -> std::io::Result<Option<PathBuf>> {
    let text = scene.to_yaml().map_err(std::io::Error::other)?;
    let backup = if path.exists() {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let backup = (1..)
            .map(|n| path.with_file_name(format!("{name}.{n}.bak")))
            .find(|candidate| !candidate.exists())
            .expect("an unbounded range always yields a free name");
        std::fs::copy(path, &backup)?;
        Some(backup)
    } else {
        None
    };
    std::fs::write(path, text)?;
    Ok(backup)
}

/// Saves the playing scene to its file (see [`save_scene`]), with its trees as edited in the
/// window. Returns the file and the backup of its previous contents.
pub fn save_live_scene(world: &mut World) -> Result<(PathBuf, Option<PathBuf>), String> {
    let active = world.resource::<ActiveScene>();
    let path = active.path.clone();
    let handle = active.handle.clone();
    let mut def = world.resource::<Assets<SceneAsset>>().get(&handle).ok_or("no scene is loaded")?.0.clone();
    let mut trees = world.query::<(&SceneEntity, &TreeSource)>();
    for (scene_entity, source) in trees.iter(world) {
        let entity = scene_entity.index.checked_sub(FIRST_FILE_ENTITY).and_then(|index| def.entities.get_mut(index));
        if let Some(entity) = entity
            && matches!(entity.kind, EntityKind::Tree(_))
        {
            entity.kind = EntityKind::Tree(source.def.clone());
        }
    }
    let backup = save_scene(&def, &path).map_err(|error| format!("{}: {error}", path.display()))?;
    Ok((path, backup))
}

/// The [`SceneEntity::index`] of the file's first entity: the camera, the light and the render
/// settings come before it.
pub const FIRST_FILE_ENTITY: usize = 3;

/// Spawns the camera, the light, the render settings and every entity of `def`.
pub fn spawn_scene(commands: &mut Commands, def: &SceneDef, meshes: &PrimitiveMeshes) {
    let scene_entity = |index: usize, name: &str, kind: &'static str| {
        (SceneEntity { index, name: name.to_string(), kind }, Name::new(name.to_string()))
    };
    commands.spawn((scene_entity(0, "camera", "camera"), CameraParams::from(&def.camera)));
    commands.spawn((scene_entity(1, "light", "light"), LightParams::from(&def.light)));
    commands.spawn((scene_entity(2, "render", "render"), RenderParams::from(&def.render)));
    for (index, entity_def) in def.entities.iter().enumerate() {
        let mut entity =
            commands.spawn(scene_entity(FIRST_FILE_ENTITY + index, entity_def.display_name(), entity_def.kind.key()));
        match &entity_def.kind {
            EntityKind::Shape(shape) => spawn_shape(&mut entity, shape, meshes),
            EntityKind::Muscle(muscle) => spawn_muscle(&mut entity, muscle, meshes),
            EntityKind::Tree(tree) => spawn_tree(&mut entity, tree),
            EntityKind::Sloth(sloth) => spawn_sloth(&mut entity, sloth),
        }
    }
}
