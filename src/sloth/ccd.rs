//! Cyclic coordinate descent for one limb.
//!
//! Each sweep goes from the joint nearest the grip back to the root. A joint turns about its
//! axis by the angle that points the grip at the target as seen from the joint (both projected
//! onto the plane the joint turns in), and is then clamped to its limits, so every pose the
//! solver returns is within limits. The solver stops within tolerance or after a sweep cap; a
//! target out of reach ends at the closest pose the sweeps found. Degenerate geometry (grip or
//! target on a joint's axis) turns that joint by zero instead of producing NaN.
//!
//! CCD's steps shrink with the error, so near a target it crawls, and with limits it can stall
//! where one joint sits at a limit. When the sweeps stall short of the target, a few damped
//! least-squares steps (also clamped) finish the approach; if the warm start still falls short,
//! the solver tries again from the rest pose and keeps the better result.

use super::rig::{BodyFrame, JOINTS, LimbRig};
use bevy::math::{Mat3, Quat, Vec3};

/// When the solver stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CcdSettings {
    /// Distance from grip to target that counts as reached, metres.
    pub tolerance: f32,
    /// Most sweeps per start.
    pub max_sweeps: u32,
}

impl Default for CcdSettings {
    fn default() -> Self {
        // Half a millimetre: a planted foot then slips less than 1 mm a step on the study's
        // pole (with 3 mm it wandered 4-6 mm), and every scenario still passes.
        Self { tolerance: 5e-4, max_sweeps: 16 }
    }
}

/// What a solve achieved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CcdResult {
    /// Distance left from the grip to the target, metres.
    pub error: f32,
    /// Sweeps taken (over both starts if the solver restarted).
    pub sweeps: u32,
}

impl CcdResult {
    /// Whether the target was reached within `settings.tolerance`.
    pub fn reached(&self, settings: &CcdSettings) -> bool {
        self.error <= settings.tolerance
    }
}

/// Moves `angles` (kept within the rig's limits) so the grip point approaches `target`.
pub fn solve(
    rig: &LimbRig,
    frame: &BodyFrame,
    angles: &mut [f32; JOINTS],
    target: Vec3,
    settings: &CcdSettings,
) -> CcdResult {
    *angles = clamp(rig, *angles);
    let first = attempt(rig, frame, angles, target, settings);
    if first.reached(settings) {
        return first;
    }
    let mut best = first;
    let mut sweeps = first.sweeps;
    for fold in RESTART_FOLDS {
        let mut fresh = clamp(rig, std::array::from_fn(|j| if j == 0 { rig.rest[0] } else { rig.rest[j] * fold }));
        let result = attempt(rig, frame, &mut fresh, target, settings);
        sweeps += result.sweeps;
        if result.error < best.error {
            *angles = fresh;
            best = result;
        }
        if best.reached(settings) {
            break;
        }
    }
    CcdResult { error: best.error, sweeps }
}

/// Restarts scale the rest pose's flexion by these factors: as it is, more and less folded.
const RESTART_FOLDS: [f32; 3] = [1.0, 1.5, 0.5];

/// CCD sweeps from `angles`, finished by damped least squares if they stall short.
fn attempt(
    rig: &LimbRig,
    frame: &BodyFrame,
    angles: &mut [f32; JOINTS],
    target: Vec3,
    settings: &CcdSettings,
) -> CcdResult {
    let result = sweeps(rig, frame, angles, target, settings);
    if result.reached(settings) {
        return result;
    }
    let error = refine(rig, frame, angles, target, settings);
    CcdResult { error, sweeps: result.sweeps }
}

/// Damped least-squares steps: where CCD crawls (its steps shrink with the error), these
/// converge quadratically. Each step is clamped to the limits and kept only if it helps.
fn refine(rig: &LimbRig, frame: &BodyFrame, angles: &mut [f32; JOINTS], target: Vec3, settings: &CcdSettings) -> f32 {
    let mut points = rig.points(frame, angles);
    let mut error = points[JOINTS - 1].distance(target);
    let mut damping = 0.02f32;
    for _ in 0..REFINE_STEPS {
        if error <= settings.tolerance {
            break;
        }
        let (abduct, flex) = rig.axes(frame, angles[0]);
        let grip = points[JOINTS - 1];
        let columns: [Vec3; JOINTS] = std::array::from_fn(|j| {
            let axis = if j == 0 { abduct } else { flex };
            axis.cross(grip - LimbRig::pivot(&points, j))
        });
        let mut normal = Mat3::from_diagonal(Vec3::splat(damping * damping));
        for column in &columns {
            normal += outer(*column, *column);
        }
        let along = normal.inverse() * (target - grip);
        let trial: [f32; JOINTS] =
            std::array::from_fn(|j| (angles[j] + columns[j].dot(along)).clamp(rig.min[j], rig.max[j]));
        let trial_points = rig.points(frame, &trial);
        let trial_error = trial_points[JOINTS - 1].distance(target);
        if trial_error.is_finite() && trial_error < error {
            (*angles, points, error) = (trial, trial_points, trial_error);
            damping *= 0.5;
        } else {
            damping *= 4.0;
        }
    }
    error
}

/// Damped least-squares steps after stalled sweeps.
const REFINE_STEPS: usize = 40;

fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

fn clamp(rig: &LimbRig, angles: [f32; JOINTS]) -> [f32; JOINTS] {
    std::array::from_fn(|j| if angles[j].is_finite() { angles[j].clamp(rig.min[j], rig.max[j]) } else { rig.rest[j] })
}

