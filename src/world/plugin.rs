//! [`WorldPlugin`]: each frame the streaming plan around the camera, chunks made on the async
//! compute pool, finished chunks spawned within the per-frame budget, far chunks despawned,
//! skirts hung where chunks of different levels meet, and the dump of the resident chunks.
//!
//! A chunk asked for is taken [`CHUNK_FRAMES`] frames later (waiting for it then if it is
//! late), so that headless runs with the same camera path have the same chunks at the same
//! frames.

use super::chunk::{ChunkHeights, ChunkKey, LEVELS, SIDES, WorldHeights};
use super::def::{WorldBuilt, WorldDef};
use super::ground::WorldGround;
use super::stream::{StreamSettings, plan};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::raster::{Material, MeshData, RasterMesh};
use crate::spatial::SpatialSystems;
use crate::spatial::ground::GroundPatch;
use crate::spatial::solid::{Collider, Solid};
use crate::terrain::bands::BandRule;
use crate::terrain::section::Geometry;
use crate::terrain::surfaces::{TerrainSurface, surface_materials};
use crate::view::CameraParams;
use bevy::ecs::world::EntityWorldMut;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on};
use serde_json::{Map, Value, json};
use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Frames between asking for a chunk and spawning it.
pub const CHUNK_FRAMES: u32 = 2;

/// Chunks being made at once at most, per world: a few frames' budget.
const IN_FLIGHT_FRAMES: usize = 4;

/// The systems of the world kind.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct WorldSystems;

/// Streams `world` entities.
#[derive(Default)]
pub struct WorldPlugin;

impl Plugin for WorldPlugin {
    fn build(&self, app: &mut App) {
        app.register_dump::<WorldBody>().add_systems(
            Update,
            (stream_chunks, spawn_finished, hang_skirts).chain().in_set(SpatialSystems::Ground).in_set(WorldSystems),
        );
    }
}

/// A resident chunk: a child of its world, itself the parent of one mesh per surface.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct WorldChunk {
    /// Which chunk.
    pub key: ChunkKey,
    /// Its level of detail.
    pub level: u8,
    /// The checksum of its heights.
    pub checksum: u64,
}

/// A skirt: a child of its chunk, the parent of one strip per surface, hanging below the
/// chunk's edges on one side where a chunk of another level lies across it.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkSkirt {
    /// Which side, an index into [`SIDES`].
    pub side: usize,
}

/// One mesh per surface, in [`TerrainSurface::index`] order (empty where it has none),
/// positions in the world's metres.
type Surfaces = Vec<Arc<MeshData>>;

/// A chunk's meshes, ready to spawn.
#[derive(Debug, Clone)]
struct MadeChunk {
    /// The checksum of its heights.
    checksum: u64,
    /// The surface.
    surfaces: Surfaces,
    /// The strips of each side of [`SIDES`], hung where levels meet.
    skirts: Arc<[Surfaces; 4]>,
    /// How long making it took.
    time: Duration,
}

/// A resident chunk as its world keeps it.
#[derive(Debug)]
struct Resident {
    level: u8,
    entity: Entity,
    checksum: u64,
    /// Its skirts' strips, and the skirt entity of each side where one hangs.
    skirts: Arc<[Surfaces; 4]>,
    hung: [Option<Entity>; 4],
}

/// A chunk being made.
#[derive(Debug)]
struct PendingChunk {
    key: ChunkKey,
    level: u8,
    task: Task<MadeChunk>,
    frames_left: u32,
    /// Made in advance and taken ready-made.
    ready: bool,
}

/// What a world's chunks are made of, shared with the tasks that make them.
#[derive(Debug)]
struct ChunkMaker {
    heights: WorldHeights,
    stream: StreamSettings,
    geometry: Geometry,
    rule: BandRule,
    skirt_m: f32,
    cells: u32,
}

