//! A flight over `scenes/world.yaml`: the camera flies straight ahead at 30 m/s for 60 s of
//! fixed 60 Hz steps, rendered at 1280x720 with the scene's shadows, and every frame's
//! wall-clock time (streaming, simulation and raster) is taken. The same flight is flown with
//! streaming and with every chunk it will want made in advance ("frozen": streaming takes
//! them ready-made, so nothing is generated during the flight), alternating, in one run.
//!
//! Every frame over twice its flight's median is traced: how much of it the rasterizer took,
//! how long the threads that draw it (the main thread and the compute pool's) waited, runnable,
//! for a core (their `/proc/self/task/*/schedstat`), how much time the machine's hypervisor
//! took from its cores (`steal` in `/proc/stat`, in ticks of 10 ms), and how many chunks were
//! spawned in it.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench world_flight [-- SECONDS]` (the profile of
//! `cargo run`); prints a table per flight, the slow frames' trace and the ratios the goal is
//! stated in.

#[path = "common/frame_times.rs"]
mod frame_times;

use bevy::math::{UVec2, Vec2, Vec3Swizzles};
use canopy::app::headless_app;
use canopy::raster::plugin::{RasterTarget, RenderPolicy};
use canopy::run::update_until_loaded;
use canopy::view::CameraParams;
use canopy::world::WorldBody;
use canopy::world::stream::plan;
use frame_times::figures;
use std::collections::{BTreeSet, HashMap};
use std::path::Path;
use std::time::{Duration, Instant};

const SCENE: &str = "scenes/world.yaml";
const SIZE: UVec2 = UVec2::new(1280, 720);
/// Metres a second, along the camera's horizontal direction of view.
const SPEED_M_S: f32 = 30.0;
const STEP_S: f32 = 1.0 / 60.0;
/// Frames before the flight: the world around the start fills in and the caches warm up.
const SETTLE: u32 = 240;

/// Where the camera's target is at frame `frame` of a flight from `start` along `heading`.
fn target_at(start: Vec2, heading: Vec2, frame: u32) -> Vec2 {
    start + heading * SPEED_M_S * STEP_S * frame as f32
}

/// What one frame took.
#[derive(Debug, Clone, Copy)]
struct Frame {
    /// Wall-clock time of its `App::update`.
    time: Duration,
    /// Of which the rasterizer's.
    raster: Duration,
    /// Time the threads drawing it waited for a core while runnable, summed.
    waited: Duration,
    /// Time the hypervisor took from the machine's cores, to the 10 ms tick.
    stolen: Duration,
    /// Chunks spawned.
    spawned: u64,
}

/// The time the threads that draw frames (all but the background pools') have spent runnable
/// but waiting for a core so far, summed, if the system says.
fn waited() -> Duration {
    let Ok(threads) = std::fs::read_dir("/proc/self/task") else { return Duration::ZERO };
    let nanos = threads
        .flatten()
        .filter(|thread| {
            let name = std::fs::read_to_string(thread.path().join("comm")).unwrap_or_default();
            !(name.starts_with("Async Compute") || name.starts_with("IO Task"))
        })
        .filter_map(|thread| {
            let schedstat = std::fs::read_to_string(thread.path().join("schedstat")).ok()?;
            schedstat.split_whitespace().nth(1)?.parse::<u64>().ok()
        })
        .sum();
    Duration::from_nanos(nanos)
}

/// Time stolen from the machine's cores by its hypervisor so far, if the system says (the
/// `steal` column of `/proc/stat`, in ticks of 10 ms).
fn stolen() -> Duration {
    let stat = std::fs::read_to_string("/proc/stat").unwrap_or_default();
    let ticks: u64 = stat.lines().next().and_then(|cpu| cpu.split_whitespace().nth(8)?.parse().ok()).unwrap_or(0);
    Duration::from_millis(ticks * 10)
}

/// Chunks spawned so far by the worlds of `app`.
fn spawned(app: &mut bevy::app::App) -> u64 {
    app.world_mut().query::<&WorldBody>().iter(app.world()).map(|body| body.made).sum()
}

