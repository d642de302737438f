//! Trees: dumped supports, picking in the view, edits with undo, saving with a backup.

use super::common::*;
use bevy::math::Vec3;
use canopy::foundation::dump::dump_state;
use serde_json::Value;

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
    use canopy::spatial::pick::{Pickable, nearest_hit};
    use canopy::tree::TreeBody;
    use canopy::view::CameraParams;
    let mut app = small_app(&path("scenes/tree.yaml"));
    let world = app.world_mut();
    let camera = world.query::<&CameraParams>().single(world).unwrap().camera();
    let aspect = SMALL.x as f32 / SMALL.y as f32;
    let mut pickables = world.query::<(bevy::prelude::Entity, &Pickable)>();
    let mut trees = world.query::<(bevy::prelude::Entity, &TreeBody)>();
    let (_, body) = trees.single(world).unwrap();
    let index = |name: &str| body.tree.supports.iter().position(|s| s.name == name).unwrap();
    for (name, fraction) in [("low", 0.7), ("high", 0.5), ("trunk", 0.2)] {
        let (point, _, _) = body.tree.supports[index(name)].at(fraction);
        let ndc = camera.view_projection(aspect).project_point3(point);
        let (origin, direction) = camera.ray(ndc.truncate(), aspect);
        let picked = nearest_hit(pickables.iter(world), origin, direction).expect("a hit");
        assert_eq!(body.segment_supports[picked.part], index(name), "aiming at {name}");
        // The hit lies about where the axis point aimed at does (within the branch's radius).
        let length = body.tree.supports[index(name)].length();
        let at = body.fraction_along(picked.part, picked.along);
        assert!((at - fraction).abs() * length < 0.3, "{name}: {at} vs {fraction}");
        assert!(picked.normal.expect("a segment's normal").dot(direction) < 0.0, "the normal faces the ray");
        // The hit is on the near side of the axis point aimed at.
        assert!(picked.point.distance(point) < 0.3 && picked.distance < (point - origin).length(), "{picked:?}");
    }
    // Aiming at the sky hits nothing.
    let (origin, direction) = camera.ray(bevy::math::Vec2::new(0.9, 0.9), aspect);
    assert!(nearest_hit(pickables.iter(world), origin, direction).is_none());

    // A click in the view selects the support under it.
    let (low, _, _) = body.tree.supports[index("low")].at(0.7);
    let low_index = index("low");
    let ndc = camera.view_projection(aspect).project_point3(low).truncate();
    world.write_message(canopy::foundation::messages::ViewClicked { ndc, aspect });
    app.update();
    let world = app.world_mut();
    let selected = world.query::<&canopy::tree::SelectedSupport>().single(world).unwrap();
    assert_eq!(selected.0, low_index);
}

#[test]
fn tree_edits_rebuild_the_tree_and_undo_restores_it() {
    use canopy::tree::edit::{Edit, ForkField};
    use canopy::tree::{TreeBody, edit_tree, undo_tree_edit};
    let mut app = small_app(&path("scenes/tree.yaml"));
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
    let mut app = small_app(&scene);
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

    let reread = canopy::app::entity_kinds().load(&scene).unwrap().def;
    let Some(tree) = reread.entities[0].def::<canopy::tree::TreeDef>() else { panic!("not a tree") };
    let built = tree.build().unwrap();
    let names: Vec<&str> = built.supports.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["trunk", "limb", "limb-1"]);
    assert!((built.supports[1].length() - 2.5).abs() < 1e-5);
}

