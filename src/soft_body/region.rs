//! The region a user outlines on a surface: three or more marks joined along the surface into
//! a closed loop, and the part of the surface inside it (the smaller side), cut out as a
//! [`Surface`] whose loop vertices are fixed and whose inside may move.

use crate::spatial::surface::{Surface, SurfaceError, triangle_cross};
use bevy::math::Vec3;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};

/// A point of the outline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mark {
    /// A vertex of the surface, by index.
    Vertex(u32),
    /// A point on the surface (within the tolerance of [`select`]); the nearest corner of the
    /// triangle it lies on stands for it.
    Point(Vec3),
}

/// Why no region follows from the marks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegionError {
    /// Fewer than three marks.
    #[error("expected at least 3 points to outline a region, found {0}")]
    TooFewMarks(usize),
    /// A mark names a vertex that does not exist.
    #[error("point {mark}: there is no vertex {vertex} (the surface has {count})")]
    NoVertex {
        /// Which mark.
        mark: usize,
        /// The index it names.
        vertex: u32,
        /// Vertices there are.
        count: usize,
    },
    /// A mark lies off the surface.
    #[error("point {mark} lies {distance_m:.4} m from the surface (at most {tolerance_m} m)")]
    OffSurface {
        /// Which mark.
        mark: usize,
        /// How far from the surface, metres.
        distance_m: f32,
        /// How far it may be.
        tolerance_m: f32,
    },
    /// Two marks are not joined by the surface.
    #[error("points {0} and {1} lie on parts of the surface that do not meet")]
    NotJoined(usize, usize),
    /// Nothing lies inside the loop.
    #[error("the outline encloses no vertex: the region is empty")]
    Empty,
    /// The cut surface is not a surface.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
}

/// A region cut out of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// The cut surface: its loop vertices fixed, its inside movable.
    pub surface: Surface,
    /// For each of its vertices, the index of the whole surface's vertex it was cut from.
    pub source: Vec<u32>,
    /// The loop, as the whole surface's vertices in order (the first not repeated).
    pub outline: Vec<u32>,
}

impl Region {
    /// The whole surface's positions `whole` with the region's vertices moved to `deformed`
    /// (one per vertex of [`Region::surface`]).
    pub fn put_back(&self, whole: &[Vec3], deformed: &[Vec3]) -> Vec<Vec3> {
        let mut positions = whole.to_vec();
        for (&source, &p) in self.source.iter().zip(deformed) {
            positions[source as usize] = p;
        }
        positions
    }
}

/// The vertex that mark number `index` stands for on the triangles `triangles` of vertices at
/// `positions`: the vertex it names, or for a point within `tolerance_m` metres of the surface
/// the nearest corner of the triangle it lies on. Only the geometry is read, so a model of a
/// surface needs no surface of its own.
pub fn vertex_of(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    mark: Mark,
    index: usize,
    tolerance_m: f32,
) -> Result<u32, RegionError> {
    let count = positions.len();
    match mark {
        Mark::Vertex(vertex) if (vertex as usize) < count => Ok(vertex),
        Mark::Vertex(vertex) => Err(RegionError::NoVertex { mark: index, vertex, count }),
        Mark::Point(point) => {
            let (distance_m, vertex) = nearest_on_surface(positions, triangles, point);
            match distance_m <= tolerance_m {
                true => Ok(vertex),
                false => Err(RegionError::OffSurface { mark: index, distance_m, tolerance_m }),
            }
        }
    }
}

