//! One fixed step of sloth locomotion, per sloth, with 100 sloths walking on a generated
//! forest: gait clock, foothold searches, body pose and clearance, and four limbs of IK.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench sloth`.

use canopy::sloth::rig::Proportions;
use canopy::sloth::{Drive, Placement, Sloth, Supports, Tuning};
use canopy::tree::{GeneratorSettings, SupportKind, Tree, generate::generate};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

/// Sloths walking at once.
const SLOTHS: usize = 100;

/// Fixed step, seconds.
const STEP: f32 = 1.0 / 60.0;

/// A seeded forest of 25 trees and sloths on its longest branches, each already walking.
fn walkers() -> (Supports, Vec<Sloth>) {
    let settings = GeneratorSettings { seed: 7, trunks: 25, height: 8.0, branches: 5, depth: 2, spacing: 6.0 };
    let trees: Vec<Tree> =
        generate(&settings).iter().map(|specs| Tree::build(specs).expect("generated trees build")).collect();
    let names: Vec<String> = (0..trees.len()).map(|i| format!("tree{i}")).collect();
    let supports = Supports::new(names.iter().map(String::as_str).zip(&trees));
    let mut branches: Vec<usize> =
        (0..supports.paths.len()).filter(|&i| supports.paths[i].kind == SupportKind::Branch).collect();
    branches.sort_by(|a, b| supports.paths[*b].length().total_cmp(&supports.paths[*a].length()));
    let mut sloths = Vec::with_capacity(SLOTHS);
    for &support in branches.iter().cycle().take(SLOTHS * 4) {
        if sloths.len() == SLOTHS {
            break;
        }
        let fraction = 0.25 + 0.1 * (sloths.len() % 3) as f32;
        let placement = Placement { support, fraction, facing: 1.0, around: 0.0 };
        if let Ok(sloth) =
            Sloth::place(&supports, placement, Proportions::default(), Tuning::animal(0.11, &Proportions::default()))
        {
            sloths.push(sloth);
        }
    }
    assert_eq!(sloths.len(), SLOTHS, "the forest has room for every sloth");
    for sloth in &mut sloths {
        for _ in 0..120 {
            sloth.step(STEP, Drive { direction: 1.0, ..Drive::default() }, &supports);
        }
    }
    (supports, sloths)
}

fn locomotion(c: &mut Criterion) {
    let (supports, mut sloths) = walkers();
    let mut directions = vec![1.0f32; SLOTHS];
    let mut group = c.benchmark_group("sloth");
    group.throughput(Throughput::Elements(SLOTHS as u64));
    group.bench_function("fixed step, 100 sloths", |b| {
        b.iter(|| {
            for (sloth, direction) in sloths.iter_mut().zip(&mut directions) {
                // Turn round at the end of a branch, so every sloth keeps walking.
                if sloth.blocked.is_some() {
                    *direction = -*direction;
                }
                sloth.step(STEP, Drive { direction: *direction, ..Drive::default() }, &supports);
            }
        })
    });
    group.finish();
}

criterion_group!(benches, locomotion);
criterion_main!(benches);
