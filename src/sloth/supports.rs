//! Every support of every tree in one place, as the sloth sees them: paths measured by arc
//! length (metres from the support's first point) and one hierarchy for the nearest-surface
//! queries of foothold search and body clearance.

use crate::spatial::bvh::SegmentBvh;
use crate::spatial::segment::{SurfacePoint, TaperedSegment};
use crate::tree::{SupportKind, Tree};
use bevy::math::Vec3;

/// A support as a path: axis polyline, radii, and arc length at each point.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportPath {
    /// `tree/support`, as in dumps and scene files.
    pub label: String,
    /// Trunk or branch.
    pub kind: SupportKind,
    /// The support it forks from, if any (its start then lies inside that parent): index into
    /// [`Supports::paths`].
    pub parent: Option<usize>,

    points: Vec<Vec3>,
    radii: Vec<f32>,
    /// Arc length at each point, metres; the first is 0.
    arc: Vec<f32>,
}

/// How far outside a support its line traces start, metres.
const TRACE_START: f32 = 0.2;

/// A point on a support's axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisPoint {
    /// The axis point, metres.
    pub point: Vec3,
    /// Unit direction of increasing arc length.
    pub tangent: Vec3,
    /// Radius there, metres.
    pub radius: f32,
}

impl SupportPath {
    fn new(label: String, kind: SupportKind, parent: Option<usize>, points: Vec<Vec3>, radii: Vec<f32>) -> Self {
        let mut arc = Vec::with_capacity(points.len());
        let mut total = 0.0;
        for (i, point) in points.iter().enumerate() {
            if i > 0 {
                total += point.distance(points[i - 1]);
            }
            arc.push(total);
        }
        Self { label, kind, parent, points, radii, arc }
    }

    /// The arc lengths a grip may take: away from free tips by `margin`, but right up to the
    /// start of a fork, where the support grows out of its parent.
    pub fn grip_range(&self, margin: f32) -> (f32, f32) {
        (if self.parent.is_some() { 0.0 } else { margin }, self.length() - margin)
    }

    /// Whether the axis is one straight segment.
    pub fn is_straight(&self) -> bool {
        self.points.len() == 2
    }

    /// Axis length, metres.
    pub fn length(&self) -> f32 {
        self.arc.last().copied().unwrap_or(0.0)
    }

    fn segment(&self, i: usize) -> TaperedSegment {
        TaperedSegment {
            a: self.points[i],
            b: self.points[i + 1],
            radius_a: self.radii[i],
            radius_b: self.radii[i + 1],
        }
    }

    fn segments(&self) -> impl Iterator<Item = TaperedSegment> + '_ {
        (0..self.points.len() - 1).map(|i| self.segment(i))
    }

    /// The axis point `s` metres along (clamped to the support).
    pub fn at(&self, s: f32) -> AxisPoint {
        let s = s.clamp(0.0, self.length());
        let i = self.arc.partition_point(|&a| a <= s).clamp(1, self.points.len() - 1) - 1;
        let span = self.arc[i + 1] - self.arc[i];
        let t = if span > 0.0 { (s - self.arc[i]) / span } else { 0.0 };
        AxisPoint {
            point: self.points[i].lerp(self.points[i + 1], t),
            tangent: (self.points[i + 1] - self.points[i]).normalize_or_zero(),
            radius: self.radii[i] + (self.radii[i + 1] - self.radii[i]) * t,
        }
    }

    /// The surface point `s` metres along, on the side `towards` points to (its part across
    /// the axis; straight below the axis if `towards` runs along it). Found like a line trace
    /// from that side towards the axis, so near a bend it lands on the outside of the whole
    /// support, not inside the next segment.
    pub fn surface_towards(&self, s: f32, towards: Vec3) -> Vec3 {
        let axis = self.at(s);
        let across = towards - axis.tangent * towards.dot(axis.tangent);
        let fallback = Vec3::NEG_Y - axis.tangent * -axis.tangent.y;
        let normal =
            across.try_normalize().or(fallback.try_normalize()).unwrap_or(axis.tangent.any_orthonormal_vector());
        let reach = axis.radius + TRACE_START;
        let origin = axis.point + normal * reach;
        // The segment at `s` and its neighbours are the only ones a short trace can meet first.
        let at = self.arc.partition_point(|&a| a <= s).clamp(1, self.points.len() - 1) - 1;
        let nearby = at.saturating_sub(1)..(at + 2).min(self.points.len() - 1);
        let hit =
            nearby.filter_map(|i| self.segment(i).ray_hit(origin, -normal, reach)).map(|h| h.distance).reduce(f32::min);
        hit.map_or(axis.point + normal * axis.radius, |distance| origin - normal * distance)
    }

    /// The nearest surface point to `p` and its arc length along the support.
    pub fn nearest(&self, p: Vec3) -> (SurfacePoint, f32) {
        let mut best: Option<(SurfacePoint, f32)> = None;
        for (i, segment) in self.segments().enumerate() {
            let surface = segment.closest(p);
            if best.is_none_or(|(b, _)| surface.distance < b.distance) {
                best = Some((surface, self.arc[i] + surface.along * (self.arc[i + 1] - self.arc[i])));
            }
        }
        best.expect("a support has at least one segment")
    }

    /// Signed distance from `p` to the support's surface, metres (negative inside).
    pub fn distance(&self, p: Vec3) -> f32 {
        self.nearest(p).0.distance
    }
}

