//! The terrain kind's plugin: its parameters and keys, regeneration of the map on the async
//! compute pool, the section's meshes written back when anything they show changed, its dump
//! and its panel section.

use super::bands::{Band, BandRule};
use super::def::{TerrainBuilt, TerrainDef};
use super::ground::{Ground, placement};
use super::heightmap::Heightmap;
use super::image_io::{self, Encoding};
use super::recipe::{PerlinLayer, Recipe};
use super::section::{Geometry, Section, mesh_section};
use super::surfaces::{TerrainSurface, surface_materials};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, WriteBackSystems};
use crate::foundation::values::{first_free_path, wrap_degrees};
use crate::raster::RasterMesh;
use crate::spatial::SpatialSystems;
use crate::spatial::solid::{Collider, Solid};
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on};
use serde_json::{Map, Value, json};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The visible section as parameters (`<name>.section.x`, ...): whole numbers held as `f32`
/// so that timelines and the panel can set them; they are rounded when applied.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
pub struct SectionParams {
    /// The map sample (along x) at the section's first vertex.
    pub x: f32,
    /// The map sample (along z) at the section's first vertex.
    pub z: f32,
    /// Vertices along x.
    pub width: f32,
    /// Vertices along z.
    pub depth: f32,
}

impl SectionParams {
    /// The section these values name in `map`: rounded, limited to the map.
    pub fn section(&self, map: &Heightmap) -> Section {
        let whole = |v: f32| if v.is_finite() { v.round().clamp(0.0, u32::MAX as f32) as u32 } else { 0 };
        Section { origin: [whole(self.x), whole(self.z)], size: [whole(self.width), whole(self.depth)] }.clamped(map)
    }

    fn of(section: Section) -> Self {
        Self {
            x: section.origin[0] as f32,
            z: section.origin[1] as f32,
            width: section.size[0] as f32,
            depth: section.size[1] as f32,
        }
    }
}

/// The first Perlin layer's parameters and the seed, as parameters: changing them makes the
/// map again (off the main thread).
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
pub struct NoiseParams {
    /// The seed (a whole number of 0 or more).
    pub seed: f64,
    /// Samples per lattice unit of the first octave.
    pub scale: f32,
    /// Octaves (1 to 16, rounded).
    pub octaves: f32,
    /// Frequency multiplier per octave.
    pub lacunarity: f32,
    /// Amplitude multiplier per octave.
    pub persistence: f32,
}

/// The terrain's editable parameters.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct TerrainParams {
    /// The visible section.
    pub section: SectionParams,
    /// Turn about the vertical axis through the section's centre, degrees (the keys keep it in
    /// `[-180, 180)`).
    pub rotation_deg: f32,
    /// Scale along x, y and z about the section's centre.
    pub scale: Vec3,
    /// Where the section's centre stands, metres.
    pub position: Vec3,
    /// Metres of height for a map height of 1.
    pub height_m: f32,
    /// The generator's main parameters (only for generated maps with a Perlin layer).
    pub noise: NoiseParams,
}

impl TerrainParams {
    /// The model transform: the section's centre at `position` (heights above it), turned and
    /// scaled about the centre.
    fn transform(&self, barycentre: Vec3) -> Transform {
        placement(self.position, self.rotation_deg, self.scale, barycentre)
    }
}

/// The live terrain: its map and how it was made, and what its meshes show.
#[derive(Component, Debug)]
pub struct TerrainBody {
    /// The heightmap.
    pub map: Arc<Heightmap>,
    /// The recipe of a generated map; `None` for one read from an image.
    pub recipe: Option<Recipe>,
    /// The seed the map was made with (generated maps).
    pub seed: Option<u64>,
    /// The banding rule.
    pub rule: BandRule,
    /// Metres between samples.
    pub cell_m: f32,
    /// Cells one repetition of a band texture covers.
    pub texture_cells: f32,
    /// The section shown and the height scale its meshes were made with; `None` before the
    /// first meshing or after the map changed.
    pub shown: Option<(Section, f32)>,
    /// Triangles per band in the meshes shown.
    pub counts: [usize; 5],
    /// The section's centre in metres from its first vertex.
    pub barycentre: Vec3,
    /// Wall-clock time the last meshing took (for display only).
    pub mesh_time: Duration,
    /// Wall-clock time the last generation took on its thread (for display only).
    pub generation_time: Duration,
    /// The noise parameters the map was made with.
    generated: NoiseParams,
    /// Whether the map was made again since the scene was loaded.
    regenerated: bool,
    /// A map being made on the async compute pool.
    pending: Option<PendingMap>,
    /// Why the last change could not be made, for the panel.
    pub message: Option<String>,
}