fn sweeps(
    rig: &LimbRig,
    frame: &BodyFrame,
    angles: &mut [f32; JOINTS],
    target: Vec3,
    settings: &CcdSettings,
) -> CcdResult {
    let mut points = rig.points(frame, angles);
    let mut error = points[JOINTS - 1].distance(target);
    let mut taken = 0;
    while taken < settings.max_sweeps && error > settings.tolerance {
        taken += 1;
        let before = error;
        // Abduction turns last, so the flexion axis holds for the whole sweep.
        let (abduct, flex) = rig.axes(frame, angles[0]);
        for joint in (0..JOINTS).rev() {
            let axis = if joint == 0 { abduct } else { flex };
            let pivot = LimbRig::pivot(&points, joint);
            let turn = turn_towards(axis, points[JOINTS - 1] - pivot, target - pivot);
            let turned = (angles[joint] + turn).clamp(rig.min[joint], rig.max[joint]);
            if turned != angles[joint] {
                // Everything beyond the joint turns rigidly about it.
                let rotation = Quat::from_axis_angle(axis, turned - angles[joint]);
                for point in &mut points[joint.max(1)..] {
                    *point = pivot + rotation * (*point - pivot);
                }
                angles[joint] = turned;
            }
        }
        // Forward kinematics once per sweep keeps the points exact.
        points = rig.points(frame, angles);
        error = points[JOINTS - 1].distance(target);
        // Sweeps that gain less than a tenth of the tolerance have stalled.
        if before - error < settings.tolerance * 0.1 {
            break;
        }
    }
    CcdResult { error, sweeps: taken }
}

/// The angle about the unit `axis` that turns `from` towards `to`, both projected onto the
/// plane perpendicular to the axis; zero when either projection vanishes.
fn turn_towards(axis: Vec3, from: Vec3, to: Vec3) -> f32 {
    let from = from - axis * from.dot(axis);
    let to = to - axis * to.dot(axis);
    if from.length_squared() < 1e-12 || to.length_squared() < 1e-12 {
        return 0.0;
    }
    axis.dot(from.cross(to)).atan2(from.dot(to))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sloth::rig::{Limb, Proportions};
    use proptest::prelude::*;

    fn frame() -> BodyFrame {
        BodyFrame { centre: Vec3::new(0.3, 1.0, -0.2), forward: Vec3::new(1.0, 0.0, 1.0).normalize(), up: Vec3::Y }
    }

    fn rig(limb: usize) -> LimbRig {
        LimbRig::new(Limb::ALL[limb], &Proportions::default())
    }

    /// A pose within limits, from fractions of each joint's range.
    fn pose(rig: &LimbRig, fractions: [f32; JOINTS]) -> [f32; JOINTS] {
        std::array::from_fn(|j| rig.min[j] + (rig.max[j] - rig.min[j]) * fractions[j])
    }

    #[test]
    fn the_rest_pose_is_its_own_solution() {
        let rig = rig(1);
        let mut angles = rig.rest;
        let result = solve(&rig, &frame(), &mut angles, rig.effector(&frame(), &rig.rest), &CcdSettings::default());
        assert_eq!(result.sweeps, 0);
        assert_eq!(angles, rig.rest);
    }

    #[test]
    fn a_target_beyond_reach_ends_stretched_towards_it_within_limits() {
        let rig = rig(0);
        let root = rig.root_in(&frame());
        let target = root + Vec3::new(0.1, 2.0, 0.0);
        let mut angles = rig.rest;
        let result = solve(&rig, &frame(), &mut angles, target, &CcdSettings::default());
        assert!(rig.within_limits(&angles, 0.0));
        let grip = rig.effector(&frame(), &angles);
        assert!(result.error > 1.0);
        assert!((grip - root).normalize().dot((target - root).normalize()) > 0.9);
    }

    proptest! {
        /// Targets made from poses within limits, near the rest pose as feet are, are reached.
        #[test]
        fn reachable_targets_near_rest_are_reached(limb in 0usize..4, f in prop::array::uniform5(0.3f32..0.7)) {
            let rig = rig(limb);
            let target = rig.effector(&frame(), &pose(&rig, f));
            let settings = CcdSettings::default();
            let mut angles = rig.rest;
            let result = solve(&rig, &frame(), &mut angles, target, &settings);
            prop_assert!(result.reached(&settings), "{:?} left {} m", rig.limb, result.error);
            prop_assert!((rig.effector(&frame(), &angles).distance(target) - result.error).abs() < 1e-5);
        }

        /// Any target, from any start: finite angles within limits, error honestly reported.
        #[test]
        fn random_targets_never_give_nan_or_break_limits(
            limb in 0usize..4,
            target in prop::array::uniform3(-2.0f32..2.0),
            start in prop::array::uniform5(-10.0f32..10.0),
        ) {
            let rig = rig(limb);
            let target = Vec3::from(target);
            let mut angles = start;
            let result = solve(&rig, &frame(), &mut angles, target, &CcdSettings::default());
            prop_assert!(angles.iter().all(|a| a.is_finite()));
            prop_assert!(rig.within_limits(&angles, 0.0));
            prop_assert!(result.error.is_finite());
            prop_assert!((rig.effector(&frame(), &angles).distance(target) - result.error).abs() < 1e-5);
        }
    }
}
