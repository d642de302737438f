//! A bounding volume hierarchy over primitives that a ray can hit (the tapered segments of a
//! forest, the triangles of a soft body), so that ray casts, and for segments closest-point and
//! radius queries, visit a few boxes and primitives instead of all of them.
//!
//! Built top-down by splitting each node's primitives at the median of their box centres along
//! the widest axis, down to leaves of at most [`LEAF_SIZE`] primitives. Queries walk the tree
//! nearest box first and prune boxes that cannot beat the best answer so far. Every query gives
//! exactly the answer of a scan over all primitives (see the property tests).

use super::segment::{SegmentHit, SurfacePoint, TaperedSegment};
use bevy::math::Vec3;

/// Most primitives in a leaf.
pub const LEAF_SIZE: usize = 4;

/// Something a [`Bvh`] holds: it has a bounding box and can be hit by a ray.
pub trait Primitive {
    /// What a ray's hit tells.
    type Hit: Copy;
    /// The axis-aligned box holding the primitive, metres: (min, max).
    fn bounds(&self) -> (Vec3, Vec3);
    /// The first hit of the ray from `origin` along the unit `direction` within
    /// `max_distance` metres.
    fn ray_hit(&self, origin: Vec3, direction: Vec3, max_distance: f32) -> Option<Self::Hit>;
    /// How far along the ray a hit lies, metres.
    fn hit_distance(hit: &Self::Hit) -> f32;
}

impl Primitive for TaperedSegment {
    type Hit = SegmentHit;

    fn bounds(&self) -> (Vec3, Vec3) {
        TaperedSegment::bounds(self)
    }

    fn ray_hit(&self, origin: Vec3, direction: Vec3, max_distance: f32) -> Option<SegmentHit> {
        TaperedSegment::ray_hit(self, origin, direction, max_distance)
    }

    fn hit_distance(hit: &SegmentHit) -> f32 {
        hit.distance
    }
}

/// A node: its box, and either two children (`count == 0`: at `first` and `first + 1`) or a
/// leaf's segments (`order[first..first + count]`).
#[derive(Debug, Clone, Copy)]
struct Node {
    min: Vec3,
    max: Vec3,
    first: u32,
    count: u32,
}

/// Primitives and the hierarchy over them.
#[derive(Debug, Clone)]
pub struct Bvh<P> {
    primitives: Vec<P>,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl<P> Default for Bvh<P> {
    fn default() -> Self {
        Self { primitives: Vec::new(), nodes: Vec::new(), order: Vec::new() }
    }
}

/// The segments of a scene and the hierarchy over them.
pub type SegmentBvh = Bvh<TaperedSegment>;

/// A ray's first hit among all primitives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit<H> {
    /// Index of the primitive hit.
    pub index: usize,
    /// Where and how it was hit.
    pub hit: H,
}

/// The nearest segment surface to a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    /// Index of the nearest segment.
    pub segment: usize,
    /// Its nearest surface point.
    pub surface: SurfacePoint,
}

impl<P: Primitive> Bvh<P> {
    /// Builds the hierarchy over `primitives` (their indices are kept in query answers).
    pub fn new(primitives: Vec<P>) -> Self {
        let mut bvh = Self { order: (0..primitives.len() as u32).collect(), primitives, nodes: Vec::new() };
        if !bvh.primitives.is_empty() {
            let boxes: Vec<(Vec3, Vec3)> = bvh.primitives.iter().map(P::bounds).collect();
            bvh.nodes.push(Node { min: Vec3::ZERO, max: Vec3::ZERO, first: 0, count: 0 });
            bvh.split(0, 0, bvh.primitives.len(), &boxes);
        }
        bvh
    }

    /// The primitive indices of a leaf node.
    fn leaf(&self, node: &Node) -> &[u32] {
        &self.order[node.first as usize..(node.first + node.count) as usize]
    }

    /// The primitives, in their original order.
    pub fn primitives(&self) -> &[P] {
        &self.primitives
    }

