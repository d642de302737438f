//! FABRIK (forward and backward reaching inverse kinematics, Aristidou and Lasenby 2011) for one
//! limb, with the same joint limits as [`super::ccd`], to repeat the source's comparison of
//! the two on the sloth's own limbs (`cargo bench -p canopy_bench --bench ik`).
//!
//! A limb's four flexion joints all turn in one plane, the one its abduction sets, so the
//! solve is planar: abduction first turns the plane through the target (within its limits),
//! then FABRIK moves the joints in that plane. Each pass places a joint on the line to its
//! neighbour at the bone's length, and turns the bone as little as it must to keep its angle
//! to the bone before (going out from the root) or after (coming back from the grip) within
//! the joint's limits, as Aristidou and Lasenby's constrained variant does. The angles are
//! read back from the joint positions, so the pose is always within limits.

use super::ccd::{CcdResult, CcdSettings};
use super::rig::{BodyFrame, JOINTS, LimbRig};
use bevy::math::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Moves `angles` (kept within the rig's limits) so the grip point approaches `target`; the
/// result counts FABRIK iterations (a backward and a forward pass each) as sweeps.
pub fn solve(
    rig: &LimbRig,
    frame: &BodyFrame,
    angles: &mut [f32; JOINTS],
    target: Vec3,
    settings: &CcdSettings,
) -> CcdResult {
    let root = rig.root_in(frame);
    let offset = target - root;
    let across = offset - frame.forward * offset.dot(frame.forward);
    if across.length_squared() > 1e-12 {
        let side = frame.right() * rig.limb.side();
        angles[0] = across.dot(side).atan2(across.dot(frame.up)).clamp(rig.min[0], rig.max[0]);
    }
    let reach = rig.reach(frame, angles[0]);
    // The plane's coordinates: along the reach direction, along the body.
    let goal = Vec2::new(offset.dot(reach), offset.dot(frame.forward));
    let mut bends = [0.0f32; 4];
    let mut total = 0.0;
    for (bone, bend) in bends.iter_mut().enumerate() {
        total += angles[bone + 1].clamp(rig.min[bone + 1], rig.max[bone + 1]);
        *bend = total;
    }
    let mut points = planar_points(&rig.bones, &bends);
    let mut iterations = 0;
    while iterations < settings.max_sweeps && points[4].distance(goal) > settings.tolerance {
        iterations += 1;
        // Backward: from the goal in to the root, each bone's bend kept within the limits of
        // the joint at its far end, relative to the bone after it.
        points[4] = goal;
        for bone in (0..4).rev() {
            let wanted = direction_angle(points[bone] - points[bone + 1]) - PI;
            let bend = if bone == 3 {
                wanted
            } else {
                let after = bends[bone + 1];
                let (low, high) = (after - rig.max[bone + 2], after - rig.min[bone + 2]);
                clamp_angle(wanted, low, high)
            };
            bends[bone] = bend;
            points[bone] = points[bone + 1] - Vec2::from_angle(bend) * rig.bones[bone];
        }
        // Forward: from the root out, each bend kept within the limits of the joint at its
        // near end, relative to the bone before it (the first relative to the reach).
        points[0] = Vec2::ZERO;
        let mut before = 0.0;
        for bone in 0..4 {
            let wanted = direction_angle(points[bone + 1] - points[bone]);
            let bend = clamp_angle(wanted, before + rig.min[bone + 1], before + rig.max[bone + 1]);
            bends[bone] = bend;
            points[bone + 1] = points[bone] + Vec2::from_angle(bend) * rig.bones[bone];
            before = bend;
        }
    }
    let mut before = 0.0;
    for (bone, bend) in bends.iter().enumerate() {
        angles[bone + 1] = (bend - before).clamp(rig.min[bone + 1], rig.max[bone + 1]);
        before = *bend;
    }
    CcdResult { error: rig.effector(frame, angles).distance(target), sweeps: iterations }
}

/// The root and each bone's end in the limb's plane for cumulative bends `bends`.
fn planar_points(bones: &[f32; 4], bends: &[f32; 4]) -> [Vec2; 5] {
    let mut points = [Vec2::ZERO; 5];
    for bone in 0..4 {
        points[bone + 1] = points[bone] + Vec2::from_angle(bends[bone]) * bones[bone];
    }
    points
}

/// The angle of `v` from the reach direction towards the body's forward, radians.
fn direction_angle(v: Vec2) -> f32 {
    v.y.atan2(v.x)
}

/// `angle` moved by whole turns next to the interval `[low, high]` and clamped into it.
fn clamp_angle(angle: f32, low: f32, high: f32) -> f32 {
    let middle = 0.5 * (low + high);
    let near = middle + (angle - middle + PI).rem_euclid(TAU) - PI;
    near.clamp(low, high)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sloth::rig::{Limb, Proportions};

    fn frame() -> BodyFrame {
        BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::NEG_Y }
    }

    #[test]
    fn reaches_poses_the_limb_can_take_and_stays_within_limits() {
        let proportions = Proportions::default();
        let mut reached = 0;
        let mut total = 0;
        for limb in Limb::ALL {
            let rig = LimbRig::new(limb, &proportions);
            for k in 0..50 {
                // A pose within limits, spread over the ranges.
                let pose: [f32; JOINTS] = std::array::from_fn(|j| {
                    let t = ((k * 7 + j * 3) % 11) as f32 / 10.0;
                    rig.min[j] + t * (rig.max[j] - rig.min[j])
                });
                let target = rig.effector(&frame(), &pose);
                let mut angles = rig.rest;
                let result =
                    solve(&rig, &frame(), &mut angles, target, &CcdSettings { tolerance: 1e-3, max_sweeps: 64 });
                assert!(rig.within_limits(&angles, 1e-5), "{angles:?}");
                assert!(result.error.is_finite());
                total += 1;
                reached += usize::from(result.error <= 1e-3);
            }
        }
        // FABRIK with limits does not reach every reachable target: the comparison measures how
        // many it does.
        assert!(reached * 2 >= total, "reached {reached} of {total}");
    }

    #[test]
    fn a_target_out_of_reach_ends_stretched_towards_it() {
        let rig = LimbRig::new(Limb::LeftFore, &Proportions::default());
        let mut angles = rig.rest;
        let far = rig.root_in(&frame()) + Vec3::new(0.0, -5.0, 0.0);
        let result = solve(&rig, &frame(), &mut angles, far, &CcdSettings::default());
        assert!(result.error.is_finite() && rig.within_limits(&angles, 1e-5));
        let reach: f32 = rig.bones.iter().sum();
        assert!(result.error < 5.0 - 0.6 * reach, "{}", result.error);
    }

    #[test]
    fn angles_wrap_to_the_nearest_turn_before_clamping() {
        assert!((clamp_angle(TAU + 0.1, -1.0, 1.0) - 0.1).abs() < 1e-5);
        assert_eq!(clamp_angle(2.0, -1.0, 1.0), 1.0);
        assert!((clamp_angle(-PI + 0.05, 2.5, 3.5) - (PI + 0.05)).abs() < 1e-5);
    }
}