/// A map being generated on the async compute pool: the result is taken a fixed number of
/// frames after the request (waiting for it then if it is late), so that headless runs take
/// it at the same frame every time.
#[derive(Debug)]
struct PendingMap {
    task: Task<(Result<Heightmap, String>, Duration)>,
    /// The recipe being made, its seed the one it is made with.
    recipe: Recipe,
    frames_left: u32,
}

/// Frames between a regeneration request and taking its map in.
const GENERATION_FRAMES: u32 = 3;

/// The first Perlin layer of a recipe, whose parameters the panel and timelines edit.
fn main_layer(recipe: Option<&Recipe>) -> PerlinLayer {
    recipe.and_then(|r| r.layers.iter().find_map(|l| l.perlin)).unwrap_or_default()
}

fn noise_params(recipe: Option<&Recipe>, seed: Option<u64>) -> NoiseParams {
    let layer = main_layer(recipe);
    NoiseParams {
        seed: seed.unwrap_or(0) as f64,
        scale: layer.scale,
        octaves: layer.octaves as f32,
        lacunarity: layer.lacunarity,
        persistence: layer.persistence,
    }
}

/// Spawns a terrain entity of `def` with the map `built` made, and one child per band.
pub(super) fn spawn_terrain(entity: &mut EntityWorldMut, def: &TerrainDef, built: &TerrainBuilt) {
    let recipe = def.height.image.is_none().then(|| def.height.recipe());
    let section = Section { origin: def.section.origin, size: def.section.size }.clamped(&built.map);
    let generated = noise_params(recipe.as_ref(), built.seed);
    let params = TerrainParams {
        section: SectionParams::of(section),
        rotation_deg: def.rotation_deg.0,
        scale: Vec3::from_array(def.scale.map(|f| f.0)),
        position: def.position.0,
        height_m: def.height_m.0,
        noise: generated,
    };
    let body = TerrainBody {
        map: built.map.clone(),
        recipe,
        seed: built.seed,
        rule: def.bands.rule(),
        cell_m: def.cell_m.0,
        texture_cells: def.bands.texture_cells.0,
        shown: None,
        counts: [0; 5],
        barycentre: Vec3::ZERO,
        mesh_time: Duration::ZERO,
        generation_time: Duration::ZERO,
        generated,
        regenerated: false,
        pending: None,
        message: None,
    };
    entity.insert((params.transform(Vec3::ZERO), params, body)).with_children(|children| {
        for (surface, material) in surface_materials(&def.bands) {
            children.spawn((surface, RasterMesh { mesh: Arc::default(), material }));
        }
    });
}

/// Brings the saved definition up to the live section, transform and generator.
pub(super) fn save_live(def: &mut TerrainDef, entity: EntityRef) {
    let (Some(params), Some(body)) = (entity.get::<TerrainParams>(), entity.get::<TerrainBody>()) else { return };
    let section = params.section.section(&body.map);
    def.section.origin = section.origin;
    def.section.size = section.size;
    def.rotation_deg.0 = params.rotation_deg;
    def.position.0 = params.position;
    for (factor, value) in def.scale.iter_mut().zip(params.scale.to_array()) {
        factor.0 = value.clamp(1e-3, 1000.0);
    }
    def.height_m.0 = params.height_m.clamp(1e-3, 1e6);
    // A map made again from the panel, keys or a timeline is saved as made; otherwise the
    // file's recipe stays as written (a seed left to chance stays -1).
    if body.regenerated
        && let Some(recipe) = &body.recipe
    {
        def.height.size = Some(recipe.size);
        def.height.layers.clone_from(&recipe.layers);
        def.height.apply.clone_from(&recipe.apply);
        def.height.seed = recipe.seed;
    }
}

/// Every system of the terrain kind, in whichever phase it runs.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TerrainSystems;

/// Runs terrains: parameters, keys, regeneration, meshes, dump and panel.
#[derive(Default)]
pub struct TerrainPlugin;

