//! Scene files: every shipped scene is valid, every malformed file in `tests/malformed/` is
//! refused with a message naming its line and field, referenced files are read once, saved
//! scenes read back the same, and a broken reload keeps the last good scene.

use super::common::*;
use canopy::foundation::dump::dump_state;
use canopy::foundation::messages::ReloadScene;
use canopy::foundation::yaml::FileError;
use canopy::muscle::MuscleDef;
use canopy::raster::texture::TextureDef;
use canopy::scene::schema::SceneDef;
use canopy::scene::{ActiveScene, SceneStatus};
use canopy::shape::ShapeDef;
use canopy::tree::TreeDef;
use std::path::{Path, PathBuf};

/// Reads and checks a scene file with every kind of the app.
fn load(path: &Path) -> Result<SceneDef, FileError> {
    canopy::app::entity_kinds().load(path).map(|scene| scene.def)
}

/// Parses and checks scene text read from `path` with every kind of the app.
fn parse(path: &Path, bytes: &[u8]) -> Result<SceneDef, FileError> {
    canopy::app::entity_kinds().parse(path, bytes).map(|scene| scene.def)
}

fn root() -> PathBuf {
    path("")
}

#[test]
fn shipped_scenes_are_valid() {
    let mut count = 0;
    for folder in ["scenes", "scenes/sloth", "tests/scenes"] {
        for entry in std::fs::read_dir(root().join(folder)).unwrap() {
            let path = entry.unwrap().path();
            let scene_test = path.to_string_lossy().ends_with(canopy::scene_test::file::TEST_FILE_SUFFIX);
            if path.extension().is_some_and(|e| e == "yaml") && !scene_test {
                load(&path).unwrap_or_else(|e| panic!("{e}"));
                count += 1;
            }
        }
    }
    assert!(count >= 3, "found only {count} scenes");
}