/// One flight of `frames` frames; with `frozen`, every chunk it will want made first.
fn fly(frames: u32, frozen: bool) -> Result<Vec<Frame>, String> {
    let scene = Path::new(SCENE);
    let mut app = headless_app(scene, SIZE, false).map_err(|e| e.to_string())?;
    update_until_loaded(&mut app, scene).map_err(|e| e.to_string())?;
    app.world_mut().resource_mut::<RenderPolicy>().every_frame = true;
    let camera = app.world_mut().query::<&CameraParams>().single(app.world()).map_err(|e| e.to_string())?.clone();
    let (start, eye) = (camera.target.xz(), camera.eye().xz());
    let heading = (start - eye).normalize();
    let eye_offset = eye - start;
    if frozen {
        let made = Instant::now();
        let mut bodies = app.world_mut().query::<&mut WorldBody>();
        for mut body in bodies.iter_mut(app.world_mut()) {
            // Every chunk the plan wants at some frame of the flight, at that frame's level.
            let stream = *body.stream();
            let mut wanted = BTreeSet::new();
            for frame in 0..frames + SETTLE {
                let eye = target_at(start, heading, frame.saturating_sub(SETTLE)) + eye_offset;
                let requests = plan(&stream, eye, heading, &HashMap::new(), &HashMap::new()).requests;
                wanted.extend(requests);
            }
            let count = wanted.len();
            body.make_in_advance(wanted);
            eprintln!("frozen: {count} chunks made in advance in {:.1} s", made.elapsed().as_secs_f64());
        }
    }
    let mut times = Vec::with_capacity(frames as usize);
    for frame in 0..SETTLE + frames {
        let at = target_at(start, heading, frame.saturating_sub(SETTLE));
        for mut camera in app.world_mut().query::<&mut CameraParams>().iter_mut(app.world_mut()) {
            camera.target.x = at.x;
            camera.target.z = at.y;
        }
        let (before, waited_before, stolen_before) = (spawned(&mut app), waited(), stolen());
        let started = Instant::now();
        app.update();
        let time = started.elapsed();
        if frame >= SETTLE {
            times.push(Frame {
                time,
                raster: app.world().resource::<RasterTarget>().raster_time,
                waited: waited() - waited_before,
                stolen: stolen() - stolen_before,
                spawned: spawned(&mut app) - before,
            });
        }
    }
    Ok(times)
}

fn main() {
    canopy_bench::at_workspace_root();
    // `cargo bench` passes `--bench`; a number is the flight's length in seconds.
    let seconds: f32 = std::env::args().skip(1).find_map(|a| a.parse().ok()).unwrap_or(60.0);
    let frames = (seconds / STEP_S).round() as u32;
    println!("{SCENE}, {}x{}, {seconds} s at {SPEED_M_S} m/s ({frames} frames), flights alternating", SIZE.x, SIZE.y);
    println!("| flight | median ms | p99 ms | max ms | max / median |");
    println!("|---|---|---|---|---|");
    let mut results: HashMap<bool, Vec<[f64; 3]>> = HashMap::new();
    let mut traces = Vec::new();
    for round in 0..2 {
        for frozen in [false, true] {
            let flight = fly(frames, frozen).unwrap_or_else(|error| {
                eprintln!("{error}");
                std::process::exit(1)
            });
            let [median, p99, max] = figures(&flight.iter().map(|f| f.time).collect::<Vec<_>>());
            let name = format!("{} {}", if frozen { "frozen" } else { "streaming" }, round + 1);
            println!("| {name} | {median:.1} | {p99:.1} | {max:.1} | {:.2} |", max / median);
            results.entry(frozen).or_default().push([median, p99, max]);
            traces.push(trace(&name, &flight, median));
        }
    }
    println!();
    println!(
        "frames over 2x their flight's median, each: ms over the median / raster ms / ms waiting for a core / ms stolen / chunks spawned"
    );
    traces.iter().for_each(|trace| println!("{trace}"));
    // Each round's streaming flight against the frozen one flown right after it.
    println!();
    for (round, (streaming, frozen)) in results[&false].iter().zip(&results[&true]).enumerate() {
        println!(
            "round {}: streaming / frozen: median {:.2}, p99 {:.2}; streaming max / its median {:.2}",
            round + 1,
            streaming[0] / frozen[0],
            streaming[1] / frozen[1],
            streaming[2] / streaming[0],
        );
    }
}

/// The frames of `flight` over twice its `median` (milliseconds), with the typical frame's
/// raster time and chunks spawned to compare them with.
fn trace(name: &str, flight: &[Frame], median: f64) -> String {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let [raster, ..] = figures(&flight.iter().map(|f| f.raster).collect::<Vec<_>>());
    let spawned = flight.iter().map(|f| f.spawned).sum::<u64>() as f64 / flight.len() as f64;
    let slow: Vec<String> = flight
        .iter()
        .filter(|f| ms(f.time) > 2.0 * median)
        .map(|f| {
            let over = ms(f.time) - median;
            format!("{over:.0}/{:.0}/{:.0}/{:.0}/{}", ms(f.raster), ms(f.waited), ms(f.stolen), f.spawned)
        })
        .collect();
    format!(
        "{name}: {} slow frames (typical: raster {raster:.1} ms, {spawned:.2} chunks): {}",
        slow.len(),
        if slow.is_empty() { "none".to_string() } else { slow.join(", ") }
    )
}
