//! Terrain: the scene's section and bands, the source's demonstrations (moves, turns, scaling)
//! by parameters and keys, a new seed taken in off the main thread at the same frame every
//! run, heightmaps read from images, and missing images reported.

use super::common::*;
use canopy::run::{RunOptions, run_headless};
use canopy::terrain::TerrainDef;
use canopy::terrain::heightmap::Heightmap;
use canopy::terrain::image_io::{self, Encoding};
use serde_json::Value;

/// The terrain scene's definition as the app reads it.
fn terrain_def() -> TerrainDef {
    let loaded = canopy::app::entity_kinds().load(&path("scenes/terrain.yaml")).unwrap();
    let entity = loaded.def.entities.iter().find(|e| e.key == "terrain").unwrap();
    entity.def.as_any().downcast_ref::<TerrainDef>().unwrap().clone()
}

fn checksum_of(map: &Heightmap) -> String {
    format!("{:016x}", map.checksum())
}

fn section(land: &Value) -> (Vec<u64>, Vec<u64>) {
    let numbers = |v: &Value| v.as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    (numbers(&land["section"]["origin"]), numbers(&land["section"]["size"]))
}

#[test]
fn the_terrain_scene_shows_its_section_banded_and_dumps_its_map() {
    let output = run("scenes/terrain.yaml", 1, None, SMALL);
    let land = entity(&output.dump, "land");
    assert_eq!(land["kind"], "terrain");
    assert_eq!(land["map_size"], serde_json::json!([256, 256]));
    assert_eq!(section(land), (vec![120, 176], vec![64, 64]));
    assert_eq!(land["seed"], 7);
    let def = terrain_def();
    assert_eq!(land["checksum"], checksum_of(&def.height.recipe().generate(7).unwrap()));
    let bands = land["triangles_per_band"].as_object().unwrap();
    let total: u64 = bands.values().map(|n| n.as_u64().unwrap()).sum();
    assert_eq!(total, 2 * 63 * 63, "two triangles a cell");
    for band in ["water", "sand", "grass"] {
        assert!(bands[band].as_u64().unwrap() > 100, "{band}: {bands:?}");
    }
    // The section fills the middle of the frame.
    let background = [0xa9, 0xc8, 0xe8, 255];
    assert_ne!(output.framebuffer.pixel(80, 70), background);
    assert_eq!(output.framebuffer.pixel(2, 2), background);
}

#[test]
fn the_sources_demonstrations_move_turn_and_scale_the_section() {
    let timeline = std::fs::read_to_string(path("timelines/terrain_demonstrations.yaml")).unwrap();
    // The state half a second after each event of the timeline (one a second from 1 s).
    let at = |seconds: f64| run("scenes/terrain.yaml", (seconds * 60.0) as u64, Some(&timeline), SMALL);
    let start = run("scenes/terrain.yaml", 30, None, SMALL);
    let moved = at(1.5);
    assert_eq!(section(entity(&moved.dump, "land")).0, vec![130, 176], "moved 10 vertices along x");
    assert_ne!(start.framebuffer.color(), moved.framebuffer.color(), "the picture changed");
    let turned = at(2.5);
    assert_eq!(entity(&turned.dump, "land")["rotation_deg"], 45.0);
    let scaled = at(3.5);
    let scale = vec3(&entity(&scaled.dump, "land")["scale"]);
    assert_eq!((scale.x, scale.y, scale.z), (1.5, 2.0, 1.5));
    let lit = at(4.5);
    assert_eq!(entity(&lit.dump, "light")["azimuth_deg"], -60.0);
    assert_ne!(scaled.framebuffer.color(), lit.framebuffer.color(), "the light moved");
    let (without, with) = (at(5.5), at(6.5));
    assert_eq!(
        (entity(&without.dump, "render")["shadows"].as_bool(), entity(&with.dump, "render")["shadows"].as_bool()),
        (Some(false), Some(true))
    );
    // Shadows only darken: the picture with them is darker somewhere and nowhere brighter.
    let brightness = |output: &canopy::run::RunOutput| -> Vec<u32> {
        output.framebuffer.color().chunks_exact(4).map(|p| p[..3].iter().map(|&c| u32::from(c)).sum()).collect()
    };
    let (dark, light) = (brightness(&with), brightness(&without));
    assert!(dark.iter().zip(&light).all(|(d, l)| d <= l), "a shadow brightened a pixel");
    assert!(dark.iter().zip(&light).filter(|(d, l)| d < l).count() > 50, "no shadow fell");
    // A section pushed past the map's edge stops at it.
    let far = run("scenes/terrain.yaml", 2, Some("- { at: 0, set: { land.section.x: 1000 } }"), SMALL);
    assert_eq!(section(entity(&far.dump, "land")).0, vec![192, 176]);
}

#[test]
fn keys_move_the_section_by_one_sample_or_ten_with_shift() {
    let timeline = "
- { at: 0.0, press: [KeyD] }
- { at: 0.05, release: [KeyD] }
- { at: 0.1, press: [ShiftLeft, KeyS] }
- { at: 0.15, release: [ShiftLeft, KeyS] }
";
    let output = run("scenes/terrain.yaml", 20, Some(timeline), SMALL);
    assert_eq!(section(entity(&output.dump, "land")).0, vec![121, 186]);
    // Pushed against the map's far edge (z 192 for 64 of 256 samples) it stops there, and the
    // first key back moves it at once.
    let timeline = "
- { at: 0.0, press: [ShiftLeft, KeyS] }
- { at: 0.05, release: [KeyS] }
- { at: 0.1, press: [KeyS] }
- { at: 0.15, release: [KeyS] }
- { at: 0.2, press: [KeyS] }
- { at: 0.25, release: [ShiftLeft, KeyS] }
- { at: 0.3, press: [KeyW] }
- { at: 0.35, release: [KeyW] }
";
    let output = run("scenes/terrain.yaml", 30, Some(timeline), SMALL);
    let land = entity(&output.dump, "land");
    assert_eq!(section(land).0, vec![120, 191]);
}

