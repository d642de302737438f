//! Soft bodies: the torso's region outlined by a timeline or by clicks in the view, shrunk by
//! each deformer into the collection, compared and saved.

use super::common::{SMALL, entity, path, run, small_app};
use bevy::prelude::*;
use canopy::foundation::actions::act;
use canopy::foundation::messages::ViewClicked;
use canopy::raster::RasterMesh;
use canopy::soft_body::SoftBody;
use canopy::soft_body::region::Mark;
use canopy::view::CameraParams;
use serde_json::Value;

/// Vertices of the torso's front, as the torso file's reader numbers them, outlining its
/// belly: found from the generator's numbering through their positions.
fn belly_outline(body: &SoftBody) -> Vec<u32> {
    let torso = canopy::soft_body::sample::torso(64, 128);
    [8 * 128 + 16, 8 * 128 + 48, 28 * 128 + 48, 28 * 128 + 16]
        .map(|g: usize| {
            let p = torso.positions[g];
            body.bench.original().positions.iter().position(|q| *q == p).expect("the file holds the sample's vertices")
                as u32
        })
        .to_vec()
}

/// A timeline marking the belly as points, then applying every deformer to the original.
fn every_deformer(points: &[[f32; 3]]) -> String {
    let marks: Vec<String> = points.iter().map(|p| format!("{{ mark: [{}, {}, {}] }}", p[0], p[1], p[2])).collect();
    let mut text = format!("- {{ at: 0.0, act: {{ torso: [{}] }} }}\n", marks.join(", "));
    // The edge sum cannot fall below the least the outline allows (a flat belly's, 0.95 of
    // this one's): it is asked for 0.97, and once for 0.9 that it cannot reach.
    let deformers = [
        ("edge_lengths", "projection", 0.9),
        ("edge_sum", "projection", 0.97),
        ("edge_sum", "source", 0.97),
        ("area", "projection", 0.9),
        ("area", "source", 0.9),
        ("edge_sum", "projection", 0.9),
    ];
    for (i, (method, variant, k)) in deformers.iter().enumerate() {
        let at = 0.05 * (i + 1) as f64;
        text +=
            &format!("- {{ at: {at}, set: {{ torso.method: {method}, torso.variant: {variant}, torso.k: {k} }} }}\n");
        text += &format!("- {{ at: {at}, act: {{ torso: [{{ show: 0 }}, apply] }} }}\n");
    }
    text
}

fn belly_points() -> Vec<[f32; 3]> {
    let torso = canopy::soft_body::sample::torso(64, 128);
    [8 * 128 + 16, 8 * 128 + 48, 28 * 128 + 48, 28 * 128 + 16].map(|g: usize| torso.positions[g].to_array()).to_vec()
}

