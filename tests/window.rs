//! The real window, driven as a user would: keys, clicks on the panel and in the view, a drag
//! to orbit and a resize, sent with `xdotool` to the app under a virtual X server. Checks the
//! state the app dumps and the window it saves when done.
//!
//! Needs `Xvfb` and `xdotool`, so it is ignored by `cargo test`; `.ci/run` runs it with
//! `cargo test --test window -- --ignored`.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

/// Frames the app shows before it saves the window and exits: room for every action below.
const FRAMES: u32 = 900;

/// The window's size after the resize at the end, in pixels.
const RESIZED: (u32, u32) = (1000, 600);

/// The scene played: a tree, whose supports are picked by clicking them in the view.
const SCENE: &str = "scenes/tree.yaml";

/// Where things are in the 1280 x 720 window of [`SCENE`]: the panel is on the right, the view
/// on the left.
mod at {
    /// The panel's Pause button.
    pub const PAUSE: (u32, u32) = (1008, 71);
    /// The panel's Keys button.
    pub const KEYS: (u32, u32) = (1196, 71);
    /// The tree's trunk in the view.
    pub const TRUNK: (u32, u32) = (490, 350);
    /// The tree's row in the panel's entity list, and the ground's above it (selected at
    /// start).
    pub const TREE_ROW: (u32, u32) = (995, 443);
    pub const GROUND_ROW: (u32, u32) = (995, 422);
    /// Inside the key help window, which opens at the view's top-left corner (the window's).
    pub const HELP: (u32, u32) = (30, 30);
    /// Empty ground in the view, where a drag starts.
    pub const DRAG_FROM: (u32, u32) = (250, 620);
}