#[test]
fn a_new_seed_makes_the_map_again_and_every_run_takes_it_at_the_same_frame() {
    let timeline = "- { at: 0.1, set: { land.noise.seed: 8, land.noise.octaves: 3 } }";
    let first = run("scenes/terrain.yaml", 20, Some(timeline), SMALL);
    let second = run("scenes/terrain.yaml", 20, Some(timeline), SMALL);
    assert_eq!(first.dump, second.dump);
    let land = entity(&first.dump, "land");
    assert_eq!(land["seed"], 8);
    let mut def = terrain_def();
    def.height.layers[0].perlin.as_mut().unwrap().octaves = 3;
    assert_eq!(land["checksum"], checksum_of(&def.height.recipe().generate(8).unwrap()));
    // Three frames after the request the old map still shows; the new one is in by the fourth.
    let early = run("scenes/terrain.yaml", 8, Some(timeline), SMALL);
    assert_eq!(entity(&early.dump, "land")["seed"], 7);
}

#[test]
fn a_heightmap_image_is_the_map_and_a_missing_one_is_an_error() {
    let folder = tempfile::tempdir().unwrap();
    let map = Heightmap::from_fn(40, 30, |x, z| ((x as f32 * 0.3).sin() + (z as f32 * 0.2).cos() + 2.0) / 4.0).unwrap();
    image_io::save(&map, &folder.path().join("map.png"), Encoding::Png16).unwrap();
    let expected = image_io::decode(&std::fs::read(folder.path().join("map.png")).unwrap()).unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(
        &scene,
        "entities:\n  - terrain:\n      height: { image: map.png }\n      section: { size: [40, 30] }\n",
    )
    .unwrap();
    let options = |scene| RunOptions { scene, frames: 1, timeline: None, size: SMALL, log: false };
    let output = run_headless(&options(scene)).unwrap();
    let terrain = entity(&output.dump, "terrain");
    assert_eq!(terrain["map_size"], serde_json::json!([40, 30]));
    assert_eq!(terrain["checksum"], checksum_of(&expected));
    assert_eq!(terrain["seed"], Value::Null);

    let missing = folder.path().join("missing.yaml");
    std::fs::write(&missing, "entities:\n  - terrain:\n      height: { image: none.png }\n").unwrap();
    let error = run_headless(&options(missing)).err().unwrap().to_string();
    assert!(error.contains("none.png") && error.contains("cannot read"), "{error}");
}

#[test]
fn the_whole_recipe_changed_in_the_panel_makes_the_map_again_and_is_saved() {
    use canopy::terrain::TerrainBody;
    use canopy::terrain::recipe::{Function, HillsLayer, Layer, Op};
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("terrain.yaml");
    let text = "entities:\n  - name: land\n    terrain:\n      height: { size: [64, 64], seed: 7, layers: \
                [{ perlin: { scale: 16 } }, { perlin: { scale: 4, octaves: 2 }, weight: 0.2 }] }\n      \
                section: { origin: [0, 0], size: [32, 32] }\n";
    std::fs::write(&scene, text).unwrap();
    let mut app = small_app(&scene);
    let world = app.world_mut();
    let mut bodies = world.query::<&mut TerrainBody>();
    let mut recipe = bodies.single(world).unwrap().recipe.clone().unwrap();
    recipe.seed = 7;
    // Another size, a hill layer moved to the front, the last layer's functions and the map's own.
    recipe.size = [96, 80];
    let hills = Layer { hills: Some(HillsLayer { count: 30, ..HillsLayer::default() }), ..Layer::default() };
    recipe.layers.insert(0, hills);
    recipe.layers[1].op = Op::Max;
    recipe.layers.last_mut().unwrap().apply.push(Function::Terraces(6));
    recipe.apply = vec![Function::Normalize, Function::Power(1.5)];
    // A recipe that fails the file's checks changes nothing and says why.
    let mut wrong = recipe.clone();
    wrong.layers[0].hills.as_mut().unwrap().radius = [40.0, 4.0];
    bodies.single_mut(world).unwrap().remake(wrong);
    let message = bodies.single(world).unwrap().message.clone().unwrap_or_default();
    assert!(message.starts_with("layers[0].hills"), "{message}");
    bodies.single_mut(world).unwrap().remake(recipe.clone());
    for _ in 0..5 {
        app.update();
    }
    let world = app.world_mut();
    let body = world.query::<&TerrainBody>().single(world).unwrap();
    assert_eq!((body.map.width(), body.map.height()), (96, 80), "{:?}", body.message);
    assert_eq!(body.recipe.as_ref(), Some(&recipe));
    assert_eq!(*body.map, recipe.generate(7).unwrap(), "off the main thread, the same map");
    canopy::scene::save_live_scene(app.world_mut()).unwrap();
    // The saved scene reads and checks, and holds the recipe as made.
    if let Err(error) = canopy::app::entity_kinds().load(&scene) {
        panic!("{error}");
    }
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("terraces: 6") && text.contains("op: max"), "{text}");
    let saved: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let height = &saved["entities"][0]["terrain"]["height"];
    assert_eq!(height["size"], serde_yaml::to_value([96, 80]).unwrap());
    assert_eq!(height["layers"][0]["hills"]["count"], 30);
    assert_eq!(height["seed"], 7);
}
