//! The headless cost of a frame of each scene given: its fixed step and the raster of its
//! frame at the size of the window's 3D view, every frame, without a window or a panel. The
//! window's frame time is measured against it (`scripts/frame_times.sh`).
//!
//! Run with `cargo bench --profile dev --bench headless_frames -- SCENE.yaml...`; prints one
//! line per scene, `SCENE MS`, the mean wall-clock milliseconds per frame.

use bevy::math::UVec2;
use canopy::app::headless_app;
use canopy::raster::plugin::RenderPolicy;
use canopy::run::update_until_loaded;
use std::path::Path;
use std::time::{Duration, Instant};

/// The 3D view's size in a 1280 x 720 window beside the panel.
const VIEW: UVec2 = UVec2::new(980, 720);
/// Frames before the measurement (caches, the first shadow map) and measured.
const WARM_UP: u32 = 30;
const MEASURED: u32 = 200;

fn frame_time(scene: &Path) -> Result<Duration, String> {
    let mut app = headless_app(scene, VIEW, false).map_err(|e| e.to_string())?;
    update_until_loaded(&mut app, scene).map_err(|e| e.to_string())?;
    app.world_mut().resource_mut::<RenderPolicy>().every_frame = true;
    for _ in 0..WARM_UP {
        app.update();
    }
    let started = Instant::now();
    for _ in 0..MEASURED {
        app.update();
    }
    Ok(started.elapsed() / MEASURED)
}

fn main() {
    // `cargo bench` passes `--bench`; everything else is a scene.
    let scenes: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    if scenes.is_empty() {
        eprintln!("usage: headless_frames SCENE.yaml...");
        std::process::exit(2);
    }
    for scene in scenes {
        match frame_time(Path::new(&scene)) {
            Ok(time) => println!("{scene} {:.2}", time.as_secs_f64() * 1000.0),
            Err(error) => {
                eprintln!("{scene}: {error}");
                std::process::exit(1);
            }
        }
    }
}