/// A virtual X server on a free display, stopped when dropped.
struct Xvfb {
    server: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Self {
        let mut server = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "1280x720x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb is installed");
        let mut line = String::new();
        BufReader::new(server.stdout.take().expect("piped")).read_line(&mut line).expect("Xvfb prints its display");
        Self { server, display: format!(":{}", line.trim()) }
    }

    /// Runs `xdotool` with `args` on this display and returns what it printed.
    fn xdotool(&self, args: &[&str]) -> String {
        let output = Command::new("xdotool").args(args).env("DISPLAY", &self.display).output().expect("xdotool runs");
        assert!(output.status.success(), "xdotool {args:?}: {}", String::from_utf8_lossy(&output.stderr));
        String::from_utf8_lossy(&output.stdout).into_owned()
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

fn click(x: &Xvfb, window: &str, (px, py): (u32, u32)) {
    x.xdotool(&["mousemove", "--window", window, &px.to_string(), &py.to_string()]);
    sleep(Duration::from_millis(150));
    x.xdotool(&["click", "1"]);
    sleep(Duration::from_millis(300));
}

fn press(x: &Xvfb, key: &str) {
    x.xdotool(&["keydown", key]);
    sleep(Duration::from_millis(120));
    x.xdotool(&["keyup", key]);
    sleep(Duration::from_millis(300));
}

fn pixel(image: &image::RgbImage, (x, y): (u32, u32)) -> [u8; 3] {
    image.get_pixel(x, y).0
}

/// Starts `canopy play scene` on the display, saving the window to `window.png` and the state
/// to `state.json` in `dir` after `frames` frames; returns the app and its window once the
/// scene has had time to load.
fn play(x: &Xvfb, scene: &Path, dir: &Path, frames: u32) -> (Child, String) {
    let app = Command::new(env!("CARGO_BIN_EXE_canopy"))
        .arg("play")
        .arg(scene)
        .arg("--screenshot")
        .arg(dir.join("window.png"))
        .args(["--frames", &frames.to_string(), "--dump"])
        .arg(dir.join("state.json"))
        .current_dir(dir)
        .env("DISPLAY", &x.display)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let window = x.xdotool(&["search", "--sync", "--name", "^Canopy"]).lines().next().unwrap().to_string();
    x.xdotool(&["windowfocus", "--sync", &window]);
    // Let the scene load and a few frames pass.
    sleep(Duration::from_secs(2));
    (app, window)
}

/// Waits for the app to exit after its capture, and checks that it succeeded.
fn wait_for_exit(mut app: Child) {
    let deadline = Instant::now() + Duration::from_secs(120);
    let status = loop {
        if let Some(status) = app.try_wait().unwrap() {
            break status;
        }
        assert!(Instant::now() < deadline, "the app did not exit after its capture");
        sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "the app failed: {status}");
}

/// A file of the project by its path from the project's root, where cargo runs its tests; made
/// absolute for the app, which runs in a scratch folder.
fn project_file(relative: &str) -> PathBuf {
    std::fs::canonicalize(relative).unwrap_or_else(|error| panic!("{relative}: {error}"))
}

/// A JSON file.
fn read(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The dump of the entity named `name`.
fn entity(state: &serde_json::Value, name: &str) -> serde_json::Value {
    state["entities"].as_array().unwrap().iter().find(|e| e["name"] == name).unwrap().clone()
}

#[test]
#[ignore = "needs Xvfb and xdotool; .ci/run runs it"]
fn keys_clicks_and_drags_reach_the_scene_through_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let scene = project_file(SCENE);
    let (shot, dump) = (dir.path().join("window.png"), dir.path().join("state.json"));
    // The state before any input, from a headless run.
    let initial = dir.path().join("initial.json");
    let mut run = Command::new(env!("CARGO_BIN_EXE_canopy"));
    run.arg("run").arg(&scene).args(["--frames", "1", "--dump"]).arg(&initial);
    assert!(run.status().unwrap().success());
    let x = Xvfb::start();
    let (app, window) = play(&x, &scene, dir.path(), FRAMES);
    let started = Instant::now();

    press(&x, "v"); // shading: gouraud -> phong
    press(&x, "h"); // shadows off
    press(&x, "F12"); // a picture of the 3D view
    click(&x, &window, at::TRUNK);
    // Drag on the view to orbit the camera.
    let (fx, fy) = at::DRAG_FROM;
    x.xdotool(&["mousemove", "--window", &window, &fx.to_string(), &fy.to_string()]);
    x.xdotool(&["mousedown", "1"]);
    for step in 1..=10 {
        sleep(Duration::from_millis(40));
        x.xdotool(&["mousemove", "--window", &window, &(fx + step * 12).to_string(), &fy.to_string()]);
    }
    x.xdotool(&["mouseup", "1"]);
    sleep(Duration::from_millis(300));
    // Drag with the right button to look around from the eye, and fly faster with Shift and
    // the wheel.
    x.xdotool(&["mousedown", "3"]);
    for step in 1..=5 {
        sleep(Duration::from_millis(40));
        x.xdotool(&["mousemove", "--window", &window, &(fx + 120 - step * 12).to_string(), &fy.to_string()]);
    }
    x.xdotool(&["mouseup", "3"]);
    sleep(Duration::from_millis(200));
    x.xdotool(&["keydown", "shift"]);
    for _ in 0..3 {
        x.xdotool(&["click", "4"]);
        sleep(Duration::from_millis(60));
    }
    x.xdotool(&["keyup", "shift"]);
    sleep(Duration::from_millis(300));
    click(&x, &window, at::KEYS);
    click(&x, &window, at::PAUSE);
    // A smaller window: the panel keeps to the right edge, the view takes the rest.
    x.xdotool(&["windowsize", &window, &RESIZED.0.to_string(), &RESIZED.1.to_string()]);
    sleep(Duration::from_millis(500));
    let acted = started.elapsed();

    wait_for_exit(app);

    let (state, initial) = (read(&dump), read(&initial));
    let render = entity(&initial, "render");
    assert_eq!((&render["shading"], &render["shadows"]), (&"gouraud".into(), &true.into()));
    let render = entity(&state, "render");
    assert_eq!(render["shading"], "phong", "the V key cycles the shading");
    assert_eq!(render["shadows"], false, "the H key switches shadows off");
    let position = |state: &serde_json::Value| -> Vec<f64> {
        serde_json::from_value(entity(state, "camera")["position"].clone()).unwrap()
    };
    let (from, to) = (position(&initial), position(&state));
    let moved: f64 = from.iter().zip(&to).map(|(a, b)| (a - b).abs()).sum();
    assert!(moved > 0.5, "dragging on the view orbits the camera: from {from:?} to {to:?}");
    let camera = |state: &serde_json::Value, field: &str| entity(state, "camera")[field].clone();
    assert_ne!(camera(&state, "target"), camera(&initial, "target"), "a right-button drag looks around");
    let speed = |state: &serde_json::Value| camera(state, "fly_speed_m_s").as_f64().unwrap();
    assert!(speed(&state) > speed(&initial) * 1.05, "Shift and the wheel fly faster: {}", speed(&state));
    let frame = state["frame"].as_u64().unwrap();
    assert!(frame < u64::from(FRAMES) * 3 / 4, "the Pause button stops the clock: {frame} steps in {FRAMES} frames");

    let window = image::open(&shot).unwrap().to_rgb8();
    assert_eq!(window.dimensions(), RESIZED, "the window is composed at its new size");
    // The panel moved with the right edge.
    let right = |(x, y): (u32, u32)| (x - (1280 - RESIZED.0), y);
    let [r, g, b] = pixel(&window, right(at::TREE_ROW));
    assert!(b > 100 && r < 60 && g > 60, "clicking the trunk selects the tree's row in the panel: {:?}", [r, g, b]);
    assert_ne!(pixel(&window, right(at::GROUND_ROW)), [r, g, b], "only the tree's row is selected");
    let help = pixel(&window, at::HELP);
    assert!(help.iter().all(|&c| c < 80), "the Keys button opens the key help over the view: {help:?}");

    let pictures: Vec<_> =
        std::fs::read_dir(dir.path().join("screenshots")).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(pictures.len(), 1, "F12 saves one picture: {pictures:?}");
    let view = image::open(&pictures[0]).unwrap();
    assert_eq!((view.width(), view.height()), (980, 720), "F12 saves the 3D view alone");
    assert!(acted < Duration::from_secs(12), "the actions took {acted:?}: the capture may have come first");
}

/// Where the belly's outline is clicked in the torso scene's 980 x 720 view, and the middle of
/// the belly.
const BELLY: [(u32, u32); 4] = [(380, 385), (570, 390), (580, 555), (375, 540)];
const BELLY_MIDDLE: (u32, u32) = (470, 465);

#[test]
#[ignore = "needs Xvfb and xdotool; .ci/run runs it"]
fn a_region_clicked_on_the_torso_is_shrunk_and_compared_in_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let scene = project_file("scenes/torso.yaml");
    let x = Xvfb::start();
    let (app, window) = play(&x, &scene, dir.path(), 600);
    for point in BELLY {
        click(&x, &window, point);
    }
    press(&x, "Return");
    press(&x, "c"); // the model over the original, tinted by its shift
    wait_for_exit(app);

    let torso = entity(&read(&dir.path().join("state.json")), "torso");
    assert_eq!(torso["marks"].as_array().unwrap().len(), 4, "each click marks a point: {torso}");
    let region = &torso["region"];
    assert!(region["inside"].as_u64().unwrap() > 200, "the clicks outline the belly: {region}");
    let models = torso["models"].as_array().unwrap();
    assert_eq!((models.len(), &torso["shown"]), (1, &1.into()), "Enter shrinks the region: {torso}");
    let report = &models[0]["report"];
    assert!((report["facts"]["area_ratio"].as_f64().unwrap() - 0.9).abs() < 1e-3, "{report}");
    assert_eq!(report["facts"]["fixed_unchanged"], true);
    let shot = image::open(dir.path().join("window.png")).unwrap().to_rgb8();
    let [r, g, b] = pixel(&shot, BELLY_MIDDLE);
    assert!(r > 2 * g && r > 2 * b, "the overlay tints the belly's middle, which moved most: {:?}", [r, g, b]);
}

