//! Helpers the system tests share: paths, headless runs, reading dumps, driving an app until
//! its scene is live.

use bevy::app::App;
use bevy::math::{UVec2, Vec3};
use canopy::raster::Framebuffer;
use canopy::run::{RunOptions, RunOutput, run_headless};
use canopy::scene::{ActiveScene, SceneStatus};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The framebuffer size of most system tests.
pub const SMALL: UVec2 = UVec2::new(160, 120);

/// A file of the project, by its path from the project's root.
///
/// The root is read when the test runs, not when it is built: a build shared by two clones of
/// the project then reads the files of the clone it runs in.
pub fn path(relative: &str) -> PathBuf {
    let root = std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR for the tests it runs");
    Path::new(&root).join(relative)
}

/// Runs `scene` for `frames` steps with an optional timeline given as YAML text.
pub fn run(scene: &str, frames: u64, timeline: Option<&str>, size: UVec2) -> RunOutput {
    let folder = tempfile::tempdir().unwrap();
    let timeline = timeline.map(|text| {
        let file = folder.path().join("timeline.yaml");
        std::fs::write(&file, text).unwrap();
        file
    });
    let options = RunOptions { scene: path(scene), frames, timeline, size, log: false };
    run_headless(&options).unwrap_or_else(|e| panic!("{e}"))
}

/// The dump of the entity named `name`.
pub fn entity<'a>(dump: &'a Value, name: &str) -> &'a Value {
    dump["entities"].as_array().unwrap().iter().find(|e| e["name"] == name).unwrap_or_else(|| panic!("no {name}"))
}

/// A dumped `[x, y, z]`.
pub fn vec3(value: &Value) -> Vec3 {
    let a: Vec<f32> = value.as_array().unwrap().iter().map(|v| v.as_f64().unwrap() as f32).collect();
    Vec3::new(a[0], a[1], a[2])
}

/// How many pixels of `framebuffer` are exactly `rgba`.
pub fn count_pixels(framebuffer: &Framebuffer, rgba: [u8; 4]) -> usize {
    framebuffer.color().chunks_exact(4).filter(|p| *p == rgba).count()
}

/// A headless app of the small size playing `scene`, once its scene is live.
pub fn small_app(scene: &Path) -> App {
    live_app(scene, SMALL)
}

/// A headless app of `size` playing `scene`, stepped until the scene is live and once more.
///
/// # Panics
/// If the scene fails to load (with its error) or takes too long.
pub fn live_app(scene: &Path, size: UVec2) -> App {
    let mut app = canopy::app::headless_app(scene, size, false).unwrap();
    update_until(&mut app, |s| s.status != SceneStatus::Loading);
    let active = app.world().resource::<ActiveScene>();
    assert!(active.status == SceneStatus::Live, "{:?}", active.error);
    app.update();
    app
}

/// Steps `app` until `done` holds, failing after a generous wall-clock limit (file loads run
/// on the IO threads).
pub fn update_until(app: &mut App, done: impl Fn(&ActiveScene) -> bool) {
    let started = Instant::now();
    while !done(app.world().resource::<ActiveScene>()) {
        assert!(started.elapsed() < Duration::from_secs(30), "timed out");
        app.update();
    }
}