#[test]
fn a_timeline_shrinks_the_torso_belly_with_every_deformer_and_the_dump_holds_the_reports() {
    let timeline = every_deformer(&belly_points());
    let first = run("scenes/torso.yaml", 20, Some(&timeline), SMALL);
    let torso = entity(&first.dump, "torso");
    assert_eq!((torso["vertices"].as_u64(), torso["triangles"].as_u64()), (Some(64 * 128), Some(2 * 63 * 128)));
    let models = torso["models"].as_array().unwrap();
    assert_eq!(models.len(), 6, "{}", torso["message"]);
    assert_eq!(torso["shown"], 6);
    let report = |n: usize| &models[n]["report"];
    for model in models {
        let r = &model["report"];
        assert_eq!(model["base"], 0, "each shrinks the original");
        assert_eq!(r["facts"]["fixed_unchanged"], true, "{r}");
        assert_eq!(r["facts"]["has_nan"], false, "{r}");
        assert!(r["region_vertices"].as_u64().unwrap() > 500 && r["outline_vertices"].as_u64().unwrap() > 50, "{r}");
        assert!(r.get("time_ms").is_none(), "no wall-clock time in a dump");
    }
    let ratio = |n: usize, fact: &str| report(n)["facts"][fact].as_f64().unwrap();
    assert!((ratio(1, "edge_sum_ratio") - 0.97).abs() < 1e-4, "the edge sum's projection meets its target");
    assert_eq!(report(1)["stop"], "converged");
    assert_eq!(report(5)["stop"], "stalled", "0.9 lies below the least edge sum of the outline");
    assert!(ratio(5, "edge_sum_ratio") > 0.94, "{}", report(5));
    assert!((ratio(3, "area_ratio") - 0.9).abs() < 1e-4, "the area's projection meets its target");
    // Every edge starts (1 - k) / k off its target; the held outline keeps some from it.
    let start = (1.0 - 0.9) / 0.9;
    assert!(ratio(0, "mean_edge_error") < 0.75 * start, "per-edge lengths near k: {}", ratio(0, "mean_edge_error"));
    // The source's edge-sum step moves every vertex by the whole excess: it overshoots.
    let error = |n: usize| report(n)["error"].as_f64().unwrap();
    assert!(report(2)["stop"] != "converged" && error(2) > 100.0 * error(1), "{} vs {}", report(2), report(1));
    assert!(ratio(4, "area_ratio") < 1.0, "the source's area step shrinks");
    // Pulled in with its outline held, the belly loses tissue: more the more it shrinks.
    let (edge_sum, area) = (ratio(1, "volume_between_m3"), ratio(3, "volume_between_m3"));
    assert!(edge_sum > 0.0 && area > edge_sum, "{edge_sum} m3 at 0.97 of the edge sum, {area} m3 at 0.9 of the area");
    for n in [0, 1, 3] {
        assert_eq!(report(n)["facts"]["inverted"], 0, "{}", models[n]["name"]);
    }
    // The same timeline gives the same dump, byte for byte.
    let again = run("scenes/torso.yaml", 20, Some(&timeline), SMALL);
    assert_eq!(serde_json::to_string(&first.dump).unwrap(), serde_json::to_string(&again.dump).unwrap());
}

#[test]
fn bad_marks_and_settings_are_refused_with_a_reason_and_change_nothing() {
    let points = belly_points();
    let two = format!(
        "- {{ at: 0.0, act: {{ torso: [{{ mark: {:?} }}, {{ mark: {:?} }}, apply] }} }}\n",
        points[0], points[1]
    );
    let dump = run("scenes/torso.yaml", 3, Some(&two), SMALL).dump;
    let torso = entity(&dump, "torso");
    assert_eq!(torso["models"].as_array().unwrap().len(), 0);
    assert!(torso["message"].as_str().unwrap().contains("at least 3 points"), "{}", torso["message"]);
    assert!(torso["region"]["error"].as_str().unwrap().contains("found 2"), "{}", torso["region"]);

    let off = format!("{two}- {{ at: 0.02, act: {{ torso: [{{ mark: [0.0, 0.3, 2.0] }}, apply] }} }}\n");
    // The region is found with the shrink, off the main thread: its refusal arrives with it.
    let dump = run("scenes/torso.yaml", 6, Some(&off), SMALL).dump;
    let message = entity(&dump, "torso")["message"].as_str().unwrap().to_string();
    assert!(message.contains("point 2 lies") && message.contains("from the surface"), "{message}");

    let marks: Vec<String> = points.iter().map(|p| format!("{{ mark: {p:?} }}")).collect();
    let k = format!(
        "- {{ at: 0.0, set: {{ torso.method: area, torso.k: 1.0 }}, act: {{ torso: [{}, apply] }} }}\n",
        marks.join(", ")
    );
    let dump = run("scenes/torso.yaml", 3, Some(&k), SMALL).dump;
    let torso = entity(&dump, "torso");
    assert_eq!(torso["models"].as_array().unwrap().len(), 0);
    assert!(torso["message"].as_str().unwrap().contains("below 1 for the area"), "{}", torso["message"]);

    // An action the kind does not take is an error before the run.
    let folder = tempfile::tempdir().unwrap();
    let file = folder.path().join("bad.yaml");
    std::fs::write(&file, "- { at: 0.0, act: { torso: { mark: [0, 1] } } }\n").unwrap();
    let options = canopy::run::RunOptions {
        scene: path("scenes/torso.yaml"),
        frames: 1,
        timeline: Some(file),
        size: SMALL,
        log: false,
    };
    let error = canopy::run::run_headless(&options).unwrap_err().to_string();
    assert!(
        error.contains("bad.yaml") && error.contains("action for `torso`") && error.contains("invalid length 2"),
        "{error}"
    );
}

