//! The surface deformers on regions of a thousand, ten thousand and a hundred thousand
//! vertices (the belly patch, its border fixed), one core: iterations and time to converge,
//! why each stopped, and for the per-edge constraints, edge projections a second (the hot
//! loop the dynamic soft bodies will share).
//!
//! Run with `cargo bench -p canopy_bench --bench deformers`; `cargo bench -p canopy_bench --bench deformers -- edge` runs only
//! the methods whose names contain `edge`.

use canopy::soft_body::deform::{Method, Settings, Variant, deform};
use canopy::soft_body::sample;
use canopy::spatial::surface::Facts;
use std::time::Instant;

/// Iterations at most, so that the largest regions finish in seconds.
const CAP: u32 = 2_000;

/// Iterations at most for the per-edge constraints run until they settle.
const SETTLE_CAP: u32 = 100_000;

fn main() {
    // The per-edge constraints, then both global ones by each step: the projection, the
    // source's own step and the step rules of the source's theory.
    let methods = std::iter::once(("edge".to_string(), Method::EdgeLengths))
        .chain(Variant::ALL.into_iter().map(|v| (format!("edge-sum, {}", v.name()), Method::EdgeSum(v))))
        .chain(Variant::ALL.into_iter().map(|v| (format!("area, {}", v.name()), Method::Area(v))))
        .collect::<Vec<_>>();
    let filters: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let chosen = |name: &str| filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str()));
    println!("the belly patch, its border fixed, k = 0.97, eps = 1e-5, at most {CAP} iterations, one core");
    println!("| vertices | method | iterations | stop | ms | ms / iteration | result | edge projections / s |");
    println!("|---|---|---|---|---|---|---|---|");
    for n in [33, 101, 317] {
        let surface = sample::belly(n);
        let edges = surface.edges().len();
        for (name, method) in methods.iter().filter(|(name, _)| chosen(name)) {
            let method = *method;
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
            let throughput = match method {
                Method::EdgeLengths => format!("{:.0} M", edges as f64 * f64::from(done.iterations) / seconds / 1e6),
                _ => "-".into(),
            };
            println!(
                "| {} | {name} | {} | {:?} | {:.1} | {:.3} | {result}, {} inverted | {throughput} |",
                n * n,
                done.iterations,
                done.stop,
                seconds * 1e3,
                seconds * 1e3 / f64::from(done.iterations.max(1)),
                facts.inverted
            );
        }
    }
    if chosen("edge") {
        // The per-edge constraints without the cap: where their error settles.
        println!("\nthe per-edge constraints until their error settles (at most {SETTLE_CAP} iterations)");
        println!("| vertices | iterations | stop | ms | error (sum of shifts, m) | mean edge error |");
        println!("|---|---|---|---|---|---|");
        for n in [33, 101] {
            let surface = sample::belly(n);
            let settings = Settings { k: 0.97, eps: 1e-5, max_iterations: SETTLE_CAP };
            let started = Instant::now();
            let done = deform(&surface, Method::EdgeLengths, settings);
            let ms = started.elapsed().as_secs_f64() * 1e3;
            let facts = Facts::of(&surface, &done.positions, settings.k);
            println!(
                "| {} | {} | {:?} | {ms:.0} | {:.4} | {:.4} |",
                n * n,
                done.iterations,
                done.stop,
                done.error,
                facts.mean_edge_error
            );
        }
    }
}
