//! Deforming and remeshing a muscle: one length change of the node model followed by a
//! rebuild of its surface, as the app does whenever the muscle's state changes.
//!
//! Run with `cargo bench -p canopy_bench --bench muscle`.

use canopy::muscle::model::Muscle;
use canopy::muscle::surface::build_surface;
use canopy::raster::MeshData;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// A muscle of `nodes` nodes with a smooth belly and positive multipliers.
fn muscle(nodes: usize) -> Muscle {
    let radii = (0..nodes).map(|i| 5.0 + 15.0 * (std::f64::consts::PI * i as f64 / (nodes - 1) as f64).sin()).collect();
    let mults = (0..nodes).map(|i| if i == 0 || i == nodes - 1 { 0.0 } else { 1.0 + (i % 3) as f64 }).collect();
    Muscle::new(radii, mults, 250.0, 0.5, 1.5).expect("a valid muscle")
}

fn deform_and_remesh(c: &mut Criterion) {
    let mut group = c.benchmark_group("muscle deform + remesh");
    for (nodes, segments) in [(10, 32), (1000, 64)] {
        let mut model = muscle(nodes);
        let mut mesh = MeshData::default();
        build_surface(model.radii(), model.node_spacing(), segments, &mut mesh);
        let mut flip = false;
        group.bench_function(BenchmarkId::from_parameter(format!("{nodes} nodes x {segments} segments")), |b| {
            b.iter(|| {
                flip = !flip;
                model.set_length(if flip { 230.0 } else { 240.0 }).expect("within bounds");
                build_surface(black_box(model.radii()), model.node_spacing(), segments, &mut mesh);
                black_box(&mesh);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, deform_and_remesh);
criterion_main!(benches);