/// Presses and releases `key` as the keyboard would, a frame each.
fn tap(app: &mut App, key_code: KeyCode) {
    use bevy::input::ButtonState;
    use bevy::input::keyboard::{Key, KeyboardInput, NativeKey};
    for state in [ButtonState::Pressed, ButtonState::Released] {
        let logical_key = Key::Unidentified(NativeKey::Unidentified);
        app.world_mut().write_message(KeyboardInput {
            key_code,
            logical_key,
            state,
            text: None,
            repeat: false,
            window: Entity::PLACEHOLDER,
        });
        app.update();
    }
}

/// The click in the small view on a point of the scene, as the scene's camera sees it.
fn clicker(world: &mut World) -> impl Fn(Vec3) -> ViewClicked + use<> {
    let camera = world.query::<&CameraParams>().single(world).unwrap().camera();
    let aspect = SMALL.x as f32 / SMALL.y as f32;
    move |point| ViewClicked { ndc: camera.view_projection(aspect).project_point3(point).truncate(), aspect }
}

/// The soft body's entity and its body.
fn torso(world: &mut World) -> (Entity, SoftBody) {
    let mut bodies = world.query::<(Entity, &SoftBody)>();
    let (entity, body) = bodies.single(world).unwrap();
    (entity, body.clone())
}

#[test]
fn clicks_mark_the_vertices_under_them_and_the_region_is_shown_compared_and_saved() {
    let mut app = small_app(&path("scenes/torso.yaml"));
    let world = app.world_mut();
    let click_at = clicker(world);
    let (torso_entity, body) = torso(world);
    let outline = belly_outline(&body);
    for &vertex in &outline {
        let point = body.bench.original().positions[vertex as usize];
        world.write_message(click_at(point));
    }
    // A click beside the torso marks nothing.
    world.write_message(ViewClicked { ndc: Vec2::new(0.95, 0.95), aspect: click_at(Vec3::ZERO).aspect });
    app.update();
    let world = app.world_mut();
    let (_, body) = torso(world);
    let marks: Vec<Mark> = outline.iter().map(|&v| Mark::Vertex(v)).collect();
    assert_eq!(body.bench.marks(), marks.as_slice(), "each click marks the vertex it aimed at");
    let region = body.region.as_ref().expect("four marks outline the belly");
    let tinted = world.get::<RasterMesh>(torso_entity).unwrap().mesh.colors.iter().filter(|&&c| c != Vec3::ONE).count();
    assert_eq!(tinted, region.inside.len() + region.outline.len(), "the region is tinted");

    // Enter applies; C twice shows the original beside the model.
    tap(&mut app, KeyCode::Enter);
    let world = app.world_mut();
    let (_, body) = torso(world);
    assert_eq!((body.bench.models().len(), body.bench.shown()), (1, 1), "{:?}", body.message);
    let children: Vec<Entity> = world.get::<Children>(torso_entity).unwrap().iter().collect();
    // The drawn parts' vertex counts: the marks' balls, the measured points' (none), and the
    // original beside or nothing.
    let parts = |world: &World| {
        let mut counts: Vec<usize> =
            children.iter().map(|&c| world.get::<RasterMesh>(c).unwrap().mesh.positions.len()).collect();
        counts.sort_unstable();
        counts
    };
    let balls = 4 * canopy::raster::MeshData::sphere(6, 10).positions.len();
    assert_eq!(parts(world), [0, 0, balls], "the model alone, with the marks");
    tap(&mut app, KeyCode::KeyC);
    tap(&mut app, KeyCode::KeyC);
    let world = app.world_mut();
    assert_eq!(parts(world), [0, balls, 64 * 128], "the original stands beside the model");

    // The model saved, read back: the whole surface with the shrunk region.
    let (_, body) = torso(world);
    let folder = tempfile::tempdir().unwrap();
    let saved = body.save(folder.path(), "torso", 1, "ply").unwrap();
    let again = body.save(folder.path(), "torso", 1, "ply").unwrap();
    assert_ne!(saved, again, "an earlier file is never overwritten");
    let (read, _) = canopy::spatial::mesh_io::read(&saved).unwrap();
    assert_eq!(read.positions, body.bench.positions(1).unwrap());
    assert!(body.save(folder.path(), "torso", 2, "obj").is_err(), "there is no second model");
    // Saved in its file's own format, the model is that file with only moved positions changed.
    let obj = std::fs::read_to_string(body.save(folder.path(), "torso", 1, "obj").unwrap()).unwrap();
    let original = std::fs::read_to_string(super::common::path("scenes/meshes/torso.obj")).unwrap();
    assert_eq!(obj.lines().count(), original.lines().count());
    let changed: Vec<(&str, &str)> = original.lines().zip(obj.lines()).filter(|(a, b)| a != b).collect();
    assert!(!changed.is_empty() && changed.iter().all(|(a, _)| a.starts_with("v ")), "{:?}", changed.first());

    // Backspace takes the last mark back; the action reaches the same state.
    act(world, "torso", &serde_yaml::from_str::<serde_yaml::Value>("undo_mark").unwrap(), true).unwrap();
    let (_, body) = torso(world);
    assert_eq!(body.bench.marks().len(), 3);
    let dump: Value = canopy::foundation::dump::dump_state(world);
    assert_eq!(entity(&dump, "torso")["marks"].as_array().unwrap().len(), 3);
}

