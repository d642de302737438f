//! Ray casts against forests of tapered segments, through the bounding volume hierarchy and,
//! for comparison, by scanning every segment.
//!
//! Run with `cargo bench -p canopy_bench --profile dev --bench tree_queries`.

use bevy::math::Vec3;
use canopy::spatial::bvh::SegmentBvh;
use canopy::spatial::segment::TaperedSegment;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

/// Rays cast per measured iteration.
const RAYS: usize = 1024;

/// A small deterministic generator (xorshift), so every run measures the same forest.
struct Random(u64);

impl Random {
    /// A number in `[0, 1)`.
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn between(&mut self, low: f32, high: f32) -> f32 {
        low + (high - low) * self.next()
    }
}

/// A forest of `segments` segments: trees on a 60 m square, each a wobbling trunk of ten
/// segments with branches of five segments reaching out and up.
fn forest(segments: usize, random: &mut Random) -> Vec<TaperedSegment> {
    let mut out = Vec::with_capacity(segments);
    while out.len() < segments {
        let base = Vec3::new(random.between(-30.0, 30.0), 0.0, random.between(-30.0, 30.0));
        let mut trunk = vec![base];
        for i in 0..10 {
            let last = trunk[i];
            trunk.push(last + Vec3::new(random.between(-0.2, 0.2), 1.2, random.between(-0.2, 0.2)));
        }
        let radius = |t: f32| 0.3 * (1.0 - t) + 0.05;
        for (i, pair) in trunk.windows(2).enumerate() {
            let (t0, t1) = (i as f32 / 10.0, (i + 1) as f32 / 10.0);
            out.push(TaperedSegment { a: pair[0], b: pair[1], radius_a: radius(t0), radius_b: radius(t1) });
        }
        for &start in &trunk[3..] {
            let mut point = start;
            let direction = Vec3::new(random.between(-1.0, 1.0), random.between(0.1, 0.6), random.between(-1.0, 1.0));
            for k in 0..5 {
                let next = point + direction.normalize() * 0.8;
                out.push(TaperedSegment {
                    a: point,
                    b: next,
                    radius_a: 0.06 - 0.01 * k as f32,
                    radius_b: 0.05 - 0.01 * k as f32,
                });
                point = next;
            }
        }
    }
    out.truncate(segments);
    out
}

/// Rays from around and above the forest towards points inside it.
fn rays(random: &mut Random) -> Vec<(Vec3, Vec3)> {
    (0..RAYS)
        .map(|_| {
            let origin = Vec3::new(random.between(-40.0, 40.0), random.between(1.0, 25.0), random.between(-40.0, 40.0));
            let target = Vec3::new(random.between(-30.0, 30.0), random.between(0.0, 12.0), random.between(-30.0, 30.0));
            (origin, (target - origin).normalize())
        })
        .collect()
}

fn ray_casts(c: &mut Criterion) {
    let mut group = c.benchmark_group("ray casts");
    group.throughput(Throughput::Elements(RAYS as u64));
    for segments in [1_000, 10_000] {
        let mut random = Random(0x5eed_1234 + segments as u64);
        let bvh = SegmentBvh::new(forest(segments, &mut random));
        let rays = rays(&mut random);
        group.bench_function(BenchmarkId::new("bvh", segments), |b| {
            b.iter(|| rays.iter().filter(|(o, d)| bvh.ray_cast(*o, *d, 200.0).is_some()).count())
        });
        // The same first hits by testing every segment.
        group.bench_function(BenchmarkId::new("scan of every segment", segments), |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|(o, d)| {
                        let first =
                            bvh.primitives().iter().filter_map(|s| s.ray_hit(*o, *d, 200.0)).map(|h| h.distance);
                        black_box(first.fold(f32::INFINITY, f32::min)).is_finite()
                    })
                    .count()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, ray_casts);
criterion_main!(benches);
