//! Canopy's rasterizer against two real CPU renderers on the standard scene, in one process,
//! interleaved frame by frame so that the machine's noise hits every renderer alike.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench peers` (the rasterizer and the peers are built
//! optimized in that profile); `-- --rounds N` sets the frames timed per renderer and camera
//! (default 40), `--workers N` Canopy's pool workers beside the calling thread (default one per
//! other core; 0 draws on the calling thread alone), and `--canopy-only` leaves the peers out of
//! the rounds. The Mesa llvmpipe peer needs `libegl1 libegl-mesa0 libgl1-mesa-dri`; without
//! them its rows say why they are missing. It draws with one thread per core unless
//! `LP_NUM_THREADS` says otherwise (on a two-core machine its median frames took 20-35% less
//! time with eight).
//!
//! Canopy draws each round's frame three times: without shadows, with shadows read at the
//! nearest texel, and with shadows filtered over four texels (PCF, its default); the shadowed
//! frames' ratios are over the unshadowed frame of the same round.
//!
//! Each round draws every renderer's frame once, in an order shuffled from a fixed seed, so that
//! no renderer always follows the same one. A frame that follows another renderer's starts with
//! caches and threads left as that renderer left them, which costs llvmpipe more than Canopy;
//! `--back-to-back` draws each renderer's frame twice in a row and times the second, as in an
//! app that draws every frame with one renderer.
//!
//! The process keeps the memory it frees (see [`keep_freed_memory`]), so that llvmpipe's
//! frames do not depend on how its heap happens to be laid out.
//!
//! Every renderer draws the same mesh with the same matrices; the coverage column (the share
//! of pixels not left at the background) shows that they drew the same picture. The ratio
//! column is the median over rounds of each frame's time over Canopy's frame of the same
//! round, which is steadier than a ratio of medians on a machine whose speed drifts. The
//! fastest-tenth columns compare each renderer at its best: a renderer whose frames fall into a
//! fast and a slow group (llvmpipe's do here) has a median that jumps between the groups from
//! run to run, while the frame a tenth of the way up its sorted times stays in the fast one.

mod euc_peer;
mod gl_peer;
mod peer_scene;

use bevy_tasks::{TaskPool, TaskPoolBuilder};
use canopy_raster::benchmark_scene::{self as standard, CAMERAS, HEIGHT, WIDTH};
use canopy_raster::{Framebuffer, RenderSettings, Renderer};
use euc_peer::EucPeer;
use gl_peer::GlPeer;
use peer_scene::PeerScene;
use std::time::Instant;

/// Frames drawn by each renderer before timing starts.
const WARM_UP: usize = 3;

/// The renderers compared, in table order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Contender {
    Canopy,
    /// With shadows looked up at the nearest texel.
    CanopyShadowed,
    /// With shadows filtered over the four nearest texels (the default).
    CanopyShadowedPcf,
    Euc,
    Llvmpipe,
}

impl Contender {
    const ALL: [Contender; 5] = [
        Contender::Canopy,
        Contender::CanopyShadowed,
        Contender::CanopyShadowedPcf,
        Contender::Euc,
        Contender::Llvmpipe,
    ];

    fn label(self) -> &'static str {
        match self {
            Contender::Canopy => "Canopy",
            Contender::CanopyShadowed => "Canopy + shadow map (nearest texel)",
            Contender::CanopyShadowedPcf => "Canopy + shadow map (PCF)",
            Contender::Euc => "euc 0.5.3",
            Contender::Llvmpipe => "Mesa llvmpipe (EGL)",
        }
    }
}

/// Canopy's renderer with its target, pool and scene.
struct Canopy {
    renderer: Renderer,
    target: Framebuffer,
    pool: TaskPool,
    instances: Vec<canopy_raster::Instance>,
}

impl Canopy {
    fn render(&mut self, camera: &standard::StandardCamera, settings: RenderSettings) {
        let frame = standard::frame(camera, &self.instances, settings);
        self.renderer.render(&mut self.target, &self.pool, &frame);
    }

    fn coverage(&self) -> f64 {
        let background = standard::BACKGROUND;
        let covered = self.target.color().chunks_exact(4).filter(|p| *p != background).count();
        covered as f64 / (self.target.width() * self.target.height()) as f64
    }
}

/// The order of the renderers in each round, shuffled from a fixed seed: what ran just before a
/// frame (how it left the caches and the cores) changes the frame's time, so no renderer always
/// follows the same one, and runs stay repeatable.
struct RoundOrder(u64);

