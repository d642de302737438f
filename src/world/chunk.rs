//! Chunks of a world: square pieces of the world's heights, `cells` cells a side, at a level of
//! detail, each made from the world's heights (a recipe without bounds, or a finite map) at
//! world sample positions alone, so that neighbouring chunks share their edge heights, and
//! their edge normals, bit for bit.
//!
//! Level `l` keeps every `2^l`-th sample: a chunk has `cells / 2^l + 1` vertices a side, and
//! two rings of samples beyond its edges (at its own spacing) from which the normals at its
//! edges are made as in the middle of the map, at its level and at the next coarser one.
//!
//! A chunk's mesh can morph into the next level's shape: every vertex has a target on the
//! coarser mesh (its own height where the coarser level keeps the sample, else the middle of
//! the coarser edge or diagonal it lies on) with the coarser level's normal there, so that a
//! fully morphed chunk has the coarser chunk's surface, and a change of level shows nothing.
//! Where chunks of different levels meet, the finer one has morphed onto the coarser edge
//! (see [`stream`](super::stream)); a skirt, a strip hanging down from every edge of a chunk,
//! fills the pixels that the meeting of their different triangles could still leave open.

use crate::terrain::bands::BandRule;
use crate::terrain::generate::Recipe;
use crate::terrain::ground::cell_surface;
use crate::terrain::heightmap::Heightmap;
use crate::terrain::noise::Fbm;
use crate::terrain::section::{
    Geometry, MorphTargets, Placement, SampleFrame, Section, SectionMesh, mesh_section_in, vertex_normals,
};
use bevy::math::Vec3;
use canopy_raster::{MeshData, Morph};
use std::sync::Arc;

/// Levels of detail: level 0 has every sample, each next level every second of the one
/// before.
pub const LEVELS: u8 = 4;

/// The chunk sizes allowed, in cells a side: powers of two with a vertex at every level.
pub const CHUNK_CELLS: [u32; 4] = [16, 32, 64, 128];

/// Samples beyond a chunk's edges on each side, at its own spacing: the normals along its
/// edges need one, and those of its coarser level (every second sample) one more.
const RING: u32 = 2;

/// The distances from the camera (horizontally, metres) over which a chunk's vertices move
/// into the shape of the next coarser level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MorphBand {
    /// Where the vertices start to move.
    pub start_m: f32,
    /// Where they have the coarser level's shape.
    pub end_m: f32,
}

/// Where a world's heights come from.
#[derive(Debug, Clone)]
pub enum WorldHeights {
    /// A recipe (checked, and unbounded by [`Recipe::check_unbounded`]) and its seed:
    /// heights of their position alone, without bounds. Made by [`WorldHeights::unbounded`].
    Unbounded {
        /// The recipe.
        recipe: Arc<Recipe>,
        /// Its seed.
        seed: u64,
        /// The recipe's noises for the seed, made once.
        noises: Arc<[Option<Fbm>]>,
    },
    /// A finite map, its first sample at world sample `(0, 0)`; a sample beyond its edges has
    /// the height of the nearest one on them.
    Map(Arc<Heightmap>),
}

impl WorldHeights {
    /// The heights of a checked, unbounded `recipe` with `seed`.
    pub fn unbounded(recipe: Arc<Recipe>, seed: u64) -> Self {
        let noises = recipe.noises(seed).into();
        Self::Unbounded { recipe, seed, noises }
    }

    /// The heights at the world samples `(x0 + i * step, z0 + j * step)` for `i < width`,
    /// `j < depth`, row by row; grids that share a sample give it bit for bit.
    pub fn sample_grid(&self, origin: [i32; 2], step: i32, size: [usize; 2]) -> Vec<f32> {
        match self {
            Self::Unbounded { recipe, noises, .. } => recipe.sample_grid_with(noises, origin, step, size),
            Self::Map(map) => {
                let [x0, z0] = origin.map(i64::from);
                let step = i64::from(step.max(1));
                let clamp = |v: i64, samples: u32| v.clamp(0, i64::from(samples) - 1) as u32;
                (0..size[1] as i64)
                    .flat_map(|j| (0..size[0] as i64).map(move |i| (i, j)))
                    .map(|(i, j)| map.at(clamp(x0 + i * step, map.width()), clamp(z0 + j * step, map.height())))
                    .collect()
            }
        }
    }