/// The supports of a scene that the sloth may grip.
#[derive(Debug, Clone, Default)]
pub struct Supports {
    /// Every support offered to grip, tree by tree.
    pub paths: Vec<SupportPath>,
    /// The labels of the supports drawn but never gripped (thinner than their tree's
    /// `grip_min_radius_m`), for messages.
    pub ungripped: Vec<String>,
    bvh: SegmentBvh,
    /// The path each segment of `bvh` belongs to, and the arc length at its start.
    owners: Vec<(usize, f32, f32)>,
}

/// The nearest support surface to a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupportHit {
    /// Index into [`Supports::paths`].
    pub support: usize,
    /// Arc length of the nearest point along that support, metres.
    pub s: f32,
    /// The surface point, normal and signed distance.
    pub surface: SurfacePoint,
}

impl Supports {
    /// Collects the supports of named trees that may be gripped.
    pub fn new<'a>(trees: impl IntoIterator<Item = (&'a str, &'a Tree)>) -> Self {
        let mut paths: Vec<SupportPath> = Vec::new();
        let mut ungripped = Vec::new();
        for (name, tree) in trees {
            // Each support's index among the paths, if it is one.
            let mut next = paths.len();
            let index_of: Vec<Option<usize>> = (0..tree.supports.len())
                .map(|index| {
                    tree.gripped(index).then(|| {
                        next += 1;
                        next - 1
                    })
                })
                .collect();
            for (index, support) in tree.supports.iter().enumerate() {
                let label = format!("{name}/{}", support.name);
                if index_of[index].is_none() {
                    ungripped.push(label);
                    continue;
                }
                let parent = support.parent.and_then(|p| index_of[p]);
                paths.push(SupportPath::new(
                    label,
                    support.kind,
                    parent,
                    support.points.clone(),
                    support.radii.clone(),
                ));
            }
        }
        let mut segments = Vec::new();
        let mut owners = Vec::new();
        for (index, path) in paths.iter().enumerate() {
            for (i, segment) in path.segments().enumerate() {
                segments.push(segment);
                owners.push((index, path.arc[i], path.arc[i + 1] - path.arc[i]));
            }
        }
        Self { paths, ungripped, bvh: SegmentBvh::new(segments), owners }
    }

    /// The support labelled `label` (`tree/support`).
    pub fn find(&self, label: &str) -> Option<usize> {
        self.paths.iter().position(|p| p.label == label)
    }

    /// The nearest support surface to `p` within `max_distance`.
    pub fn nearest(&self, p: Vec3, max_distance: f32) -> Option<SupportHit> {
        self.bvh.nearest(p, max_distance).map(|n| {
            let (support, start, span) = self.owners[n.segment];
            SupportHit { support, s: start + n.surface.along * span, surface: n.surface }
        })
    }

    /// Signed distance from `p` to the nearest support surface, or `max_distance` when none
    /// comes that close.
    pub fn clearance(&self, p: Vec3, max_distance: f32) -> f32 {
        self.nearest(p, max_distance).map_or(max_distance, |hit| hit.surface.distance)
    }

    /// The segments (of every support) whose surface comes within `radius` of `p`, into
    /// `found` (cleared first), as indices for [`Supports::segment`].
    pub fn segments_near(&self, p: Vec3, radius: f32, found: &mut Vec<usize>) {
        self.bvh.within(p, radius, found);
    }

    /// Segment `index` of [`Supports::segments_near`].
    pub fn segment(&self, index: usize) -> TaperedSegment {
        self.bvh.primitives()[index]
    }

    /// The supports other than `except` whose surface comes within `radius` of `p`, in index
    /// order without repeats.
    pub fn others_near(&self, p: Vec3, radius: f32, except: usize) -> Vec<usize> {
        let mut segments = Vec::new();
        self.bvh.within(p, radius, &mut segments);
        let mut found: Vec<usize> = segments.iter().map(|&s| self.owners[s].0).filter(|&i| i != except).collect();
        found.sort_unstable();
        found.dedup();
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::{Shape, SupportSpec};

    fn bent() -> Tree {
        let shape = Shape::Polyline {
            points: vec![Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 1.0)],
            radii: vec![0.05, 0.04, 0.03],
        };
        Tree::build(&[SupportSpec { name: "b".into(), shape, kind: None }]).unwrap()
    }

    #[test]
    fn arc_length_walks_round_a_bend() {
        let tree = bent();
        let supports = Supports::new([("t", &tree)]);
        let path = &supports.paths[0];
        assert_eq!(path.label, "t/b");
        assert!((path.length() - 2.0).abs() < 1e-6);
        let a = path.at(1.5);
        assert!(a.point.distance(Vec3::new(1.0, 0.0, 0.5)) < 1e-6);
        assert!(a.tangent.distance(Vec3::Z) < 1e-6);
        assert!((a.radius - 0.035).abs() < 1e-6);
        let side = path.surface_towards(0.5, Vec3::new(0.3, 0.0, -1.0));
        assert!(side.distance(Vec3::new(0.5, 0.0, -0.045)) < 1e-3, "{side}");
        assert!(path.distance(side).abs() < 1e-5);
    }

    #[test]
    fn the_hierarchy_reports_the_support_and_arc_length_of_the_nearest_surface() {
        let tree = bent();
        let supports = Supports::new([("t", &tree)]);
        let hit = supports.nearest(Vec3::new(1.3, 0.0, 0.6), 1.0).unwrap();
        assert_eq!(hit.support, 0);
        assert!((hit.s - 1.6).abs() < 0.01, "{}", hit.s);
        let (surface, s) = supports.paths[0].nearest(Vec3::new(1.3, 0.0, 0.6));
        assert!((s - hit.s).abs() < 1e-5 && (surface.distance - hit.surface.distance).abs() < 1e-6);
        assert_eq!(supports.clearance(Vec3::new(5.0, 0.0, 0.0), 0.5), 0.5);
    }

    #[test]
    fn supports_thinner_than_the_grip_radius_are_left_out_and_parents_follow() {
        // A twig described first, a trunk, and a bough growing from the trunk.
        let line = |name: &str, x: f32, radius: f32| SupportSpec {
            name: name.into(),
            shape: Shape::Polyline {
                points: vec![Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)],
                radii: vec![radius; 2],
            },
            kind: None,
        };
        let bough = SupportSpec {
            name: "bough".into(),
            shape: Shape::Attached {
                parent: "trunk".into(),
                points: vec![Vec3::new(1.0, 0.5, 0.0), Vec3::new(2.0, 0.6, 0.0)],
                radii: vec![0.05, 0.04],
            },
            kind: None,
        };
        let mut tree = Tree::build(&[line("twig", 0.0, 0.004), line("trunk", 1.0, 0.2), bough]).unwrap();
        tree.grip_min_radius_m = 0.01;
        let supports = Supports::new([("t", &tree)]);
        let labels: Vec<&str> = supports.paths.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["t/trunk", "t/bough"]);
        assert_eq!(supports.paths[1].parent, Some(0), "the bough still grows from the trunk");
        assert_eq!(supports.ungripped, ["t/twig"]);
        assert!(supports.nearest(Vec3::new(0.0, 0.5, 0.0), 0.5).is_none(), "the twig is not met");
    }
}