/// The first state of [`RoundOrder`]'s generator (any non-zero value).
const ORDER_SEED: u64 = 0x9E37_79B9_7F4A_7C15;

impl RoundOrder {
    /// The next round's order: a permutation of the renderers' indices (Fisher-Yates).
    fn next(&mut self) -> [usize; Contender::ALL.len()] {
        let mut order = std::array::from_fn(|index| index);
        for last in (1..order.len()).rev() {
            // The slight bias of a remainder over so few choices does not matter here.
            order.swap(last, (self.random() % (last as u64 + 1)) as usize);
        }
        order
    }

    /// A xorshift64 step.
    fn random(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Canopy's settings with shadows, filtered (`pcf`) or read at the nearest texel.
fn shadowed(pcf: bool) -> RenderSettings {
    RenderSettings { shadows: true, pcf, ..RenderSettings::default() }
}

fn median(samples: &mut [f64]) -> f64 {
    quantile(samples, 0.5)
}

/// The sample a `fraction` of the way up the sorted `samples`.
fn quantile(samples: &mut [f64], fraction: f64) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[((samples.len() - 1) as f64 * fraction).round() as usize]
}

/// The fraction of the way up a renderer's sorted frame times the fastest-tenth columns read.
const FASTEST_TENTH: f64 = 0.1;

/// The median over rounds of `samples[round] / base[round]`: each frame is compared with
/// Canopy's frame of the same round, so that the machine's slow and fast stretches, which
/// last many rounds, cancel out of the ratio as far as they slow every renderer alike. A stall
/// that adds the same time to every frame still lowers the ratio of the fastest renderer most.
fn median_ratio(samples: &[f64], base: &[f64]) -> f64 {
    let mut ratios: Vec<f64> = samples.iter().zip(base).map(|(sample, base)| sample / base).collect();
    median(&mut ratios)
}

/// The count given after `flag` on the command line; when it is missing, not a whole number or
/// below `least`, says so and exits.
fn count_arg(flag: &str, value: Option<String>, least: usize) -> usize {
    match value.as_deref().map(str::parse::<usize>) {
        Some(Ok(count)) if count >= least => count,
        _ => {
            let given = value.map_or("nothing".to_string(), |value| format!("{value:?}"));
            eprintln!("{flag} takes a whole number of at least {least}, not {given}");
            std::process::exit(2);
        }
    }
}

/// Stops glibc from returning freed memory at the top of the heap to the kernel, so that a
/// renderer that allocates and frees its working memory every frame (llvmpipe bins its
/// triangles in memory allocated per frame) reuses mapped pages instead of faulting fresh ones
/// in. With trimming, this process took about 1,300 more page faults a round, and llvmpipe's
/// frames took 2-3 ms longer in some processes than in others, depending on the heap's layout.
/// Canopy allocates nothing per frame, so this changes nothing for it. Returns what the header
/// says about the heap.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() -> &'static str {
    // SAFETY: `mallopt` only changes a setting of the allocator; it is called first thing in
    // `main`, before any other thread exists, as glibc asks (it must not race other threads'
    // first use of the allocator).
    match unsafe { libc::mallopt(libc::M_TRIM_THRESHOLD, libc::c_int::MAX) } {
        1 => "freed memory kept (glibc's heap trimming off)",
        _ => "glibc refused to keep freed memory: llvmpipe's frames may fault pages in",
    }
}

/// See the glibc version: other allocators are left as they are.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn keep_freed_memory() -> &'static str {
    "the system allocator's defaults"
}