    /// Fills node `index` with the primitives `order[start..end]`, splitting when there are many.
    fn split(&mut self, index: usize, start: usize, end: usize, boxes: &[(Vec3, Vec3)]) {
        let members = &mut self.order[start..end];
        let (min, max) = members
            .iter()
            .map(|&i| boxes[i as usize])
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(min, max), (a, b)| {
                (min.min(a), max.max(b))
            });
        if members.len() <= LEAF_SIZE {
            self.nodes[index] = Node { min, max, first: start as u32, count: members.len() as u32 };
            return;
        }
        let centre = |i: u32| (boxes[i as usize].0 + boxes[i as usize].1) * 0.5;
        let (low, high) =
            members.iter().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(low, high), &i| {
                (low.min(centre(i)), high.max(centre(i)))
            });
        let extent = high - low;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let middle = members.len() / 2;
        members.select_nth_unstable_by(middle, |&a, &b| centre(a)[axis].total_cmp(&centre(b)[axis]));
        let children = self.nodes.len();
        self.nodes[index] = Node { min, max, first: children as u32, count: 0 };
        let empty = Node { min: Vec3::ZERO, max: Vec3::ZERO, first: 0, count: 0 };
        self.nodes.extend([empty, empty]);
        self.split(children, start, start + middle, boxes);
        self.split(children + 1, start + middle, end, boxes);
    }

    /// The first primitive the ray from `origin` along the unit `direction` meets within
    /// `max_distance`.
    pub fn ray_cast(&self, origin: Vec3, direction: Vec3, max_distance: f32) -> Option<RayHit<P::Hit>> {
        let inverse = direction.recip();
        let mut best: Option<RayHit<P::Hit>> = None;
        let mut limit = max_distance;
        let mut stack = Stack::default();
        if let Some(root) = self.nodes.first()
            && slab(root, origin, inverse, limit).is_some()
        {
            stack.push(0u32);
        }
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            if node.count > 0 {
                for &index in self.leaf(&node) {
                    if let Some(hit) = self.primitives[index as usize].ray_hit(origin, direction, limit)
                        && P::hit_distance(&hit) <= limit
                    {
                        limit = P::hit_distance(&hit);
                        best = Some(RayHit { index: index as usize, hit });
                    }
                }
                continue;
            }
            // Visit the nearer child first: push it last.
            let (left, right) = (node.first, node.first + 1);
            let entry = |child: u32| slab(&self.nodes[child as usize], origin, inverse, limit);
            match (entry(left), entry(right)) {
                (Some(l), Some(r)) if l <= r => stack.extend([right, left]),
                (Some(_), Some(_)) => stack.extend([left, right]),
                (Some(_), None) => stack.push(left),
                (None, Some(_)) => stack.push(right),
                (None, None) => {}
            }
        }
        best
    }
}

impl SegmentBvh {
    /// The segment whose surface is nearest to `p` (signed: a point inside a segment is nearest
    /// to the one it is deepest in), if any lies within `max_distance`.
    pub fn nearest(&self, p: Vec3, max_distance: f32) -> Option<Nearest> {
        let mut best: Option<Nearest> = None;
        let mut limit = max_distance;
        let mut stack = Stack::default();
        if !self.nodes.is_empty() {
            stack.push(0u32);
        }
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            // A surface distance is negative inside a segment, but a box's is never below 0,
            // so a box holding `p` stays open however deep inside the best segment `p` lies.
            if box_distance(&node, p) > limit.max(0.0) {
                continue;
            }
            if node.count > 0 {
                for &segment in self.leaf(&node) {
                    let surface = self.primitives[segment as usize].closest(p);
                    if surface.distance <= limit && best.is_none_or(|b| surface.distance < b.surface.distance) {
                        limit = surface.distance;
                        best = Some(Nearest { segment: segment as usize, surface });
                    }
                }
                continue;
            }
            let (left, right) = (node.first, node.first + 1);
            let near_left = box_distance(&self.nodes[left as usize], p) <= box_distance(&self.nodes[right as usize], p);
            stack.extend(if near_left { [right, left] } else { [left, right] });
        }
        best
    }

    /// Appends to `found` (cleared first) the indices of the segments whose surface comes
    /// within `radius` of `p`, in increasing index order.
    pub fn within(&self, p: Vec3, radius: f32, found: &mut Vec<usize>) {
        found.clear();
        let mut stack = Stack::default();
        if !self.nodes.is_empty() {
            stack.push(0u32);
        }
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            if box_distance(&node, p) > radius {
                continue;
            }
            if node.count > 0 {
                found.extend(
                    self.leaf(&node)
                        .iter()
                        .map(|&i| i as usize)
                        .filter(|&i| self.primitives[i].closest(p).distance <= radius),
                );
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
        found.sort_unstable();
    }
}

/// The nodes still to visit. Median splits keep the tree's depth at about
/// `log2(segments / LEAF_SIZE)`, and a walk holds at most one pending node per level.
struct Stack {
    nodes: [u32; 64],
    len: usize,
}