/// Section keys: (key, action, samples along x, samples along z). With Shift, ten times as far.
pub(super) const MOVE_KEYS: [(KeyCode, &str, i64, i64); 4] = [
    (KeyCode::KeyA, "move the section 1 sample along -x (Shift: 10)", -1, 0),
    (KeyCode::KeyD, "move the section 1 sample along +x (Shift: 10)", 1, 0),
    (KeyCode::KeyW, "move the section 1 sample along -z (Shift: 10)", 0, -1),
    (KeyCode::KeyS, "move the section 1 sample along +z (Shift: 10)", 0, 1),
];
/// Turning speed of the model, degrees per second.
const TURN_DEG_PER_S: f32 = 45.0;
/// Scaling speed: the scale changes by this factor per second.
const SCALE_PER_S: f32 = 1.5;
/// Held keys: (key, action, turn, horizontal scale exponent, vertical scale exponent).
pub(super) const MODEL_KEYS: [(KeyCode, &str, f32, f32, f32); 6] = [
    (KeyCode::KeyR, "turn the terrain left", 1.0, 0.0, 0.0),
    (KeyCode::KeyF, "turn the terrain right", -1.0, 0.0, 0.0),
    (KeyCode::KeyX, "make the terrain wider", 0.0, 1.0, 0.0),
    (KeyCode::KeyZ, "make the terrain narrower", 0.0, -1.0, 0.0),
    (KeyCode::KeyT, "make the terrain taller", 0.0, 0.0, 1.0),
    (KeyCode::KeyG, "make the terrain flatter", 0.0, 0.0, -1.0),
];
/// Makes the map again with the next seed.
pub(super) const NEW_SEED: KeyCode = KeyCode::KeyN;
/// Saves the heightmap as a 16-bit PNG.
pub(super) const SAVE_MAP: KeyCode = KeyCode::KeyU;

impl Plugin for TerrainPlugin {
    fn build(&self, app: &mut App) {
        app.register_params::<TerrainParams>()
            .register_dump::<TerrainParams>()
            .register_dump::<TerrainBody>()
            .add_systems(
                RunFixedMainLoop,
                (move_with_keys, shape_with_keys, seed_and_save_with_keys)
                    .in_set(ControlSystems::Input)
                    .in_set(TerrainSystems),
            )
            .add_systems(Update, regenerate.after(ControlSystems::Load).in_set(TerrainSystems))
            .add_systems(PostUpdate, write_back_terrain.in_set(WriteBackSystems).in_set(TerrainSystems))
            .add_systems(PostUpdate, publish_ground.in_set(SpatialSystems::Publish).in_set(TerrainSystems));
    }
}

/// Moves the sections by whole samples (the source's Move), stopping at the map's edges so
/// that a key pressed towards an edge never moves the parameters past what is shown.
fn move_with_keys(keys: Res<ButtonInput<KeyCode>>, mut terrains: Query<(&mut TerrainParams, &TerrainBody)>) {
    let factor = if keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]) { 10 } else { 1 };
    let (mut dx, mut dz) = (0, 0);
    for (key, _, x, z) in MOVE_KEYS {
        if keys.just_pressed(key) {
            (dx, dz) = (dx + x * factor, dz + z * factor);
        }
    }
    if (dx, dz) != (0, 0) {
        for (mut params, body) in &mut terrains {
            let moved = params.section.section(&body.map).moved(dx, dz, &body.map);
            params.section.x = moved.origin[0] as f32;
            params.section.z = moved.origin[1] as f32;
        }
    }
}

fn shape_with_keys(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut terrains: Query<&mut TerrainParams>) {
    let dt = time.delta_secs();
    let (mut turn, mut wide, mut tall) = (0.0, 0.0, 0.0);
    for (key, _, t, w, h) in MODEL_KEYS {
        if keys.pressed(key) {
            (turn, wide, tall) = (turn + t, wide + w, tall + h);
        }
    }
    if (turn, wide, tall) == (0.0, 0.0, 0.0) {
        return;
    }
    for mut params in &mut terrains {
        params.rotation_deg = wrap_degrees(params.rotation_deg + turn * TURN_DEG_PER_S * dt);
        let (horizontal, vertical) = (SCALE_PER_S.powf(wide * dt), SCALE_PER_S.powf(tall * dt));
        params.scale =
            (params.scale * Vec3::new(horizontal, vertical, horizontal)).clamp(Vec3::splat(1e-3), Vec3::splat(1000.0));
    }
}

fn seed_and_save_with_keys(keys: Res<ButtonInput<KeyCode>>, mut terrains: Query<(&mut TerrainParams, &TerrainBody)>) {
    if keys.just_pressed(NEW_SEED) {
        for (mut params, body) in &mut terrains {
            if body.recipe.is_some() {
                params.noise.seed += 1.0;
            }
        }
    }
    if keys.just_pressed(SAVE_MAP) {
        for (_, body) in &terrains {
            save_heightmap(&body.map);
        }
    }
}