impl ChunkMaker {
    /// Makes chunk `key` at `level`.
    fn make(&self, key: ChunkKey, level: u8) -> MadeChunk {
        let started = Instant::now();
        let heights = ChunkHeights::generate(&self.heights, key, level, self.cells);
        let mesh = heights.mesh(self.geometry, &self.rule, self.skirt_m, self.stream.morph_band(level));
        let shared = |meshes: Vec<MeshData>| meshes.into_iter().map(Arc::new).collect();
        let surfaces = shared(mesh.surfaces.into_surfaces());
        let skirts = Arc::new(mesh.skirts.map(shared));
        MadeChunk { checksum: heights.checksum(), surfaces, skirts, time: started.elapsed() }
    }
}

/// The live world: what it is made of and which chunks it has.
#[derive(Component, Debug)]
pub struct WorldBody {
    maker: Arc<ChunkMaker>,
    /// The seed the heights were made with; none for an image.
    seed: Option<u64>,
    budget: usize,
    /// The surfaces a chunk is drawn in, with their materials.
    surfaces: Vec<(TerrainSurface, Material)>,
    /// Resident chunks.
    resident: HashMap<ChunkKey, Resident>,
    /// Whether chunks came or went since the skirts were last hung.
    changed: bool,
    /// Chunks being made, in the order they were asked for.
    pending: Vec<PendingChunk>,
    /// Chunks made (or taken ready-made) and spawned since the world was spawned.
    pub made: u64,
    /// Of those, the chunks that were made in advance.
    pub taken_ready: u64,
    /// Time spent making them (on the pool's threads; none for those made in advance).
    pub making_time: Duration,
    /// When the chunks of the last second were spawned (wall clock, for the panel's rate).
    recent: VecDeque<Instant>,
    /// Chunks made in advance ([`WorldBody::make_in_advance`]), taken instead of being made.
    in_advance: HashMap<(ChunkKey, u8), MadeChunk>,
}

impl WorldBody {
    /// Where the heights come from, and the metres between samples and for a height of 1.
    pub fn ground(&self) -> (&WorldHeights, Geometry) {
        (&self.maker.heights, self.maker.geometry)
    }

    /// The square chunk `key` covers: its corner's x and z and its side, metres.
    pub fn chunk_square(&self, key: ChunkKey) -> ((f32, f32), f32) {
        let side = self.maker.cells as f32 * self.maker.geometry.cell_m;
        ((key.x as f32 * side, key.z as f32 * side), side)
    }

    /// Resident chunks at each level of detail.
    pub fn per_level(&self) -> [usize; LEVELS as usize] {
        let mut counts = [0; LEVELS as usize];
        self.resident.values().for_each(|chunk| counts[chunk.level as usize] += 1);
        counts
    }

    /// The level of each resident chunk.
    fn resident_levels(&self) -> HashMap<ChunkKey, u8> {
        self.resident.iter().map(|(&key, chunk)| (key, chunk.level)).collect()
    }

    /// Chunks being made.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Chunks spawned in the last second of wall-clock time.
    pub fn per_second(&self) -> usize {
        self.recent.len()
    }

    /// The mean time making a chunk took on the pool's threads.
    pub fn mean_making_time(&self) -> Duration {
        self.making_time.checked_div(self.made.max(1) as u32).unwrap_or_default()
    }

    /// The seed the heights are made with; none for an image.
    pub fn seed(&self) -> Option<u64> {
        self.seed
    }

    /// Where and at what detail chunks are wanted.
    pub fn stream(&self) -> &StreamSettings {
        &self.maker.stream
    }

    /// Makes `chunks` (at their levels) now, on the async compute pool's threads, and keeps
    /// them: streaming then takes them ready-made, at the same frames as it would have made
    /// them. For a camera path known in advance, and to measure a flight with nothing left to
    /// make against the same flight streamed.
    pub fn make_in_advance(&mut self, chunks: impl IntoIterator<Item = (ChunkKey, u8)>) {
        let wanted: Vec<(ChunkKey, u8)> =
            chunks.into_iter().filter(|chunk| !self.in_advance.contains_key(chunk)).collect();
        let made = AsyncComputeTaskPool::get().scope(|scope| {
            for &(key, level) in &wanted {
                let maker = &self.maker;
                scope.spawn(async move { maker.make(key, level) });
            }
        });
        self.in_advance.extend(wanted.into_iter().zip(made));
    }
}

