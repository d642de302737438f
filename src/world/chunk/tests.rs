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
    let camera =
        Camera { eye: EYE, target: Vec3::new(60.0, 20.0, 16.0), lens: Lens::FieldOfView(1.2), near: 0.1, far: 500.0 };
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
                m.positions.iter().zip(&m.normals).map(|(p, n)| (grid(local(&coarse_heights, *p, geometry.cell_m)), *n))
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
                let surface = if fv >= fu { a + fv * (c - a) + fu * (d - c) } else { a + fu * (b - a) + fv * (d - b) };
                assert!((p.y - surface).abs() < 1e-3, "level {level}: {p} off the coarser surface {surface}");
                if (fu.abs() < 1e-4 || fu > 1.0 - 1e-4) && (fv.abs() < 1e-4 || fv > 1.0 - 1e-4) {
                    assert_eq!(Some(normal), coarse_normals.get(&grid(p)), "level {level}: the coarser normal at {p}");
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
