//! Helpers the system tests share: driving a headless app until its scene is live.

use bevy::app::App;
use bevy::math::UVec2;
use canopy::scene::{ActiveScene, SceneStatus};
use std::path::Path;
use std::time::{Duration, Instant};

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