/// The region of `whole` outlined by `marks`, points on the surface taken within
/// `tolerance_m` metres of it.
pub fn select(whole: &Surface, marks: &[Mark], tolerance_m: f32) -> Result<Region, RegionError> {
    if marks.len() < 3 {
        return Err(RegionError::TooFewMarks(marks.len()));
    }
    let count = whole.positions.len();
    let vertices = marks
        .iter()
        .enumerate()
        .map(|(index, &mark)| vertex_of(&whole.positions, &whole.triangles, mark, index, tolerance_m))
        .collect::<Result<Vec<u32>, RegionError>>()?;
    // The loop: the shortest paths along the edges from each mark to the next, and back.
    let mut outline: Vec<u32> = Vec::new();
    for (index, &from) in vertices.iter().enumerate() {
        let next = (index + 1) % vertices.len();
        let path = shortest_path(whole, from, vertices[next]).ok_or(RegionError::NotJoined(index, next))?;
        outline.extend(&path[..path.len() - 1]);
    }
    outline.dedup();
    let mut on_loop = vec![false; count];
    outline.iter().for_each(|&v| on_loop[v as usize] = true);
    // The parts the loop cuts the rest into; the region is the one of least area.
    let mut part = vec![usize::MAX; count];
    let mut parts = 0;
    for start in 0..count {
        if on_loop[start] || part[start] != usize::MAX {
            continue;
        }
        let mut stack = vec![start];
        part[start] = parts;
        while let Some(v) = stack.pop() {
            for &n in whole.neighbours(v) {
                let n = n as usize;
                if !on_loop[n] && part[n] == usize::MAX {
                    part[n] = parts;
                    stack.push(n);
                }
            }
        }
        parts += 1;
    }
    let mut areas = vec![0.0f64; parts];
    for &t in &whole.triangles {
        let area = f64::from(triangle_cross(&whole.positions, t).length()) * 0.5;
        for p in t.iter().map(|&v| part[v as usize]).filter(|&p| p != usize::MAX) {
            areas[p] += area;
        }
    }
    // One part (or none) means the loop separates nothing: it encloses no vertex.
    if parts < 2 {
        return Err(RegionError::Empty);
    }
    let inside = (0..parts).min_by(|&a, &b| areas[a].total_cmp(&areas[b]).then(a.cmp(&b))).unwrap_or(0);
    // The triangles of the region: those with a corner inside and the rest on the loop, and
    // those with every corner on the loop that share an edge across it with one of them.
    let in_region = |v: u32| part[v as usize] == inside || on_loop[v as usize];
    let mut chosen: Vec<[u32; 3]> = whole
        .triangles
        .iter()
        .copied()
        .filter(|t| t.iter().any(|&v| part[v as usize] == inside) && t.iter().all(|&v| in_region(v)))
        .collect();
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let edges_of = |t: [u32; 3]| [key(t[0], t[1]), key(t[1], t[2]), key(t[2], t[0])];
    let along_loop: HashSet<(u32, u32)> =
        outline.iter().zip(outline.iter().cycle().skip(1)).map(|(&a, &b)| key(a, b)).collect();
    let inner_edges: HashSet<(u32, u32)> = chosen.iter().flat_map(|&t| edges_of(t)).collect();
    let on_loop_alone = whole.triangles.iter().copied().filter(|t| {
        t.iter().all(|&v| on_loop[v as usize])
            && edges_of(*t).iter().any(|e| !along_loop.contains(e) && inner_edges.contains(e))
    });
    chosen.extend(on_loop_alone.collect::<Vec<_>>());
    let mut local = vec![u32::MAX; count];
    let mut source = Vec::new();
    for &v in chosen.iter().flatten() {
        if local[v as usize] == u32::MAX {
            local[v as usize] = source.len() as u32;
            source.push(v);
        }
    }
    let positions = source.iter().map(|&v| whole.positions[v as usize]).collect();
    let triangles = chosen.iter().map(|t| t.map(|v| local[v as usize])).collect();
    let movable = source.iter().map(|&v| part[v as usize] == inside).collect();
    Ok(Region { surface: Surface::new(positions, triangles, movable)?, source, outline })
}

/// The distance from `point` to the surface, and the corner nearest it of the triangle
/// nearest it.
fn nearest_on_surface(positions: &[Vec3], triangles: &[[u32; 3]], point: Vec3) -> (f32, u32) {
    let mut best = (f32::INFINITY, 0);
    for &t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let distance = closest_on_triangle(point, a, b, c).distance(point);
        if distance < best.0 {
            let near = |v: u32| positions[v as usize].distance_squared(point);
            let corner = t.into_iter().min_by(|&u, &v| near(u).total_cmp(&near(v))).unwrap_or(t[0]);
            best = (distance, corner);
        }
    }
    best
}

/// The point of triangle `a b c` nearest `p` (by the regions of the triangle's plane, as in
/// Ericson's "Real-Time Collision Detection").
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denominator = va + vb + vc;
    if denominator == 0.0 {
        return a;
    }
    a + ab * (vb / denominator) + ac * (vc / denominator)
}