#[test]
fn a_click_marks_the_nearest_of_several_placed_and_scaled_surfaces() {
    let mut app = small_app(&path("scenes/soft_bodies.yaml"));
    let world = app.world_mut();
    let click_at = clicker(world);
    let mut bodies = world.query::<(&canopy::foundation::entity::SceneEntity, &SoftBody, &GlobalTransform)>();
    let (_, belly, placed) = bodies.iter(world).find(|(scene, ..)| scene.name == "belly").unwrap();
    // The belly patch's top, 225 x 225 vertices: the middle one.
    let top = 112 * 225 + 112;
    let point = placed.transform_point(belly.bench.original().positions[top]);
    world.write_message(click_at(point));
    app.update();
    let world = app.world_mut();
    let mut bodies = world.query::<(&canopy::foundation::entity::SceneEntity, &SoftBody)>();
    for (scene, body) in bodies.iter(world) {
        let expected: &[Mark] = if scene.name == "belly" { &[Mark::Vertex(top as u32)] } else { &[] };
        assert_eq!(body.bench.marks(), expected, "{}", scene.name);
    }
}

#[test]
fn a_shrink_runs_off_the_main_thread_and_a_second_waits_for_it() {
    use canopy::foundation::schedule::LongWorkArrival;
    let mut app = small_app(&path("scenes/torso.yaml"));
    // As in the window: the result is taken in once it is done.
    app.insert_resource(LongWorkArrival::WhenReady);
    let world = app.world_mut();
    let marks: Vec<String> = belly_points().iter().map(|p| format!("{{ mark: {p:?} }}")).collect();
    let actions: serde_yaml::Value = serde_yaml::from_str(&format!("[{}, apply, apply]", marks.join(", "))).unwrap();
    act(world, "torso", &actions, true).unwrap();
    let (_, body) = torso(world);
    assert!(body.shrinking && body.bench.models().is_empty());
    assert_eq!(body.message.as_deref(), Some("not applied: a shrink is under way"));
    let started = std::time::Instant::now();
    while torso(app.world_mut()).1.shrinking {
        assert!(started.elapsed() < std::time::Duration::from_secs(30), "the shrink never arrived");
        app.update();
    }
    let (_, body) = torso(app.world_mut());
    assert_eq!((body.bench.models().len(), body.bench.shown()), (1, 1));
}

#[test]
fn a_saved_scene_keeps_the_deformer_set_in_the_window() {
    use canopy::foundation::params::{ParamValue, set_param};
    use canopy::soft_body::SoftBodyDef;
    use canopy::soft_body::deform::Deformer;
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("patch.yaml");
    std::fs::write(&scene, "entities:\n  - name: patch\n    soft_body:\n      sample: { shape: belly, size: 17 }\n")
        .unwrap();
    let mut app = small_app(&scene);
    let world = app.world_mut();
    set_param(world, "patch.method", ParamValue::Choice("edge_sum".into())).unwrap();
    set_param(world, "patch.k", ParamValue::Number(0.8)).unwrap();
    canopy::scene::save_live_scene(world).unwrap();
    let reread = canopy::app::entity_kinds().load(&scene).unwrap().def;
    let def = reread.entities[0].def::<SoftBodyDef>().expect("a soft body");
    assert_eq!((def.method, def.k.0), (Deformer::EdgeSum, 0.8));
    assert_eq!(def.sample.map(|s| s.size.0), Some(17), "the rest as written");
}

