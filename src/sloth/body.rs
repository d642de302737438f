//! The body: where it hangs from its grips, which way it faces, and how far it keeps from
//! every support.
//!
//! The body's centre is the mean of the four grips moved `hang` metres away from them; its
//! heading is the mean of the two hind-to-fore directions (right hind to right fore, left hind
//! to left fore), eased over [`HEADING_EASE`] seconds so it follows bends without snapping. If
//! that would put any part of the body (torso, neck, head, each a chain of spheres) closer than
//! [`BODY_MARGIN`] to a support, the body is pushed out along the offending surface's normal.

use super::rig::{BodyFrame, Proportions};
use super::supports::Supports;
use crate::spatial::segment::TaperedSegment;
use bevy::math::Vec3;

/// Time constant of the heading's easing, seconds.
pub const HEADING_EASE: f32 = 0.3;

/// The smallest distance, metres, the body keeps from any support surface.
pub const BODY_MARGIN: f32 = 0.01;

/// Spacing of the spheres that stand for the body in clearance checks, as a fraction of their
/// radius: between two spheres the body's surface bulges out of them by at most 3% of the
/// radius.
const SAMPLE_SPACING: f32 = 0.5;

/// Most sphere gaps along one part of the body. The thin neck reaches it: its gaps are wider
/// than [`SAMPLE_SPACING`], and its surface bulges out of its spheres by up to 4.3 mm at the
/// default proportions, less than [`BODY_MARGIN`].
const MAX_SPHERES: f32 = 6.0;

/// How far around the body clearance queries look, metres: farther supports do not matter,
/// and a clearance this large or larger is reported as this.
pub const QUERY_RANGE: f32 = 0.1;

/// The body's parts as capsules: rear torso, front torso, neck, head (a capsule of no length):
/// each axis start, end and radius.
fn parts(frame: &BodyFrame, proportions: &Proportions) -> [(Vec3, Vec3, f32); PARTS] {
    let (hips, shoulders, head) = (frame.hips(proportions), frame.shoulders(proportions), frame.head(proportions));
    [
        (hips, frame.centre, proportions.torso_radius),
        (frame.centre, shoulders, proportions.torso_radius),
        (shoulders, head, proportions.head_radius * 0.6),
        (head, head, proportions.head_radius),
    ]
}

/// Parts of [`parts`].
const PARTS: usize = 4;

/// The spheres the body is made of, each with the index of its part.
pub fn body_spheres(frame: &BodyFrame, proportions: &Proportions) -> impl Iterator<Item = (Vec3, f32, usize)> {
    parts(frame, proportions).into_iter().enumerate().flat_map(|(part, (a, b, radius))| {
        let count = (a.distance(b) / (radius * SAMPLE_SPACING)).ceil().clamp(1.0, MAX_SPHERES) as usize;
        (0..=count).map(move |i| (a.lerp(b, i as f32 / count as f32), radius, part))
    })
}

/// The support segments near each part of the body, gathered with some slack so that most
/// steps reuse them: they are gathered again once the hips or the head have moved half the
/// slack.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NearSupports {
    /// Where the hips and the head were when the segments were gathered.
    gathered_at: Option<(Vec3, Vec3)>,
    /// The segments near each part.
    parts: [Vec<TaperedSegment>; PARTS],
}

/// How much farther than [`QUERY_RANGE`] the gathered segments reach, metres.
const GATHER_SLACK: f32 = 0.05;

impl NearSupports {
    /// The segments within [`QUERY_RANGE`] of the body at `frame`, all of them.
    pub fn around(frame: &BodyFrame, proportions: &Proportions, supports: &Supports) -> Self {
        let mut near = Self::default();
        near.refresh(frame, proportions, supports);
        near
    }

    /// Gathers the segments again if the body has moved too far since the last time, each
    /// part's with a query ball round that part.
    pub fn refresh(&mut self, frame: &BodyFrame, proportions: &Proportions, supports: &Supports) {
        let (hips, head) = (frame.hips(proportions), frame.head(proportions));
        let fresh = self
            .gathered_at
            .is_some_and(|(h, d)| h.distance(hips) < GATHER_SLACK * 0.5 && d.distance(head) < GATHER_SLACK * 0.5);
        if fresh {
            return;
        }
        let mut found = Vec::new();
        for (part, (a, b, radius)) in parts(frame, proportions).into_iter().enumerate() {
            supports.segments_near(
                (a + b) * 0.5,
                a.distance(b) * 0.5 + radius + QUERY_RANGE + GATHER_SLACK,
                &mut found,
            );
            self.parts[part].clear();
            self.parts[part].extend(found.iter().map(|&i| supports.segment(i)));
        }
        self.gathered_at = Some((hips, head));
    }
}

/// The nearest surface among `segments` to a sphere: its signed distance from the sphere's
/// surface and the outward normal there.
fn nearest(segments: &[TaperedSegment], centre: Vec3, radius: f32) -> Option<(f32, Vec3)> {
    let mut best: Option<(f32, Vec3)> = None;
    for segment in segments {
        // A segment whose bounding sphere lies beyond the best so far, or beyond the range
        // that matters, cannot be nearer.
        let (middle, bound) = segment.bounding_sphere();
        let least = centre.distance(middle) - bound;
        if least - radius > QUERY_RANGE || best.is_some_and(|(distance, _)| least > distance) {
            continue;
        }
        let surface = segment.closest(centre);
        if best.is_none_or(|(distance, _)| surface.distance < distance) {
            best = Some((surface.distance, surface.normal));
        }
    }
    best.map(|(distance, normal)| (distance - radius, normal))
}

