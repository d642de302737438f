//! System tests: the real plugins, headless, on scenes from disk, checked through the state
//! dump and the framebuffer.

mod common;

use bevy::math::{UVec2, Vec3};
use canopy::controls::ReloadScene;
use canopy::dump::dump_state;
use canopy::raster::Framebuffer;
use canopy::run::{RunOptions, RunOutput, run_headless};
use canopy::scene::{ActiveScene, SceneStatus};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Runs `scene` for `frames` steps with an optional timeline given as YAML text.
fn run(scene: &str, frames: u64, timeline: Option<&str>, size: UVec2) -> RunOutput {
    let folder = tempfile::tempdir().unwrap();
    let timeline = timeline.map(|text| {
        let file = folder.path().join("timeline.yaml");
        std::fs::write(&file, text).unwrap();
        file
    });
    let options = RunOptions { scene: path(scene), frames, timeline, size, log: false };
    run_headless(&options).unwrap_or_else(|e| panic!("{e}"))
}

fn entity<'a>(dump: &'a Value, name: &str) -> &'a Value {
    dump["entities"].as_array().unwrap().iter().find(|e| e["name"] == name).unwrap_or_else(|| panic!("no {name}"))
}

fn vec3(value: &Value) -> Vec3 {
    let a: Vec<f32> = value.as_array().unwrap().iter().map(|v| v.as_f64().unwrap() as f32).collect();
    Vec3::new(a[0], a[1], a[2])
}

fn count_pixels(framebuffer: &Framebuffer, rgba: [u8; 4]) -> usize {
    framebuffer.color().chunks_exact(4).filter(|p| *p == rgba).count()
}

const SMALL: UVec2 = UVec2::new(160, 120);
const RED: [u8; 4] = [255, 0, 0, 255];
const GREEN: [u8; 4] = [0, 255, 0, 255];
const SKY: [u8; 4] = [0, 0, 255, 255];

#[test]
fn a_red_sphere_in_front_of_the_camera_is_red_at_the_centre_with_sky_at_the_corners() {
    let output = run("tests/scenes/red_sphere.yaml", 1, None, SMALL);
    let fb = &output.framebuffer;
    assert_eq!((fb.width(), fb.height()), (160, 120));
    assert_eq!(fb.pixel(80, 60), RED);
    for (x, y) in [(0, 0), (159, 0), (0, 119), (159, 119)] {
        assert_eq!(fb.pixel(x, y), SKY, "corner {x},{y}");
    }
    // A sphere of radius 1 at distance 5 under a 40 degree fov covers a disc of radius
    // ~ tan(asin(1/5)) / tan(20 deg) * 60 pixels.
    let radius = (1.0f64 / 5.0).asin().tan() / 20f64.to_radians().tan() * 60.0;
    let expected = std::f64::consts::PI * radius * radius;
    let red = count_pixels(fb, RED) as f64;
    assert!((red - expected).abs() < expected * 0.03, "{red} red pixels, expected about {expected}");
}

#[test]
fn a_box_behind_another_is_hidden_until_the_front_one_moves() {
    let hidden = run("tests/scenes/occlusion.yaml", 1, None, SMALL);
    assert_eq!(count_pixels(&hidden.framebuffer, RED), 0);
    assert!(count_pixels(&hidden.framebuffer, GREEN) > 1000);
    let moved = run("tests/scenes/occlusion.yaml", 1, Some("- { at: 0, set: { front.position.x: 10 } }"), SMALL);
    assert!(count_pixels(&moved.framebuffer, RED) > 100);
    assert_eq!(count_pixels(&moved.framebuffer, GREEN), 0);
}