    /// The height of the ground at world point `(x, z)`, metres, as the finest level draws it
    /// with `geometry`'s metres (a chunk's vertex at world sample `(i, j)` stands at
    /// `(i * cell_m, height * height_m, j * cell_m)`).
    pub fn ground_height(&self, x: f32, z: f32, geometry: Geometry) -> f32 {
        self.ground_surface(x, z, geometry).0
    }

    /// The height of the ground at world point `(x, z)`, metres, and its upward unit normal,
    /// as [`ground_height`](Self::ground_height) finds them.
    pub fn ground_surface(&self, x: f32, z: f32, geometry: Geometry) -> (f32, Vec3) {
        let (u, v) = (x / geometry.cell_m, z / geometry.cell_m);
        let (i, j) = (u.floor(), v.floor());
        let samples = self.sample_grid([i as i32, j as i32], 1, [2, 2]);
        let corners = [samples[0], samples[1], samples[2], samples[3]].map(|h| h * geometry.height_m);
        cell_surface(corners, u - i, v - j, geometry.cell_m)
    }

    /// The highest the ground drawn at the finest level can stand anywhere over the world
    /// rectangle from `min` to `max` (x and z, metres): the highest sample of the cells it
    /// covers, as every triangle lies between its corners. Rectangles of more than
    /// [`HIGHEST_CELLS`] cells get infinity (no bound worth the sampling).
    pub fn highest_over(&self, min: [f32; 2], max: [f32; 2], geometry: Geometry) -> f32 {
        let cell = |v: f32| (v / geometry.cell_m).floor();
        let (i0, j0, i1, j1) = (cell(min[0]), cell(min[1]), cell(max[0]) + 1.0, cell(max[1]) + 1.0);
        let size = [i1 - i0 + 1.0, j1 - j0 + 1.0];
        let cells = size[0] * size[1];
        if cells.is_nan() || cells > HIGHEST_CELLS as f32 {
            return f32::INFINITY;
        }
        let samples = self.sample_grid([i0 as i32, j0 as i32], 1, size.map(|n| n as usize));
        samples.into_iter().fold(f32::NEG_INFINITY, f32::max) * geometry.height_m
    }

    /// Chunks of `cells` cells along x and z that cover a finite map, from chunk `(0, 0)`
    /// (its far edges extended by their samples to whole chunks); `None` without bounds.
    pub fn chunks(&self, cells: u32) -> Option<[u32; 2]> {
        match self {
            Self::Unbounded { .. } => None,
            Self::Map(map) => Some([map.width(), map.height()].map(|samples| (samples - 1).div_ceil(cells).max(1))),
        }
    }
}

/// The most samples [`WorldHeights::highest_over`] reads.
pub const HIGHEST_CELLS: usize = 64;

/// The four sides of a chunk, as the step to the chunk across each: -x, +x, -z, +z.
pub const SIDES: [[i32; 2]; 4] = [[-1, 0], [1, 0], [0, -1], [0, 1]];

/// A chunk's meshes.
#[derive(Debug, Clone, PartialEq)]
pub struct ChunkMesh {
    /// The surface itself.
    pub surfaces: SectionMesh,
    /// Per side of [`SIDES`], one strip per surface (in [`SectionMesh::into_surfaces`] order,
    /// empty where the surface has no edge there) hanging below that side's edges; no strips
    /// without skirts. Chunks of one level meet without a gap, so only where levels meet
    /// are they needed.
    pub skirts: [Vec<MeshData>; 4],
}

/// Which chunk: its place on the grid of chunks (chunk `(x, z)` starts at world sample
/// `(x * cells, z * cells)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ChunkKey {
    /// Along x.
    pub x: i32,
    /// Along z.
    pub z: i32,
}

/// A chunk's heights at one level of detail.
#[derive(Debug, Clone, PartialEq)]
pub struct ChunkHeights {
    /// Which chunk.
    pub key: ChunkKey,
    /// Its level of detail.
    pub level: u8,
    /// Its vertices and the rings beyond them: `cells / 2^level + 5` samples a side, the
    /// first vertex at `(2, 2)`.
    pub map: Heightmap,
}

