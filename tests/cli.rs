//! The command line as scripts use it: exit codes, files written, messages on stderr.

use std::path::Path;
use std::process::{Command, Output};

fn canopy(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_canopy"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn run_twice_gives_identical_files() {
    let folder = tempfile::tempdir().unwrap();
    let files = |n: usize| {
        let png = folder.path().join(format!("a{n}.png"));
        let json = folder.path().join(format!("a{n}.json"));
        let output = canopy(&[
            "run",
            "scenes/demo.yaml",
            "--frames",
            "30",
            "--size",
            "320x180",
            "--screenshot",
            png.to_str().unwrap(),
            "--dump",
            json.to_str().unwrap(),
        ]);
        assert!(output.status.success(), "{}", stderr(&output));
        (std::fs::read(png).unwrap(), std::fs::read_to_string(json).unwrap())
    };
    let (png_a, json_a) = files(1);
    let (png_b, json_b) = files(2);
    assert_eq!(png_a, png_b);
    assert_eq!(json_a, json_b);
    let dump: serde_json::Value = serde_json::from_str(&json_a).unwrap();
    assert_eq!(dump["frame"], 30);
    assert!((dump["time"].as_f64().unwrap() - 0.5).abs() < 1e-6);
    let image = image::load_from_memory(&png_a).unwrap();
    assert_eq!((image.width(), image.height()), (320, 180));
}

