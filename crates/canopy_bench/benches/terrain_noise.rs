//! fBm Perlin noise on one core against the `fastnoise-lite` and `noise` crates, and the cost of
//! making and meshing terrain.
//!
//! Every implementation fills the same grid with the same fractal sum (6 octaves, lacunarity
//! 2, persistence 0.5, 64 samples per lattice unit of the first octave); the implementations
//! take turns within each round, so a slow spell of the machine falls on all of them. Ratios are
//! taken per round and reported as their median and range.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench terrain_noise [-- --rounds N]`.

use canopy::terrain::Heightmap;
use canopy::terrain::bands::BandRule;
use canopy::terrain::generate::perlin;
use canopy::terrain::noise::{Fbm, FbmSettings};
use canopy::terrain::recipe::PerlinLayer;
use canopy::terrain::section::{Geometry, Section, mesh_section};
use fastnoise_lite::{FastNoiseLite, FractalType, NoiseType};
use noise::{MultiFractal, NoiseFn};
use std::hint::black_box;
use std::time::Instant;

/// The grid every implementation fills: `SIDE x SIDE` samples.
const SIDE: usize = 512;
const OCTAVES: u32 = 6;
/// Samples per lattice unit of the first octave.
const SCALE: f32 = 64.0;
const SEED: u32 = 7;
const DEFAULT_ROUNDS: usize = 15;

/// Fills the grid, row by row, and returns a sum of the values so that the work cannot be
/// optimised away.
type Fill = Box<dyn Fn(&mut [f32]) -> f32>;

/// The noise at sample `(x, z)`.
type Value = Box<dyn Fn(usize, usize) -> f32>;

/// One implementation.
struct Peer {
    name: &'static str,
    fill: Fill,
}

fn peers() -> Vec<Peer> {
    let settings =
        FbmSettings { seed: u64::from(SEED), scale: SCALE, octaves: OCTAVES, lacunarity: 2.0, persistence: 0.5 };
    let canopy = Fbm::new(settings);
    let reference = canopy.clone();
    let mut fast = FastNoiseLite::with_seed(SEED as i32);
    fast.set_noise_type(Some(NoiseType::Perlin));
    fast.set_fractal_type(Some(FractalType::FBm));
    fast.set_fractal_octaves(Some(OCTAVES as i32));
    fast.set_fractal_lacunarity(Some(2.0));
    fast.set_fractal_gain(Some(0.5));
    fast.set_frequency(Some(1.0 / SCALE));
    let libnoise = noise::Fbm::<noise::Perlin>::new(SEED)
        .set_octaves(OCTAVES as usize)
        .set_frequency(1.0 / f64::from(SCALE))
        .set_lacunarity(2.0)
        .set_persistence(0.5);
    let per_sample = |value: Value| -> Fill {
        Box::new(move |grid: &mut [f32]| {
            for (z, row) in grid.chunks_exact_mut(SIDE).enumerate() {
                for (x, out) in row.iter_mut().enumerate() {
                    *out = value(x, z);
                }
            }
            grid.iter().sum()
        })
    };
    vec![
        Peer {
            name: "canopy (8 lanes)",
            fill: Box::new(move |grid: &mut [f32]| {
                for (z, row) in grid.chunks_exact_mut(SIDE).enumerate() {
                    canopy.fill_row(0, z as i32, row);
                }
                grid.iter().sum()
            }),
        },
        Peer {
            name: "canopy (scalar reference)",
            fill: per_sample(Box::new(move |x, z| reference.sample(x as f32, z as f32))),
        },
        Peer {
            name: "fastnoise-lite 1.1",
            fill: per_sample(Box::new(move |x, z| fast.get_noise_2d(x as f32, z as f32))),
        },
        Peer { name: "noise 0.9", fill: per_sample(Box::new(move |x, z| libnoise.get([x as f64, z as f64]) as f32)) },
    ]
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rounds = args
        .iter()
        .position(|a| a == "--rounds")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_ROUNDS);
    let peers = peers();
    let mut grid = vec![0.0f32; SIDE * SIDE];
    // Nanoseconds per sample, per peer and round.
    let mut times = vec![Vec::with_capacity(rounds); peers.len()];
    for peer in &peers {
        black_box((peer.fill)(&mut grid));
    }
    for round in 0..rounds {
        for k in 0..peers.len() {
            let index = (k + round) % peers.len();
            let started = Instant::now();
            black_box((peers[index].fill)(black_box(&mut grid)));
            times[index].push(started.elapsed().as_secs_f64() * 1e9 / (SIDE * SIDE) as f64);
        }
    }

    println!("fBm Perlin noise, {OCTAVES} octaves, {SIDE} x {SIDE} samples, one core, {rounds} interleaved rounds");
    println!("| implementation | ns / sample (median) | fastest round | Canopy's 8 lanes faster by (median, range) |");
    println!("|---|---|---|---|");
    for (peer, peer_times) in peers.iter().zip(&times) {
        let mut ratios: Vec<f64> = peer_times.iter().zip(&times[0]).map(|(t, canopy)| t / canopy).collect();
        let (low, high) = ratios.iter().fold((f64::MAX, f64::MIN), |(l, h), &r| (l.min(r), h.max(r)));
        let fastest = peer_times.iter().copied().fold(f64::MAX, f64::min);
        println!(
            "| {} | {:.2} | {:.2} | {:.2}x ({:.2}-{:.2}) |",
            peer.name,
            median(&mut peer_times.clone()),
            fastest,
            median(&mut ratios),
            low,
            high
        );
    }

    let layer = PerlinLayer { scale: SCALE, octaves: OCTAVES, lacunarity: 2.0, persistence: 0.5 };
    let geometry = Geometry { cell_m: 0.25, height_m: 20.0, texture_cells: 8.0 };
    let rule = BandRule::default();
    let generate = |side: u32| perlin(layer, u64::from(SEED), side, side).expect("a map of this size");
    let mesh = |map: &Heightmap| {
        let side = map.width();
        black_box(mesh_section(map, Section { origin: [0, 0], size: [side, side] }, geometry, &rule).counts)
    };
    let time = |work: &dyn Fn()| {
        let mut samples: Vec<f64> = (0..rounds)
            .map(|_| {
                let started = Instant::now();
                work();
                started.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        median(&mut samples)
    };
    let section_map = generate(257);
    let rows: [(&str, &dyn Fn()); 4] = [
        ("generate a 257 x 257 map", &|| drop(black_box(generate(257)))),
        ("mesh a 257 x 257 section of it", &|| {
            mesh(&section_map);
        }),
        ("both: generate and mesh a 257 x 257 section", &|| {
            mesh(&generate(257));
        }),
        ("generate a 512 x 512 map", &|| drop(black_box(generate(512)))),
    ];
    println!();
    println!("| terrain work, one core, {OCTAVES} octaves | ms (median of {rounds}) |");
    println!("|---|---|");
    for (name, work) in rows {
        println!("| {name} | {:.2} |", time(work));
    }
}