/// Each malformed file, the line the error must point at (None: the whole file), and words
/// the message must contain (the field and what was expected).
const MALFORMED: &[(&str, Option<usize>, &[&str])] = &[
    ("empty.yaml", None, &["the file is empty: expected a scene"]),
    ("tree_unknown_parent.yaml", Some(6), &["supports[1].parent", "no support is named \"trunks\""]),
    ("tree_cycle.yaml", Some(5), &["supports[1].parent", "forks from itself"]),
    ("tree_duplicate_support.yaml", Some(8), &["supports[1].name", "used by an earlier support"]),
    ("tree_at_outside.yaml", Some(5), &["supports[1].at", "from 0 to 1", "found 1.5"]),
    ("tree_zero_radius.yaml", Some(6), &["supports[0].radii[1]", "greater than 0", "found 0"]),
    ("tree_coincident_points.yaml", Some(5), &["supports[0].points", "points 1 and 2 coincide"]),
    ("tree_nan_point.yaml", Some(5), &["supports[0].points[1][1]", "NaN"]),
    ("tree_absurd_length.yaml", Some(8), &["supports[1].length", "at most 1000", "found 50000"]),
    ("tree_radii_mismatch.yaml", Some(6), &["supports[0].radii", "one radius per point (3), found 2"]),
    ("tree_generate_and_supports.yaml", Some(4), &["entities[0].tree.generate", "either supports or generate"]),
    ("tree_attached_with_fork_field.yaml", Some(9), &["supports[1].yaw_deg", "belongs to forks"]),
    ("tree_import_and_supports.yaml", Some(3), &["entities[0].tree.import", "import alone"]),
    ("sloth_unknown_support.yaml", Some(8), &["entities[1].sloth.support", "no support named `branch`", "oak/bough"]),
    ("sloth_ambiguous_support.yaml", Some(10), &["entities[2].sloth.support", "in 2 trees", "tree/support"]),
    ("sloth_speed.yaml", Some(7), &["speed", "from 0.05 to 0.35", "found 2.5"]),
    ("sloth_ik_sweeps.yaml", Some(7), &["ik_sweeps", "a whole number of sweeps from 1 to 256", "found 2.5"]),
    ("sloth_too_thick.yaml", Some(6), &["entities[1].sloth.support", "cannot hang", "feet do not reach"]),
    ("sloth_biceps_too_short.yaml", Some(8), &["entities[1].sloth.biceps", "cannot follow the elbow at 0 degrees"]),
    ("binary.yaml", Some(3), &["not UTF-8"]),
    ("syntax.yaml", Some(3), &["did not find expected key, while parsing a block mapping at line 2"]),
    ("unknown_section.yaml", Some(4), &["unknown field `camra`", "expected one of"]),
    ("unknown_shape_field.yaml", Some(5), &["entities[0].shape: unknown field `sise`"]),
    ("negative_size.yaml", Some(6), &["entities[0].shape.size", "greater than 0", "found -1"]),
    ("nan_position.yaml", Some(6), &["entities[1].shape.position", "expected a coordinate", "NaN"]),
    ("huge_number.yaml", Some(2), &["camera.position", "expected a coordinate", "found 1e300"]),
    ("unknown_primitive.yaml", Some(4), &["entities[0].shape.primitive", "unknown variant `cone`"]),
    ("ar_board_too_large.yaml", Some(7), &["entities[0].ar.board", "400 markers", "6x6_250 has 250"]),
    ("ar_marker_and_board.yaml", Some(3), &["entities[0].ar.marker_id", "or a `board`"]),
    ("shape_nothing.yaml", Some(5), &["entities[1].shape.primitive", "expected `primitive: box`", "or `mesh: FILE`"]),
    ("shape_mesh_and_primitive.yaml", Some(5), &["entities[0].shape.mesh", "a primitive or a mesh, not both"]),
    ("shape_mesh_texture.yaml", Some(5), &["entities[0].shape.texture", "takes its textures from its file"]),
    (
        "shape_mesh_index_out_of_range.yaml",
        Some(5),
        &["entities[0].shape.mesh", "index_out_of_range.gltf", "face 0 names vertex 5, but there are 3 vertices"],
    ),
    (
        "shape_mesh_huge_buffer.yaml",
        Some(4),
        &["entities[0].shape.mesh", "huge_buffer.gltf", "buffer 0 claims 2147483648 bytes but holds 44"],
    ),
    ("no_kind.yaml", Some(4), &["entities[1]", "an entity needs a kind: one of shape"]),
    ("unknown_kind.yaml", Some(3), &["entities[0]: unknown field `shap`", "expected", "`shape`"]),
    ("bad_hex_colour.yaml", Some(1), &["background", "six hex digits", "#12345"]),
    ("colour_out_of_range.yaml", Some(4), &["entities[0].shape.color", "from 0 to 1", "found 1.5"]),
    ("duplicate_names.yaml", Some(6), &["entities[2].name", "\"ball\" is used by an earlier entity"]),
    ("camera_looks_at_itself.yaml", Some(3), &["camera.look_at", "different from camera.position"]),
    ("fov_out_of_range.yaml", Some(3), &["camera.fov_deg", "less than 180", "found 180"]),
    ("far_before_near.yaml", Some(3), &["camera.far", "beyond camera.near"]),
    ("entities_not_a_list.yaml", Some(1), &["entities: invalid type: string", "expected a sequence"]),
    ("reserved_name.yaml", Some(2), &["entities[0].name", "reserved"]),
    ("dotted_name.yaml", Some(2), &["entities[0].name", "letters, digits", "my.ball"]),
    ("wrong_arity.yaml", Some(2), &["light.direction", "invalid length 2"]),
    ("zero_light_direction.yaml", Some(2), &["light.direction", "non-zero"]),
    (
        "muscle_mismatched_arrays.yaml",
        Some(4),
        &["entities[0].muscle.muscle_config", "radiuses has 3 values but grow_mults has 2"],
    ),
    ("muscle_zero_radius.yaml", Some(4), &["entities[0].muscle.muscle_config.radiuses", "greater than 0", "found 0"]),
    ("muscle_nan_length.yaml", Some(3), &["entities[0].muscle.muscle_config.len", "found NaN"]),
    ("muscle_missing_carcass.yaml", Some(4), &["entities[0].muscle", "needs muscle_config and carcass_config"]),
    ("muscle_bad_carcass.yaml", Some(6), &["entities[0].muscle.carcass_config.data", "invalid length 1"]),
    ("muscle_file_outside.yaml", Some(4), &["entities[0].muscle.file", "inside the scene's folder", "../../scenes"]),
    ("muscle_file_and_inline.yaml", Some(5), &["entities[0].muscle.file", "either inline or from a file, not both"]),
    ("deep_nesting.yaml", Some(1), &["entities[0]: invalid type: sequence", "expected an entity"]),
    ("terrain_zero_size.yaml", Some(4), &["entities[0].terrain.height.size", "0 x 64", "from 1 to 4096"]),
    ("terrain_section_too_large.yaml", Some(7), &["entities[0].terrain.section.size", "40 x 40", "does not fit"]),
    ("terrain_section_beyond.yaml", Some(9), &["entities[1].terrain.section.origin", "reaches beyond"]),
    ("terrain_nan_scale.yaml", Some(8), &["entities[0].terrain.height.layers[1].perlin", "scale", "found NaN"]),
    ("terrain_unknown_generator.yaml", Some(6), &["height.layers[0]", "unknown field `ridged`", "`hills`"]),
    ("terrain_colour_image.yaml", Some(4), &["entities[0].terrain.height.image", "colour.png", "grayscale"]),
    ("terrain_image_outside.yaml", Some(4), &["entities[0].terrain.height.image", "inside the scene's folder"]),
    ("terrain_image_and_layers.yaml", Some(4), &["entities[0].terrain.height", "an image or from size and layers"]),
    ("terrain_bad_thresholds.yaml", Some(7), &["entities[0].terrain.bands", "four rising heights"]),
    ("terrain_image_clamp.yaml", Some(5), &["entities[0].terrain.height.apply", "clamp", "found [1, 0]"]),
    ("terrain_bad_blend.yaml", Some(8), &["entities[0].terrain.bands", "blend.height", "found 0"]),
    ("world_hills.yaml", Some(6), &["entities[0].world.layers[1]", "the hill algorithm needs a whole map"]),
    ("world_radii.yaml", Some(6), &["entities[0].world.unload_radius_m", "greater than the load radius (200)"]),
    ("world_cells.yaml", Some(5), &["entities[0].world.chunk_cells", "one of [16, 32, 64, 128]", "found 20"]),
    ("world_map_and_layers.yaml", Some(3), &["entities[0].world.map", "`layers` beside `map`", "go inside `map`"]),
    ("world_no_heights.yaml", Some(3), &["entities[0].world.layers", "expected `layers`", "or a `map`"]),
    ("world_map_image_and_size.yaml", Some(4), &["entities[0].world.map", "an image or from size and layers"]),
    (
        "world_levels_too_close.yaml",
        Some(6),
        &["entities[0].world.level_distances_m", "levels at 50 m and 80 m lie 30 m apart", "need 69.3 m"],
    ),
    ("elastic_position_and_stem.yaml", Some(5), &["entities[0].elastic_body.position", "hangs below it"]),
    (
        "elastic_unknown_support.yaml",
        Some(8),
        &["entities[1].elastic_body.stem.support", "no support `oak/twig`", "oak/limb"],
    ),
    ("elastic_poisson.yaml", Some(5), &["entities[0].elastic_body.poisson_ratio", "from 0 to 0.5", "found 0.7"]),
    ("elastic_open_surface.yaml", Some(3), &["entities[0].elastic_body.sample", "not closed", "edges border a hole"]),
    ("elastic_too_many_tets.yaml", Some(5), &["entities[0].elastic_body.cell_m", "more than 200000 tetrahedra"]),
    (
        "elastic_stem_point_and_support.yaml",
        Some(6),
        &["entities[0].elastic_body.stem.point", "a support or a point, not both"],
    ),
    ("elastic_substeps.yaml", Some(4), &["entities[0].elastic_body.substeps", "whole number of substeps", "found 0"]),
    ("soft_body_mesh_and_sample.yaml", Some(4), &["entities[0].soft_body.sample", "a mesh or a sample, not both"]),
    ("soft_body_no_surface.yaml", Some(4), &["entities[1].soft_body.mesh", "expected `mesh: FILE`", "or `sample:"]),
    ("soft_body_area_k.yaml", Some(5), &["entities[0].soft_body.k", "below 1 for the area method", "found 1"]),
    ("soft_body_nan_mesh.yaml", Some(3), &["entities[0].soft_body.mesh", "nan.obj", "vertex 1", "not a finite number"]),
    (
        "soft_body_index_out_of_range.yaml",
        Some(3),
        &["entities[0].soft_body.mesh", "out_of_range.ply", "face 0 names vertex 7", "3 vertices"],
    ),
    ("soft_body_mesh_outside.yaml", Some(3), &["entities[0].soft_body.mesh", "inside the scene's folder"]),
    ("soft_body_sample_size.yaml", Some(5), &["entities[0].soft_body.sample.size", "from 3 to 1000", "found 2"]),
];

