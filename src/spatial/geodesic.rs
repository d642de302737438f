//! Distances along a triangle surface: the shortest way from one vertex to another without
//! leaving the surface, as a tape measure laid on the skin gives it, by fast marching
//! (Kimmel and Sethian 1998).
//!
//! Vertices are settled in order of distance from the source, as in Dijkstra's algorithm on
//! the edges; but a vertex is reached across each triangle whose other two corners are
//! settled, from the point in the triangle's plane that lies at their distances (the source
//! unfolded into the plane), when the straight line from it crosses the edge between them.
//! On a flat surface that is the source itself, and the distance is exact; on a curved one it
//! follows the unfolded strip of triangles. Where no such line crosses, the way along an edge
//! is taken, as Dijkstra's would. Along the edges alone a grid's diagonal comes out up to 8 %
//! too long; across the triangles it does not.

use super::surface::triangles_at;
use bevy::math::{DVec2, Vec3};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The distance along the surface from vertex `from` to vertex `to`, metres; `None` when no
/// way joins them (another piece of the surface) or either vertex does not exist.
pub fn along_surface(positions: &[Vec3], triangles: &[[u32; 3]], from: u32, to: u32) -> Option<f64> {
    let (from, to) = (from as usize, to as usize);
    if from >= positions.len() || to >= positions.len() {
        return None;
    }
    let triangles_of = triangles_at(positions.len(), triangles);
    let mut distance = vec![f64::INFINITY; positions.len()];
    let mut settled = vec![false; positions.len()];
    // Distances are never negative, so their bits order as they do.
    let mut queue = BinaryHeap::new();
    distance[from] = 0.0;
    queue.push(Reverse((0f64.to_bits(), from)));
    while let Some(Reverse((bits, v))) = queue.pop() {
        if settled[v] || f64::from_bits(bits) > distance[v] {
            continue;
        }
        settled[v] = true;
        if v == to {
            return Some(distance[v]);
        }
        for &t in &triangles_of[v] {
            let triangle = triangles[t as usize].map(|c| c as usize);
            if triangle.iter().any(|&c| c >= positions.len()) {
                continue;
            }
            for &next in triangle.iter().filter(|&&c| c != v && !settled[c]) {
                let other = triangle.iter().copied().find(|&c| c != v && c != next).unwrap_or(v);
                let along_edge = distance[v] + f64::from(positions[v].distance(positions[next]));
                let across = (settled[other] && other != v)
                    .then(|| across_triangle(positions, [v, other, next], [distance[v], distance[other]]))
                    .flatten();
                let reached = across.map_or(along_edge, |across| across.min(along_edge));
                if reached < distance[next] {
                    distance[next] = reached;
                    queue.push(Reverse((reached.to_bits(), next)));
                }
            }
        }
    }
    None
}

