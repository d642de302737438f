//! The same view drawn through a world's chunks and as the terrain kind's fixed section: the
//! 65 x 65 vertices of `scenes/terrain.yaml`'s section (its map cut there, written as a 16-bit
//! PNG) seen from that scene's camera at 1280x720 with shadows, once as a `terrain` section and
//! once as a finite `world` of 4 x 4 chunks of 16 cells, with every chunk at level 0 (the same
//! triangles, plus skirts) and with the levels of detail a world would use. Frames with the
//! camera still, every frame drawn, the three alternating in rounds; the frames' wall-clock
//! time (simulation, streaming and raster) is taken.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench section_chunks [-- FRAMES]` (the profile of
//! `cargo run`).

#[path = "common/frame_times.rs"]
mod frame_times;

use bevy::math::UVec2;
use canopy::app::{entity_kinds, headless_app};
use canopy::raster::Framebuffer;
use canopy::raster::plugin::{RasterTarget, RenderPolicy};
use canopy::run::update_until_loaded;
use canopy::terrain::TerrainDef;
use canopy::terrain::heightmap::Heightmap;
use canopy::terrain::image_io::{self, Encoding};
use frame_times::figures;
use std::path::Path;
use std::time::{Duration, Instant};

const SIZE: UVec2 = UVec2::new(1280, 720);
/// Frames before the measured ones: chunks arrive, caches warm up.
const SETTLE: u32 = 30;
/// Vertices a side of the section: 64 cells, four chunks of 16.
const SIDE: u32 = 65;
/// Metres between samples, as in the terrain scene.
const CELL_M: f32 = 0.25;

/// The camera, light and render settings of `scenes/terrain.yaml`, the camera moved by
/// `offset` metres along x and z (the section is centred on the origin, the world starts
/// there).
fn view(offset: f32) -> String {
    format!(
        "camera: {{ position: [{x}, 11.0, {z}], look_at: [{offset}, 1.5, {offset}], fov_deg: 90 }}
light: {{ direction: [-0.6, -0.7, -0.4], diffuse: 1.0, ambient: 0.175 }}
background: \"#a9c8e8\"
render: {{ shading: gouraud, shadows: true }}
",
        x = offset,
        z = 13.0 + offset
    )
}

/// The bands of `scenes/terrain.yaml` (with the project's own textures).
const BANDS: &str = "{ thresholds: [0.3, 0.34, 0.6, 0.78], rock_slope_deg: 45, \
                     blend: { height: 0.015, slope_deg: 5 }, texture_cells: 8 }";

/// The three scenes, written into `folder` with the map as `map.png`: name and file.
fn scenes(folder: &Path) -> Vec<(&'static str, std::path::PathBuf)> {
    let section = format!(
        "{}entities:
  - name: land
    terrain:
      height: {{ image: map.png }}
      section: {{ origin: [0, 0], size: [{SIDE}, {SIDE}] }}
      cell_m: {CELL_M}
      height_m: 6
      bands: {BANDS}
",
        view(0.0)
    );
    let world = |levels: &str| {
        format!(
            "{}entities:
  - name: land
    world:
      map: {{ image: map.png }}
      chunk_cells: 16
      cell_m: {CELL_M}
      height_m: 6
      load_radius_m: 40
      unload_radius_m: 50
      level_distances_m: {levels}
      skirt_m: 0.5
      spawn_budget: 16
      bands: {BANDS}
",
            view((SIDE - 1) as f32 * CELL_M / 2.0)
        )
    };
    let files = [
        ("section", section),
        ("chunks, level 0", world("[1000, 2000, 3000]")),
        ("chunks, levels", world("[9, 18, 27]")),
    ];
    files
        .into_iter()
        .enumerate()
        .map(|(index, (name, text))| {
            let file = folder.join(format!("scene{index}.yaml"));
            std::fs::write(&file, text).expect("a scene in the temporary folder");
            (name, file)
        })
        .collect()
}