impl ChunkHeights {
    /// The heights of chunk `key` at `level` (below [`LEVELS`]) of a world of chunks of
    /// `cells` cells (one of [`CHUNK_CELLS`]) with `heights`.
    pub fn generate(heights: &WorldHeights, key: ChunkKey, level: u8, cells: u32) -> Self {
        let level = level.min(LEVELS - 1);
        // Other sizes are brought to the nearest allowed bound: a chunk stays small.
        let cells = cells.clamp(CHUNK_CELLS[0], CHUNK_CELLS[CHUNK_CELLS.len() - 1]);
        let step = 1i32 << level;
        let side = (cells >> level) + 1 + 2 * RING;
        let ring = RING as i32 * step;
        let origin = [key.x * cells as i32 - ring, key.z * cells as i32 - ring];
        let heights = heights.sample_grid(origin, step, [side as usize; 2]);
        let map =
            Heightmap::from_values(side, side, heights).expect("a grid of side x side heights, at most 133 a side");
        Self { key, level, map }
    }

    /// Vertices a side.
    pub fn vertices(&self) -> u32 {
        self.map.width() - 2 * RING
    }

    /// The height of vertex `(i, j)` (map units).
    fn height(&self, i: u32, j: u32) -> f32 {
        self.map.at(i + RING, j + RING)
    }

    /// Metres between the chunk's vertices, for `cell_m` metres between level-0 samples.
    pub fn spacing_m(&self, cell_m: f32) -> f32 {
        cell_m * (1u32 << self.level) as f32
    }

    /// The chunk's meshes, banded by `rule`, with `geometry`'s spacing between level-0
    /// samples (the chunk's own vertices are `2^level` times as far apart), skirts `skirt_m`
    /// metres deep along its four sides (none for 0), and with `morph` (below the coarsest
    /// level) morphing into the next level's shape over its distances. Positions are in the
    /// world's metres (the barycentre is zero), so that the vertices neighbouring chunks share
    /// are placed bit for bit alike and their meshes meet without a gap.
    pub fn mesh(&self, geometry: Geometry, rule: &BandRule, skirt_m: f32, morph: Option<MorphBand>) -> ChunkMesh {
        let geometry = Geometry { cell_m: self.spacing_m(geometry.cell_m), ..geometry };
        let frame = self.frame();
        let n = self.vertices();
        let section = Section { origin: [RING, RING], size: [n, n] };
        let targets = morph.filter(|_| self.level + 1 < LEVELS).map(|band| self.morph_targets(geometry, band));
        let surfaces = mesh_section_in(&self.map, section, geometry, rule, frame, Placement::Samples, targets.as_ref());
        let corners = [frame.metres([0, 0], geometry.cell_m), frame.metres([n - 1, n - 1], geometry.cell_m)];
        let skirts = std::array::from_fn(|side| match skirt_m > 0.0 {
            true => {
                surfaces.bands.iter().chain(&surfaces.borders).map(|part| skirt(part, side, corners, skirt_m)).collect()
            }
            false => Vec::new(),
        });
        ChunkMesh { surfaces, skirts }
    }

    /// The world samples the chunk's vertices stand for: texture coordinates and positions
    /// fixed to them run on across chunks of every level.
    fn frame(&self) -> SampleFrame {
        let step = 1u32 << self.level;
        let cells = (self.vertices() - 1) * step;
        SampleFrame { origin: [self.key.x, self.key.z].map(|k| i64::from(k) * i64::from(cells)), step }
    }

    /// Where each vertex lies on the next coarser level's mesh, and that mesh's normal there,
    /// for vertices `geometry.cell_m` apart.
    fn morph_targets(&self, geometry: Geometry, band: MorphBand) -> MorphTargets {
        let (n, frame) = (self.vertices(), self.frame());
        // The coarser level's samples are every second of this chunk's, the first ring
        // dropped and the second kept as theirs.
        let side = self.map.width() / 2 + 1;
        let coarse = Heightmap::from_fn(side, side, |x, z| self.map.at(2 * x, 2 * z))
            .expect("half the chunk's samples, at most 67 a side");
        let coarse_geometry = Geometry { cell_m: geometry.cell_m * 2.0, ..geometry };
        let coarse_side = n.div_ceil(2);
        let coarse_section = Section { origin: [1, 1], size: [coarse_side; 2] };
        let coarse_normals = vertex_normals(&coarse, coarse_section, coarse_geometry);
        let (mut positions, mut normals) = (Vec::with_capacity((n * n) as usize), Vec::with_capacity((n * n) as usize));
        for j in 0..n {
            for i in 0..n {
                // The ends of the coarser edge or diagonal (of the cells' `a d` diagonal) the
                // vertex lies in the middle of; both itself where the coarser level keeps it.
                let [a, b] = match (i % 2, j % 2) {
                    (0, 0) => [[i, j]; 2],
                    (1, 0) => [[i - 1, j], [i + 1, j]],
                    (0, _) => [[i, j - 1], [i, j + 1]],
                    _ => [[i - 1, j - 1], [i + 1, j + 1]],
                };
                let metres = |[i, j]: [u32; 2]| self.height(i, j) * geometry.height_m;
                let normal = |[i, j]: [u32; 2]| coarse_normals[(j / 2 * coarse_side + i / 2) as usize];
                let (height, normal) = match a == b {
                    true => (metres(a), normal(a)),
                    false => ((metres(a) + metres(b)) * 0.5, (normal(a) + normal(b)).normalize_or(Vec3::Y)),
                };
                let [x, z] = frame.metres([i, j], geometry.cell_m);
                positions.push(Vec3::new(x, height, z));
                normals.push(normal);
            }
        }
        MorphTargets { positions, normals, start_m: band.start_m, end_m: band.end_m }
    }