/// The distance to corner `c` of the triangle `a b c` from the point in its plane at
/// distances `da` from `a` and `db` from `b`, on the side of `a b` away from `c`, when the
/// straight line from that point to `c` crosses the edge `a b`.
fn across_triangle(positions: &[Vec3], [a, b, c]: [usize; 3], [da, db]: [f64; 2]) -> Option<f64> {
    let (pa, pb, pc) = (positions[a].as_dvec3(), positions[b].as_dvec3(), positions[c].as_dvec3());
    let ab = pb - pa;
    let side = ab.length();
    if side == 0.0 {
        return None;
    }
    // The triangle laid flat: a at the origin, b along +x, c above the x axis.
    let along = ab / side;
    let ac = pc - pa;
    let cx = ac.dot(along);
    let cy = (ac - along * cx).length();
    if cy == 0.0 {
        return None;
    }
    let sx = (da * da - db * db + side * side) / (2.0 * side);
    let sy_squared = da * da - sx * sx;
    if sy_squared < 0.0 {
        return None;
    }
    let source = DVec2::new(sx, -sy_squared.sqrt());
    let corner = DVec2::new(cx, cy);
    // Where the line from the source to c crosses the x axis: between a and b, or no way.
    let t = -source.y / (corner.y - source.y);
    let crossing = source.x + t * (corner.x - source.x);
    (0.0..=side).contains(&crossing).then(|| source.distance(corner))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat grid of `n` x `n` vertices `step` metres apart, each square cut along one
    /// diagonal.
    fn grid(n: u32, step: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let positions = (0..n * n).map(|i| Vec3::new((i % n) as f32 * step, 0.0, (i / n) as f32 * step)).collect();
        let mut triangles = Vec::new();
        for row in 0..n - 1 {
            for column in 0..n - 1 {
                let v = row * n + column;
                triangles.push([v, v + n, v + 1]);
                triangles.push([v + 1, v + n, v + n + 1]);
            }
        }
        (positions, triangles)
    }

    #[test]
    fn on_a_flat_surface_the_distance_is_the_straight_one() {
        let (positions, triangles) = grid(41, 0.01);
        for to in [40, 41 * 40, 41 * 41 - 1, 41 * 13 + 29] {
            let along = along_surface(&positions, &triangles, 0, to).unwrap();
            let straight = f64::from(positions[0].distance(positions[to as usize]));
            assert!((along - straight).abs() < 1e-3 * straight, "to {to}: {along} against {straight}");
        }
        // Along the edges alone, the way to the far corner across the grid's diagonals is
        // the two sides: 41 % longer. Across the triangles it is straight.
        let (positions, triangles) = grid(3, 1.0);
        let along = along_surface(&positions, &triangles, 0, 8).unwrap();
        assert!((along - 8f64.sqrt()).abs() < 1e-6, "{along}");
    }

    #[test]
    fn on_a_sphere_the_distance_follows_the_great_circle() {
        // A unit sphere of 48 rings of 96 vertices between two poles.
        let (rings, segments) = (48u32, 96u32);
        let mut positions = vec![Vec3::Y];
        for ring in 1..rings {
            let polar = std::f32::consts::PI * ring as f32 / rings as f32;
            for segment in 0..segments {
                let azimuth = std::f32::consts::TAU * segment as f32 / segments as f32;
                positions.push(Vec3::new(polar.sin() * azimuth.cos(), polar.cos(), polar.sin() * azimuth.sin()));
            }
        }
        positions.push(Vec3::NEG_Y);
        let at = |ring: u32, segment: u32| 1 + (ring - 1) * segments + segment % segments;
        let mut triangles = Vec::new();
        for segment in 0..segments {
            triangles.push([0, at(1, segment + 1), at(1, segment)]);
            triangles.push([positions.len() as u32 - 1, at(rings - 1, segment), at(rings - 1, segment + 1)]);
            for ring in 1..rings - 1 {
                triangles.push([at(ring, segment), at(ring, segment + 1), at(ring + 1, segment)]);
                triangles.push([at(ring, segment + 1), at(ring + 1, segment + 1), at(ring + 1, segment)]);
            }
        }
        let (positions, triangles) = (&positions, &triangles);
        let top = 0;
        for target in [0.3f32, 0.0, -0.6] {
            // The vertex nearest the height `target` on the sphere's first meridian side.
            let to = (0..positions.len())
                .filter(|&v| positions[v].x >= 0.0)
                .min_by(|&a, &b| {
                    let distance = |v: usize| (positions[v].y - target).abs() + positions[v].z.abs();
                    distance(a).total_cmp(&distance(b))
                })
                .unwrap();
            let along = along_surface(positions, triangles, top as u32, to as u32).unwrap();
            let great_circle =
                f64::from(positions[top].normalize().dot(positions[to].normalize()).clamp(-1.0, 1.0)).acos();
            let straight = f64::from(positions[top].distance(positions[to]));
            assert!((along - great_circle).abs() < 0.01 * great_circle, "to {target}: {along} against {great_circle}");
            assert!(along > straight, "the way along a sphere is longer than through it");
        }
    }

    #[test]
    fn pieces_not_joined_have_no_way_between_them() {
        let positions =
            vec![Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::Y * 5.0, Vec3::new(1.0, 5.0, 0.0), Vec3::new(0.0, 5.0, 1.0)];
        let triangles = vec![[0, 2, 1], [3, 5, 4]];
        assert_eq!(along_surface(&positions, &triangles, 0, 4), None);
        assert_eq!(along_surface(&positions, &triangles, 0, 9), None);
        assert_eq!(along_surface(&positions, &triangles, 0, 0), Some(0.0));
    }
}