#[test]
fn trees_on_a_terrain_stand_on_its_ground_through_edits_and_say_when_they_cannot() {
    use canopy::terrain::def::TerrainBuilt;
    use canopy::tree::edit::{Edit, ForkField};
    use canopy::tree::{Tree, TreeBody, edit_tree};
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("hill.yaml");
    let text = "entities:\n  - name: land\n    terrain:\n      height: {size: [40, 40], seed: 5, layers: [{perlin: {scale: 16, octaves: 2}}], apply: [normalize]}\n      \
        section: {origin: [4, 4], size: [32, 32]}\n      cell_m: 0.5\n      height_m: 3\n      position: [1, 0.5, 0]\n      rotation_deg: 20\n  \
        - name: oak\n    tree:\n      ground: land\n      supports:\n        \
        - { name: trunk, points: [[2.0, 0, -1.5], [2.1, 3, -1.5]], radii: [0.2, 0.1] }\n        \
        - { name: limb, parent: trunk, at: 0.6, length: 1.2, radius: [0.08, 0.03] }\n  \
        - name: grove\n    tree:\n      ground: land\n      generate: {seed: 4, trunks: 4, height: 3, spacing: 3, depth: 1}\n";
    std::fs::write(&scene, text).unwrap();
    let loaded = canopy::app::entity_kinds().load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let terrain = loaded.built[0].downcast_ref::<TerrainBuilt>().unwrap();
    for index in [1, 2] {
        let tree = loaded.built[index].downcast_ref::<Tree>().unwrap();
        let trunks: Vec<_> =
            tree.supports.iter().filter(|s| tree.lifts.iter().any(|(name, _)| *name == s.name)).collect();
        assert!(!trunks.is_empty());
        for trunk in trunks {
            let base = trunk.points[0];
            let ground = terrain.ground.height_under(base.x, base.z).unwrap();
            assert!((base.y - ground).abs() < 1e-5, "{} stands at {} over ground at {ground}", trunk.name, base.y);
        }
    }
    // Edited in the window, the tree keeps standing on the ground.
    let mut app = small_app(&scene);
    let world = app.world_mut();
    let mut oaks = world.query::<(bevy::prelude::Entity, &TreeBody)>();
    let (oak, body) = oaks.iter(world).find(|(_, body)| body.tree.supports.len() == 2).unwrap();
    let base = body.tree.supports[0].points[0];
    assert!(base.y.abs() > 1e-3, "raised off y = 0: {base}");
    edit_tree(world, oak, Edit::Fork { support: 1, field: ForkField::Length, value: 2.0 }).unwrap();
    assert_eq!(world.get::<TreeBody>(oak).unwrap().tree.supports[0].points[0], base);

    let changes = [
        (
            "ground: land\n      supports",
            "ground: lamd\n      supports",
            "no terrain or world named `lamd` (grounds: land)",
        ),
        (
            "[[2.0, 0, -1.5], [2.1, 3, -1.5]]",
            "[[40, 0, 0], [40, 3, 0]]",
            "support `trunk` starts at x 40.00, z 0.00, off the terrain `land`'s section",
        ),
    ];
    assert_refused(&scene, text, &changes, "entities[1].tree.ground", 12);
}

/// Writes `text` with each of `changes` (from, to, the reason expected) into `scene` in turn,
/// and checks that loading it is refused for that reason at `field`, on line `line`.
fn assert_refused(scene: &std::path::Path, text: &str, changes: &[(&str, &str, &str)], field: &str, line: usize) {
    for (from, to, expected) in changes {
        assert!(text.contains(from), "`{from}` is in the scene");
        std::fs::write(scene, text.replace(from, to)).unwrap();
        let error = canopy::app::entity_kinds().load(scene).unwrap_err();
        assert!(error.message.contains(field) && error.message.contains(expected), "{error}");
        assert_eq!(error.location.map(|l| l.0), Some(line), "{error}");
    }
}

#[test]
fn trees_are_scattered_only_over_a_streamed_world_with_sensible_settings() {
    // The scene as written loads; each change below is refused at `scatter`.
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("scatter.yaml");
    let text = "entities:\n  - name: land\n    world:\n      seed: 7\n      layers: [{perlin: {scale: 90}}]\n  \
        - name: woods\n    tree:\n      ground: land\n      scatter: {seed: 4, per_chunk: 2}\n";
    std::fs::write(&scene, text).unwrap();
    canopy::app::entity_kinds().load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let changes = [
        (
            "ground: land",
            "ground: lamd",
            "trees are scattered over the chunks of a streamed world: name one in `ground` (worlds: land)",
        ),
        ("per_chunk: 2", "per_chunk: 0", "per_chunk: expected 1 to 8 trees, found 0"),
        (
            "per_chunk: 2}",
            "per_chunk: 2}\n      generate: {seed: 1}",
            "give scatter alone, without supports or generate",
        ),
    ];
    assert_refused(&scene, text, &changes, "entities[1].tree.scatter", 9);
}