/// Writes `map` as a 16-bit PNG under `heightmaps/`, never over an earlier file; logs where.
pub fn save_heightmap(map: &Heightmap) -> Option<PathBuf> {
    let folder = PathBuf::from("heightmaps");
    let saved = std::fs::create_dir_all(&folder).map_err(|e| e.to_string()).and_then(|()| {
        let path = first_free_path(|n| folder.join(format!("terrain-{n:04}.png")));
        image_io::save(map, &path, Encoding::Png16).map(|()| path).map_err(|e| e.to_string())
    });
    match saved {
        Ok(path) => {
            info!("heightmap saved to {}", path.display());
            Some(path)
        }
        Err(error) => {
            error!("could not save the heightmap in {}: {error}", folder.display());
            None
        }
    }
}

/// The recipe `params` asks for: `recipe` with its first Perlin layer's parameters and the
/// seed replaced; `None` when they make no valid recipe (the message says why).
fn edited_recipe(recipe: &Recipe, noise: &NoiseParams) -> Result<Recipe, String> {
    let mut edited = recipe.clone();
    if let Some(layer) = edited.layers.iter_mut().find_map(|l| l.perlin.as_mut()) {
        *layer = PerlinLayer {
            scale: noise.scale,
            octaves: noise.octaves.round().clamp(0.0, 1e3) as u32,
            lacunarity: noise.lacunarity,
            persistence: noise.persistence,
        };
    }
    if !(noise.seed.is_finite() && noise.seed >= 0.0 && noise.seed <= 9.0e15) {
        return Err(format!("seed: expected a whole number from 0 to 9e15, found {}", noise.seed));
    }
    edited.seed = noise.seed.round() as i64;
    edited.check().map_err(|e| e.to_string())?;
    Ok(edited)
}

impl TerrainBody {
    /// Makes the map again from `recipe` (its seed the one to use) off the main thread, after
    /// the same checks as a scene file's; a recipe that fails them changes nothing, and the
    /// message says why. A generated map only: an image's heights have no recipe to change.
    pub fn remake(&mut self, recipe: Recipe) {
        if self.recipe.is_none() {
            self.message = Some("the heights come from an image: there is no generator to change".into());
            return;
        }
        match recipe.check() {
            Ok(()) if recipe.seed >= 0 => self.start(recipe),
            Ok(()) => self.message = Some("seed: expected a seed of 0 or more to make the map with".into()),
            Err(error) => self.message = Some(error.to_string()),
        }
    }

    /// Whether a map is being made.
    pub fn remaking(&self) -> bool {
        self.pending.is_some()
    }

    /// Starts generating `recipe` (checked, its seed not negative) on the async compute pool.
    fn start(&mut self, recipe: Recipe) {
        let job = recipe.clone();
        let task = AsyncComputeTaskPool::get().spawn(async move {
            let started = Instant::now();
            let map = job.generate(job.seed as u64).map_err(|e| e.to_string());
            (map, started.elapsed())
        });
        self.pending = Some(PendingMap { task, recipe, frames_left: GENERATION_FRAMES });
        self.message = None;
    }
}

/// Starts making the map again when the generator's parameters changed, and takes a finished
/// map in [`GENERATION_FRAMES`] frames after it was asked for; the parameters then follow the
/// recipe the map was made with (which the panel may have changed whole).
fn regenerate(mut terrains: Query<(&mut TerrainParams, &mut TerrainBody)>) {
    for (mut params, mut body) in &mut terrains {
        let body = &mut *body;
        if let Some(pending) = &mut body.pending {
            if pending.frames_left > 0 {
                pending.frames_left -= 1;
                continue;
            }
            let Some(pending) = body.pending.take() else { continue };
            let (result, time) = block_on(pending.task);
            body.generation_time = time;
            match result {
                Ok(map) => {
                    let seed = pending.recipe.seed as u64;
                    body.generated = noise_params(Some(&pending.recipe), Some(seed));
                    if params.noise != body.generated {
                        params.noise = body.generated;
                    }
                    body.map = Arc::new(map);
                    body.recipe = Some(pending.recipe);
                    body.seed = Some(seed);
                    body.shown = None;
                    body.regenerated = true;
                    body.message = None;
                }
                Err(error) => body.message = Some(error),
            }
        }
        let Some(recipe) = &body.recipe else { continue };
        if params.noise == body.generated {
            continue;
        }
        body.generated = params.noise;
        match edited_recipe(recipe, &params.noise) {
            Ok(recipe) => body.start(recipe),
            Err(error) => body.message = Some(error),
        }
    }
}

/// What write-back reads and writes of a terrain.
type TerrainWriteBack<'a> = (&'a TerrainParams, &'a mut TerrainBody, &'a mut Transform, &'a Children);