/// Where the jelly of `scenes/softbody.yaml` rests on its crate in the window's view, and the
/// way a drag takes it: up, then right, beyond the crate.
const JELLY: (u32, u32) = (608, 375);

#[test]
#[ignore = "needs Xvfb and xdotool; .ci/run runs it"]
fn the_jelly_is_dragged_off_its_crate_with_the_mouse_and_let_fall_on_the_floor() {
    let dir = tempfile::tempdir().unwrap();
    let scene = project_file("scenes/softbody.yaml");
    let x = Xvfb::start();
    let (app, window) = play(&x, &scene, dir.path(), 700);
    // Let the jelly land and settle on the crate.
    sleep(Duration::from_secs(2));
    let (jx, jy) = JELLY;
    x.xdotool(&["mousemove", "--window", &window, &jx.to_string(), &jy.to_string()]);
    x.xdotool(&["mousedown", "1"]);
    for step in 1..=15 {
        x.xdotool(&["mousemove", "--window", &window, &jx.to_string(), &(jy - step * 12).to_string()]);
        sleep(Duration::from_millis(30));
    }
    for step in 1..=20 {
        x.xdotool(&["mousemove", "--window", &window, &(jx + step * 12).to_string(), &(jy - 180).to_string()]);
        sleep(Duration::from_millis(30));
    }
    sleep(Duration::from_secs(1));
    x.xdotool(&["mouseup", "1"]);
    wait_for_exit(app);

    let state = read(&dir.path().join("state.json"));
    let jelly = entity(&state, "jelly");
    let centre: Vec<f64> = jelly["centre_of_mass"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert!(centre[0] > 0.6, "dragged beyond the crate's right side (x 0.55): {jelly}");
    assert!(jelly["contacts"]["floor"].as_u64().unwrap() > 0 && jelly["contacts"]["crate"].is_null(), "{jelly}");
    assert_eq!(jelly["held"], false, "let go: {jelly}");
    let camera = entity(&state, "camera");
    let eye: Vec<f64> = camera["position"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let file = [0.0, 1.1, 2.2];
    assert!(
        eye.iter().zip(file).all(|(a, b)| (a - b).abs() < 1e-4),
        "the camera stayed still during the drag: {eye:?}"
    );
}

/// Where the overlay's entry is in the panel's entity list of `scenes/ar.yaml`, and its outline
/// switch once it is selected, in the 1280 x 720 window.
const OVERLAY_ENTRY: (u32, u32) = (1015, 422);
const OUTLINE_SWITCH: (u32, u32) = (1060, 554);

#[test]
#[ignore = "needs Xvfb and xdotool; .ci/run runs it"]
fn the_ar_scene_plays_its_camera_frames_with_the_scene_on_the_marker() {
    let dir = tempfile::tempdir().unwrap();
    let scene = project_file("scenes/ar.yaml");
    let x = Xvfb::start();
    let (app, window) = play(&x, &scene, dir.path(), 240);
    // Select the overlay in the panel's entity list, then switch its outline on.
    click(&x, &window, OVERLAY_ENTRY);
    click(&x, &window, OUTLINE_SWITCH);
    wait_for_exit(app);

    let state = read(&dir.path().join("state.json"));
    let overlay = entity(&state, "overlay");
    assert!(overlay["shown"].as_u64().unwrap() > 0, "the frames advance: {overlay}");
    assert_eq!(overlay["outline"], true, "the panel's switch reached the overlay");
    let error = overlay["overlay_error_max_px"].as_f64().unwrap();
    assert!(error > 0.0 && error < 1.0, "the drawn marker lies on the photographed one: {error} px");
    // The window shows the photograph (the table's brown) and the scene on it (the land's
    // green), in the view fitted to the frame's shape, and the outline while the marker is
    // found: its first side red.
    let image = image::open(dir.path().join("window.png")).unwrap().to_rgb8();
    let (mut table, mut land, mut red) = (0, 0, 0);
    for p in image.pixels() {
        let [r, g, b] = p.0.map(i32::from);
        table += usize::from(r > b + 15 && r >= g && g >= b);
        land += usize::from(g > r + 20 && g > b + 20);
        red += usize::from(p.0 == [230, 40, 40]);
    }
    assert!(table > 50_000 && land > 500, "table {table} pixels, land {land}");
    let last = overlay["poses"].as_array().unwrap().last().unwrap();
    if last["marker"] == "found" {
        assert!(red > 40, "the outline's first side: {red} pixels");
    }
}

#[test]
#[ignore = "needs Xvfb and xdotool; .ci/run runs it"]
fn f3_shows_the_sloths_debug_view_in_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let x = Xvfb::start();
    let (app, _window) = play(&x, &project_file("scenes/sloth/pole.yaml"), dir.path(), 300);
    press(&x, "F3");
    wait_for_exit(app);
    let shot = image::open(dir.path().join("window.png")).unwrap().to_rgb8();
    let [r, g, b, _] = canopy::sloth::debug::CHAIN;
    let chain = shot.pixels().filter(|p| p.0 == [r, g, b]).count();
    assert!(chain > 20, "the limb chains drawn in the view: {chain} pixels");
}
