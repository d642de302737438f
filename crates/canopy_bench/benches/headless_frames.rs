//! The headless cost of a frame of each scene given: its fixed step and the raster of its
//! frame at the size of the window's 3D view, every frame, without a window or a panel. The
//! window's frame time is measured against it (`scripts/frame_times.sh`).
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench headless_frames -- SCENE.yaml...`; prints one
//! line per scene: `SCENE MEAN P99 simulation MEAN P99 raster MEAN P99 other MEAN P99`, the
//! wall-clock milliseconds of a whole frame and of its phases, their mean and 99th percentile
//! ("other" is the rest of the frame: streaming, write-back, Bevy's own systems).

use bevy::math::UVec2;
use canopy::app::headless_app;
use canopy::foundation::frame_times::FrameLog;
use canopy::foundation::schedule::FixedStepTime;
use canopy::raster::plugin::RasterTarget;
use canopy::raster::plugin::RenderPolicy;
use canopy::run::update_until_loaded;
use std::path::Path;
use std::time::Instant;

/// The 3D view's size in a 1280 x 720 window beside the panel.
const VIEW: UVec2 = UVec2::new(980, 720);
/// Frames before the measurement (caches, the first shadow map) and measured.
const WARM_UP: u32 = 30;
const MEASURED: u32 = 600;

/// The phases of [`frame_times`]' log, in order.
const PHASES: [&str; 3] = ["simulation", "raster", "other"];

fn frame_times(scene: &Path) -> Result<FrameLog<3>, String> {
    let mut app = headless_app(scene, VIEW, false).map_err(|e| e.to_string())?;
    update_until_loaded(&mut app, scene).map_err(|e| e.to_string())?;
    app.world_mut().resource_mut::<RenderPolicy>().every_frame = true;
    for _ in 0..WARM_UP {
        app.update();
    }
    let mut log = FrameLog::new(MEASURED as usize);
    for _ in 0..MEASURED {
        let started = Instant::now();
        app.update();
        let frame = started.elapsed();
        let world = app.world();
        let (simulation, raster) =
            (world.resource::<FixedStepTime>().last, world.resource::<RasterTarget>().raster_time);
        log.push(frame, [simulation, raster, frame.saturating_sub(simulation + raster)]);
    }
    Ok(log)
}

fn main() {
    canopy_bench::at_workspace_root();
    // `cargo bench` passes `--bench`; everything else is a scene.
    let scenes: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    if scenes.is_empty() {
        eprintln!("usage: headless_frames SCENE.yaml...");
        std::process::exit(2);
    }
    for scene in scenes {
        match frame_times(Path::new(&scene)) {
            Ok(log) => {
                let frame = log.frame(0.99);
                let mut line = format!("{scene} {:.2} {:.2}", frame.mean, frame.quantile);
                for (phase, name) in PHASES.iter().enumerate() {
                    let summary = log.phase(phase, 0.99);
                    line += &format!(" {name} {:.2} {:.2}", summary.mean, summary.quantile);
                }
                println!("{line}");
            }
            Err(error) => {
                eprintln!("{scene}: {error}");
                std::process::exit(1);
            }
        }
    }
}
