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
use crate::terrain::ground::cell_surface;
use crate::terrain::heightmap::Heightmap;
use crate::terrain::noise::Fbm;
use crate::terrain::recipe::Recipe;
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
mod tests;
