//! The streamed world: chunks around the camera at their levels, the same chunks for the same
//! camera path, new chunks ahead of a moving camera and far ones let go, the per-frame spawn
//! budget, finite worlds (a generated map, an image) streamed within their bounds, and trees
//! scattered over the near chunks, streaming with them.

use super::common::*;
use canopy::run::{RunOptions, run_headless};
use canopy::terrain::heightmap::Heightmap;
use canopy::terrain::image_io::{self, Encoding};
use canopy::tree::{ChunkTrees, SupportKind};
use canopy::view::CameraParams;
use canopy::world::chunk::{ChunkHeights, ChunkKey, SIDES, WorldHeights};
use canopy::world::{ChunkSkirt, WorldBody, WorldChunk};
use serde_json::Value;

/// The world scene's chunks as dumped: `(x, z, level, checksum)`.
fn chunks(land: &Value) -> Vec<(i64, i64, u64, String)> {
    let chunks = land["chunks"].as_array().unwrap();
    chunks
        .iter()
        .map(|c| {
            (c[0].as_i64().unwrap(), c[1].as_i64().unwrap(), c[2].as_u64().unwrap(), c[3].as_str().unwrap().into())
        })
        .collect()
}

/// The side of the world scene's chunks, metres.
const CHUNK_M: f32 = 16.0;

/// Horizontal distance from the camera of the centre of chunk `(x, z)`.
fn distance(camera: bevy::math::Vec3, x: i64, z: i64) -> f32 {
    let centre = (bevy::math::Vec2::new(x as f32, z as f32) + 0.5) * CHUNK_M;
    centre.distance(bevy::math::Vec2::new(camera.x, camera.z))
}

/// Horizontal distance from the camera of the nearest point of chunk `(x, z)`.
fn nearest(camera: bevy::math::Vec3, x: i64, z: i64) -> f32 {
    let [dx, dz] = [(x, camera.x), (z, camera.z)].map(|(k, at)| {
        let (low, high) = (k as f32 * CHUNK_M, (k + 1) as f32 * CHUNK_M);
        (low - at).max(at - high).max(0.0)
    });
    dx.hypot(dz)
}