impl Default for Stack {
    fn default() -> Self {
        Self { nodes: [0; 64], len: 0 }
    }
}

impl Stack {
    fn push(&mut self, node: u32) {
        self.nodes[self.len] = node;
        self.len += 1;
    }

    fn extend(&mut self, nodes: [u32; 2]) {
        nodes.into_iter().for_each(|node| self.push(node));
    }

    fn pop(&mut self) -> Option<u32> {
        self.len = self.len.checked_sub(1)?;
        Some(self.nodes[self.len])
    }
}

/// Where the ray enters a node's box, if it does before `limit`.
fn slab(node: &Node, origin: Vec3, inverse: Vec3, limit: f32) -> Option<f32> {
    let t1 = (node.min - origin) * inverse;
    let t2 = (node.max - origin) * inverse;
    // NaN (a zero direction component with the origin on a slab plane) counts as inside.
    let near = t1.min(t2).max_element().max(0.0);
    let far = t1.max(t2).min_element().min(limit);
    (near <= far || near.is_nan() || far.is_nan()).then_some(near)
}

/// Distance from `p` to a node's box (0 inside).
fn box_distance(node: &Node, p: Vec3) -> f32 {
    (node.min - p).max(p - node.max).max(Vec3::ZERO).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn vec3(extent: f32) -> impl Strategy<Value = Vec3> {
        (-extent..extent, -extent..extent, -extent..extent).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// A random forest: short tapered segments scattered in a 10 m box.
    fn forest() -> impl Strategy<Value = Vec<TaperedSegment>> {
        proptest::collection::vec(
            (vec3(5.0), vec3(1.0), 0.02f32..0.3, 0.02f32..0.3)
                .prop_map(|(a, offset, radius_a, radius_b)| TaperedSegment { a, b: a + offset, radius_a, radius_b }),
            0..120,
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn ray_casts_match_a_scan_of_every_segment(segments in forest(), origin in vec3(8.0), target in vec3(5.0)) {
            let Some(direction) = (target - origin).try_normalize() else { return Ok(()) };
            let bvh = SegmentBvh::new(segments.clone());
            let scan = segments
                .iter()
                .filter_map(|s| s.ray_hit(origin, direction, 50.0))
                .map(|hit| hit.distance)
                .fold(f32::INFINITY, f32::min);
            match bvh.ray_cast(origin, direction, 50.0) {
                Some(found) => prop_assert!((found.hit.distance - scan).abs() < 1e-4, "{} vs {scan}", found.hit.distance),
                None => prop_assert!(scan.is_infinite(), "the scan hit at {scan}"),
            }
        }

        #[test]
        fn nearest_matches_a_scan_of_every_segment(segments in forest(), p in vec3(7.0), limit in 0.1f32..20.0) {
            let bvh = SegmentBvh::new(segments.clone());
            let scan = segments.iter().map(|s| s.closest(p).distance).fold(f32::INFINITY, f32::min);
            match bvh.nearest(p, limit) {
                Some(found) => {
                    prop_assert_eq!(found.surface.distance, scan);
                    prop_assert_eq!(segments[found.segment].closest(p).distance, scan);
                }
                None => prop_assert!(scan > limit, "the scan found {scan} within {limit}"),
            }
        }

        #[test]
        fn within_matches_a_scan_of_every_segment(segments in forest(), p in vec3(7.0), radius in 0.0f32..3.0) {
            let bvh = SegmentBvh::new(segments.clone());
            let scan: Vec<usize> = (0..segments.len()).filter(|&i| segments[i].closest(p).distance <= radius).collect();
            let mut found = Vec::new();
            bvh.within(p, radius, &mut found);
            prop_assert_eq!(found, scan);
        }
    }

    #[test]
    fn leaves_hold_every_segment_once() {
        let segments: Vec<TaperedSegment> = (0..1000)
            .map(|i| {
                let a = Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
                TaperedSegment { a, b: a + Vec3::Y * 0.5, radius_a: 0.1, radius_b: 0.05 }
            })
            .collect();
        let bvh = SegmentBvh::new(segments);
        let mut seen = vec![0; 1000];
        for node in bvh.nodes.iter().filter(|n| n.count > 0) {
            assert!(node.count as usize <= LEAF_SIZE);
            for &i in bvh.leaf(node) {
                seen[i as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
        assert!(SegmentBvh::new(Vec::new()).ray_cast(Vec3::ZERO, Vec3::X, 10.0).is_none());
    }
}