/// The terrain scene's map, cut to its section's 65 x 65 vertices.
fn section_map() -> Heightmap {
    let loaded = entity_kinds().load(Path::new("scenes/terrain.yaml")).expect("scenes/terrain.yaml");
    let entity = loaded.def.entities.iter().find(|e| e.key == "terrain").expect("its terrain");
    let def = entity.def.as_any().downcast_ref::<TerrainDef>().expect("a terrain definition");
    let map = def.height.recipe().generate(def.height.seed as u64).expect("the scene's map");
    let [x0, z0] = def.section.origin;
    Heightmap::from_fn(SIDE, SIDE, |x, z| map.at(x0 + x, z0 + z)).expect("a 65 x 65 map")
}

/// `frames` frames of `scene` with the camera still; their times and the last frame.
fn frames(scene: &Path, frames: u32) -> Result<(Vec<Duration>, Framebuffer), String> {
    let mut app = headless_app(scene, SIZE, false).map_err(|e| e.to_string())?;
    update_until_loaded(&mut app, scene).map_err(|e| e.to_string())?;
    app.world_mut().resource_mut::<RenderPolicy>().every_frame = true;
    let mut times = Vec::with_capacity(frames as usize);
    for frame in 0..SETTLE + frames {
        let started = Instant::now();
        app.update();
        if frame >= SETTLE {
            times.push(started.elapsed());
        }
    }
    Ok((times, app.world().resource::<RasterTarget>().framebuffer.clone()))
}

/// The background of the scenes.
const BACKGROUND: [u8; 4] = [0xa9, 0xc8, 0xe8, 255];

/// The mean difference of two frames' colour channels (0 to 255) over the pixels where
/// either shows the terrain, and the share of those pixels that differ at all.
fn difference(a: &Framebuffer, b: &Framebuffer) -> (f64, f64) {
    let pixels = a.color().chunks_exact(4).zip(b.color().chunks_exact(4));
    let terrain: Vec<(&[u8], &[u8])> = pixels.filter(|(p, q)| *p != BACKGROUND || *q != BACKGROUND).collect();
    let channels: u32 =
        terrain.iter().flat_map(|(p, q)| p.iter().zip(*q)).map(|(x, y)| u32::from(x.abs_diff(*y))).sum();
    let differing = terrain.iter().filter(|(p, q)| p != q).count();
    let count = terrain.len().max(1) as f64;
    (f64::from(channels) / (count * 4.0), differing as f64 / count)
}

fn main() {
    canopy_bench::at_workspace_root();
    // `cargo bench` passes `--bench`; a number is the frames measured per scene and round.
    let count: u32 = std::env::args().skip(1).find_map(|a| a.parse().ok()).unwrap_or(300);
    let folder = tempfile::tempdir().expect("a temporary folder");
    image_io::save(&section_map(), &folder.path().join("map.png"), Encoding::Png16).expect("the map written");
    let scenes = scenes(folder.path());
    println!("scenes/terrain.yaml's section and view, {}x{}, {count} frames each, alternating", SIZE.x, SIZE.y);
    println!("| drawn as | round | median ms | p99 ms |");
    println!("|---|---|---|---|");
    let mut medians = vec![Vec::new(); scenes.len()];
    let mut last = Vec::new();
    for round in 0..3 {
        last.clear();
        for (index, (name, scene)) in scenes.iter().enumerate() {
            let (times, image) = frames(scene, count).unwrap_or_else(|error| {
                eprintln!("{error}");
                std::process::exit(1)
            });
            let [median, p99, _] = figures(&times);
            println!("| {name} | {} | {median:.2} | {p99:.2} |", round + 1);
            medians[index].push(median);
            last.push(image);
        }
    }
    println!();
    for (index, (name, _)) in scenes.iter().enumerate().skip(1) {
        let ratios: Vec<String> = medians[index]
            .iter()
            .zip(&medians[0])
            .map(|(chunks, section)| format!("{:.2}", chunks / section))
            .collect();
        let (mean, share) = difference(&last[index], &last[0]);
        println!(
            "{name} / section, median per round: {}; against the section's frame, over the terrain's pixels: \
             {:.0} % differ, by {mean:.2} of 255 on average",
            ratios.join(", "),
            share * 100.0
        );
    }
}