#[test]
fn malformed_scenes_name_their_line_and_field() {
    let folder = root().join("tests/malformed");
    let files = std::fs::read_dir(&folder)
        .unwrap()
        .filter(|entry| entry.as_ref().unwrap().path().extension().is_some_and(|e| e == "yaml"))
        .count();
    assert_eq!(files, MALFORMED.len(), "every malformed file has an expectation");
    for &(file, line, words) in MALFORMED {
        let path = folder.join(file);
        let error = load(&path).expect_err(file);
        assert_eq!(error.path, path, "{file}");
        assert_eq!(error.location.map(|(l, _)| l), line, "{file}: {error}");
        let shown = error.to_string();
        assert!(shown.starts_with(&path.display().to_string()), "{shown}");
        for word in words {
            assert!(error.message.contains(word), "{file}: `{word}` missing from: {error}");
        }
    }
}

#[test]
fn a_missing_file_is_an_error_not_a_panic() {
    let error = load(Path::new("no/such/scene.yaml")).unwrap_err();
    assert!(error.to_string().starts_with("no/such/scene.yaml: cannot read the file"), "{error}");
}

mod never_panics {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        /// Arbitrary bytes are refused or accepted, never a panic.
        #[test]
        fn on_arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = parse(Path::new("fuzz.yaml"), &bytes);
        }

        /// The demo scene with one span of characters replaced by random text: every error
        /// still names a place inside the file.
        #[test]
        fn on_mutated_scenes(start in 0usize..2000, len in 0usize..40, junk in "[ -~\n]{0,12}") {
            let text = std::fs::read_to_string(root().join("scenes/demo.yaml")).unwrap();
            let start = start.min(text.len());
            let end = (start + len).min(text.len());
            if text.is_char_boundary(start) && text.is_char_boundary(end) {
                let mutated = format!("{}{}{}", &text[..start], junk, &text[end..]);
                if let Err(error) = parse(Path::new("m.yaml"), mutated.as_bytes())
                    && let Some((line, _)) = error.location
                {
                    prop_assert!(line >= 1 && line <= mutated.lines().count() + 1, "{error}");
                }
            }
        }
    }
}