/// The shortest path along the edges from `from` to `to` (both included), by Dijkstra's
/// algorithm over the edges' lengths; `None` when they are not joined.
fn shortest_path(surface: &Surface, from: u32, to: u32) -> Option<Vec<u32>> {
    let count = surface.positions.len();
    let mut distance = vec![f32::INFINITY; count];
    let mut previous = vec![u32::MAX; count];
    let mut queue = BinaryHeap::new();
    distance[from as usize] = 0.0;
    queue.push(Reverse((Ordered(0.0), from)));
    while let Some(Reverse((Ordered(d), v))) = queue.pop() {
        if v == to {
            break;
        }
        if d > distance[v as usize] {
            continue;
        }
        for &n in surface.neighbours(v as usize) {
            let through = d + surface.positions[v as usize].distance(surface.positions[n as usize]);
            if through < distance[n as usize] {
                distance[n as usize] = through;
                previous[n as usize] = v;
                queue.push(Reverse((Ordered(through), n)));
            }
        }
    }
    if !distance[to as usize].is_finite() {
        return None;
    }
    let mut path = vec![to];
    while let Some(&last) = path.last().filter(|&&v| v != from) {
        path.push(previous[last as usize]);
    }
    path.reverse();
    Some(path)
}

/// A distance ordered totally, for the queue.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ordered(f32);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::sample;
    use super::*;

    /// A flat 17 x 17 patch and the vertex at column `i`, row `j`.
    fn flat() -> (Surface, impl Fn(u32, u32) -> u32) {
        (sample::patch(17, 0.0), |i, j| j * 17 + i)
    }

    #[test]
    fn four_corners_outline_the_square_between_them_in_any_order() {
        let (patch, at) = flat();
        let corners = [at(4, 4), at(12, 4), at(12, 12), at(4, 12)];
        let expected: Vec<u32> = (5..12).flat_map(|j| (5..12).map(move |i| j * 17 + i)).collect();
        for start in 0..4 {
            for reversed in [false, true] {
                let mut order: Vec<u32> = (0..4).map(|k| corners[(start + k) % 4]).collect();
                if reversed {
                    order.reverse();
                }
                let marks: Vec<Mark> = order.iter().map(|&v| Mark::Vertex(v)).collect();
                let region = select(&patch, &marks, 1e-3).unwrap();
                let mut inside: Vec<u32> =
                    region.source.iter().zip(&region.surface.movable).filter(|(_, m)| **m).map(|(&v, _)| v).collect();
                inside.sort();
                assert_eq!(inside, expected, "start {start}, reversed {reversed}");
                assert_eq!(region.outline.len(), 32, "the square's border");
                assert_eq!(region.surface.triangles.len(), 2 * 8 * 8);
            }
        }
    }

    #[test]
    fn points_on_the_surface_mark_its_nearest_vertices_and_points_off_it_are_refused() {
        let (patch, at) = flat();
        let place = |v: u32| patch.positions[v as usize] + Vec3::new(0.002, 0.0, 0.001);
        let marks = [at(4, 4), at(12, 4), at(12, 12), at(4, 12)].map(|v| Mark::Point(place(v)));
        let region = select(&patch, &marks, 1e-3).unwrap();
        assert_eq!(region.surface.movable.iter().filter(|&&m| m).count(), 49);
        let off = [Mark::Vertex(0), Mark::Vertex(5), Mark::Point(Vec3::new(0.0, 0.05, 0.0))];
        assert!(matches!(select(&patch, &off, 1e-3), Err(RegionError::OffSurface { mark: 2, .. })));
        assert_eq!(select(&patch, &off[..2], 1e-3), Err(RegionError::TooFewMarks(2)));
        let missing = [Mark::Vertex(0), Mark::Vertex(5), Mark::Vertex(999)];
        assert_eq!(select(&patch, &missing, 1e-3), Err(RegionError::NoVertex { mark: 2, vertex: 999, count: 289 }));
    }

    #[test]
    fn an_outline_around_nothing_is_an_empty_region() {
        let (patch, at) = flat();
        // Three neighbours in a row: the loop runs there and back and separates nothing.
        let marks = [at(4, 4), at(5, 4), at(6, 4)].map(Mark::Vertex);
        assert_eq!(select(&patch, &marks, 1e-3), Err(RegionError::Empty));
    }

    #[test]
    fn a_deformed_region_goes_back_into_the_whole_surface() {
        let (patch, at) = flat();
        let marks = [at(4, 4), at(12, 4), at(12, 12), at(4, 12)].map(Mark::Vertex);
        let region = select(&patch, &marks, 1e-3).unwrap();
        let lifted: Vec<Vec3> = region.surface.positions.iter().map(|p| *p + Vec3::Y).collect();
        let whole = region.put_back(&patch.positions, &lifted);
        assert_eq!(whole[at(8, 8) as usize].y, 1.0);
        assert_eq!(whole[at(0, 0) as usize], patch.positions[at(0, 0) as usize]);
    }

    #[test]
    fn a_region_outlined_on_the_belly_shrinks_with_its_outline_held() {
        use super::super::deform::{Method, Settings, Variant, deform};
        use crate::spatial::surface::Facts;
        let belly = sample::belly(25);
        let at = |i: u32, j: u32| Mark::Vertex(j * 25 + i);
        let region = select(&belly, &[at(6, 6), at(18, 6), at(18, 18), at(6, 18)], 1e-3).unwrap();
        let settings = Settings { k: 0.95, eps: 1e-5, max_iterations: 2000 };
        let done = deform(&region.surface, Method::Area(Variant::Projection), settings);
        let facts = Facts::of(&region.surface, &done.positions, 0.95);
        assert!(facts.fixed_unchanged && facts.inverted == 0 && (facts.area_ratio - 0.95).abs() < 1e-4, "{facts:?}");
        let whole = region.put_back(&belly.positions, &done.positions);
        let moved: Vec<usize> = (0..whole.len()).filter(|&v| whole[v] != belly.positions[v]).collect();
        assert!(!moved.is_empty() && moved.iter().all(|&v| region.source.contains(&(v as u32))));
        assert!(region.outline.iter().all(|&v| whole[v as usize] == belly.positions[v as usize]), "the outline held");
    }

    #[test]
    fn points_around_a_sphere_outline_the_cap_around_its_pole_in_any_order() {
        let sphere = sample::sphere(1.0, 23, 48);
        // Four vertices of the ring 40 degrees from the north pole, a quarter of the way round
        // from each other.
        let ring = 5;
        let at = |s: u32| 1 + (ring - 1) * 48 + s;
        let polar = |v: u32| sphere.positions[v as usize].y.clamp(-1.0, 1.0).acos().to_degrees();
        let ring_deg = polar(at(0));
        let marks = [at(0), at(12), at(24), at(36)];
        let mut regions = Vec::new();
        for start in 0..4 {
            for reversed in [false, true] {
                let mut order: Vec<Mark> = (0..4).map(|k| Mark::Vertex(marks[(start + k) % 4])).collect();
                if reversed {
                    order.reverse();
                }
                let region = select(&sphere, &order, 1e-3).unwrap();
                let mut inside: Vec<u32> =
                    region.source.iter().zip(&region.surface.movable).filter(|(_, m)| **m).map(|(&v, _)| v).collect();
                inside.sort();
                regions.push(inside);
            }
        }
        assert!(regions.windows(2).all(|w| w[0] == w[1]), "the same region whatever the order");
        let inside = &regions[0];
        assert!(inside.contains(&0), "the north pole is inside");
        assert!(inside.iter().all(|&v| polar(v) < ring_deg), "nothing beyond the marks' ring");
        // The loop bends towards the pole between the marks, but the first ring is whole.
        assert!((0..48).map(|s| 1 + s).all(|v| inside.contains(&v)));
    }

    #[test]
    fn four_marks_on_the_torso_outline_its_belly_in_any_order() {
        let (rings, segments) = (64u32, 128u32);
        let torso = sample::torso(rings, segments);
        let whole =
            Surface::new(torso.positions.clone(), torso.triangles.clone(), vec![true; torso.positions.len()]).unwrap();
        let at = |r: u32, s: u32| r * segments + s;
        let corners = [at(8, 16), at(8, 48), at(28, 48), at(28, 16)];
        let inside = |region: &Region| -> HashSet<u32> {
            region.source.iter().zip(&region.surface.movable).filter(|(_, m)| **m).map(|(&v, _)| v).collect()
        };
        let marks = |order: [usize; 4]| order.map(|i| Mark::Vertex(corners[i]));
        let region = select(&whole, &marks([0, 1, 2, 3]), 1e-3).unwrap();
        let found = inside(&region);
        // The loop follows the rings and columns between the corners, a ring or column astray
        // at most where the belly bulges; everything well inside it is in the region.
        for &v in &found {
            let (r, s) = (v / segments, v % segments);
            assert!((7..=29).contains(&r) && (15..=49).contains(&s), "vertex {v} at ring {r}, segment {s}");
        }
        for r in 10..=26 {
            for s in 18..=46 {
                assert!(found.contains(&at(r, s)), "ring {r}, segment {s} is inside");
            }
        }
        for order in [[3, 2, 1, 0], [2, 3, 0, 1], [1, 0, 3, 2]] {
            assert_eq!(inside(&select(&whole, &marks(order), 1e-3).unwrap()), found, "{order:?}");
        }
    }
}
