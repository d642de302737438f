//! The source's comparison of IK methods (its Table 5) repeated on the sloth's own limbs: CCD
//! (with its damped least-squares finish and restarts, as the walk uses it) against FABRIK with
//! the same joint limits, from the rest pose, on targets every limb can reach (poses drawn
//! within its limits) and on barely reachable ones (poses with every flexion joint near a
//! limit). Prints, per set, the share reached within the walk's tolerance, the mean
//! iterations, the mean final error, limit violations and the time per solve (the two solvers
//! alternating target by target); then criterion times each.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench ik`.

use bevy::math::Vec3;
use canopy::foundation::random::Random;
use canopy::sloth::ccd::{self, CcdResult, CcdSettings};
use canopy::sloth::fabrik;
use canopy::sloth::rig::{BodyFrame, JOINTS, Limb, LimbRig, Proportions};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Targets per limb and set.
const TARGETS: usize = 250;

type Solver = fn(&LimbRig, &BodyFrame, &mut [f32; JOINTS], Vec3, &CcdSettings) -> CcdResult;

const SOLVERS: [(&str, Solver); 2] = [("CCD", ccd::solve), ("FABRIK", fabrik::solve)];

fn frame() -> BodyFrame {
    BodyFrame { centre: Vec3::new(0.0, 2.0, 0.0), forward: Vec3::X, up: Vec3::NEG_Y }
}

/// Each limb's rig with its targets: grip points of poses drawn within the limits, or (when
/// `edge`) with every flexion joint within a tenth of its range of a limit.
fn targets(edge: bool) -> Vec<(LimbRig, Vec3)> {
    let mut random = Random::new(if edge { 11 } else { 7 });
    let mut out = Vec::new();
    for limb in Limb::ALL {
        let rig = LimbRig::new(limb, &Proportions::default());
        for _ in 0..TARGETS {
            let pose: [f32; JOINTS] = std::array::from_fn(|j| {
                let t = random.unit();
                let t = if edge && j > 0 { if t < 0.5 { t * 0.2 } else { 0.9 + (t - 0.5) * 0.2 } } else { t };
                rig.min[j] + t * (rig.max[j] - rig.min[j])
            });
            out.push((rig, rig.effector(&frame(), &pose)));
        }
    }
    out
}

/// The figures of one solver over one set.
#[derive(Default)]
struct Figures {
    reached: usize,
    iterations: u64,
    error: f64,
    violations: usize,
    time: Duration,
}

fn table() {
    let settings = CcdSettings::default();
    println!(
        "IK on the sloth's limbs from the rest pose, tolerance {} mm, at most {} sweeps or iterations a start",
        settings.tolerance * 1e3,
        settings.max_sweeps
    );
    println!(
        "{:<18}{:<8}{:>9}{:>12}{:>14}{:>12}{:>12}",
        "targets", "solver", "reached", "iterations", "error mm", "violations", "us/solve"
    );
    for (name, edge) in [("reachable", false), ("barely reachable", true)] {
        let set = targets(edge);
        let mut figures: [Figures; 2] = Default::default();
        for (rig, target) in &set {
            for ((_, solve), f) in SOLVERS.iter().zip(&mut figures) {
                let mut angles = rig.rest;
                let started = Instant::now();
                let result = solve(rig, &frame(), &mut angles, *target, &settings);
                f.time += started.elapsed();
                f.reached += usize::from(result.error <= settings.tolerance);
                f.iterations += u64::from(result.sweeps);
                f.error += f64::from(result.error);
                f.violations += usize::from(!rig.within_limits(&angles, 1e-6));
            }
        }
        let n = set.len() as f64;
        for ((solver, _), f) in SOLVERS.iter().zip(&figures) {
            println!(
                "{name:<18}{solver:<8}{:>8.1}%{:>12.1}{:>14.3}{:>12}{:>12.1}",
                100.0 * f.reached as f64 / n,
                f.iterations as f64 / n,
                1e3 * f.error / n,
                f.violations,
                f.time.as_secs_f64() * 1e6 / n
            );
        }
    }
}

fn solves(c: &mut Criterion) {
    table();
    let settings = CcdSettings::default();
    let mut group = c.benchmark_group("ik");
    for (name, edge) in [("reachable", false), ("barely reachable", true)] {
        let set = targets(edge);
        for (solver, solve) in SOLVERS {
            group.bench_function(format!("{solver}, {name}, {} targets", set.len()), |b| {
                b.iter(|| {
                    for (rig, target) in &set {
                        let mut angles = rig.rest;
                        black_box(solve(rig, &frame(), &mut angles, *target, &settings));
                    }
                });
            });
        }
    }
    group.finish();
}

criterion_group!(benches, solves);
criterion_main!(benches);