#[test]
fn referenced_configurations_are_read_and_their_errors_located() {
    let from_file = load(&root().join("scenes/biceps_from_file.yaml")).unwrap();
    let inline = load(&root().join("scenes/biceps.yaml")).unwrap();
    let muscle = |scene: &SceneDef| match scene.entities[0].def::<MuscleDef>() {
        Some(muscle) => muscle.build().unwrap(),
        None => panic!("not a muscle: {:?}", scene.entities[0]),
    };
    assert_eq!(muscle(&from_file), muscle(&inline));

    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(&scene, "entities:\n  - muscle: { file: arm.yaml }\n").unwrap();
    let error = load(&scene).unwrap_err();
    assert_eq!(error.path, folder.path().join("arm.yaml"));
    assert!(error.message.contains("cannot read the file"), "{error}");
    // Errors inside the referenced file name that file and their line there.
    let broken: [(&str, usize, &str); 2] = [
        ("muscle_config:\n  radiuses: [1, 2]\n  grow_mults: [1, 1]\n  len: -3\n", 4, "muscle_config.len"),
        (
            "# an arm\nmuscle_config:\n  radiuses: [1, 2]\n  grow_mults: [1]\n  len: 3\ncarcass_config: { data: [[1, 2], [1, 2]], thickness: 1 }\n",
            2,
            "radiuses has 2 values but grow_mults has 1",
        ),
    ];
    for (contents, line, words) in broken {
        std::fs::write(folder.path().join("arm.yaml"), contents).unwrap();
        let error = load(&scene).unwrap_err();
        assert_eq!(
            (error.path.clone(), error.location.map(|l| l.0)),
            (folder.path().join("arm.yaml"), Some(line)),
            "{error}"
        );
        assert!(error.message.contains(words), "{error}");
    }
}