fn main() {
    let heap = keep_freed_memory();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut rounds = 40;
    // The thread that calls `render` works through the frame's tasks too, so one worker per
    // other core keeps every core busy without two of Canopy's threads sharing one.
    let mut workers = (cores - 1).max(1);
    let mut canopy_only = false;
    let mut back_to_back = false;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--rounds" => rounds = count_arg("--rounds", args.next(), 1),
            "--workers" => workers = count_arg("--workers", args.next(), 0),
            "--canopy-only" => canopy_only = true,
            "--back-to-back" => back_to_back = true,
            _ => {}
        }
    }

    let mut canopy = Canopy {
        renderer: Renderer::default(),
        target: Framebuffer::new(WIDTH, HEIGHT),
        pool: TaskPoolBuilder::new().num_threads(workers).build(),
        instances: vec![standard::instance()],
    };
    let mesh = canopy.instances[0].mesh.clone();
    let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let normals: Vec<[f32; 3]> = mesh.normals.iter().map(|n| n.to_array()).collect();
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let scene = PeerScene {
        positions: &positions,
        normals: &normals,
        indices: &indices,
        color: standard::COLOR.to_array(),
        light: standard::towards_light().to_array(),
    };
    let mut euc = EucPeer::new(WIDTH as usize, HEIGHT as usize);
    let mut gl = GlPeer::new(WIDTH, HEIGHT, &scene);
    let triangles = mesh.triangle_count() as f64;

    println!(
        "Standard scene: {} triangles at {WIDTH}x{HEIGHT}, {rounds} interleaved frames per renderer",
        mesh.triangle_count()
    );
    println!(
        "Canopy: the calling thread and {workers} task pool worker(s) on {cores} cores; \
         euc 0.5.3: one thread (it has no parallel mode)"
    );
    match &gl {
        Ok(gl) => {
            let threads = std::env::var("LP_NUM_THREADS")
                .map_or_else(|_| format!("one per core ({cores})"), |n| format!("LP_NUM_THREADS={n}"));
            println!("llvmpipe: {} (rendering threads: {threads})", gl.renderer_name());
        }
        Err(reason) => println!("llvmpipe: not measured: {reason}"),
    }
    let frames = if back_to_back {
        "each timed right after an untimed one of the same renderer (--back-to-back)"
    } else {
        "each timed after the previous renderer's in the round"
    };
    println!("Heap: {heap}; frames: {frames}");
    println!("Ratios: median over rounds of a frame's time over Canopy's (unshadowed) frame of the same round;");
    println!("fastest tenths: the frame a tenth of the way up each renderer's sorted times, over Canopy's");
    println!();
    println!(
        "| camera | renderer | ms / frame (median) | triangles / s | coverage | Canopy faster by | \
         ms / frame (fastest tenth) | faster by (fastest tenths) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    let mut order = RoundOrder(ORDER_SEED);
    for camera in &CAMERAS {
        let clip = camera.camera().view_projection(WIDTH as f32 / HEIGHT as f32).to_cols_array();
        let mut samples: Vec<Vec<f64>> = vec![Vec::with_capacity(rounds); Contender::ALL.len()];
        // Draws `contender`'s frame; false when it cannot draw (llvmpipe missing).
        let mut draw = |contender| {
            match contender {
                Contender::Canopy => canopy.render(camera, RenderSettings::default()),
                Contender::CanopyShadowed => canopy.render(camera, shadowed(false)),
                Contender::CanopyShadowedPcf => canopy.render(camera, shadowed(true)),
                Contender::Euc => euc.render(&scene, clip),
                Contender::Llvmpipe => match &mut gl {
                    Ok(gl) => gl.render(clip),
                    Err(_) => return false,
                },
            }
            true
        };
        for round in 0..WARM_UP + rounds {
            for index in order.next() {
                let contender = Contender::ALL[index];
                if canopy_only && matches!(contender, Contender::Euc | Contender::Llvmpipe) {
                    continue;
                }
                if back_to_back && !draw(contender) {
                    continue;
                }
                let started = Instant::now();
                if !draw(contender) {
                    continue;
                }
                if round >= WARM_UP {
                    samples[index].push(started.elapsed().as_secs_f64() * 1e3);
                }
            }
        }
        // Coverage of each renderer's last frame of this camera (Canopy's without shadows).
        canopy.render(camera, RenderSettings::default());
        let coverage =
            [Some(canopy.coverage()), None, None, Some(euc.coverage()), gl.as_mut().ok().map(|gl| gl.coverage())];
        let canopy_frames = samples[0].clone();
        let canopy_fastest = quantile(&mut samples[0].clone(), FASTEST_TENTH);
        for (index, contender) in Contender::ALL.into_iter().enumerate() {
            if samples[index].is_empty() {
                continue;
            }
            let ratio = median_ratio(&samples[index], &canopy_frames);
            let ms = median(&mut samples[index]);
            let fastest = quantile(&mut samples[index], FASTEST_TENTH);
            let fastest_ratio = fastest / canopy_fastest;
            let coverage = coverage[index].map_or("same".to_string(), |c| format!("{:.1}%", c * 100.0));
            let [ratio, fastest_ratio] = [ratio, fastest_ratio].map(|ratio| match contender {
                Contender::Canopy => "-".to_string(),
                Contender::CanopyShadowed | Contender::CanopyShadowedPcf => format!("shadows cost {ratio:.2}x"),
                _ => format!("{ratio:.2}x"),
            });
            println!(
                "| {} | {} | {ms:.2} | {:.1} M | {coverage} | {ratio} | {fastest:.2} | {fastest_ratio} |",
                camera.name,
                contender.label(),
                triangles / ms * 1e-3,
            );
        }
    }
}