/// Spawns a world entity of `def`.
pub(super) fn spawn_world(entity: &mut EntityWorldMut, def: &WorldDef, built: &WorldBuilt) {
    // Its ground is the same for as long as it lives: a solid from the start.
    let ground = WorldGround { heights: built.heights.clone(), geometry: built.geometry };
    entity.insert((
        Transform::default(),
        Solid(Collider::Ground(Arc::new(ground))),
        WorldBody {
            maker: Arc::new(ChunkMaker {
                heights: built.heights.clone(),
                stream: built.stream,
                geometry: built.geometry,
                rule: def.bands.rule(),
                skirt_m: def.skirt_m.0,
                cells: def.chunk_cells,
            }),
            seed: built.seed,
            budget: def.spawn_budget as usize,
            surfaces: surface_materials(&def.bands),
            resident: HashMap::new(),
            changed: false,
            pending: Vec::new(),
            made: 0,
            taken_ready: 0,
            making_time: Duration::ZERO,
            recent: VecDeque::new(),
            in_advance: HashMap::new(),
        },
    ));
}

/// Lets go of the chunks beyond the unload radius and asks for those the plan wants, around
/// the scene's camera as its parameters place it this frame.
fn stream_chunks(cameras: Query<&CameraParams>, mut worlds: Query<&mut WorldBody>, mut commands: Commands) {
    let Some(camera) = cameras.iter().next() else { return };
    let (eye, target) = (camera.eye(), camera.target);
    let (camera, forward) = (eye.xz(), (target - eye).xz());
    for mut body in &mut worlds {
        let body = &mut *body;
        let resident = body.resident_levels();
        let pending: HashMap<ChunkKey, u8> = body.pending.iter().map(|p| (p.key, p.level)).collect();
        let plan = plan(&body.maker.stream, camera, forward, &resident, &pending);
        for key in plan.unload {
            if let Some(chunk) = body.resident.remove(&key) {
                commands.entity(chunk.entity).despawn();
                body.changed = true;
            }
        }
        let stream = body.maker.stream;
        body.pending.retain(|p| stream.centre(p.key).distance(camera) <= stream.unload_radius_m);
        let room = (body.budget * IN_FLIGHT_FRAMES).saturating_sub(body.pending.len());
        for (key, level) in plan.requests.into_iter().take(room) {
            // A chunk asked for at another level is asked for again at this one.
            body.pending.retain(|p| p.key != key);
            let pool = AsyncComputeTaskPool::get();
            let (task, ready) = match body.in_advance.get(&(key, level)) {
                Some(made) => {
                    let made = MadeChunk { time: Duration::ZERO, ..made.clone() };
                    (pool.spawn(async move { made }), true)
                }
                None => {
                    let maker = body.maker.clone();
                    (pool.spawn(async move { maker.make(key, level) }), false)
                }
            };
            body.pending.push(PendingChunk { key, level, task, frames_left: CHUNK_FRAMES, ready });
        }
    }
}