#[test]
fn the_demo_scene_dumps_every_entity_in_order_and_spins_at_its_rate() {
    let output = run("scenes/demo.yaml", 60, None, SMALL);
    let dump = &output.dump;
    assert_eq!(dump["frame"], 60);
    assert!((dump["time"].as_f64().unwrap() - 1.0).abs() < 1e-6);
    let names: Vec<&str> = dump["entities"].as_array().unwrap().iter().map(|e| e["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["camera", "light", "render", "ground", "ball", "crate", "column", "spinner"]);
    let spinner = entity(dump, "spinner");
    assert_eq!(spinner["kind"], "shape");
    assert_eq!(spinner["primitive"], "box");
    // 90 degrees per second for one second.
    assert!((vec3(&spinner["rotation_deg"]).y - 90.0).abs() < 1e-3, "{spinner}");
    assert_eq!(vec3(&entity(dump, "ball")["position"]), Vec3::new(0.0, 0.6, 0.0));
}

#[test]
fn held_keys_orbit_the_camera_at_their_documented_rate() {
    let start = run("scenes/demo.yaml", 30, None, SMALL);
    let turned = run(
        "scenes/demo.yaml",
        30,
        Some("- { at: 0, press: [ArrowLeft] }\n- { at: 0.5, release: [ArrowLeft] }"),
        SMALL,
    );
    let yaw = |dump: &Value| {
        let camera = entity(dump, "camera");
        let offset = vec3(&camera["position"]) - vec3(&camera["target"]);
        offset.x.atan2(offset.z).to_degrees()
    };
    // 60 degrees per second for half a second, to the left.
    let turn = yaw(&turned.dump) - yaw(&start.dump);
    assert!((turn + 30.0).abs() < 1e-2, "turned {turn} degrees");
    assert_ne!(start.framebuffer.color(), turned.framebuffer.color());
}

#[test]
fn timelines_set_parameters_by_name() {
    let output = run(
        "scenes/demo.yaml",
        2,
        Some("- { at: 0, set: { light.azimuth_deg: 90, light.elevation_deg: 0, ball.color.red: 0.25 } }"),
        SMALL,
    );
    let light = entity(&output.dump, "light");
    assert!((vec3(&light["direction"]) - Vec3::NEG_X).length() < 1e-6, "{light}");
    assert_eq!(entity(&output.dump, "ball")["color"][0], 0.25);
}

#[test]
fn pause_stops_the_clock_and_step_advances_it_by_one() {
    let pause = "- { at: 0.25, press: [Space] }\n- { at: 0.3, release: [Space] }\n";
    let paused_early = run("scenes/demo.yaml", 40, Some(pause), SMALL);
    let paused_late = run("scenes/demo.yaml", 60, Some(pause), SMALL);
    let frame = |output: &RunOutput| output.dump["frame"].as_u64().unwrap();
    assert_eq!(frame(&paused_early), frame(&paused_late));
    assert!(frame(&paused_early) < 40 && frame(&paused_early) > 10);
    let stepped = run(
        "scenes/demo.yaml",
        60,
        Some(&format!("{pause}- {{ at: 0.5, press: [Period] }}\n- {{ at: 0.55, release: [Period] }}\n")),
        SMALL,
    );
    assert_eq!(frame(&stepped), frame(&paused_late) + 1);
}

#[test]
fn runs_are_deterministic() {
    let timeline = Some("- { at: 0.1, press: [KeyJ, ArrowUp] }\n- { at: 0.3, release: [KeyJ] }\n");
    let a = run("scenes/demo.yaml", 25, timeline, SMALL);
    let b = run("scenes/demo.yaml", 25, timeline, SMALL);
    assert_eq!(a.dump, b.dump);
    assert_eq!(a.framebuffer.color(), b.framebuffer.color());
}

/// A headless app of the small size playing `scene`, once its scene is live.
fn live_app(scene: &Path) -> bevy::app::App {
    common::live_app(scene, SMALL)
}

#[test]
fn a_broken_reload_keeps_the_last_good_scene_and_a_fixed_one_replaces_it() {
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("live.yaml");
    std::fs::write(&scene, "entities:\n  - name: first\n    shape: { primitive: box }\n").unwrap();
    let mut app = canopy::app::headless_app(&scene, SMALL, false).unwrap();
    common::update_until(&mut app, |s| s.status == SceneStatus::Live);
    let names = |app: &mut bevy::app::App| -> Vec<String> {
        let dump = dump_state(app.world_mut());
        dump["entities"].as_array().unwrap().iter().map(|e| e["name"].as_str().unwrap().to_string()).collect()
    };
    assert_eq!(names(&mut app), ["camera", "light", "render", "first"]);

    std::fs::write(&scene, "entities:\n  - name: first\n    shape: { primitive: bx }\n").unwrap();
    app.world_mut().write_message(ReloadScene);
    common::update_until(&mut app, |s| s.error.is_some());
    let scene_state = app.world().resource::<ActiveScene>();
    assert_eq!(scene_state.status, SceneStatus::Live);
    let error = scene_state.error.clone().unwrap();
    assert!(error.contains("live.yaml:3:") && error.contains("unknown variant `bx`"), "{error}");
    app.update();
    assert_eq!(names(&mut app), ["camera", "light", "render", "first"]);

    std::fs::write(&scene, "entities:\n  - name: first\n    shape: { primitive: box }\n  - name: second\n    shape: { primitive: sphere }\n").unwrap();
    app.world_mut().write_message(ReloadScene);
    common::update_until(&mut app, |s| s.generation == 2);
    app.update();
    assert_eq!(app.world().resource::<ActiveScene>().error, None);
    assert_eq!(names(&mut app), ["camera", "light", "render", "first", "second"]);
}

#[test]
fn the_readme_key_table_lists_every_registered_key() {
    let app = canopy::app::headless_app(&path("scenes/demo.yaml"), SMALL, false).unwrap();
    let readme = std::fs::read_to_string(path("README.md")).unwrap();
    let keys_section = readme.split("## Keys").nth(1).unwrap().split("\n## ").next().unwrap();
    let key_map = app.world().resource::<canopy::controls::KeyMap>();
    assert!(key_map.0.len() >= 15);
    for help in &key_map.0 {
        let name = help.key_name();
        let listed = keys_section.lines().any(|line| {
            line.starts_with('|')
                && line.split('|').nth(1).is_some_and(|cell| cell.split(" / ").any(|k| k.trim() == name))
        });
        assert!(listed, "the README's key table does not list {name} ({})", help.action);
    }
}

#[test]
fn setting_the_flexion_thickens_the_belly_at_constant_volume() {
    let timeline = "- { at: 0.0, set: { biceps.flexion_deg: 30 } }\n- { at: 0.5, set: { biceps.flexion_deg: 60 } }\n- { at: 1.0, set: { biceps.flexion_deg: 90 } }\n";
    let mut belly = Vec::new();
    for (frames, flexion) in [(10, 30.0), (40, 60.0), (70, 90.0)] {
        let output = run("scenes/biceps_real.yaml", frames, Some(timeline), SMALL);
        let muscle = entity(&output.dump, "biceps");
        assert_eq!(muscle["kind"], "muscle");
        assert!((muscle["flexion_deg"].as_f64().unwrap() - flexion).abs() < 1e-9, "{muscle}");
        // The length follows from the carcass (b1 = 220, a2 = 30) by the law of cosines.
        let expected_length =
            (220.0f64.powi(2) + 30.0f64.powi(2) + 2.0 * 220.0 * 30.0 * flexion.to_radians().cos()).sqrt();
        let length = muscle["length"].as_f64().unwrap();
        assert!((length - expected_length).abs() < 1e-9, "{length} vs {expected_length}");
        assert!((muscle["node_spacing"].as_f64().unwrap() - length / 10.0).abs() < 1e-12);
        // The radii follow from the model and keep the rest volume.
        let radii: Vec<f64> = muscle["radii"].as_array().unwrap().iter().map(|r| r.as_f64().unwrap()).collect();
        let spacing = length / 10.0;
        let volume: f64 = radii.windows(2).map(|w| (w[0] * w[0] + w[0] * w[1] + w[1] * w[1]) / 3.0).sum::<f64>()
            * std::f64::consts::PI
            * spacing;
        let rest = muscle["rest_volume"].as_f64().unwrap();
        assert!(((volume - rest) / rest).abs() < 1e-12, "volume {volume} vs rest {rest}");
        assert_eq!(radii[0], 5.0);
        belly.push(radii[7]);
    }
    assert!(belly[0] < belly[1] && belly[1] < belly[2], "the belly thickens with flexion: {belly:?}");
}

#[test]
fn holding_w_flexes_the_elbow_at_its_documented_rate() {
    let output = run("scenes/biceps.yaml", 30, Some("- { at: 0, press: [KeyW] }"), SMALL);
    let start = run("scenes/biceps.yaml", 1, None, SMALL);
    let flexion = |o: &RunOutput| entity(&o.dump, "biceps")["flexion_deg"].as_f64().unwrap();
    // 30 degrees per second for 30 frames at 60 Hz.
    assert!((flexion(&output) - flexion(&start) - 15.0).abs() < 1e-3, "{} -> {}", flexion(&start), flexion(&output));
}

#[test]
fn the_source_config_file_alone_is_a_playable_scene() {
    let output = run("scenes/biceps_config.yaml", 2, Some("- { at: 0, set: { muscle.flexion_deg: 60 } }"), SMALL);
    let muscle = entity(&output.dump, "muscle");
    assert_eq!(muscle["kind"], "muscle");
    assert!((muscle["flexion_deg"].as_f64().unwrap() - 60.0).abs() < 1e-9);
    // The default camera frames the arm: the muscle's red is on screen, around the middle.
    let width = output.framebuffer.width() as usize;
    let columns: Vec<usize> = output
        .framebuffer
        .color()
        .chunks_exact(4)
        .enumerate()
        .filter(|(_, p)| p[0] as u32 > 2 * p[1] as u32 && p[0] > 60)
        .map(|(i, _)| i % width)
        .collect();
    assert!(columns.len() > 100, "{} muscle pixels", columns.len());
    let centre = columns.iter().sum::<usize>() as f64 / columns.len() as f64;
    assert!((width as f64 * 0.2..width as f64 * 0.8).contains(&centre), "muscle centred at column {centre}");
}

#[test]
fn a_muscle_configured_from_another_file_plays_like_the_inline_one() {
    let timeline = Some("- { at: 0, set: { biceps.flexion_deg: 80 } }");
    let from_file = run("scenes/biceps_from_file.yaml", 3, timeline, SMALL);
    let inline = run("scenes/biceps.yaml", 3, timeline, SMALL);
    assert_eq!(entity(&from_file.dump, "biceps")["radii"], entity(&inline.dump, "biceps")["radii"]);
}

/// Mean brightness of a frame, 0 to 765.
fn brightness(framebuffer: &Framebuffer) -> f64 {
    let sum: u64 = framebuffer.color().chunks_exact(4).map(|p| p[..3].iter().map(|&c| u64::from(c)).sum::<u64>()).sum();
    sum as f64 / (framebuffer.width() * framebuffer.height()) as f64
}

#[test]
fn shadows_and_shading_switch_at_run_time_by_parameter_and_key() {
    let render = |output: &RunOutput| entity(&output.dump, "render").clone();
    let shadowed = run("scenes/demo.yaml", 2, None, SMALL);
    assert_eq!(render(&shadowed)["shadows"], true);

    // The parameter and the key reach the same frame; without shadows it is brighter.
    let by_param = run("scenes/demo.yaml", 2, Some("- { at: 0, set: { render.shadows: false } }"), SMALL);
    let by_key = run("scenes/demo.yaml", 2, Some("- { at: 0, press: [KeyH] }"), SMALL);
    assert_eq!(render(&by_key)["shadows"], false);
    assert_eq!(by_param.framebuffer.color(), by_key.framebuffer.color());
    assert!(brightness(&by_param.framebuffer) > brightness(&shadowed.framebuffer) + 1.0);

    // V cycles Gouraud -> Phong -> flat; each mode draws a different frame.
    let mut frames = vec![shadowed.framebuffer.color().to_vec()];
    for (presses, mode) in [(1, "phong"), (2, "flat")] {
        // Press and release on alternate frames (timeline times are seconds at 60 steps per second).
        let frame = |n: u32| f64::from(n) / 60.0;
        let timeline: String = (0..presses)
            .map(|i| {
                format!(
                    "- {{ at: {}, press: [KeyV] }}\n- {{ at: {}, release: [KeyV] }}\n",
                    frame(2 * i),
                    frame(2 * i + 1)
                )
            })
            .collect();
        let output = run("scenes/demo.yaml", 6, Some(&timeline), SMALL);
        assert_eq!(render(&output)["shading"], mode);
        let by_param =
            run("scenes/demo.yaml", 6, Some(&format!("- {{ at: 0, set: {{ render.shading: {mode} }} }}")), SMALL);
        assert_eq!(output.framebuffer.color(), by_param.framebuffer.color(), "{mode}");
        assert!(!frames.contains(&output.framebuffer.color().to_vec()), "{mode} looks like another mode");
        frames.push(output.framebuffer.color().to_vec());
    }
}

#[test]
fn tree_scenes_play_and_dump_their_supports() {
    for scene in [
        "scenes/branch.yaml",
        "scenes/fork.yaml",
        "scenes/tree.yaml",
        "scenes/forest.yaml",
        "scenes/generated_forest.yaml",
    ] {
        let output = run(scene, 1, None, SMALL);
        let trees: Vec<&Value> =
            output.dump["entities"].as_array().unwrap().iter().filter(|e| e["kind"] == "tree").collect();
        assert!(!trees.is_empty(), "{scene}");
        for tree in trees {
            for support in tree["supports"].as_array().unwrap() {
                let (points, radii) = (support["points"].as_array().unwrap(), support["radii"].as_array().unwrap());
                assert!(points.len() >= 2 && points.len() == radii.len(), "{scene}: {support}");
                assert!(support["kind"] == "trunk" || support["kind"] == "branch");
            }
        }
        // Something besides the sky was drawn.
        assert!(count_pixels(&output.framebuffer, output.framebuffer.pixel(0, 0)) < 160 * 120, "{scene}");
    }
    let oak = run("scenes/tree.yaml", 1, None, SMALL);
    let supports = entity(&oak.dump, "oak")["supports"].as_array().unwrap().clone();
    let kind = |name: &str| supports.iter().find(|s| s["name"] == name).unwrap()["kind"].clone();
    assert_eq!((kind("trunk"), kind("low"), kind("twig")), ("trunk".into(), "branch".into(), "branch".into()));
    // The twig starts on its parent branch, 60% along it.
    let low = supports.iter().find(|s| s["name"] == "low").unwrap();
    let twig = supports.iter().find(|s| s["name"] == "twig").unwrap();
    let low_points: Vec<Vec3> = low["points"].as_array().unwrap().iter().map(vec3).collect();
    let length: f32 = low_points.windows(2).map(|p| p[0].distance(p[1])).sum();
    let start = vec3(&twig["points"][0]);
    let along: f32 = {
        let mut best = f32::INFINITY;
        let mut walked = 0.0;
        let mut at = 0.0;
        for pair in low_points.windows(2) {
            let span = pair[0].distance(pair[1]);
            let t = ((start - pair[0]).dot(pair[1] - pair[0]) / (span * span)).clamp(0.0, 1.0);
            let distance = start.distance(pair[0].lerp(pair[1], t));
            if distance < best {
                (best, at) = (distance, walked + t * span);
            }
            walked += span;
        }
        assert!(best < 1e-4, "the twig starts {best} m off its parent");
        at / length
    };
    assert!((along - 0.6).abs() < 1e-3, "{along}");
}

#[test]
fn a_ray_through_a_branch_on_screen_picks_that_branch() {
    use canopy::tree::{TreeBody, pick};
    use canopy::view::CameraParams;
    let mut app = live_app(&path("scenes/tree.yaml"));
    let world = app.world_mut();
    let camera = world.query::<&CameraParams>().single(world).unwrap().camera();
    let aspect = SMALL.x as f32 / SMALL.y as f32;
    let mut trees = world.query::<(bevy::prelude::Entity, &TreeBody)>();
    let (_, body) = trees.single(world).unwrap();
    let index = |name: &str| body.tree.supports.iter().position(|s| s.name == name).unwrap();
    for (name, fraction) in [("low", 0.7), ("high", 0.5), ("trunk", 0.2)] {
        let (point, _, _) = body.tree.supports[index(name)].at(fraction);
        let ndc = camera.view_projection(aspect).project_point3(point);
        let (origin, direction) = camera.ray(ndc.truncate(), aspect);
        let picked = pick(trees.iter(world), origin, direction).expect("a hit");
        assert_eq!(picked.support, index(name), "aiming at {name}");
        // The hit lies about where the axis point aimed at does (within the branch's radius).
        let length = body.tree.supports[index(name)].length();
        assert!((picked.fraction - fraction).abs() * length < 0.3, "{name}: {} vs {fraction}", picked.fraction);
        assert!(picked.normal.dot(direction) < 0.0, "the normal faces the ray");
        // The hit is on the near side of the axis point aimed at.
        assert!(picked.point.distance(point) < 0.3 && picked.distance < (point - origin).length(), "{picked:?}");
    }
    // Aiming at the sky hits nothing.
    let (origin, direction) = camera.ray(bevy::math::Vec2::new(0.9, 0.9), aspect);
    assert!(pick(trees.iter(world), origin, direction).is_none());

    // A click in the view selects the support under it.
    let (low, _, _) = body.tree.supports[index("low")].at(0.7);
    let low_index = index("low");
    let ndc = camera.view_projection(aspect).project_point3(low).truncate();
    world.write_message(canopy::controls::ViewClicked { ndc, aspect });
    app.update();
    let world = app.world_mut();
    let selected = world.query::<&canopy::tree::SelectedSupport>().single(world).unwrap();
    assert_eq!(selected.0, low_index);
}

#[test]
fn tree_edits_rebuild_the_tree_and_undo_restores_it() {
    use canopy::tree::edit::{Edit, ForkField};
    use canopy::tree::{TreeBody, edit_tree, undo_tree_edit};
    let mut app = live_app(&path("scenes/tree.yaml"));
    let world = app.world_mut();
    let (oak, body) = world.query::<(bevy::prelude::Entity, &TreeBody)>().single(world).unwrap();
    let low = body.tree.supports.iter().position(|s| s.name == "low").unwrap();
    let supports = |world: &mut bevy::prelude::World| dump_state(world)["entities"][4]["supports"].clone();
    let before = supports(world);

    edit_tree(world, oak, Edit::Fork { support: low, field: ForkField::Length, value: 3.0 }).unwrap();
    let longer = world.get::<TreeBody>(oak).unwrap().tree.supports[low].length();
    assert!((longer - 3.0).abs() < 1e-4, "{longer}");
    edit_tree(world, oak, Edit::AddChild { parent: low }).unwrap();
    assert_eq!(world.get::<TreeBody>(oak).unwrap().tree.supports.len(), 6);
    // A refused edit changes nothing.
    let error = edit_tree(world, oak, Edit::Fork { support: low, field: ForkField::At, value: 2.0 }).unwrap_err();
    assert!(error.contains("0 to 1"), "{error}");
    // Deleting `low` takes its twig and the new child with it.
    edit_tree(world, oak, Edit::Delete { support: low }).unwrap();
    assert_eq!(world.get::<TreeBody>(oak).unwrap().tree.supports.len(), 3);

    for _ in 0..3 {
        assert!(undo_tree_edit(world, oak));
    }
    assert!(!undo_tree_edit(world, oak));
    assert_eq!(supports(world), before);
}

#[test]
fn saving_an_edited_tree_keeps_a_backup_and_reloads_as_edited() {
    use canopy::scene::save_live_scene;
    use canopy::tree::edit::{Edit, ForkField};
    use canopy::tree::{TreeBody, edit_tree};
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("grove.yaml");
    let original = "# my grove\nentities:\n  - name: oak\n    tree:\n      supports:\n        \
        - { name: trunk, points: [[0, 0, 0], [0, 3, 0]], radii: [0.2, 0.1] }\n        \
        - { name: limb, parent: trunk, at: 0.5, length: 1, radius: [0.08, 0.03] }\n";
    std::fs::write(&scene, original).unwrap();
    let mut app = live_app(&scene);
    let world = app.world_mut();
    let (oak, _) = world.query::<(bevy::prelude::Entity, &TreeBody)>().single(world).unwrap();
    edit_tree(world, oak, Edit::Fork { support: 1, field: ForkField::Length, value: 2.5 }).unwrap();
    edit_tree(world, oak, Edit::AddChild { parent: 1 }).unwrap();

    let (saved, backup) = save_live_scene(world).unwrap();
    assert_eq!(saved, scene);
    let backup = backup.expect("the file existed");
    assert_eq!(backup, folder.path().join("grove.yaml.1.bak"));
    assert_eq!(std::fs::read_to_string(&backup).unwrap(), original);
    // A second save keeps the first backup.
    let (_, second) = save_live_scene(world).unwrap();
    assert_eq!(second.unwrap(), folder.path().join("grove.yaml.2.bak"));
    assert_eq!(std::fs::read_to_string(&backup).unwrap(), original);

    let reread = canopy::scene::schema::SceneDef::load(&scene).unwrap();
    let canopy::scene::schema::EntityKind::Tree(tree) = &reread.entities[0].kind else { panic!("not a tree") };
    let built = tree.build().unwrap();
    let names: Vec<&str> = built.supports.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["trunk", "limb", "limb-1"]);
    assert!((built.supports[1].length() - 2.5).abs() < 1e-5);
}