#[test]
fn textures_are_decoded_with_the_scene_and_bad_ones_name_their_file() {
    let demo = load(&root().join("scenes/demo.yaml")).unwrap();
    let textures: Vec<(u32, u32)> = demo
        .entities
        .iter()
        .filter_map(|entity| entity.def::<ShapeDef>().and_then(|shape| shape.texture.as_ref()))
        .map(|texture| texture.image.as_ref().map(|i| (i.width(), i.height())).expect("decoded"))
        .collect();
    // The checker board is a PNG, the bricks a BMP.
    assert_eq!(textures, [(64, 64), (64, 64)]);
    // Trees take textures too.
    let tree = load(&root().join("scenes/tree.yaml")).unwrap();
    fn texture(e: &canopy::scene::schema::EntityDef) -> Option<&TextureDef> {
        e.def::<TreeDef>().and_then(|t| t.texture.as_ref()).or_else(|| e.def::<ShapeDef>()?.texture.as_ref())
    }
    let bark = tree.entities.iter().find_map(texture).and_then(|t| t.image.as_ref()).expect("decoded");
    assert_eq!((bark.width(), bark.height()), (64, 64));

    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(&scene, "entities:\n  - shape: { primitive: box, texture: { file: wood.png } }\n").unwrap();
    let error = load(&scene).unwrap_err();
    assert_eq!(error.path, folder.path().join("wood.png"));
    assert!(error.message.contains("cannot read the file"), "{error}");
    std::fs::write(folder.path().join("wood.png"), "not an image").unwrap();
    let error = load(&scene).unwrap_err();
    assert_eq!(error.path, folder.path().join("wood.png"));
    assert!(error.message.contains("entities[0].shape.texture.file: not a readable PNG or BMP image"), "{error}");
}

#[test]
fn every_shipped_scene_survives_being_written_and_read_back() {
    let mut checked = 0;
    let folders = ["scenes", "scenes/sloth"].map(|folder| std::fs::read_dir(root().join(folder)).unwrap());
    for entry in folders.into_iter().flatten() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        let scene = load(&path).unwrap();
        let text = canopy::app::entity_kinds().to_yaml(&scene).unwrap();
        // Read back from the same folder, so that referenced files resolve alike.
        let again = parse(&path, text.as_bytes()).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(again, scene, "{}", path.display());
        checked += 1;
    }
    assert!(checked >= 12, "{checked} scenes");
}

#[test]
fn a_broken_reload_keeps_the_last_good_scene_and_a_fixed_one_replaces_it() {
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("live.yaml");
    std::fs::write(&scene, "entities:\n  - name: first\n    shape: { primitive: box }\n").unwrap();
    let mut app = canopy::app::headless_app(&scene, SMALL, false).unwrap();
    update_until(&mut app, |s| s.status == SceneStatus::Live);
    let names = |app: &mut bevy::app::App| -> Vec<String> {
        let dump = dump_state(app.world_mut());
        dump["entities"].as_array().unwrap().iter().map(|e| e["name"].as_str().unwrap().to_string()).collect()
    };
    assert_eq!(names(&mut app), ["camera", "light", "render", "first"]);

    std::fs::write(&scene, "entities:\n  - name: first\n    shape: { primitive: bx }\n").unwrap();
    app.world_mut().write_message(ReloadScene);
    update_until(&mut app, |s| s.error.is_some());
    let scene_state = app.world().resource::<ActiveScene>();
    assert_eq!(scene_state.status, SceneStatus::Live);
    let error = scene_state.error.clone().unwrap();
    assert!(error.contains("live.yaml:3:") && error.contains("unknown variant `bx`"), "{error}");
    app.update();
    assert_eq!(names(&mut app), ["camera", "light", "render", "first"]);

    std::fs::write(&scene, "entities:\n  - name: first\n    shape: { primitive: box }\n  - name: second\n    shape: { primitive: sphere }\n").unwrap();
    app.world_mut().write_message(ReloadScene);
    update_until(&mut app, |s| s.generation == 2);
    app.update();
    assert_eq!(app.world().resource::<ActiveScene>().error, None);
    assert_eq!(names(&mut app), ["camera", "light", "render", "first", "second"]);
}