/// Moves the body out of any support it comes within [`BODY_MARGIN`] of, a few pushes along
/// the deepest offender's normal, and returns its clearance then: the smallest distance from
/// the body's surface to any support, metres (negative if still inside), or [`QUERY_RANGE`]
/// when nothing is nearer.
pub fn push_clear(frame: &mut BodyFrame, proportions: &Proportions, near: &NearSupports) -> f32 {
    let start = frame.centre;
    let mut pushes = 0;
    loop {
        match deepest(frame, proportions, near) {
            Some((distance, normal))
                if distance < BODY_MARGIN - 1e-5 && pushes < MAX_PUSHES && frame.centre.distance(start) < MAX_PUSH =>
            {
                frame.centre += normal * (BODY_MARGIN - distance + 1e-4);
                pushes += 1;
            }
            Some((distance, _)) => return distance.min(QUERY_RANGE),
            None => return QUERY_RANGE,
        }
    }
}

/// The clearance of the body at `frame` without moving it: the smallest distance from its
/// surface to any support, metres (negative if inside), or [`QUERY_RANGE`] when nothing is
/// nearer.
pub fn clearance(frame: &BodyFrame, proportions: &Proportions, near: &NearSupports) -> f32 {
    deepest(frame, proportions, near).map_or(QUERY_RANGE, |(distance, _)| distance.min(QUERY_RANGE))
}

/// The body's sphere nearest to a support: its distance from the surface and the surface's
/// outward normal there.
fn deepest(frame: &BodyFrame, proportions: &Proportions, near: &NearSupports) -> Option<(f32, Vec3)> {
    body_spheres(frame, proportions)
        .filter_map(|(centre, radius, part)| nearest(&near.parts[part], centre, radius))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// Most pushes per pose: a body wedged between supports stops there.
const MAX_PUSHES: u32 = 4;

/// Farthest the body is pushed out of the supports in one pose, metres (within the gathered
/// range, the supports it could be pushed into are known).
const MAX_PUSH: f32 = 0.1;

/// The heading the grips ask for: the mean of the hind-to-fore directions on each side, or
/// `None` if they cancel.
pub fn heading_of(right_hind: Vec3, right_fore: Vec3, left_hind: Vec3, left_fore: Vec3) -> Option<Vec3> {
    ((right_fore - right_hind).normalize_or_zero() + (left_fore - left_hind).normalize_or_zero()).try_normalize()
}

/// `current` turned towards `target` over `dt` seconds with time constant `ease`.
pub fn ease_towards(current: Vec3, target: Vec3, dt: f32, ease: f32) -> Vec3 {
    let blend = 1.0 - (-dt / ease).exp();
    current.lerp(target, blend).try_normalize().unwrap_or(target)
}

/// The unit vector nearest to `preferred` that is perpendicular to `forward`.
pub fn perpendicular_towards(preferred: Vec3, forward: Vec3) -> Vec3 {
    (preferred - forward * preferred.dot(forward)).try_normalize().unwrap_or_else(|| forward.any_orthonormal_vector())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::{Shape, SupportSpec, Tree};

    fn branch_at(height: f32) -> Tree {
        let shape = Shape::Polyline {
            points: vec![Vec3::new(-2.0, height, 0.0), Vec3::new(2.0, height, 0.0)],
            radii: vec![0.04, 0.04],
        };
        Tree::build(&[SupportSpec { name: "b".into(), shape, kind: None }]).unwrap()
    }

    #[test]
    fn a_body_pressed_into_a_branch_is_pushed_out_to_the_margin() {
        let tree = branch_at(0.05);
        let supports = Supports::new([("t", &tree)]);
        let proportions = Proportions::default();
        let mut frame = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y };
        let before = frame;
        let after = push_clear(&mut frame, &proportions, &NearSupports::around(&before, &proportions, &supports));
        assert!((0.0..0.02).contains(&after), "clearance {after}");
        assert!(frame.centre != before.centre);
        assert!(frame.centre.y < 0.0);
    }

    #[test]
    fn a_clear_body_stays_where_it_is() {
        let tree = branch_at(0.2);
        let supports = Supports::new([("t", &tree)]);
        let mut frame = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y };
        let near = NearSupports::around(&frame, &Proportions::default(), &supports);
        let clearance = push_clear(&mut frame, &Proportions::default(), &near);
        assert_eq!(frame.centre, Vec3::ZERO);
        // The head, a little towards the grips, comes nearest: 0.2 - 0.04 - (0.3 * 0.085 + 0.06).
        assert!((clearance - 0.0745).abs() < 0.002, "{clearance}");
        let far = Supports::new([("t", &branch_at(0.5))]);
        let near = NearSupports::around(&frame, &Proportions::default(), &far);
        assert_eq!(push_clear(&mut frame, &Proportions::default(), &near), QUERY_RANGE);
    }

    #[test]
    fn heading_is_the_mean_of_the_two_sides_and_eases_without_snapping() {
        let heading = heading_of(Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::Z + Vec3::Y).unwrap();
        assert!(heading.distance(Vec3::new(1.0, 1.0, 0.0).normalize()) < 1e-6);
        let eased = ease_towards(Vec3::X, Vec3::Z, 1.0 / 60.0, HEADING_EASE);
        assert!(eased.angle_between(Vec3::X) < 0.1 && eased.angle_between(Vec3::X) > 0.01);
    }
}