/// Spawns the chunks whose time has come, in the order they were asked for, at most the
/// budget a frame; a chunk replacing one of another level despawns it.
fn spawn_finished(mut worlds: Query<(Entity, &mut WorldBody)>, mut commands: Commands) {
    for (world, mut body) in &mut worlds {
        let body = &mut *body;
        body.pending.iter_mut().for_each(|p| p.frames_left = p.frames_left.saturating_sub(1));
        let now = Instant::now();
        while body.recent.front().is_some_and(|&at| now.duration_since(at) > Duration::from_secs(1)) {
            body.recent.pop_front();
        }
        let mut spawned = 0;
        while spawned < body.budget {
            let Some(index) = body.pending.iter().position(|p| p.frames_left == 0) else { break };
            let PendingChunk { key, level, task, ready, .. } = body.pending.remove(index);
            let made = block_on(task);
            body.made += 1;
            body.taken_ready += u64::from(ready);
            body.making_time += made.time;
            body.recent.push_back(now);
            let chunk = WorldChunk { key, level, checksum: made.checksum };
            let (corner, side) = body.chunk_square(key);
            let patch =
                GroundPatch { key: IVec2::new(key.x, key.z), level, corner: Vec2::new(corner.0, corner.1), side };
            // The meshes are placed in the world already: with no transform of their own, the
            // vertices neighbouring chunks share stay alike bit for bit.
            let entity = commands
                .spawn((chunk, patch, Transform::IDENTITY, ChildOf(world)))
                .with_children(|parts| spawn_surfaces(parts, &body.surfaces, &made.surfaces))
                .id();
            let resident = Resident { level, entity, checksum: made.checksum, skirts: made.skirts, hung: [None; 4] };
            if let Some(old) = body.resident.insert(key, resident) {
                commands.entity(old.entity).despawn();
            }
            body.changed = true;
            spawned += 1;
        }
    }
}

/// Spawns one mesh entity per non-empty surface of `meshes` under `parent`, with its material.
fn spawn_surfaces(parent: &mut ChildSpawnerCommands, materials: &[(TerrainSurface, Material)], meshes: &Surfaces) {
    for (surface, material) in materials {
        let Some(mesh) = meshes.get(surface.index()) else { continue };
        if !mesh.triangles.is_empty() {
            parent.spawn((*surface, RasterMesh { mesh: mesh.clone(), material: material.clone() }));
        }
    }
}

/// Hangs a skirt on each side of a resident chunk where a chunk of another level lies across
/// it, and takes down those that no longer have one: chunks of one level meet without a gap,
/// and a skirt drawn where it is not needed costs raster time for nothing. Runs the frame
/// chunks come or go, so a border between levels never goes a frame without its skirts.
fn hang_skirts(mut worlds: Query<&mut WorldBody>, mut commands: Commands) {
    for mut body in &mut worlds {
        let body = &mut *body;
        if !std::mem::take(&mut body.changed) {
            continue;
        }
        let levels = body.resident_levels();
        for (key, chunk) in &mut body.resident {
            for (side, [dx, dz]) in SIDES.into_iter().enumerate() {
                let across = levels.get(&ChunkKey { x: key.x + dx, z: key.z + dz });
                let wanted = across.is_some_and(|&level| level != chunk.level);
                match (wanted, chunk.hung[side]) {
                    (true, None) => {
                        let strips = &chunk.skirts[side];
                        let skirt = commands
                            .spawn((ChunkSkirt { side }, Transform::IDENTITY, ChildOf(chunk.entity)))
                            .with_children(|parts| spawn_surfaces(parts, &body.surfaces, strips))
                            .id();
                        chunk.hung[side] = Some(skirt);
                    }
                    (false, Some(skirt)) => {
                        commands.entity(skirt).despawn();
                        chunk.hung[side] = None;
                    }
                    _ => {}
                }
            }
        }
    }
}

impl DumpState for WorldBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        out.insert("seed".into(), json!(self.seed()));
        if let Some(bounds) = self.stream().bounds {
            out.insert("bounds_chunks".into(), json!(bounds));
        }
        let mut chunks: Vec<(ChunkKey, u8, u64)> =
            self.resident.iter().map(|(&key, chunk)| (key, chunk.level, chunk.checksum)).collect();
        chunks.sort();
        out.insert("resident".into(), json!(chunks.len()));
        out.insert("resident_per_level".into(), json!(self.per_level()));
        let skirts = self.resident.values().flat_map(|chunk| chunk.hung).flatten().count();
        out.insert("skirts".into(), json!(skirts));
        out.insert("pending".into(), json!(self.pending.len()));
        out.insert("made".into(), json!(self.made));
        let keys: Vec<Value> = chunks
            .iter()
            .map(|(key, level, checksum)| json!([key.x, key.z, level, format!("{checksum:016x}")]))
            .collect();
        out.insert("chunks".into(), Value::Array(keys));
    }
}