    /// A checksum of the chunk's heights (vertices and ring), equal on every machine for
    /// equal heights.
    pub fn checksum(&self) -> u64 {
        self.map.checksum()
    }
}

/// The strip hanging `depth` metres below the edges of `mesh` on side `side` (an index into
/// [`SIDES`]) of its chunk, whose vertices lie from `corners[0]` to `corners[1]` metres along
/// x and z, facing out of the chunk; empty where the mesh has no edge there. Its top vertices
/// are copies of the edge's own, so it meets the surface without a gap.
fn skirt(mesh: &MeshData, side: usize, [low, high]: [[f32; 2]; 2], depth: f32) -> MeshData {
    // A vertex on the side has the corners' own coordinate there.
    let on_side = |v: u32| {
        let p = mesh.positions[v as usize];
        [p.x == low[0], p.x == high[0], p.z == low[1], p.z == high[1]][side]
    };
    let mut strip = MeshData {
        morph: mesh.morph.as_ref().map(|morph| Morph { positions: Vec::new(), normals: Vec::new(), ..*morph }),
        ..MeshData::default()
    };
    // Each edge vertex's top copy in the strip (its bottom copy follows it).
    let mut copies = vec![u32::MAX; mesh.positions.len()];
    for triangle in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (triangle[k], triangle[(k + 1) % 3]);
            if !(on_side(a) && on_side(b)) {
                continue;
            }
            let [a, b] = [a, b].map(|v| {
                if copies[v as usize] == u32::MAX {
                    copies[v as usize] = strip.positions.len() as u32;
                    let v = v as usize;
                    for drop in [0.0, depth] {
                        strip.positions.push(mesh.positions[v] - Vec3::Y * drop);
                        strip.normals.push(mesh.normals[v]);
                        if let (Some(from), Some(to)) = (&mesh.morph, &mut strip.morph) {
                            to.positions.push(from.positions[v] - Vec3::Y * drop);
                            to.normals.push(from.normals[v]);
                        }
                        strip.uvs.push(mesh.uvs[v]);
                        if !mesh.blend.is_empty() {
                            strip.blend.push(mesh.blend[v]);
                        }
                    }
                }
                copies[v as usize]
            });
            // Taken in its triangle's winding, the edge gives the strip's triangles the
            // winding that faces out of the chunk (front faces are counter-clockwise from
            // outside).
            strip.triangles.push([a, a + 1, b]);
            strip.triangles.push([b, a + 1, b + 1]);
        }
    }
    strip
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// A world of hills and mountains with `seed`.
    fn world_seeded(seed: u64) -> WorldHeights {
        let recipe = serde_yaml::from_str(
            "{size: [1, 1], seed: 3, layers: [{perlin: {scale: 40, octaves: 5}}, \
             {perlin: {scale: 150, octaves: 2}, weight: 0.8, apply: [{power: 3}]}]}",
        )
        .unwrap();
        WorldHeights::unbounded(Arc::new(recipe), seed)
    }

    fn world() -> WorldHeights {
        world_seeded(3)
    }

    /// Where world position `p` lies from the first vertex of `chunk` (samples `cell_m` apart).
    fn local(chunk: &ChunkHeights, p: Vec3, cell_m: f32) -> Vec3 {
        let cells = ((chunk.vertices() - 1) << chunk.level) as f32;
        p - Vec3::new(chunk.key.x as f32, 0.0, chunk.key.z as f32) * cells * cell_m
    }

    /// The heights of a chunk's vertices (without the ring), row by row.
    fn vertex_rows(chunk: &ChunkHeights) -> Vec<Vec<u32>> {
        let n = chunk.vertices() as usize;
        (0..n).map(|j| (0..n).map(|i| chunk.height(i as u32, j as u32).to_bits()).collect()).collect()
    }

    #[test]
    fn neighbours_share_their_edges_at_every_level() {
        let recipe = world();
        for level in 0..LEVELS {
            let chunk = |x, z| ChunkHeights::generate(&recipe, ChunkKey { x, z }, level, 32);
            let (here, east, south) = (chunk(-1, 2), chunk(0, 2), chunk(-1, 3));
            let (rows, east_rows, south_rows) = (vertex_rows(&here), vertex_rows(&east), vertex_rows(&south));
            let n = rows.len();
            assert_eq!(n, (32 >> level) + 1);
            for (row, east_row) in rows.iter().zip(&east_rows) {
                assert_eq!(row[n - 1], east_row[0], "level {level}: the east edge");
            }
            assert_eq!(rows[n - 1], south_rows[0], "level {level}: the south edge");
            // The meshes' vertices along the shared edge, placed in the world, and their
            // normals are equal too.
            let geometry = Geometry { cell_m: 0.3, height_m: 30.0, texture_cells: 8.0 };
            let rule = BandRule::default();
            let edge = |chunk: &ChunkHeights, column: usize| {
                let mesh = chunk.mesh(geometry, &rule, 0.0, None).surfaces;
                let spacing = geometry.cell_m * (1u32 << level) as f32;
                let mut edge: Vec<(i64, [u32; 3], [u32; 3])> = mesh
                    .bands
                    .iter()
                    .flat_map(|m| m.positions.iter().zip(&m.normals))
                    .filter(|(p, _)| (local(chunk, **p, geometry.cell_m).x / spacing).round() as usize == column)
                    .map(|(p, n)| {
                        let row = (local(chunk, *p, geometry.cell_m).z / spacing).round() as i64;
                        (row, p.to_array().map(f32::to_bits), n.to_array().map(f32::to_bits))
                    })
                    .collect();
                edge.sort();
                edge.dedup();
                edge
            };
            assert_eq!(edge(&here, n - 1), edge(&east, 0), "level {level}: vertices across the east edge");
        }
    }

    #[test]
    fn chunks_of_a_finite_map_cover_it_and_take_its_samples() {
        // 50 x 35 samples: 49 x 34 cells, whole chunks of 16 cells 4 x 3, the last ones
        // reaching beyond the map.
        let map = Heightmap::from_fn(50, 35, |x, z| (x * 100 + z) as f32 * 1e-4).unwrap();
        let heights = WorldHeights::Map(Arc::new(map.clone()));
        assert_eq!(heights.chunks(16), Some([4, 3]));
        assert_eq!(heights.chunks(64), Some([1, 1]));
        assert_eq!(world().chunks(16), None);
        for level in 0..LEVELS {
            let step = 1u32 << level;
            for (x, z) in [(0, 0), (3, 1), (2, 2)] {
                let chunk = ChunkHeights::generate(&heights, ChunkKey { x, z }, level, 16);
                let n = chunk.vertices();
                for (j, i) in (0..n).flat_map(|j| (0..n).map(move |i| (j, i))) {
                    // Samples beyond the map take the nearest edge sample's height.
                    let sample = |v: u32, key: i32, samples: u32| (key as u32 * 16 + v * step).min(samples - 1);
                    let expected = map.at(sample(i, x, 50), sample(j, z, 35));
                    assert_eq!(chunk.height(i, j), expected, "level {level}, chunk ({x}, {z}), vertex ({i}, {j})");
                }
                // The ring before the map's first sample repeats it.
                if x == 0 {
                    assert_eq!(chunk.map.at(0, RING), chunk.map.at(RING, RING));
                }
            }
        }
    }

    /// The eye and target the drawings look with: from above chunk `(0, 0)` across the border
    /// with chunk `(1, 0)` (chunks of 32 m).
    const EYE: Vec3 = Vec3::new(10.0, 75.0, 16.0);

    /// Chunks of 32 cells of a metre, each at its level and with `morph`, seen from [`EYE`]
    /// against a background the terrain cannot show, in white; with the lowest and highest
    /// heights inside them (metres).
    fn draw_chunks(
        chunks: &[(ChunkKey, u8)],
        skirt_m: f32,
        morph: Option<MorphBand>,
    ) -> (crate::raster::Framebuffer, crate::raster::Camera, [f32; 2]) {
        use crate::raster::{Camera, Frame, Framebuffer, Instance, Lens, Light, Material, RenderSettings, Renderer};
        use bevy::math::Mat4;
        use bevy::tasks::TaskPool;
        let geometry = Geometry { cell_m: 1.0, height_m: 60.0, texture_cells: 8.0 };
        let mut instances = Vec::new();
        let (mut lowest, mut highest) = (f32::MAX, f32::MIN);
        for &(key, level) in chunks {
            let chunk = ChunkHeights::generate(&world(), key, level, 32);
            let stats = chunk.map.stats();
            (lowest, highest) = (lowest.min(stats.min * geometry.height_m), highest.max(stats.max * geometry.height_m));
            let mesh = chunk.mesh(geometry, &BandRule::default(), skirt_m, morph);
            for part in mesh.surfaces.bands.into_iter().chain(mesh.skirts.into_iter().flatten()) {
                let model = Mat4::IDENTITY;
                instances.push(Instance { mesh: Arc::new(part), model, material: Material::colored(Vec3::ONE) });
            }
        }
        assert!(EYE.y > highest, "the eye above the ground");
        let camera = Camera {
            eye: EYE,
            target: Vec3::new(60.0, 20.0, 16.0),
            lens: Lens::FieldOfView(1.2),
            near: 0.1,
            far: 500.0,
        };
        let mut image = Framebuffer::new(400, 300);
        let light = Light { direction: Vec3::new(-0.5, -1.0, 0.3).normalize(), diffuse: 0.7, fill: 0.0, ambient: 0.3 };
        let settings = RenderSettings::default();
        let frame = Frame { camera, light, background: BACKGROUND, instances: &instances, settings };
        Renderer::default().render(&mut image, &TaskPool::new(), &frame);
        (image, camera, [lowest, highest])
    }

    const BACKGROUND: [u8; 4] = [255, 0, 255, 255];

    /// Chunks `(0, 0)` and `(1, 0)` side by side at `levels`, seen from above the first
    /// looking across their border: how many pixels whose ray must meet the ground (it ends
    /// below the lowest height inside the two chunks) show the background.
    fn background_through_the_border(levels: [u8; 2], skirt_m: f32) -> usize {
        let chunks = [(ChunkKey { x: 0, z: 0 }, levels[0]), (ChunkKey { x: 1, z: 0 }, levels[1])];
        let (image, camera, [lowest, _]) = draw_chunks(&chunks, skirt_m, None);
        let (width, height) = (image.width(), image.height());
        let world_from_ndc = camera.view_projection(width as f32 / height as f32).inverse();
        let floor = lowest - 1.0;
        let (x_end, z_end) = (64.0, 32.0);
        let mut holes = 0;
        for py in 0..height {
            for px in 0..width {
                let ndc = Vec3::new(
                    (px as f32 + 0.5) / width as f32 * 2.0 - 1.0,
                    1.0 - (py as f32 + 0.5) / height as f32 * 2.0,
                    0.0,
                );
                let (near, far) = (world_from_ndc.project_point3(ndc), world_from_ndc.project_point3(ndc.with_z(1.0)));
                if far.y >= near.y {
                    continue;
                }
                let end = near + (far - near) * ((near.y - floor) / (near.y - far.y));
                let inside = (0.5..x_end - 0.5).contains(&end.x) && (0.5..z_end - 0.5).contains(&end.z);
                holes += usize::from(inside && image.pixel(px, py) == BACKGROUND);
            }
        }
        holes
    }

    #[test]
    fn skirts_close_the_cracks_between_levels() {
        assert!(background_through_the_border([0, 2], 0.0) > 0, "without skirts the border shows cracks");
        assert_eq!(background_through_the_border([0, 2], 4.0), 0);
    }

    #[test]
    fn each_sides_skirt_hangs_from_that_side_alone_and_faces_out() {
        let geometry = Geometry { cell_m: 0.5, height_m: 30.0, texture_cells: 8.0 };
        let chunk = ChunkHeights::generate(&world(), ChunkKey { x: -3, z: 2 }, 1, 32);
        let mesh = chunk.mesh(geometry, &BandRule::default(), 2.0, None);
        // Chunk (-3, 2) of 16 m spans x from -48 to -32 m and z from 32 to 48 m.
        let sides = [(0, -48.0), (0, -32.0), (2, 32.0), (2, 48.0)];
        for (side, strips) in mesh.skirts.iter().enumerate() {
            let (axis, at) = sides[side];
            let outward = Vec3::new(SIDES[side][0] as f32, 0.0, SIDES[side][1] as f32);
            let mut triangles = 0;
            for strip in strips {
                assert!(strip.positions.iter().all(|p| p.to_array()[axis] == at), "side {side}");
                for t in &strip.triangles {
                    let [a, b, c] = t.map(|v| strip.positions[v as usize]);
                    // Counter-clockwise seen from outside: the face's normal points out.
                    assert!((b - a).cross(c - a).dot(outward) > 0.0, "side {side}: {t:?}");
                }
                triangles += strip.triangles.len();
            }
            assert_eq!(triangles, 2 * 16, "side {side}: two triangles under each of its 16 edges");
        }
        assert!(chunk.mesh(geometry, &BandRule::default(), 0.0, None).skirts.iter().all(Vec::is_empty));
    }

    #[test]
    fn chunks_of_one_level_meet_without_a_crack_and_without_skirts() {
        for level in 0..LEVELS {
            assert_eq!(background_through_the_border([level; 2], 0.0), 0, "level {level}");
        }
    }

    #[test]
    fn texture_coordinates_run_on_across_chunks_and_levels() {
        let recipe = world();
        let geometry = Geometry { cell_m: 0.5, height_m: 30.0, texture_cells: 8.0 };
        // The texture coordinates along one edge of a chunk, by the edge vertex's place along
        // z in level-0 samples.
        let edge = |key: ChunkKey, level: u8, east: bool| {
            let chunk = ChunkHeights::generate(&recipe, key, level, 32);
            let mesh = chunk.mesh(geometry, &BandRule::default(), 0.0, None).surfaces;
            let spacing = chunk.spacing_m(geometry.cell_m);
            let column = if east { 32.0 } else { 0.0 };
            let mut uvs: Vec<(i64, [u32; 2])> = mesh
                .bands
                .iter()
                .flat_map(|m| m.uvs.iter().zip(&m.positions))
                .map(|(uv, p)| (uv, local(&chunk, *p, geometry.cell_m)))
                .filter(|(_, p)| ((p.x / spacing).round() * (1 << level) as f32 - column).abs() < 0.5)
                .map(|(uv, p)| (((p.z / spacing).round() as i64) << level, uv.to_array().map(f32::to_bits)))
                .collect();
            uvs.sort();
            uvs.dedup();
            uvs
        };
        let (fine, coarse) = (edge(ChunkKey { x: 0, z: 0 }, 0, true), edge(ChunkKey { x: 1, z: 0 }, 2, false));
        assert_eq!(coarse.len(), 9);
        for (z, uv) in &coarse {
            assert_eq!(fine.iter().find(|(f, _)| f == z).map(|f| f.1), Some(*uv), "sample {z}");
        }
        // One texture repetition every `texture_cells` samples of the world.
        assert_eq!(fine[8].1.map(f32::from_bits), [32.0 / 8.0, 1.0]);
    }

    #[test]
    fn a_coarser_level_keeps_every_other_sample_and_chunks_are_deterministic() {
        let recipe = world();
        let key = ChunkKey { x: 4, z: -7 };
        let (fine, coarse) = (ChunkHeights::generate(&recipe, key, 0, 64), ChunkHeights::generate(&recipe, key, 1, 64));
        let (fine_rows, coarse_rows) = (vertex_rows(&fine), vertex_rows(&coarse));
        for (j, row) in coarse_rows.iter().enumerate() {
            for (i, h) in row.iter().enumerate() {
                assert_eq!(*h, fine_rows[2 * j][2 * i], "({i}, {j})");
            }
        }
        assert_eq!(fine.checksum(), ChunkHeights::generate(&recipe, key, 0, 64).checksum());
        assert_ne!(fine.checksum(), ChunkHeights::generate(&world_seeded(4), key, 0, 64).checksum());
    }

    #[test]
    fn a_fully_morphed_chunk_has_the_next_levels_surface_and_normals() {
        let recipe = world();
        let geometry = Geometry { cell_m: 0.5, height_m: 30.0, texture_cells: 8.0 };
        let band = MorphBand { start_m: 10.0, end_m: 20.0 };
        let key = ChunkKey { x: -2, z: 5 };
        for level in 0..LEVELS - 1 {
            let fine = ChunkHeights::generate(&recipe, key, level, 32)
                .mesh(geometry, &BandRule::default(), 0.0, Some(band))
                .surfaces;
            let coarse_heights = ChunkHeights::generate(&recipe, key, level + 1, 32);
            let coarse = coarse_heights.mesh(geometry, &BandRule::default(), 0.0, None).surfaces;
            let spacing = coarse_heights.spacing_m(geometry.cell_m);
            let at = |i: u32, j: u32| coarse_heights.height(i, j) * geometry.height_m;
            // The coarse mesh's normals by vertex.
            let grid = |p: Vec3| ((p.x / spacing).round() as u32, (p.z / spacing).round() as u32);
            let coarse_normals: HashMap<(u32, u32), Vec3> = coarse
                .bands
                .iter()
                .flat_map(|m| {
                    m.positions
                        .iter()
                        .zip(&m.normals)
                        .map(|(p, n)| (grid(local(&coarse_heights, *p, geometry.cell_m)), *n))
                })
                .collect();
            let mut on_vertices = 0;
            for part in &fine.bands {
                let morph = part.morph.as_ref().expect("a morph below the coarsest level");
                assert_eq!((morph.start_m, morph.end_m), (10.0, 20.0));
                assert_eq!(morph.positions.len(), part.positions.len());
                for (target, normal) in morph.positions.iter().zip(&morph.normals) {
                    let p = local(&coarse_heights, *target, geometry.cell_m);
                    // The height of the coarse triangle under the target (cells split along
                    // their a d diagonal).
                    let (u, v) = (p.x / spacing, p.z / spacing);
                    let (ci, cj) = (
                        (u.floor() as u32).min(coarse_heights.vertices() - 2),
                        (v.floor() as u32).min(coarse_heights.vertices() - 2),
                    );
                    let (fu, fv) = (u - ci as f32, v - cj as f32);
                    let (a, b, c, d) = (at(ci, cj), at(ci + 1, cj), at(ci, cj + 1), at(ci + 1, cj + 1));
                    let surface =
                        if fv >= fu { a + fv * (c - a) + fu * (d - c) } else { a + fu * (b - a) + fv * (d - b) };
                    assert!((p.y - surface).abs() < 1e-3, "level {level}: {p} off the coarser surface {surface}");
                    if (fu.abs() < 1e-4 || fu > 1.0 - 1e-4) && (fv.abs() < 1e-4 || fv > 1.0 - 1e-4) {
                        assert_eq!(
                            Some(normal),
                            coarse_normals.get(&grid(p)),
                            "level {level}: the coarser normal at {p}"
                        );
                        on_vertices += 1;
                    }
                }
            }
            assert!(on_vertices >= coarse_normals.len(), "level {level}: {on_vertices} targets on coarser vertices");
        }
    }

    /// The mean difference of two images of the same size, per colour channel.
    fn mean_difference(a: &crate::raster::Framebuffer, b: &crate::raster::Framebuffer) -> f64 {
        let sum: u64 = a.color().iter().zip(b.color()).map(|(x, y)| u64::from(x.abs_diff(*y))).sum();
        sum as f64 / a.color().len() as f64
    }

    #[test]
    fn a_change_of_level_after_the_morph_shows_almost_nothing() {
        let pair = |level| [(ChunkKey { x: 0, z: 0 }, level), (ChunkKey { x: 1, z: 0 }, level)];
        // Every vertex beyond the band: fully morphed.
        let through = Some(MorphBand { start_m: -2.0, end_m: -1.0 });
        for level in 0..LEVELS - 1 {
            let (coarse, ..) = draw_chunks(&pair(level + 1), 0.0, None);
            let (fine, ..) = draw_chunks(&pair(level), 0.0, None);
            let (morphed, ..) = draw_chunks(&pair(level), 0.0, through);
            let (pop, left) = (mean_difference(&fine, &coarse), mean_difference(&morphed, &coarse));
            assert!(pop > 0.5, "level {level}: the levels differ ({pop})");
            // What is left is Gouraud shading: lighting interpolated between the coarser vertices
            // against lit at the finer ones.
            assert!(left < pop * 0.25, "level {level}: {left} left of a change of {pop}");
        }
    }
}