#[test]
fn chunks_come_in_around_the_camera_at_their_levels_and_the_same_every_run() {
    let (first, second) = (run("scenes/world.yaml", 90, None, SMALL), run("scenes/world.yaml", 90, None, SMALL));
    let land = entity(&first.dump, "land");
    assert_eq!(land["kind"], "world");
    let resident = chunks(land);
    assert!(resident.len() > 50, "{} chunks", resident.len());
    assert_eq!(chunks(entity(&second.dump, "land")), resident, "the same chunks and heights every run");
    let camera = vec3(&entity(&first.dump, "camera")["position"]);
    // Within the load radius (180 m), each at the level of its nearest point taken half a
    // chunk nearer (levels from 50, 100 and 150 m).
    for &(x, z, level, _) in &resident {
        let d = distance(camera, x, z);
        assert!(d < 180.0, "({x}, {z}) at {d} m");
        let ahead = nearest(camera, x, z) - CHUNK_M / 2.0;
        let expected = [50.0, 100.0, 150.0].iter().filter(|&&from| ahead >= from).count() as u64;
        assert_eq!(level, expected, "({x}, {z}) at {d} m");
    }
    let per_level: Vec<u64> =
        land["resident_per_level"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    assert!(per_level.iter().all(|&n| n > 0), "every level in use: {per_level:?}");
    // The world is drawn: the ground fills the bottom of the frame.
    let background = [0xa9, 0xc8, 0xe8, 255];
    assert_ne!(first.framebuffer.pixel(80, 115), background);
}

#[test]
fn a_moving_camera_brings_chunks_ahead_and_lets_far_ones_go() {
    let timeline = std::fs::read_to_string(path("timelines/world_flight.yaml")).unwrap();
    let output = run("scenes/world.yaml", 240, Some(&timeline), SMALL);
    let again = run("scenes/world.yaml", 240, Some(&timeline), SMALL);
    assert_eq!(output.dump, again.dump, "the same camera path, the same chunks and heights");
    let land = entity(&output.dump, "land");
    let camera = vec3(&entity(&output.dump, "camera")["position"]);
    let resident = chunks(land);
    assert!(resident.iter().all(|&(x, z, ..)| distance(camera, x, z) <= 220.0), "nothing beyond the unload radius");
    assert!(resident.iter().all(|&(x, ..)| x > 10), "the chunks around the start are gone");
    assert!(resident.iter().any(|&(x, z, level, _)| level == 0 && distance(camera, x, z) < 50.0), "near chunks made");
    assert!(land["made"].as_u64().unwrap() > resident.len() as u64);
}

#[test]
fn no_frame_spawns_more_chunks_than_the_budget() {
    let mut app = small_app(&path("scenes/world.yaml"));
    let made =
        |app: &mut bevy::app::App| app.world_mut().query::<&WorldBody>().iter(app.world()).map(|b| b.made).sum::<u64>();
    let mut before = made(&mut app);
    let mut most = 0;
    for _ in 0..60 {
        app.update();
        let after = made(&mut app);
        most = most.max(after - before);
        before = after;
    }
    assert_eq!(most, 4, "the budget of scenes/world.yaml, reached and never passed");
    let chunks = app.world_mut().query::<&WorldChunk>().iter(app.world()).count();
    assert!(chunks > 50, "{chunks}");
}

#[test]
fn shift_and_the_arrows_fly_the_camera_level_at_its_speed() {
    let timeline = "
- { at: 0.0, press: [ShiftLeft, ArrowUp] }
- { at: 1.0, release: [ArrowUp] }
- { at: 1.0, press: [ArrowRight] }
- { at: 1.5, release: [ShiftLeft, ArrowRight] }
";
    let start = run("scenes/world.yaml", 1, None, SMALL);
    let flown = run("scenes/world.yaml", 120, Some(timeline), SMALL);
    let (camera, before) = (entity(&flown.dump, "camera"), entity(&start.dump, "camera"));
    let moved = vec3(&camera["target"]) - vec3(&before["target"]);
    // Looking towards -z from +z: 30 m forward (-z) in one second, then 15 m to the right (+x).
    assert!((moved.z + 30.0).abs() < 1.0 && (moved.x - 15.0).abs() < 1.0 && moved.y == 0.0, "{moved}");
    // The eye went along: the view itself did not turn.
    let eye_moved = vec3(&camera["position"]) - vec3(&before["position"]);
    assert!((eye_moved - moved).length() < 1e-3, "{eye_moved} vs {moved}");
}

#[test]
fn a_camera_jump_across_many_chunks_keeps_to_the_budget_and_settles() {
    let mut app = small_app(&path("scenes/world.yaml"));
    for _ in 0..30 {
        app.update();
    }
    let made =
        |app: &mut bevy::app::App| app.world_mut().query::<&WorldBody>().iter(app.world()).map(|b| b.made).sum::<u64>();
    // Two kilometres east in one step: every chunk wanted is new.
    for mut camera in app.world_mut().query::<&mut canopy::view::CameraParams>().iter_mut(app.world_mut()) {
        camera.target.x += 2000.0;
    }
    let mut before = made(&mut app);
    for frame in 0..90 {
        app.update();
        let after = made(&mut app);
        assert!(after - before <= 4, "frame {frame}: {} chunks spawned", after - before);
        before = after;
    }
    // The old neighbourhood is gone and the new one is there, nearest first at level 0.
    let chunks: Vec<WorldChunk> = app.world_mut().query::<&WorldChunk>().iter(app.world()).copied().collect();
    assert!(chunks.iter().all(|c| c.key.x as f32 * CHUNK_M > 1500.0), "only chunks around the new place");
    assert!(chunks.iter().any(|c| c.level == 0) && chunks.len() > 50, "{} chunks", chunks.len());
}

#[test]
fn chunks_made_in_advance_stream_as_the_same_chunks_at_the_same_frames() {
    // The same short flight twice: streamed, and with every chunk of it made beforehand.
    let resident = |in_advance: bool| {
        let mut app = small_app(&path("scenes/world.yaml"));
        let stream = *app.world_mut().query::<&WorldBody>().single(app.world()).unwrap().stream();
        if in_advance {
            let wanted: Vec<_> = (0..40)
                .flat_map(|frame| {
                    let camera = bevy::math::Vec2::new(frame as f32 * 4.0, 150.0);
                    let none = std::collections::HashMap::new();
                    canopy::world::stream::plan(&stream, camera, bevy::math::Vec2::X, &none, &none).requests
                })
                .collect();
            for mut body in app.world_mut().query::<&mut WorldBody>().iter_mut(app.world_mut()) {
                body.make_in_advance(wanted.iter().copied());
            }
        }
        let mut frames = Vec::new();
        for frame in 0..40 {
            for mut camera in app.world_mut().query::<&mut canopy::view::CameraParams>().iter_mut(app.world_mut()) {
                camera.target.x = frame as f32 * 4.0;
            }
            app.update();
            let mut chunks: Vec<WorldChunk> =
                app.world_mut().query::<&WorldChunk>().iter(app.world()).copied().collect();
            chunks.sort_by_key(|c| (c.key, c.level));
            frames.push(chunks);
        }
        let body = app.world_mut().query::<&WorldBody>().single(app.world()).unwrap();
        (frames, body.made, body.taken_ready)
    };
    let ((streamed, made, none_ready), (ready, made_too, taken)) = (resident(false), resident(true));
    assert_eq!(streamed, ready, "the same chunks, levels and heights at every frame");
    assert_eq!((made, none_ready), (made_too, 0), "as many chunks, none ready-made when streamed");
    // Made during the flight: only those of the start, asked for before the flight began.
    assert!(taken > 0 && made_too - taken < made / 2, "little left to make while flying: {taken} of {made} ready");
}

/// The valley scene's world definition as the app reads it.
fn valley_def() -> canopy::world::WorldDef {
    let loaded = canopy::app::entity_kinds().load(&path("scenes/valley.yaml")).unwrap();
    let entity = loaded.def.entities.iter().find(|e| e.key == "world").unwrap();
    entity.def.as_any().downcast_ref::<canopy::world::WorldDef>().unwrap().clone()
}

/// The checksum a chunk of `heights` has, as dumped.
fn checksum(heights: &WorldHeights, (x, z, level): (i64, i64, u64), cells: u32) -> String {
    let key = ChunkKey { x: x as i32, z: z as i32 };
    format!("{:016x}", ChunkHeights::generate(heights, key, level as u8, cells).checksum())
}

#[test]
fn a_finite_world_streams_the_chunks_of_its_map_and_no_others() {
    let output = run("scenes/valley.yaml", 90, None, SMALL);
    let valley = entity(&output.dump, "valley");
    assert_eq!(valley["bounds_chunks"], serde_json::json!([16, 16]), "257 samples: 16 chunks of 16 cells");
    let camera = vec3(&entity(&output.dump, "camera")["position"]);
    let resident = chunks(valley);
    let inside = |x: i64, z: i64| (0..16).contains(&x) && (0..16).contains(&z);
    assert!(resident.iter().all(|&(x, z, ..)| inside(x, z)), "only the map's chunks");
    // Every chunk of the map within the load radius (400 m) is there.
    let wanted = (0..16).flat_map(|z| (0..16).map(move |x| (x, z))).filter(|&(x, z)| distance(camera, x, z) < 400.0);
    assert_eq!(resident.len(), wanted.count());
    // Each has the map's heights: the whole generated map (hills and `normalize`), cut.
    let def = valley_def();
    let map = def.map.as_ref().unwrap().recipe().generate(5).unwrap();
    let heights = WorldHeights::Map(std::sync::Arc::new(map));
    for &(x, z, level, ref dumped) in &resident {
        assert_eq!(*dumped, checksum(&heights, (x, z, level), 16), "({x}, {z}) at level {level}");
    }
}

#[test]
fn a_world_over_an_image_streams_its_heights() {
    let folder = tempfile::tempdir().unwrap();
    // 40 x 24 samples: chunks of 16 cells 3 x 2, the last ones reaching beyond the image.
    let map =
        Heightmap::from_fn(40, 24, |x, z| ((x as f32 * 0.3).sin() + (z as f32 * 0.2).cos()) * 0.25 + 0.5).unwrap();
    image_io::save(&map, &folder.path().join("heights.png"), Encoding::Png16).unwrap();
    let scene = "
camera: { position: [20, 40, -30], look_at: [20, 0, 12] }
background: \"#ff00ff\"
entities:
  - name: land
    world:
      map: { image: heights.png }
      height_m: 10
";
    std::fs::write(folder.path().join("scene.yaml"), scene).unwrap();
    let options =
        RunOptions { scene: folder.path().join("scene.yaml"), frames: 10, timeline: None, size: SMALL, log: false };
    let output = run_headless(&options).unwrap_or_else(|e| panic!("{e}"));
    let land = entity(&output.dump, "land");
    assert_eq!(land["seed"], Value::Null, "an image has no seed");
    assert_eq!(land["bounds_chunks"], serde_json::json!([3, 2]));
    let decoded = image_io::decode(&std::fs::read(folder.path().join("heights.png")).unwrap()).unwrap();
    let heights = WorldHeights::Map(std::sync::Arc::new(decoded));
    let resident = chunks(land);
    assert_eq!(resident.len(), 6);
    for &(x, z, level, ref dumped) in &resident {
        assert_eq!(*dumped, checksum(&heights, (x, z, level), 16), "({x}, {z}) at level {level}");
    }
    // The ground fills the middle of the frame.
    assert_ne!(output.framebuffer.pixel(80, 60), [255, 0, 255, 255]);
}

#[test]
fn skirts_hang_where_levels_meet_and_nowhere_else() {
    let mut app = small_app(&path("scenes/world.yaml"));
    for frame in 0..120 {
        // Some flight, so that chunks change level under their skirts.
        for mut camera in app.world_mut().query::<&mut canopy::view::CameraParams>().iter_mut(app.world_mut()) {
            camera.target.x = frame as f32 * 0.5;
        }
        app.update();
    }
    let chunks: std::collections::HashMap<(i32, i32), (bevy::prelude::Entity, u8)> = app
        .world_mut()
        .query::<(bevy::prelude::Entity, &WorldChunk)>()
        .iter(app.world())
        .map(|(entity, c)| ((c.key.x, c.key.z), (entity, c.level)))
        .collect();
    let mut hung: Vec<(bevy::prelude::Entity, usize)> = app
        .world_mut()
        .query::<(&ChunkSkirt, &bevy::prelude::ChildOf)>()
        .iter(app.world())
        .map(|(skirt, parent)| (parent.parent(), skirt.side))
        .collect();
    hung.sort();
    let mut wanted = Vec::new();
    for (&(x, z), &(entity, level)) in &chunks {
        for (side, [dx, dz]) in SIDES.into_iter().enumerate() {
            if chunks.get(&(x + dx, z + dz)).is_some_and(|&(_, across)| across != level) {
                wanted.push((entity, side));
            }
        }
    }
    wanted.sort();
    assert!(wanted.len() > 20, "levels meet along many sides: {}", wanted.len());
    assert_eq!(hung, wanted, "a skirt on both sides of every border between levels, and on no other side");
}

/// The world scene's scattered trees: each chunk holding some, its level, and its trunks' bases.
fn scattered(app: &mut bevy::app::App) -> Vec<((i32, i32), u8, Vec<bevy::math::Vec3>)> {
    let mut trees = app.world_mut().query::<(&ChunkTrees, &bevy::prelude::ChildOf)>();
    let world = app.world();
    let mut found: Vec<_> = trees
        .iter(world)
        .map(|(trees, child_of)| {
            let chunk = world.get::<WorldChunk>(child_of.parent()).expect("trees are a chunk's children");
            let bases = trees.tree.supports.iter().filter(|s| s.kind == SupportKind::Trunk).map(|s| s.points[0]);
            ((chunk.key.x, chunk.key.z), chunk.level, bases.collect())
        })
        .collect();
    found.sort_by_key(|(key, ..)| *key);
    found
}

#[test]
fn trees_grow_on_the_near_chunks_stand_on_the_ground_and_stream_with_them() {
    let settle = |app: &mut bevy::app::App| (0..60).for_each(|_| app.update());
    let mut app = small_app(&path("scenes/world.yaml"));
    settle(&mut app);
    let trees = scattered(&mut app);
    let mut chunks = app.world_mut().query::<&WorldChunk>();
    let near: Vec<(i32, i32)> =
        chunks.iter(app.world()).filter(|chunk| chunk.level == 0).map(|chunk| (chunk.key.x, chunk.key.z)).collect();
    assert!(!near.is_empty());
    // A tree (`per_chunk`) on every chunk of the finest level, on no other.
    assert_eq!(trees.len(), near.len());
    assert!(trees.iter().all(|(key, level, bases)| *level == 0 && bases.len() == 1 && near.contains(key)));
    // Each trunk inside its chunk, standing on the ground as the chunk draws it.
    let mut bodies = app.world_mut().query::<&WorldBody>();
    let body = bodies.single(app.world()).unwrap();
    let (heights, geometry) = body.ground();
    for ((x, z), _, bases) in &trees {
        for base in bases {
            let ground = heights.ground_height(base.x, base.z, geometry);
            assert!((base.y - ground).abs() < 1e-4, "a trunk at {base} stands off the ground at {ground}");
            assert_eq!(((base.x / CHUNK_M).floor(), (base.z / CHUNK_M).floor()), (*x as f32, *z as f32));
        }
    }
    // The same trees in another run.
    let mut again = small_app(&path("scenes/world.yaml"));
    settle(&mut again);
    assert_eq!(scattered(&mut again), trees);
    // Far from there, the old chunks' trees are gone with them and the new near chunks have theirs.
    let mut cameras = app.world_mut().query::<&mut CameraParams>();
    cameras.single_mut(app.world_mut()).unwrap().target.x += 600.0;
    (0..4).for_each(|_| settle(&mut app));
    let moved = scattered(&mut app);
    assert!(!moved.is_empty() && moved.iter().all(|(key, ..)| !trees.iter().any(|(old, ..)| old == key)));
    let mut chunks = app.world_mut().query::<&WorldChunk>();
    let near = chunks.iter(app.world()).filter(|chunk| chunk.level == 0).count();
    assert_eq!(moved.len(), near);
}
