//! Making the chunks of a streamed world on one core: chunks a second at each level of detail
//! (heights and meshes, as the world kind makes them), the memory a resident chunk's meshes
//! take, and what that gives for the resident set the streaming radii allow.
//!
//! Run with `cargo bench -p canopy_bench --bench world_chunks`.

use canopy::terrain::bands::{BandBlend, BandRule};
use canopy::terrain::recipe::Recipe;
use canopy::terrain::section::Geometry;
use canopy::world::chunk::{ChunkHeights, ChunkKey, LEVELS, WorldHeights};
use canopy::world::stream::StreamSettings;
use std::hint::black_box;
use std::time::Instant;

/// Chunks made per level and measurement.
const CHUNKS: i32 = 64;
const CELLS: u32 = 16;

fn main() {
    // The recipe, geometry and bands of scenes/world.yaml.
    let recipe: Recipe = serde_yaml::from_str(
        "{size: [1, 1], seed: 11, layers: [{perlin: {scale: 120, octaves: 5}}, \
         {perlin: {scale: 400, octaves: 3}, weight: 0.9, apply: [{power: 3}]}]}",
    )
    .expect("the world's recipe");
    let heights = WorldHeights::unbounded(std::sync::Arc::new(recipe), 11);
    let geometry = Geometry { cell_m: 1.0, height_m: 60.0, texture_cells: 8.0 };
    let rule = BandRule {
        thresholds: [0.32, 0.36, 0.62, 0.8],
        rock_slope_deg: Some(40.0),
        blend: Some(BandBlend { height: 0.02, slope_deg: 5.0 }),
    };
    // The streaming settings of scenes/world.yaml, for the morph bands.
    let world = StreamSettings {
        chunk_m: CELLS as f32 * geometry.cell_m,
        load_radius_m: 180.0,
        unload_radius_m: 220.0,
        level_distances_m: [50.0, 100.0, 150.0],
        bounds: None,
    };
    println!("chunks of {CELLS} x {CELLS} cells, one core, {CHUNKS} chunks a level");
    println!("| level | vertices a side | chunks / s | ms / chunk | mesh bytes / chunk |");
    println!("|---|---|---|---|---|");
    let mut bytes_per_level = [0usize; LEVELS as usize];
    for level in 0..LEVELS {
        let mut bytes = 0;
        let started = Instant::now();
        for k in 0..CHUNKS {
            let key = ChunkKey { x: k % 8, z: k / 8 + 100 * i32::from(level) };
            let chunk = ChunkHeights::generate(&heights, key, level, CELLS);
            let mesh = black_box(chunk.mesh(geometry, &rule, 3.0, world.morph_band(level)));
            bytes += mesh
                .surfaces
                .into_surfaces()
                .iter()
                .chain(mesh.skirts.iter().flatten())
                .map(|m| {
                    let morph = m.morph.as_ref().map_or(0, |morph| morph.positions.len() * 24);
                    m.positions.len() * 24 + morph + m.uvs.len() * 8 + m.blend.len() * 4 + m.triangles.len() * 12
                })
                .sum::<usize>();
        }
        let seconds = started.elapsed().as_secs_f64();
        bytes_per_level[level as usize] = bytes / CHUNKS as usize;
        println!(
            "| {level} | {} | {:.0} | {:.2} | {} |",
            (CELLS >> level) + 1,
            f64::from(CHUNKS) / seconds,
            seconds * 1e3 / f64::from(CHUNKS),
            bytes / CHUNKS as usize
        );
    }
    println!();
    println!("| load radius | unload radius | resident bound | chunks within the unload radius | their meshes |");
    println!("|---|---|---|---|---|");
    for load in [90.0f32, 180.0, 360.0] {
        let settings = StreamSettings { load_radius_m: load, unload_radius_m: load * 1.25, ..world };
        // A camera over the middle of a chunk: the chunks whose centres lie within the
        // unload radius, each with the meshes of its level.
        let camera = settings.centre(ChunkKey { x: 0, z: 0 });
        let reach = (settings.unload_radius_m / settings.chunk_m).ceil() as i32;
        let within: Vec<ChunkKey> = (-reach..=reach)
            .flat_map(|z| (-reach..=reach).map(move |x| ChunkKey { x, z }))
            .filter(|&key| settings.centre(key).distance(camera) <= settings.unload_radius_m)
            .collect();
        let bytes: usize = within.iter().map(|&key| bytes_per_level[settings.chunk_level(key, camera) as usize]).sum();
        println!(
            "| {load} m | {} m | {} chunks | {} chunks | {:.1} MB |",
            settings.unload_radius_m,
            settings.max_resident(),
            within.len(),
            bytes as f64 / 1e6
        );
    }
}
