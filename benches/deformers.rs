//! The surface deformers on regions of a thousand, ten thousand and a hundred thousand
//! vertices (the belly patch, its border fixed), one core: iterations and time to converge,
//! why each stopped, and for the per-edge constraints, edge projections a second (the hot
//! loop the dynamic soft bodies will share).
//!
//! The per-edge loop has a peer in the same run: the textbook loop, the same constraints
//! projected in the edges' sorted order, timed for the same iterations.
//!
//! Run with `cargo bench --bench deformers`; `cargo bench --bench deformers -- edge` runs only
//! the methods whose names contain `edge`.

use bevy::math::Vec3;
use canopy::soft_body::deform::{Method, Settings, Variant, deform};
use canopy::soft_body::sample;
use canopy::soft_body::surface::{Facts, Surface};
use std::time::Instant;

/// The peer: `iterations` of every movable edge projected onto `k` times its length in the
/// edges' sorted order, unit weights; returns the seconds taken.
fn sorted_order(surface: &Surface, k: f32, iterations: u32) -> f64 {
    let movable = |v: u32| surface.movable[v as usize];
    let edges: Vec<(u32, u32, f32, [f32; 2])> = surface
        .edges()
        .iter()
        .filter(|&&[a, b]| movable(a) || movable(b))
        .map(|&[a, b]| {
            let (wa, wb) = (f32::from(u8::from(movable(a))), f32::from(u8::from(movable(b))));
            (
                a,
                b,
                k * surface.positions[a as usize].distance(surface.positions[b as usize]),
                [wa / (wa + wb), wb / (wa + wb)],
            )
        })
        .collect();
    let mut positions: Vec<Vec3> = surface.positions.clone();
    let started = Instant::now();
    let mut shifted = 0.0;
    for _ in 0..iterations {
        for &(a, b, rest, share) in &edges {
            let (a, b) = (a as usize, b as usize);
            let delta = positions[a] - positions[b];
            let length = delta.length();
            if length == 0.0 {
                continue;
            }
            let c = length - rest;
            let correction = delta * (c / length);
            if share[0] > 0.0 {
                positions[a] -= correction * share[0];
            }
            if share[1] > 0.0 {
                positions[b] += correction * share[1];
            }
            shifted += f64::from(c.abs());
        }
    }
    std::hint::black_box((shifted, positions));
    started.elapsed().as_secs_f64()
}

/// Iterations at most, so that the largest regions finish in seconds.
const CAP: u32 = 2_000;

fn main() {
    let methods = [
        ("edge", Method::EdgeLengths),
        ("edge-sum, projection", Method::EdgeSum(Variant::Projection)),
        ("edge-sum, source", Method::EdgeSum(Variant::Source)),
        ("area, projection", Method::Area(Variant::Projection)),
        ("area, source", Method::Area(Variant::Source)),
    ];
    let filters: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let chosen = |name: &str| filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str()));
    println!("the belly patch, its border fixed, k = 0.97, eps = 1e-5, at most {CAP} iterations, one core");
    println!(
        "| vertices | method | iterations | stop | ms | ms / iteration | result | edge projections / s | in sorted order (peer) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for n in [33, 101, 317] {
        let surface = sample::belly(n);
        let edges = surface
            .edges()
            .iter()
            .filter(|&&[a, b]| surface.movable[a as usize] || surface.movable[b as usize])
            .count();
        for (name, method) in methods.into_iter().filter(|(name, _)| chosen(name)) {
            let settings = Settings { k: 0.97, eps: 1e-5, max_iterations: CAP };
            let started = Instant::now();
            let done = deform(&surface, method, settings);
            let seconds = started.elapsed().as_secs_f64();
            let facts = Facts::of(&surface, &done.positions, settings.k);
            let result = match method {
                Method::EdgeLengths => format!("mean edge error {:.4}", facts.mean_edge_error),
                Method::EdgeSum(_) => format!("edge sum ratio {:.4}", facts.edge_sum_ratio),
                Method::Area(_) => format!("area ratio {:.4}", facts.area_ratio),
            };
            let rate = |seconds: f64| format!("{:.0} M", edges as f64 * f64::from(done.iterations) / seconds / 1e6);
            let (throughput, peer) = match method {
                Method::EdgeLengths => (rate(seconds), rate(sorted_order(&surface, settings.k, done.iterations))),
                _ => ("-".into(), "-".into()),
            };
            println!(
                "| {} | {name} | {} | {:?} | {:.1} | {:.3} | {result}, {} inverted | {throughput} | {peer} |",
                n * n,
                done.iterations,
                done.stop,
                seconds * 1e3,
                seconds * 1e3 / f64::from(done.iterations.max(1)),
                facts.inverted
            );
        }
    }
}