/// A terrain whose parameters or map changed since write-back last ran.
type TerrainChanged = Or<(Changed<TerrainParams>, Changed<TerrainBody>)>;

/// Re-meshes a terrain whose section, height scale or map changed, and writes its transform.
fn write_back_terrain(
    mut terrains: Query<TerrainWriteBack, TerrainChanged>,
    mut surfaces: Query<(&TerrainSurface, &mut RasterMesh)>,
) {
    for (params, mut body, mut transform, children) in &mut terrains {
        let section = params.section.section(&body.map);
        let height_m = params.height_m.clamp(1e-3, 1e6);
        if body.shown != Some((section, height_m)) {
            let started = Instant::now();
            let geometry = Geometry { cell_m: body.cell_m, height_m, texture_cells: body.texture_cells };
            let mesh = mesh_section(&body.map, section, geometry, &body.rule);
            let (counts, barycentre) = (mesh.counts, mesh.barycentre);
            let mut meshes = mesh.into_surfaces();
            for child in children.iter() {
                if let Ok((surface, mut raster)) = surfaces.get_mut(child) {
                    let mesh = meshes.get_mut(surface.index()).map(std::mem::take);
                    raster.mesh = Arc::new(mesh.unwrap_or_default());
                }
            }
            body.counts = counts;
            body.barycentre = barycentre;
            body.shown = Some((section, height_m));
            body.mesh_time = started.elapsed();
        }
        *transform = params.transform(body.barycentre);
    }
}

/// A terrain's shown section is the ground solids meet, where the terrain stands now; made
/// again when the section or the terrain's place changed.
fn publish_ground(terrains: Query<(Entity, Ref<TerrainBody>, Ref<GlobalTransform>)>, mut commands: Commands) {
    for (entity, body, placed) in &terrains {
        if !(body.is_changed() || placed.is_changed()) {
            continue;
        }
        let Some((section, height_m)) = body.shown else { continue };
        let geometry = Geometry { cell_m: body.cell_m, height_m, texture_cells: body.texture_cells };
        let ground = Ground::of_section(&body.map, section, geometry, body.barycentre, placed.affine());
        commands.entity(entity).insert(Solid(Collider::Ground(Arc::new(ground))));
    }
}

impl DumpState for TerrainParams {
    fn dump(&self, out: &mut Map<String, Value>) {
        out.insert("rotation_deg".into(), json!(self.rotation_deg));
        out.insert("scale".into(), json!(self.scale.to_array()));
        out.insert("position".into(), json!(self.position.to_array()));
    }
}

impl DumpState for TerrainBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let stats = self.map.stats();
        out.insert("map_size".into(), json!([stats.width, stats.height]));
        if let Some((section, height_m)) = self.shown {
            out.insert("section".into(), json!({ "origin": section.origin, "size": section.size }));
            out.insert("height_m".into(), json!(height_m));
        }
        out.insert("height".into(), json!({ "min": stats.min, "max": stats.max, "mean": stats.mean }));
        out.insert("checksum".into(), json!(format!("{:016x}", stats.checksum)));
        out.insert("seed".into(), self.seed.map_or(Value::Null, |seed| json!(seed)));
        let bands: Map<String, Value> =
            Band::ALL.iter().zip(self.counts).map(|(band, n)| (band.key().to_string(), json!(n))).collect();
        out.insert("triangles_per_band".into(), Value::Object(bands));
        if let Some(message) = &self.message {
            out.insert("message".into(), json!(message));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_of_the_noise_make_a_checked_recipe() {
        let recipe: Recipe =
            serde_yaml::from_str("{size: [16, 16], seed: 2, layers: [{hills: {count: 3}}, {perlin: {scale: 8}}]}")
                .unwrap();
        let noise = NoiseParams { seed: 5.0, scale: 4.0, octaves: 3.2, lacunarity: 2.5, persistence: 0.4 };
        let edited = edited_recipe(&recipe, &noise).unwrap();
        let seed = edited.seed;
        assert_eq!(seed, 5);
        assert_eq!(
            edited.layers[1].perlin,
            Some(PerlinLayer { scale: 4.0, octaves: 3, lacunarity: 2.5, persistence: 0.4 })
        );
        assert_eq!(edited.layers[0], recipe.layers[0]);
        assert!(edited_recipe(&recipe, &NoiseParams { octaves: 0.0, ..noise }).unwrap_err().contains("octaves"));
        assert!(edited_recipe(&recipe, &NoiseParams { seed: -1.0, ..noise }).unwrap_err().contains("seed"));
    }
}