#[test]
fn seconds_are_rounded_to_fixed_steps() {
    let folder = tempfile::tempdir().unwrap();
    let json = folder.path().join("s.json");
    let output =
        canopy(&["run", "scenes/demo.yaml", "--seconds", "0.25", "--size", "64x36", "--dump", json.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    let dump: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    assert_eq!(dump["frame"], 15);
}

#[test]
fn check_accepts_valid_scenes_and_reports_every_broken_file() {
    let output = canopy(&["check", "scenes/demo.yaml", "tests/scenes/red_sphere.yaml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(String::from_utf8_lossy(&output.stdout).contains("scenes/demo.yaml: ok"));

    let output = canopy(&[
        "check",
        "tests/malformed/negative_size.yaml",
        "scenes/demo.yaml",
        "tests/malformed/unknown_shape_field.yaml",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let errors = stderr(&output);
    assert!(errors.contains("tests/malformed/negative_size.yaml:6:"), "{errors}");
    assert!(
        errors.contains("tests/malformed/unknown_shape_field.yaml:5:7: entities[0].shape: unknown field `sise`"),
        "{errors}"
    );
}

#[test]
fn invalid_input_exits_with_1_and_says_where() {
    let output = canopy(&["run", "tests/malformed/nan_position.yaml", "--frames", "1"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("nan_position.yaml:6:"), "{}", stderr(&output));

    let folder = tempfile::tempdir().unwrap();
    let timeline = folder.path().join("t.yaml");
    std::fs::write(&timeline, "- { at: 0, press: [KeyW] }\n- { at: 1, press: [Kew] }\n").unwrap();
    let output = canopy(&["run", "scenes/demo.yaml", "--input", timeline.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(1));
    assert!(
        stderr(&output).contains("t.yaml:2:") && stderr(&output).contains("unknown key `Kew`"),
        "{}",
        stderr(&output)
    );

    std::fs::write(&timeline, "- { at: 0, set: { lamp.azimuth_deg: 3 } }\n").unwrap();
    let output = canopy(&["run", "scenes/demo.yaml", "--input", timeline.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("no entity is named `lamp`"), "{}", stderr(&output));

    let output = canopy(&["run", "no/such/scene.yaml"]);
    assert_eq!(output.status.code(), Some(1));
}

#[test]
fn a_bad_command_line_exits_with_2() {
    for args in [
        &["run"][..],
        &["run", "scenes/demo.yaml", "--size", "0x10"],
        &["run", "scenes/demo.yaml", "--frames", "3", "--seconds", "1"],
        &["run", "scenes/demo.yaml", "--seconds", "NaN"],
        &["check"],
        &["fly"],
    ] {
        let output = canopy(args);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {}", stderr(&output));
    }
}

#[test]
fn play_without_a_display_renders_headless_and_prints_the_png() {
    let output = canopy(&["play", "tests/scenes/red_sphere.yaml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stderr(&output).contains("no display available"), "{}", stderr(&output));
    let printed = String::from_utf8_lossy(&output.stdout).trim().to_string();
    assert!(printed.ends_with(".png") && Path::new(&printed).is_file(), "printed `{printed}`");
    let image = image::open(&printed).unwrap().to_rgba8();
    assert_eq!(image.get_pixel(640, 360).0, [255, 0, 0, 255]);
}

#[test]
fn generated_forests_are_deterministic_valid_and_never_overwrite() {
    let folder = tempfile::tempdir().unwrap();
    let out = |name: &str| folder.path().join(name).to_string_lossy().into_owned();
    let generate = |seed: &str, file: &str, extra: &[&str]| {
        let mut args = vec!["tree", "generate", "--seed", seed, "--trunks", "6", "--out"];
        let file = out(file);
        args.push(&file);
        args.extend_from_slice(extra);
        canopy(&args)
    };
    assert!(generate("11", "a.yaml", &[]).status.success());
    assert!(generate("11", "b.yaml", &[]).status.success());
    assert!(generate("12", "c.yaml", &[]).status.success());
    let read = |name: &str| std::fs::read_to_string(out(name)).unwrap();
    assert_eq!(read("a.yaml"), read("b.yaml"));
    assert_ne!(read("a.yaml"), read("c.yaml"));
    assert_eq!(read("a.yaml").matches("tree:").count(), 6);

    // The output is an ordinary scene: it checks and plays.
    assert!(canopy(&["check", &out("a.yaml")]).status.success());
    let frame = out("a.png");
    assert!(
        canopy(&["run", &out("a.yaml"), "--frames", "1", "--size", "64x48", "--screenshot", &frame]).status.success()
    );

    // An existing file is kept unless --force.
    std::fs::write(out("mine.yaml"), "# my scene\n").unwrap();
    let refused = generate("11", "mine.yaml", &[]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(stderr(&refused).contains("already exists"), "{}", stderr(&refused));
    assert_eq!(read("mine.yaml"), "# my scene\n");
    assert!(generate("11", "mine.yaml", &["--force"]).status.success());
    assert_eq!(read("mine.yaml"), read("a.yaml"));

    // Settings out of range are a usage error.
    let bad = generate("11", "d.yaml", &["--depth", "9"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("depth: expected at most 4 levels"), "{}", stderr(&bad));
}

#[test]
fn scanned_tree_models_import_as_scenes_and_bad_ones_are_located() {
    let folder = tempfile::tempdir().unwrap();
    let out = |name: &str| folder.path().join(name).to_string_lossy().into_owned();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/qsm/itsme_qsm_tree_v230.mat");
    let model = model.to_string_lossy();
    let imported = canopy(&["tree", "import", &model, "--out", &out("scan.yaml")]);
    assert!(imported.status.success(), "{}", stderr(&imported));
    let said = String::from_utf8_lossy(&imported.stdout);
    assert!(said.contains("of the 88 cylinders"), "{said}");
    // The written scene is an ordinary one: it checks, and its branches grow from their parents.
    let scene = std::fs::read_to_string(out("scan.yaml")).unwrap();
    assert!(scene.contains("name: stem") && scene.contains("parent: stem"), "{scene}");
    assert!(canopy(&["check", &out("scan.yaml")]).status.success());
    // With a sloth: refused for a small tree with no bough long enough to walk; on the shipped
    // scan, on autorun on a bough it walks along, and the scene plays.
    let none = canopy(&["tree", "import", &model, "--sloth", "--out", &out("none.yaml")]);
    assert_eq!(none.status.code(), Some(2));
    assert!(stderr(&none).contains("no bough"), "{}", stderr(&none));
    let scan = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/scans/itsme_tree_v240.mat");
    let scan = scan.to_string_lossy();
    let with_sloth =
        canopy(&["tree", "import", &scan, "--min-radius-m", "0.01", "--sloth", "--out", &out("sloth.yaml")]);
    assert!(with_sloth.status.success(), "{}", stderr(&with_sloth));
    let scene = std::fs::read_to_string(out("sloth.yaml")).unwrap();
    assert!(scene.contains("sloth: { support: scan/") && scene.contains("autorun: true"), "{scene}");
    let dump = out("sloth.json");
    assert!(
        canopy(&["run", &out("sloth.yaml"), "--seconds", "10", "--size", "64x48", "--dump", &dump]).status.success()
    );
    let state: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&dump).unwrap()).unwrap();
    let sloth = state["entities"].as_array().unwrap().iter().find(|e| e["name"] == "sloth").unwrap();
    assert!(sloth["distance_travelled"].as_f64().unwrap() > 0.5, "{sloth}");

    // Thin twigs kept to draw: every cylinder of the piece is there, the twigs are supports no
    // thicker than the least radius, offered to no sloth.
    let drawn =
        canopy(&["tree", "import", &scan, "--min-radius-m", "0.01", "--draw-thin", "--out", &out("drawn.yaml")]);
    assert!(drawn.status.success(), "{}", stderr(&drawn));
    assert!(String::from_utf8_lossy(&drawn.stdout).contains("thinner than 0.01 m drawn, never gripped"));
    let scene = std::fs::read_to_string(out("drawn.yaml")).unwrap();
    assert!(scene.contains("grip_min_radius_m: 0.01"), "{scene}");
    let dump = out("drawn.json");
    assert!(canopy(&["run", &out("drawn.yaml"), "--frames", "1", "--size", "64x48", "--dump", &dump]).status.success());
    let state: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&dump).unwrap()).unwrap();
    let tree = state["entities"].as_array().unwrap().iter().find(|e| e["name"] == "scan").unwrap();
    let supports = tree["supports"].as_array().unwrap();
    let thickest =
        |s: &serde_json::Value| s["radii"].as_array().unwrap().iter().map(|r| r.as_f64().unwrap()).fold(0.0, f64::max);
    let (gripped, twigs): (Vec<_>, Vec<_>) = supports.iter().partition(|s| s["gripped"] == true);
    assert!(twigs.len() > 10 && gripped.len() > 100, "{} twigs, {} gripped", twigs.len(), gripped.len());
    let least = f64::from(0.01f32);
    assert!(twigs.iter().all(|s| thickest(s) < least) && gripped.iter().all(|s| thickest(s) >= least));
    let twig = twigs[0]["name"].as_str().unwrap();
    let on_twig = scene.replace("entities:\n", &format!("entities:\n  - sloth: {{ support: scan/{twig} }}\n"));
    std::fs::write(out("on_twig.yaml"), on_twig).unwrap();
    let refused = canopy(&["check", &out("on_twig.yaml")]);
    assert!(stderr(&refused).contains(&format!("`scan/{twig}` is drawn but never gripped")), "{}", stderr(&refused));

    // The same model inline, in SimpleForest's CSV, with a parent that is no cylinder.
    let csv = "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,0.1\n1,7,0,0,1,0,0,2,0.1\n";
    std::fs::write(out("bad.csv"), csv).unwrap();
    let inline = "entities:\n  - name: scan\n    tree:\n      import: { file: bad.csv }\n";
    std::fs::write(out("inline.yaml"), inline).unwrap();
    let checked = canopy(&["check", &out("inline.yaml")]);
    assert!(!checked.status.success());
    assert!(stderr(&checked).contains("bad.csv:3:3: parentID: no cylinder has the ID 7"), "{}", stderr(&checked));
    std::fs::write(out("bad.csv"), csv.replace(",7,", ",0,")).unwrap();
    assert!(canopy(&["check", &out("inline.yaml")]).status.success(), "fixed, it loads");

    // A truncated MATLAB file and a misnamed format are refused with the file named.
    let bytes = std::fs::read(model.as_ref()).unwrap();
    std::fs::write(out("cut.mat"), &bytes[..bytes.len() / 2]).unwrap();
    let cut = canopy(&["tree", "import", &out("cut.mat"), "--out", &out("cut.yaml")]);
    assert_eq!(cut.status.code(), Some(2));
    assert!(stderr(&cut).contains("cut.mat"), "{}", stderr(&cut));
    assert!(!Path::new(&out("cut.yaml")).exists());
    let misnamed = canopy(&["tree", "import", &model, "--format", "obj", "--out", &out("x.yaml")]);
    assert_eq!(misnamed.status.code(), Some(2));
}

#[test]
fn a_survey_walks_every_bough_and_says_how_each_walk_ended() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tree.yaml");
    let surveyed = canopy(&["sloth", "survey", &scene.to_string_lossy()]);
    assert!(surveyed.status.success(), "{}", stderr(&surveyed));
    let said = String::from_utf8_lossy(&surveyed.stdout);
    // The oak's three boughs, each a line, and the tally.
    assert_eq!(said.lines().filter(|l| l.starts_with("oak/")).count(), 3, "{said}");
    assert!(said.contains("3 branches: the sloth hangs from 3, walks 3 from end to end"), "{said}");
    let slow = canopy(&["sloth", "survey", &scene.to_string_lossy(), "--speed", "2"]);
    assert_eq!(slow.status.code(), Some(1));
    assert!(stderr(&slow).contains("--speed"), "{}", stderr(&slow));
}

#[test]
fn deform_writes_a_gltf_file_back_standing_alone_in_another_folder() {
    use bevy::math::Vec3;
    use canopy::spatial::mesh_io::{self, Format};
    let input = Path::new("scenes/props/boulder.gltf");
    let (boulder, _) = mesh_io::read(input).unwrap();
    // Four vertices around the boulder's top outline its cap.
    let top = boulder.positions.iter().copied().fold(Vec3::NEG_INFINITY, |a, p| if p.y > a.y { p } else { a });
    let nearest = |to: Vec3| {
        let p = *boulder.positions.iter().min_by(|a, b| a.distance(to).total_cmp(&b.distance(to))).unwrap();
        format!("{}:{}:{}", p.x, p.y, p.z)
    };
    let around = [Vec3::X, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Z].map(|d| nearest(top + d * 0.25 - Vec3::Y * 0.05));
    let folder = tempfile::tempdir().unwrap();
    let out = folder.path().join("boulder.gltf");
    let args = [
        "deform",
        input.to_str().unwrap(),
        "--region",
        &around.join(","),
        "--k",
        "0.9",
        "--out",
        out.to_str().unwrap(),
    ];
    let output = canopy(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    // Read where it was written, with no boulder.bin or boulder.png beside it.
    let bytes = std::fs::read(&out).unwrap();
    let (shrunk, _) = mesh_io::parse(&bytes, Format::Gltf, folder.path()).unwrap();
    assert_eq!((shrunk.positions.len(), &shrunk.triangles), (boulder.positions.len(), &boulder.triangles));
    let moved = boulder.positions.iter().zip(&shrunk.positions).filter(|(a, b)| a != b).count();
    assert!(moved > 0 && moved < boulder.positions.len() / 2, "{moved} vertices moved");
    let drawn = mesh_io::drawing(&bytes, Format::Gltf, folder.path()).unwrap();
    let original = mesh_io::drawing(&std::fs::read(input).unwrap(), Format::Gltf, Path::new("scenes/props")).unwrap();
    assert_eq!(drawn.images, original.images);
}

#[test]
fn deform_shrinks_a_region_of_a_mesh_file_and_prints_its_report() {
    use canopy::soft_body::sample;
    use canopy::spatial::mesh_io;
    let folder = tempfile::tempdir().unwrap();
    let belly = sample::belly(25);
    let input = folder.path().join("belly.obj");
    let written = canopy(&["mesh", "sample", "belly", "--size", "25", "--out", input.to_str().unwrap()]);
    assert!(written.status.success(), "{}", stderr(&written));
    assert_eq!(mesh_io::read(&input).unwrap().0.triangles.len(), belly.triangles.len());
    let corner = |i: u32, j: u32| {
        let p = belly.positions[(j * 25 + i) as usize];
        format!("{}:{}:{}", p.x, p.y, p.z)
    };
    let region = [corner(6, 6), corner(18, 6), corner(18, 18), corner(6, 18)].join(",");
    let out = folder.path().join("shrunk.obj");
    let (input, out) = (input.to_str().unwrap(), out.to_str().unwrap());
    let args = ["deform", input, "--region", &region, "--method", "edge-sum", "--k", "0.97", "--out", out];
    let output = canopy(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["region_vertices"], 121);
    assert_eq!(report["stop"], "converged");
    assert_eq!(report["facts"]["fixed_unchanged"], true);
    let ratio = report["facts"]["edge_sum_ratio"].as_f64().unwrap();
    assert!((ratio - 0.97).abs() < 1e-4, "{ratio}");
    // The volume between the surface before and after, as the shrunk file and the original
    // give it.
    let volume = report["facts"]["volume_between_m3"].as_f64().unwrap();
    let (shrunk, _) = mesh_io::read(std::path::Path::new(out)).unwrap();
    let measured = belly.volume_between(&belly.positions, &shrunk.positions);
    assert!(volume > 0.0 && (volume - measured).abs() < 1e-3 * volume, "{volume} reported, {measured} measured");
    // The result is never overwritten unasked; settings out of range are usage errors.
    let again = canopy(&args);
    assert_eq!(again.status.code(), Some(1));
    assert!(stderr(&again).contains("already exists"), "{}", stderr(&again));
    let area_of_one = ["deform", input, "--region", &region, "--method", "area", "--k", "1", "--out", "x.obj"];
    let bad = canopy(&area_of_one);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(!Path::new("x.obj").exists());
}

#[test]
fn ar_tools_print_markers_poses_and_sequences() {
    let folder = tempfile::tempdir().unwrap();
    // A printable marker, read back by the detector tool.
    let marker = folder.path().join("marker.png");
    let output = canopy(&[
        "ar",
        "marker",
        "--dictionary",
        "4x4_50",
        "--id",
        "7",
        "--cell-px",
        "20",
        "--out",
        marker.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let image = image::open(&marker).unwrap();
    assert_eq!((image.width(), image.height()), (160, 160), "4 cells, the border and a margin of a cell: 8 cells");
    let again = canopy(&["ar", "marker", "--id", "7", "--out", marker.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(1), "an existing file is never replaced unasked");
    let wrong = canopy(&["ar", "marker", "--dictionary", "4x4_50", "--id", "50", "--out", "x.png"]);
    assert!(wrong.status.code() == Some(2) && stderr(&wrong).contains("markers 0 to 49"), "{}", stderr(&wrong));

    // A printable grid board: the detector finds each of its markers where the layout has it.
    let board = folder.path().join("board.png");
    let args = ["ar", "board", "--markers", "4x3", "--marker-m", "0.03", "--separation-m", "0.006", "--first-id", "5"];
    let output = canopy(&[&args[..], &["--pixels-per-metre", "4000", "--out", board.to_str().unwrap()]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let found = canopy(&["ar", "detect", board.to_str().unwrap()]);
    let found: serde_json::Value = serde_json::from_slice(&found.stdout).unwrap();
    let markers = found[0]["markers"].as_array().unwrap();
    assert_eq!(markers.len(), 12);
    for marker in markers {
        let index = marker["id"].as_u64().unwrap() - 5;
        // 144 pixels a marker and its gap, a 24-pixel margin: the top-left corner's pixel centre.
        let top_left = [24.0 + 144.0 * (index % 4) as f64 - 0.5, 24.0 + 144.0 * (index / 4) as f64 - 0.5];
        let corner = marker["corners"][0].as_array().unwrap();
        assert!((corner[0].as_f64().unwrap() - top_left[0]).abs() < 0.6, "{marker}");
        assert!((corner[1].as_f64().unwrap() - top_left[1]).abs() < 0.6, "{marker}");
    }
    let too_many =
        canopy(&["ar", "board", "--markers", "20x20", "--marker-m", "0.03", "--separation-m", "0", "--out", "x.png"]);
    assert!(too_many.status.code() == Some(2) && stderr(&too_many).contains("has 250"), "{}", stderr(&too_many));

    // A short synthetic sequence, then the detector on two of its frames and a bad file.
    let sequence = folder.path().join("seq");
    let output = canopy(&[
        "ar",
        "sequence",
        "--out",
        sequence.to_str().unwrap(),
        "--frames",
        "3",
        "--size",
        "320x240",
        "--no-look-away",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sequence.join("truth.json")).unwrap()).unwrap();
    let broken = folder.path().join("broken.png");
    std::fs::write(&broken, b"not an image").unwrap();
    let frame = sequence.join("frame-0001.png");
    let calibration = sequence.join("calibration.yaml");
    let output = canopy(&[
        "ar",
        "detect",
        frame.to_str().unwrap(),
        broken.to_str().unwrap(),
        "--calibration",
        calibration.to_str().unwrap(),
        "--dictionary",
        "6x6_250",
        "--side",
        "0.1",
    ]);
    assert_eq!(output.status.code(), Some(1), "an unreadable image fails the run: {}", stderr(&output));
    assert!(stderr(&output).contains("broken.png"));
    let results: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let found = &results[0]["markers"];
    assert_eq!(found.as_array().unwrap().len(), 1);
    assert_eq!(found[0]["id"], 23);
    for (corner, expected) in
        found[0]["corners"].as_array().unwrap().iter().zip(truth["frames"][0]["corners"].as_array().unwrap())
    {
        let d = (0..2).map(|k| (corner[k].as_f64().unwrap() - expected[k].as_f64().unwrap()).powi(2)).sum::<f64>();
        assert!(d.sqrt() < 0.5, "{corner} for {expected}");
    }
    let tz = found[0]["tvec"][2].as_f64().unwrap();
    let true_tz = truth["frames"][0]["tvec"][2].as_f64().unwrap();
    assert!((tz - true_tz).abs() < 0.01 * true_tz, "{tz} for {true_tz}");
    assert!(results[1]["error"].as_str().unwrap().contains("broken.png"));
    // The printed marker, without a calibration: ids and corners only.
    let read = |dictionary: &str| {
        let output = canopy(&["ar", "detect", marker.to_str().unwrap(), "--dictionary", dictionary]);
        assert!(output.status.success(), "{}", stderr(&output));
        serde_json::from_slice::<serde_json::Value>(&output.stdout).unwrap()[0]["markers"].clone()
    };
    assert_eq!(read("6x6_250"), serde_json::json!([]), "a 4x4 marker is not in 6x6_250: none found");
    let printed = read("4x4_50");
    assert_eq!((printed[0]["id"].as_u64(), printed[0].get("rvec")), (Some(7), None));

    let unknown = canopy(&["ar", "detect", frame.to_str().unwrap(), "--dictionary", "8x8_1"]);
    assert!(
        unknown.status.code() == Some(2) && stderr(&unknown).contains("unknown dictionary `8x8_1`"),
        "{}",
        stderr(&unknown)
    );
}

/// The scene tests of `tests/scenes/`, through the runner as a user runs it: every one passes,
/// and the JUnit report read back lists each test once.
#[test]
fn shipped_scene_tests_pass() {
    let folder = tempfile::tempdir().unwrap();
    let junit = folder.path().join("junit.xml");
    let artifacts = folder.path().join("artifacts");
    let output = canopy(&[
        "test",
        "tests/scenes",
        "--jobs",
        "2",
        "--junit",
        junit.to_str().unwrap(),
        "--artifacts",
        artifacts.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}\n{}", stderr(&output));
    let listed = canopy(&["test", "tests/scenes", "--list"]);
    let names: Vec<String> = String::from_utf8_lossy(&listed.stdout).lines().map(str::to_string).collect();
    let report = quick_junit::Report::deserialize_from_str(&std::fs::read_to_string(junit).unwrap()).unwrap();
    let mut cases: Vec<String> =
        report.test_suites.iter().flat_map(|s| s.test_cases.iter().map(|c| c.name.to_string())).collect();
    cases.sort();
    assert_eq!(cases, names);
    assert!(stdout.ends_with(&format!("{} passed, 0 failed\n", names.len())), "{stdout}");
}

/// A scene test file in a temporary folder, its scene named by absolute path.
fn scene_test(folder: &Path, name: &str, scene: &str, body: &str) -> std::path::PathBuf {
    let scene = std::env::current_dir().unwrap().join(scene);
    let path = folder.join(format!("{name}.test.yaml"));
    std::fs::write(&path, format!("scene: {}\n{body}", scene.display())).unwrap();
    path
}

fn run_tests(folder: &Path, extra: &[&str]) -> (Output, String) {
    let artifacts = folder.join("artifacts");
    let mut args = vec!["test", folder.to_str().unwrap(), "--jobs", "2", "--artifacts", artifacts.to_str().unwrap()];
    args.extend_from_slice(extra);
    let output = canopy(&args);
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    (output, stdout)
}

#[test]
fn each_kind_of_expectation_passes_and_fails_with_the_values_it_read() {
    let folder = tempfile::tempdir().unwrap();
    let dir = folder.path();
    let timeline = "timeline:\n  - { at: 0.0, press: [KeyW] }\n  - { at: 1.0, release: [KeyW] }\n";
    scene_test(
        dir,
        "holds",
        "scenes/sloth.yaml",
        &format!(
            "seconds: 2\n{timeline}expect:\n  - {{ at: 0, that: sloth.distance_travelled == 0.0 }}\n  - {{ at: 1.5, that: sloth.distance_travelled > 0.05 }}\n  - always: sloth.min_body_clearance >= 0\n  - {{ eventually: sloth.distance_travelled > 0.02, before: 1 }}\n  - always: sloth.feet.all(l, !sloth.feet[l].planted || math.abs(sloth.feet[l].surface_distance) < 0.02)\n"
        ),
    );
    scene_test(
        dir,
        "fails",
        "scenes/sloth.yaml",
        &format!(
            "seconds: 2\n{timeline}expect:\n  - at: 1.5\n    that: sloth.distance_travelled > 5\n  - always: sloth.distance_travelled < 0.05\n  - {{ eventually: sloth.support == \"tree/twin\", before: 1.5 }}\n  - always: sloth.body_position\n"
        ),
    );
    let (output, stdout) = run_tests(dir, &[]);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("passed  holds"), "{stdout}");
    assert!(stdout.contains("FAILED  fails"), "{stdout}");
    let fails = dir.join("fails.test.yaml");
    let at = format!(
        "{}:8:11: at 1.500 s: sloth.distance_travelled > 5 is false (sloth.distance_travelled = ",
        fails.display()
    );
    assert!(stdout.contains(&at), "{stdout}");
    let always = format!("{}:9:13: at ", fails.display());
    assert!(
        stdout.contains(&always)
            && stdout.contains("(the first step it fails): sloth.distance_travelled < 0.05 is false"),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "by 1.500 s: sloth.support == \"tree/twin\" never held (at 1.500 s: sloth.support = \"tree/bough\")"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("sloth.body_position cannot be evaluated: gives ["), "{stdout}");
    assert!(stdout.ends_with("1 passed, 1 failed\n"), "{stdout}");
    let left = dir.join("artifacts/fails");
    let dump: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(left.join("dump.json")).unwrap()).unwrap();
    assert!(dump["time"].as_f64().unwrap() < 1.0, "the dump of the first failure, an `always` early on");
    assert!(std::fs::read_dir(&left).unwrap().flatten().any(|e| e.file_name().to_string_lossy().starts_with("frame-")));
    assert!(!dir.join("artifacts/holds").exists());
}

#[test]
fn golden_frames_fail_with_a_diff_and_are_written_only_when_blessed() {
    let folder = tempfile::tempdir().unwrap();
    let dir = folder.path();
    let body = "frames: 10\nexpect:\n  - { at: 0.1, screenshot: golden/demo.png, size: [160, 90] }\n";
    scene_test(dir, "shot", "scenes/demo.yaml", body);
    let golden = dir.join("golden/demo.png");
    let (output, stdout) = run_tests(dir, &[]);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("no golden image at") && stdout.contains("--bless"), "{stdout}");
    assert!(!golden.exists(), "no golden is written unasked");
    let (output, stdout) = run_tests(dir, &["--bless"]);
    assert!(output.status.success(), "{stdout}");
    assert!(stdout.contains(&format!("wrote {}", golden.display())), "{stdout}");
    let (output, stdout) = run_tests(dir, &[]);
    assert!(output.status.success(), "{stdout}");
    // Paint a block into the golden: the frame now differs there, and the diff shows where.
    let mut image = image::open(&golden).unwrap().to_rgba8();
    for x in 10..40 {
        for y in 10..30 {
            image.put_pixel(x, y, image::Rgba([0, 255, 0, 255]));
        }
    }
    image.save(&golden).unwrap();
    let (output, stdout) = run_tests(dir, &[]);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("the frame differs from") && stdout.contains("4.17 % of its pixels"), "{stdout}");
    let diff = image::open(dir.join("artifacts/shot/demo.diff.png")).unwrap().to_rgba8();
    assert_eq!(diff.get_pixel(20, 20), &image::Rgba([255, 0, 0, 255]));
    assert_ne!(diff.get_pixel(100, 60), &image::Rgba([255, 0, 0, 255]));
    assert!(dir.join("artifacts/shot/demo.png").exists() && dir.join("artifacts/shot/demo.golden.png").exists());
    let (output, stdout) = run_tests(dir, &["--bless"]);
    assert!(output.status.success() && stdout.contains("wrote"), "{stdout}");
    assert_ne!(image::open(&golden).unwrap().to_rgba8().get_pixel(20, 20), &image::Rgba([0, 255, 0, 255]));
}

#[test]
fn repeated_runs_must_agree_and_shards_filters_and_reports_choose_and_say() {
    let folder = tempfile::tempdir().unwrap();
    let dir = folder.path();
    for name in ["a", "b", "c", "d", "e"] {
        scene_test(
            dir,
            name,
            "scenes/demo.yaml",
            "frames: 6\nrepeat: 2\nexpect:\n  - always: spinner.rotation_deg[1] >= 0\n",
        );
    }
    let mut union: Vec<String> = Vec::new();
    for k in 1..=3 {
        let (output, stdout) = run_tests(dir, &["--list", "--shard", &format!("{k}/3")]);
        assert!(output.status.success());
        union.extend(stdout.lines().map(str::to_string));
    }
    union.sort();
    assert_eq!(union, ["a", "b", "c", "d", "e"]);
    let (output, stdout) = run_tests(dir, &["--filter", "c", "--json"]);
    assert!(output.status.success(), "{stdout}{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!((report["passed"].as_u64(), report["tests"][0]["name"].as_str()), (Some(1), Some("c")));
    assert!(report["tests"][0]["evaluations"].as_u64().unwrap() >= 6);
    let (output, _) = run_tests(dir, &["--shard", "4/3"]);
    assert_eq!(output.status.code(), Some(2), "a bad command line");
}

/// Each malformed test file in `tests/malformed_tests/`, the line its error must point at (None:
/// the whole file), and words the message must hold.
const MALFORMED_TESTS: &[(&str, Option<usize>, &str)] = &[
    ("at_after_end", Some(4), "after the run ends at 1 s"),
    ("empty", None, "the file is empty"),
    ("expression_syntax", Some(5), "does not parse"),
    ("missing_scene", Some(1), "no file at"),
    ("timeline_parameter", Some(4), "ball.nothing"),
    ("unknown_entity", Some(4), "no entity or variable `bal`; did you mean `ball`?"),
    ("unknown_expectation_field", Some(5), "unknown field `within`"),
    ("unknown_field", Some(5), "`ball` has no field `postion`; did you mean `position`?"),
    ("unknown_key", Some(4), "unknown key `KeyQQ`"),
    ("yaml_syntax", Some(5), ""),
];

#[test]
fn malformed_test_files_name_their_line_and_exit_2() {
    let mut files = 0;
    for entry in std::fs::read_dir("tests/malformed_tests").unwrap().flatten() {
        files += 1;
        let path = entry.path();
        let name = path.file_name().unwrap().to_string_lossy().replace(".test.yaml", "");
        let (_, line, words) =
            MALFORMED_TESTS.iter().find(|(n, ..)| *n == name).unwrap_or_else(|| panic!("{name}: no expectation"));
        let output = canopy(&["test", path.to_str().unwrap()]);
        let text = format!("{}{}", String::from_utf8_lossy(&output.stdout), stderr(&output));
        assert_eq!(output.status.code(), Some(2), "{name}: {text}");
        let place = match line {
            Some(line) => format!("{}:{line}:", path.display()),
            None => format!("{}: ", path.display()),
        };
        assert!(text.contains(&place), "{name}: expected {place} in {text}");
        assert!(text.contains(words), "{name}: expected {words} in {text}");
    }
    assert_eq!(files, MALFORMED_TESTS.len(), "every malformed file has an expectation");
}

#[test]
fn watch_reruns_a_test_when_its_file_changes() {
    use std::io::{BufRead, BufReader};
    use std::time::Duration;
    let folder = tempfile::tempdir().unwrap();
    let dir = folder.path();
    let body = |limit: f64| format!("frames: 3\nexpect:\n  - always: spinner.rotation_deg[1] < {limit}\n");
    let test = scene_test(dir, "watched", "scenes/demo.yaml", &body(90.0));
    scene_test(dir, "other", "scenes/demo.yaml", &body(90.0));
    let artifacts = dir.join("artifacts");
    let mut child = Command::new(env!("CARGO_BIN_EXE_canopy"))
        .args(["test", dir.to_str().unwrap(), "--watch", "--artifacts", artifacts.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let (sender, lines) = std::sync::mpsc::channel();
    let stdout = child.stdout.take().unwrap();
    std::thread::spawn(move || BufReader::new(stdout).lines().map_while(Result::ok).for_each(|l| drop(sender.send(l))));
    let stderr = BufReader::new(child.stderr.take().unwrap());
    let (watching, waiting) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        stderr.lines().map_while(Result::ok).filter(|l| l.starts_with("watching")).for_each(|_| {
            let _ = watching.send(());
        })
    });
    let until_tally = || {
        let mut seen = Vec::new();
        while let Ok(line) = lines.recv_timeout(Duration::from_secs(60)) {
            let tally = line.contains(" passed, ");
            seen.push(line);
            if tally {
                break;
            }
        }
        seen
    };
    assert_eq!(until_tally().last().map(String::as_str), Some("2 passed, 0 failed"));
    waiting.recv_timeout(Duration::from_secs(60)).expect("it watches after the first run");
    std::fs::write(&test, std::fs::read_to_string(&test).unwrap().replace(&body(90.0), &body(1.0))).unwrap();
    let rerun = until_tally();
    let _ = child.kill();
    let _ = child.wait();
    assert!(rerun.iter().any(|l| l.starts_with("FAILED  watched")), "{rerun:?}");
    assert!(!rerun.iter().any(|l| l.contains("other")), "only the changed test reruns: {rerun:?}");
    assert_eq!(rerun.last().map(String::as_str), Some("0 passed, 1 failed"));
}

#[test]
fn sloth_gait_prints_the_study_beside_the_walk_and_draws_the_footfalls() {
    let folder = tempfile::tempdir().unwrap();
    let plot = folder.path().join("footfalls.png");
    let output =
        canopy(&["sloth", "gait", "scenes/sloth/pole.yaml", "--seconds", "10", "--plot", plot.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}{}", stderr(&output));
    assert!(stdout.contains("(1.50 +- 0.20)") && stdout.contains("(0.60 +- 0.05)"), "{stdout}");
    assert!(stdout.contains("in the diagonal sequence") && stdout.contains("largest slip"), "{stdout}");
    let image = image::open(&plot).unwrap();
    assert!(image.width() > 200, "{} px wide", image.width());
    let missing = canopy(&["sloth", "gait", "scenes/demo.yaml", "--seconds", "1"]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(stderr(&missing).contains("the scene has no sloth"), "{}", stderr(&missing));
}

#[test]
fn a_camera_is_calibrated_from_photographs_of_a_printed_board() {
    use bevy::math::{DMat3, DVec3};
    use canopy_vision::board::{Board, CharucoBoard, GridBoard};
    use canopy_vision::synth::photograph_print;
    use canopy_vision::{Distortion, Intrinsics, Pose};
    let dictionary = canopy_vision::Dictionary::named("6x6_250").unwrap();
    let grid = Board::Grid(GridBoard::new([5, 4], 0.03, 0.006, 0, &dictionary).unwrap());
    let charuco = Board::Charuco(CharucoBoard::new([7, 5], 0.03, 0.018, 0, false, &dictionary).unwrap());
    let grid_args = ["--markers", "5x4", "--marker-m", "0.03", "--separation-m", "0.006"];
    let charuco_args = ["--board", "charuco", "--squares", "7x5", "--square-m", "0.03", "--marker-m", "0.018"];
    for (board, layout) in [(grid, &grid_args[..]), (charuco, &charuco_args[..])] {
        let folder = tempfile::tempdir().unwrap();
        let print = board.image(&dictionary, 4000.0, 0.006).unwrap();
        let truth = Intrinsics {
            fx: 610.0,
            fy: 606.0,
            cx: 318.0,
            cy: 244.0,
            distortion: Distortion([-0.1, 0.04, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            size: [640, 480],
        };
        let centre = (board.size_m() * 0.5).extend(0.0);
        let mut images = Vec::new();
        for (k, (turn, tilt, roll)) in
            [(0.4, -0.3, 0.1), (-0.35, -0.4, -0.3), (0.1, 0.5, 0.4), (-0.5, 0.2, 0.0), (0.2, -0.55, -0.5)]
                .into_iter()
                .enumerate()
        {
            let rotation = DMat3::from_rotation_z(roll) * DMat3::from_rotation_y(turn) * DMat3::from_rotation_x(tilt);
            let pose = Pose { rotation, translation: DVec3::new(0.0, 0.0, 0.36) - rotation * centre };
            let frame = photograph_print(&print, 4000.0, 0.006, &pose, &truth);
            let path = folder.path().join(format!("view-{k}.png"));
            image::GrayImage::from_raw(640, 480, frame.pixels).unwrap().save(&path).unwrap();
            images.push(path.to_string_lossy().into_owned());
        }
        let out = folder.path().join("camera.yaml");
        let args = [&["ar", "calibrate"], layout, &["--out"]].concat();
        let image_args: Vec<&str> = images.iter().map(String::as_str).collect();
        let output = canopy(&[&args[..], &[out.to_str().unwrap()], &image_args].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        let said = String::from_utf8_lossy(&output.stdout);
        assert!(said.contains("5 views") && said.lines().filter(|l| l.contains("view-")).count() == 5, "{said}");
        // The file written is read as any calibration is, and holds the camera within 0.5 %.
        let camera = canopy::ar::calibration::read(&out).unwrap().for_frames([640, 480]).unwrap();
        for (got, want) in [(camera.fx, truth.fx), (camera.fy, truth.fy), (camera.cx, truth.cx), (camera.cy, truth.cy)]
        {
            assert!((got - want).abs() / want < 0.005, "{got} against {want}\n{said}");
        }
        // Too few photographs: the camera cannot be found, and nothing is written.
        let few = canopy(&[&args[..], &[folder.path().join("few.yaml").to_str().unwrap()], &image_args[..2]].concat());
        assert_eq!(few.status.code(), Some(1));
        assert!(stderr(&few).contains("at least 3 views"), "{}", stderr(&few));
        assert!(!folder.path().join("few.yaml").exists());
    }
}

/// A file of `tests/charuco/`.
fn charuco_file(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/charuco").join(name)
}

/// OpenCV's four tutorial photographs of a 5 x 7 ChArUco board (`tests/charuco/`), and the
/// chessboard corners OpenCV 4.14's `CharucoDetector` found in each.
fn opencv_charuco_corners(photo: usize) -> Vec<(u32, bevy::math::DVec2)> {
    let text = std::fs::read_to_string(charuco_file(&format!("img_0{photo}_opencv_corners.txt"))).unwrap();
    text.lines()
        .filter(|line| !line.starts_with('#'))
        .map(|line| {
            let fields: Vec<f64> = line.split_whitespace().map(|f| f.parse().unwrap()).collect();
            (fields[0] as u32, bevy::math::DVec2::new(fields[1], fields[2]))
        })
        .collect()
}

#[test]
fn real_photographs_of_a_charuco_board_calibrate_as_well_as_opencv() {
    use canopy_vision::board::CharucoBoard;
    use canopy_vision::calibrate::{View, calibrate};
    use canopy_vision::{Dictionary, Gray, Scratch, Settings, detect};
    let dictionary = Dictionary::named("6x6_250").unwrap();
    let board = CharucoBoard::new([5, 7], 0.04, 0.02, 0, false, &dictionary).unwrap();
    // Every corner OpenCV finds is found, within a few tenths of a pixel of OpenCV's.
    let mut gaps = Vec::new();
    for photo in 0..4 {
        let image = image::open(charuco_file(&format!("img_0{photo}.jpg"))).unwrap().to_rgba8();
        let gray = Gray::from_rgba(image.width(), image.height(), image.as_raw());
        let markers = detect(&gray, &dictionary, &Settings::default(), None, &mut Scratch::default());
        // All 17 of the board's markers, as OpenCV finds them, the small steep ones of the far
        // row included.
        assert_eq!(markers.len(), 17, "photo {photo}");
        let ours = board.find_corners(&gray, &markers);
        let theirs = opencv_charuco_corners(photo);
        assert_eq!(ours.len(), theirs.len(), "photo {photo}: every corner OpenCV finds");
        for ((id, mine), (their_id, their)) in ours.iter().zip(&theirs) {
            assert_eq!(id, their_id);
            gaps.push(mine.distance(*their));
        }
    }
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    assert!(mean < 0.15, "Canopy's corners are {mean} px from OpenCV's on average");
    // Canopy's solver on OpenCV's corners: OpenCV 4.14's `calibrateCamera` made of them a
    // camera of fx 479.76, fy 479.79, cx 317.19, cy 256.80, 0.1891 px RMS.
    let views: Vec<View> = (0..4)
        .map(|photo| {
            let (object, pixels) = opencv_charuco_corners(photo)
                .into_iter()
                .map(|(id, pixel)| (board.chessboard_corner(id).truncate(), pixel))
                .unzip();
            View { object, pixels }
        })
        .collect();
    // OpenCV 5.1, on the same corners, lands in a better minimum than 4.14: fx 457.29, fy
    // 461.32, cx 317.22, cy 275.61, 0.18776 px. Canopy's solver finds that one.
    let found = calibrate(&views, [640, 480]).unwrap();
    assert!(found.error_px <= 0.18776, "{} px RMS against OpenCV's 0.18776", found.error_px);
    let camera = found.camera;
    for (got, want) in [(camera.fx, 457.29), (camera.fy, 461.32), (camera.cx, 317.22), (camera.cy, 275.61)] {
        assert!((got - want).abs() / want < 0.001, "{got} against OpenCV 5.1's {want}: {camera:?}");
    }
    // Through `canopy ar calibrate` on the photographs themselves: no larger an error than
    // OpenCV's on its own corners.
    let folder = tempfile::tempdir().unwrap();
    let out = folder.path().join("camera.yaml");
    let photos: Vec<String> =
        (0..4).map(|photo| charuco_file(&format!("img_0{photo}.jpg")).to_string_lossy().into_owned()).collect();
    let args =
        ["ar", "calibrate", "--board", "charuco", "--squares", "5x7", "--square-m", "0.04", "--marker-m", "0.02"];
    let photo_args: Vec<&str> = photos.iter().map(String::as_str).collect();
    let output = canopy(&[&args[..], &["--out", out.to_str().unwrap()], &photo_args].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let said = String::from_utf8_lossy(&output.stdout);
    let overall: f64 = said
        .split("views, ")
        .nth(1)
        .and_then(|rest| rest.split(" px").next())
        .and_then(|number| number.parse().ok())
        .unwrap_or_else(|| panic!("{said}"));
    assert!(overall <= 0.18776, "{overall} px RMS against OpenCV's 0.18776\n{said}");
}

#[test]
fn a_dictionary_of_the_users_prints_and_reads_its_markers() {
    let dictionary = std::fs::read_to_string(charuco_file("opencv_dictionary.yml")).unwrap();
    let folder = tempfile::tempdir().unwrap();
    let file = folder.path().join("mine.yml");
    std::fs::write(&file, &dictionary).unwrap();
    let (file, marker) = (file.to_str().unwrap(), folder.path().join("marker.png"));
    let printed = canopy(&["ar", "marker", "--dictionary", file, "--id", "2", "--out", marker.to_str().unwrap()]);
    assert!(printed.status.success(), "{}", stderr(&printed));
    let found = canopy(&["ar", "detect", marker.to_str().unwrap(), "--dictionary", file]);
    assert!(found.status.success(), "{}", stderr(&found));
    let results: serde_json::Value = serde_json::from_slice(&found.stdout).unwrap();
    assert_eq!(results[0]["markers"][0]["id"], 2, "{results}");
    // A marker past its end, and a broken file, are refused with the file's line.
    let other = folder.path().join("other.png");
    let past = canopy(&["ar", "marker", "--dictionary", file, "--id", "5", "--out", other.to_str().unwrap()]);
    assert_eq!(past.status.code(), Some(2), "{}", stderr(&past));
    assert!(stderr(&past).contains("mine has markers 0 to 4"), "{}", stderr(&past));
    std::fs::write(folder.path().join("mine.yml"), dictionary.replace("\"0100101101001100\"", "\"01\"")).unwrap();
    let broken = canopy(&["ar", "detect", marker.to_str().unwrap(), "--dictionary", file]);
    assert_eq!(broken.status.code(), Some(2));
    assert!(stderr(&broken).contains("mine.yml:8") && stderr(&broken).contains("marker_2"), "{}", stderr(&broken));
}

#[test]
fn the_detector_sweep_writes_its_table_json_plot_and_frames() {
    let folder = tempfile::tempdir().unwrap();
    let out = folder.path().to_str().unwrap();
    let output = canopy(&["ar", "sweep", "--out", out, "--frames", "1", "--write-frames"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let said = String::from_utf8_lossy(&output.stdout);
    assert!(said.contains("| distance_m | 0.6 | 1/1 | 0 |"), "the baseline is found\n{said}");
    let steps: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.path().join("sweep.json")).unwrap()).unwrap();
    let conditions: std::collections::BTreeSet<&str> =
        steps.as_array().unwrap().iter().map(|s| s["condition"].as_str().unwrap()).collect();
    assert_eq!(conditions.len(), 7, "{conditions:?}");
    assert_eq!(image::image_dimensions(folder.path().join("sweep.png")).unwrap(), (1200, 1210));
    let frames: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.path().join("frames/frames.json")).unwrap()).unwrap();
    let first = &frames[0];
    assert!(folder.path().join("frames").join(first["file"].as_str().unwrap()).is_file(), "{first}");
    assert_eq!(first["corners"].as_array().unwrap().len(), 4);
    // Run again, it does not replace what it wrote unless told to.
    let again = canopy(&["ar", "sweep", "--out", out, "--frames", "1"]);
    assert_eq!(again.status.code(), Some(1), "{}", stderr(&again));
}

#[test]
fn a_printed_charuco_board_is_laid_out_as_opencv_draws_it() {
    use canopy_vision::{Dictionary, Gray, Scratch, Settings, detect};
    let folder = tempfile::tempdir().unwrap();
    let out = folder.path().join("board.png");
    let args = ["ar", "board", "--board", "charuco", "--squares", "5x7", "--square-m", "0.04", "--marker-m", "0.02"];
    let sizes = ["--pixels-per-metre", "2500", "--margin-m", "0", "--out", out.to_str().unwrap()];
    let output = canopy(&[&args[..], &sizes].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(String::from_utf8_lossy(&output.stdout).contains("markers 0 to 16"));
    let ours = image::open(&out).unwrap().to_luma8();
    let theirs = image::open(charuco_file("opencv_board_5x7.png")).unwrap().to_luma8();
    assert_eq!(ours.dimensions(), theirs.dimensions());
    // The same squares black: each square's middle.
    for y in 0..7 {
        for x in 0..5 {
            let (px, py) = (x * 100 + 5, y * 100 + 5);
            assert_eq!(ours.get_pixel(px, py), theirs.get_pixel(px, py), "square {x}, {y}");
        }
    }
    // The same markers in the same places (cells' edges may round to the other pixel).
    let dictionary = Dictionary::named("6x6_250").unwrap();
    let found = |image: &image::GrayImage| {
        let gray = Gray { width: image.width(), height: image.height(), pixels: image.as_raw().clone() };
        detect(&gray, &dictionary, &Settings::default(), None, &mut Scratch::default())
    };
    let (mine, opencvs) = (found(&ours), found(&theirs));
    assert_eq!(mine.len(), 17);
    for (a, b) in mine.iter().zip(&opencvs) {
        assert_eq!(a.id, b.id);
        for (p, q) in a.corners_f64().iter().zip(b.corners_f64()) {
            assert!(p.distance(q) < 1.0, "marker {}: {p} against {q}", a.id);
        }
    }
}

#[test]
fn muscle_table_prints_the_sources_tables_and_the_fitted_growth() {
    let output = canopy(&["muscle", "table", "scenes/biceps_real.yaml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = String::from_utf8(output.stdout).unwrap();
    // Node 5's row: real, model and fitted radii at each flexion; the real ones are Table 4.1's.
    let row = text.lines().find(|line| line.trim_start().starts_with("5 |")).unwrap();
    let cells: Vec<f64> = row.split(['|', ' ']).filter_map(|cell| cell.parse().ok()).skip(1).collect();
    assert_eq!(cells.len(), 12, "{row}");
    assert_eq!([cells[0], cells[3], cells[6], cells[9]], [21.7, 27.5, 32.4, 35.2], "{row}");
    assert_eq!(cells[1], 21.7, "at 0 degrees the model is at rest: {row}");
    assert!(cells[4] < cells[7] && cells[7] < cells[10], "the model's node grows with flexion: {row}");
    assert!(text.contains("Growth from 0 to 90 degrees (Table 4.3)"), "{text}");
    let closes = text.lines().find(|line| line.contains("the fit closes")).unwrap();
    assert!(closes.contains("% of the gap"), "{closes}");

    let output = canopy(&["muscle", "table", "scenes/biceps_real.yaml", "--muscle", "triceps"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("no muscle is named `triceps` (muscles: biceps)"), "{}", stderr(&output));
    let output = canopy(&["muscle", "table", "scenes/sloth.yaml"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("the scene has no muscle"), "{}", stderr(&output));
}

#[test]
fn the_figures_timeline_saves_the_biceps_at_four_flexions() {
    let folder = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let output = Command::new(env!("CARGO_BIN_EXE_canopy"))
        .current_dir(folder.path())
        .args(["run", "--seconds", "2", "--size", "96x72", "--input"])
        .arg(root.join("timelines/biceps_figures.yaml"))
        .arg(root.join("scenes/biceps_real.yaml"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr(&output));
    let shots: Vec<Vec<u8>> = (1..=4)
        .map(|n| {
            image::open(folder.path().join(format!("screenshots/canopy-{n:04}.png"))).unwrap().to_rgba8().into_raw()
        })
        .collect();
    // Each flexion is a different picture: the forearm turns up.
    for pair in shots.windows(2) {
        assert_ne!(pair[0], pair[1]);
    }
}