#[test]
fn a_body_read_from_a_gltf_file_is_saved_as_that_file_wherever_it_goes() {
    // The boulder prop as a soft body: its buffer and texture lie beside its file.
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("boulder.yaml");
    std::fs::create_dir(folder.path().join("props")).unwrap();
    for file in ["boulder.gltf", "boulder.bin", "boulder.png"] {
        std::fs::copy(path("scenes/props").join(file), folder.path().join("props").join(file)).unwrap();
    }
    std::fs::write(&scene, "entities:\n  - name: boulder\n    soft_body: { mesh: props/boulder.gltf }\n").unwrap();
    let mut app = small_app(&scene);
    let (_, body) = torso(app.world_mut());
    assert_eq!(body.save_extensions(), ["obj", "ply", "gltf"]);
    let saved = body.save(&folder.path().join("meshes"), "boulder", 0, "gltf").unwrap();
    // Saved into another folder, it stands alone: what lay beside its file is in it.
    let bytes = std::fs::read(&saved).unwrap();
    let json: Value = serde_json::from_slice(&bytes).unwrap();
    assert!(json["buffers"][0]["uri"].as_str().unwrap().starts_with("data:"));
    assert!(json["images"][0]["uri"].as_str().unwrap().starts_with("data:image/png;base64,"));
    use canopy::spatial::mesh_io::{Format, parse};
    let (read, _) = parse(&bytes, Format::Gltf, saved.parent().unwrap()).unwrap();
    let (original, _) = canopy::spatial::mesh_io::read(&path("scenes/props/boulder.gltf")).unwrap();
    assert_eq!(read, original);
}

#[test]
fn the_measure_tool_gives_two_clicked_points_distances_on_the_original_and_after_a_shrink() {
    let mut app = small_app(&path("scenes/torso.yaml"));
    let world = app.world_mut();
    let click_at = clicker(world);
    let (_, body) = torso(world);
    let outline = belly_outline(&body);
    let yaml = |text: &str| serde_yaml::from_str::<serde_yaml::Value>(text).unwrap();
    act(world, "torso", &yaml("{ use_tool: measure }"), true).unwrap();
    // Two opposite corners of the belly, clicked: measured, not marked.
    let (a, b) = (outline[0], outline[2]);
    for vertex in [a, b] {
        world.write_message(click_at(body.bench.original().positions[vertex as usize]));
    }
    app.update();
    let world = app.world_mut();
    let (_, body) = torso(world);
    assert!(body.bench.marks().is_empty());
    assert_eq!(body.bench.measured(), [a, b]);
    let original = body.bench.distances(0).unwrap();
    let along = original.along_m.unwrap();
    // Over the belly's curve the way is longer than the straight line, but not by a detour.
    assert!(along > original.straight_m && along < original.straight_m * 1.3, "{original:?}");

    // The belly outlined and shrunk: the corners hold, the way over it shortens.
    let marks: Vec<String> = outline.iter().map(|v| format!("{{ mark_vertex: {v} }}")).collect();
    act(world, "torso", &yaml(&format!("[{}]", marks.join(", "))), true).unwrap();
    act(world, "torso", &yaml("apply"), true).unwrap();
    for _ in 0..4 {
        app.update();
    }
    let output = canopy::foundation::dump::dump_state(app.world_mut());
    let dumped = entity(&output, "torso");
    let report = &dumped["models"][0]["report"]["measure"];
    assert_eq!(report["vertices"], serde_json::json!([a, b]));
    let before = report["before"]["along_m"].as_f64().unwrap();
    let after = report["after"]["along_m"].as_f64().unwrap();
    assert!((before - along).abs() < 1e-12 && after < before, "{report}");
    assert_eq!(report["before"]["straight_m"], report["after"]["straight_m"], "the outline holds");
    // The dump measures on the surface shown, the model.
    assert_eq!(dumped["measure"]["distances"]["along_m"].as_f64(), Some(after));
    // A point off the surface is refused, with why, and the points measured stay.
    let world = app.world_mut();
    act(world, "torso", &yaml("{ measure: [5, 5, 5] }"), true).unwrap();
    let (_, body) = torso(world);
    assert!(body.message.as_deref().is_some_and(|m| m.starts_with("not measured:")), "{:?}", body.message);
    assert_eq!(body.bench.measured(), [a, b]);
}
