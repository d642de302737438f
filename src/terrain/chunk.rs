//! Chunks of an unbounded world: square pieces of the world's heights, `cells` cells a side,
//! at a level of detail, each made from the world's recipe at world sample positions alone, so
//! that neighbouring chunks share their edge heights, and their edge normals, bit for bit.
//!
//! Level `l` keeps every `2^l`-th sample: a chunk has `cells / 2^l + 1` vertices a side, and
//! one ring of samples beyond its edges (at its own spacing) from which the normals at its
//! edges are made as in the middle of the map.

use super::bands::BandRule;
use super::generate::Recipe;
use super::heightmap::Heightmap;
use super::section::{Geometry, Section, SectionMesh, mesh_section};

/// Levels of detail: level 0 has every sample, each next level every second of the one
/// before.
pub const LEVELS: u8 = 4;

/// The chunk sizes allowed, in cells a side: powers of two with a vertex at every level.
pub const CHUNK_CELLS: [u32; 4] = [16, 32, 64, 128];

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
    /// Its vertices and the ring beyond them: `cells / 2^level + 3` samples a side, the first
    /// vertex at `(1, 1)`.
    pub map: Heightmap,
}

impl ChunkHeights {
    /// The heights of chunk `key` at `level` (below [`LEVELS`]) of a world of chunks of
    /// `cells` cells (one of [`CHUNK_CELLS`]) made by `recipe` (checked, and unbounded by
    /// [`Recipe::check_unbounded`]) with `seed`.
    pub fn generate(recipe: &Recipe, seed: u64, key: ChunkKey, level: u8, cells: u32) -> Self {
        let level = level.min(LEVELS - 1);
        // Other sizes are brought to the nearest allowed bound: a chunk stays small.
        let cells = cells.clamp(CHUNK_CELLS[0], CHUNK_CELLS[CHUNK_CELLS.len() - 1]);
        let step = 1i32 << level;
        let side = (cells >> level) as usize + 3;
        let origin = [key.x * cells as i32 - step, key.z * cells as i32 - step];
        let heights = recipe.sample_grid(seed, origin, step, [side, side]);
        let map = Heightmap::from_values(side as u32, side as u32, heights)
            .expect("a grid of side x side heights, at most 131 a side");
        Self { key, level, map }
    }

    /// Vertices a side.
    pub fn vertices(&self) -> u32 {
        self.map.width() - 2
    }

    /// The chunk's meshes, banded by `rule`, with `geometry`'s spacing between level-0
    /// samples (the chunk's own vertices are `2^level` times as far apart).
    pub fn mesh(&self, geometry: Geometry, rule: &BandRule) -> SectionMesh {
        let geometry = Geometry { cell_m: geometry.cell_m * (1u32 << self.level) as f32, ..geometry };
        let n = self.vertices();
        mesh_section(&self.map, Section { origin: [1, 1], size: [n, n] }, geometry, rule)
    }

    /// A checksum of the chunk's heights (vertices and ring), equal on every machine for
    /// equal heights.
    pub fn checksum(&self) -> u64 {
        self.map.checksum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn world() -> Recipe {
        serde_yaml::from_str(
            "{size: [1, 1], seed: 3, layers: [{perlin: {scale: 40, octaves: 5}}, \
             {perlin: {scale: 150, octaves: 2}, weight: 0.8, apply: [{power: 3}]}]}",
        )
        .unwrap()
    }

    /// The heights of a chunk's vertices (without the ring), row by row.
    fn vertex_rows(chunk: &ChunkHeights) -> Vec<Vec<u32>> {
        let n = chunk.vertices() as usize;
        (1..=n).map(|z| chunk.map.row(z as u32)[1..=n].iter().map(|h| h.to_bits()).collect()).collect()
    }

    #[test]
    fn neighbours_share_their_edges_at_every_level() {
        let recipe = world();
        for level in 0..LEVELS {
            let chunk = |x, z| ChunkHeights::generate(&recipe, 3, ChunkKey { x, z }, level, 32);
            let (here, east, south) = (chunk(-1, 2), chunk(0, 2), chunk(-1, 3));
            let (rows, east_rows, south_rows) = (vertex_rows(&here), vertex_rows(&east), vertex_rows(&south));
            let n = rows.len();
            assert_eq!(n, (32 >> level) + 1);
            for (row, east_row) in rows.iter().zip(&east_rows) {
                assert_eq!(row[n - 1], east_row[0], "level {level}: the east edge");
            }
            assert_eq!(rows[n - 1], south_rows[0], "level {level}: the south edge");
            // The meshes' normals along the shared edge are equal too.
            let geometry = Geometry { cell_m: 0.3, height_m: 30.0, texture_cells: 8.0 };
            let rule = BandRule::default();
            let normals = |chunk: &ChunkHeights, column: usize| {
                let mesh = chunk.mesh(geometry, &rule);
                let spacing = geometry.cell_m * (1u32 << level) as f32;
                let mut edge: Vec<(i64, [u32; 3])> = mesh
                    .bands
                    .iter()
                    .flat_map(|m| m.positions.iter().zip(&m.normals))
                    .map(|(p, n)| (*p + mesh.barycentre, n))
                    .filter(|(p, _)| (p.x / spacing).round() as usize == column)
                    .map(|(p, n)| ((p.z / spacing).round() as i64, n.to_array().map(f32::to_bits)))
                    .collect();
                edge.sort();
                edge.dedup();
                edge
            };
            assert_eq!(normals(&here, n - 1), normals(&east, 0), "level {level}: normals across the east edge");
        }
    }

    #[test]
    fn a_coarser_level_keeps_every_other_sample_and_chunks_are_deterministic() {
        let recipe = world();
        let key = ChunkKey { x: 4, z: -7 };
        let (fine, coarse) =
            (ChunkHeights::generate(&recipe, 3, key, 0, 64), ChunkHeights::generate(&recipe, 3, key, 1, 64));
        let (fine_rows, coarse_rows) = (vertex_rows(&fine), vertex_rows(&coarse));
        for (j, row) in coarse_rows.iter().enumerate() {
            for (i, h) in row.iter().enumerate() {
                assert_eq!(*h, fine_rows[2 * j][2 * i], "({i}, {j})");
            }
        }
        assert_eq!(fine.checksum(), ChunkHeights::generate(&recipe, 3, key, 0, 64).checksum());
        assert_ne!(fine.checksum(), ChunkHeights::generate(&recipe, 4, key, 0, 64).checksum());
    }
}
