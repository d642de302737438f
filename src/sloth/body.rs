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
use bevy::math::Vec3;

/// Time constant of the heading's easing, seconds.
pub const HEADING_EASE: f32 = 0.3;

/// The smallest distance, metres, the body keeps from any support surface.
pub const BODY_MARGIN: f32 = 0.01;

/// Spacing of the spheres that stand for the body in clearance checks, metres.
const SAMPLE_SPACING: f32 = 0.02;

/// How far around the body clearance queries look, metres: farther supports do not matter.
const QUERY_RANGE: f32 = 1.0;

/// The spheres the body is made of: along the torso, along the neck, and the head.
pub fn body_spheres(frame: &BodyFrame, proportions: &Proportions) -> impl Iterator<Item = (Vec3, f32)> {
    let (hips, shoulders, head) = (frame.hips(proportions), frame.shoulders(proportions), frame.head(proportions));
    let torso = chain(hips, shoulders, proportions.torso_radius);
    let neck = chain(shoulders, head, proportions.head_radius * 0.6);
    torso.chain(neck).chain(std::iter::once((head, proportions.head_radius)))
}

fn chain(a: Vec3, b: Vec3, radius: f32) -> impl Iterator<Item = (Vec3, f32)> {
    let count = (a.distance(b) / SAMPLE_SPACING).ceil().max(1.0) as usize;
    (0..=count).map(move |i| (a.lerp(b, i as f32 / count as f32), radius))
}

/// The smallest distance from the body's surface to any support, metres (negative if inside);
/// [`QUERY_RANGE`] when nothing is near.
pub fn clearance(frame: &BodyFrame, proportions: &Proportions, supports: &Supports) -> f32 {
    body_spheres(frame, proportions)
        .map(|(centre, radius)| supports.clearance(centre, QUERY_RANGE) - radius)
        .fold(QUERY_RANGE, f32::min)
}

/// Moves the body out of any support it comes within [`BODY_MARGIN`] of, a few pushes along
/// the deepest offender's normal.
pub fn push_clear(frame: &mut BodyFrame, proportions: &Proportions, supports: &Supports) {
    for _ in 0..4 {
        let mut worst: Option<(f32, Vec3)> = None;
        for (centre, radius) in body_spheres(frame, proportions) {
            if let Some(hit) = supports.nearest(centre, radius + BODY_MARGIN) {
                let deficit = radius + BODY_MARGIN - hit.surface.distance;
                if worst.is_none_or(|(d, _)| deficit > d) {
                    worst = Some((deficit, hit.surface.normal));
                }
            }
        }
        match worst {
            Some((deficit, normal)) if deficit > 1e-5 => frame.centre += normal * (deficit + 1e-4),
            _ => return,
        }
    }
}

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
        assert!(clearance(&frame, &proportions, &supports) < 0.0);
        push_clear(&mut frame, &proportions, &supports);
        let after = clearance(&frame, &proportions, &supports);
        assert!((0.0..0.02).contains(&after), "clearance {after}");
        assert!(frame.centre.y < 0.0);
    }

    #[test]
    fn a_clear_body_stays_where_it_is() {
        let tree = branch_at(0.5);
        let supports = Supports::new([("t", &tree)]);
        let mut frame = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y };
        push_clear(&mut frame, &Proportions::default(), &supports);
        assert_eq!(frame.centre, Vec3::ZERO);
    }

    #[test]
    fn heading_is_the_mean_of_the_two_sides_and_eases_without_snapping() {
        let heading = heading_of(Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::Z + Vec3::Y).unwrap();
        assert!(heading.distance(Vec3::new(1.0, 1.0, 0.0).normalize()) < 1e-6);
        let eased = ease_towards(Vec3::X, Vec3::Z, 1.0 / 60.0, HEADING_EASE);
        assert!(eased.angle_between(Vec3::X) < 0.1 && eased.angle_between(Vec3::X) > 0.01);
    }
}
