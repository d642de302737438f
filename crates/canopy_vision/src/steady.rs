//! Poses that do not flip between frames. A marker seen face on, or small in the frame, fits
//! two poses almost equally well (the planar ambiguity: the same outline seen tilted one way
//! or mirrored the other), and taking the better fit of each frame alone makes the pose flip
//! between them with the noise of the corners. A [`PoseFollower`] keeps, frame after frame, the
//! solution that continues the pose it showed last, unless the other fits the corners clearly
//! better, and counts the flips it could not avoid.

use crate::pose::{Pose, PoseEstimate};

/// The solution that continues the last pose is kept while its error is at most this many
/// times the better solution's error, plus [`KEEP_MARGIN_PX`]: within that, both explain the
/// corners and only continuity can tell them apart.
pub const KEEP_FACTOR: f64 = 2.0;

/// See [`KEEP_FACTOR`], pixels.
pub const KEEP_MARGIN_PX: f64 = 0.5;

/// Two solutions nearer each other than this, radians (10 degrees), are one pose within the
/// noise: going from one to the other is no flip.
pub const FLIP_SEPARATION: f64 = 0.1745;

/// Whether a frame that could show `pose` or `other` turned over by showing `pose` after
/// `before` was shown: `pose` is the farther of the two from `before`, and they lie apart.
pub fn turned_over(pose: &Pose, other: &Pose, before: &Pose) -> bool {
    pose.angle_to(other) > FLIP_SEPARATION && pose.angle_to(before) > other.angle_to(before)
}

/// The pose shown for one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown {
    /// The solution shown.
    pub pose: Pose,
    /// The other solution of the frame.
    pub other: Pose,
    /// Whether the shown solution is the estimate's alternative, kept because it continues
    /// the pose shown before.
    pub kept_alternative: bool,
    /// Whether the shown pose turned over from the last one shown (see [`turned_over`]).
    pub flipped: bool,
}

/// Follows one marker's pose from frame to frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseFollower {
    last: Option<Shown>,
    flips: u64,
    kept: u64,
}

impl PoseFollower {
    /// The pose to show for a frame's `estimate`: the solution nearer in rotation to the last
    /// pose shown while it fits within [`KEEP_FACTOR`] and [`KEEP_MARGIN_PX`] of the better
    /// one, otherwise the better one.
    pub fn follow(&mut self, estimate: &PoseEstimate) -> Shown {
        let continues = |last: &Shown| {
            estimate.alternative.angle_to(&last.pose) < estimate.pose.angle_to(&last.pose)
                && estimate.alternative_error_px <= KEEP_FACTOR * estimate.error_px + KEEP_MARGIN_PX
        };
        let kept_alternative = self.last.as_ref().is_some_and(continues);
        let (pose, other) = match kept_alternative {
            true => (estimate.alternative, estimate.pose),
            false => (estimate.pose, estimate.alternative),
        };
        let flipped = self.last.is_some_and(|last| turned_over(&pose, &other, &last.pose));
        let shown = Shown { pose, other, kept_alternative, flipped };
        self.flips += u64::from(flipped);
        self.kept += u64::from(kept_alternative);
        self.last = Some(shown);
        shown
    }

    /// Forgets the last pose (the marker was lost): the next frame shows its better fit.
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// Frames whose pose turned over from the one before.
    pub fn flips(&self) -> u64 {
        self.flips
    }

    /// Frames that showed the alternative solution for its continuity.
    pub fn kept(&self) -> u64 {
        self.kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Intrinsics;
    use crate::pose::{estimate, marker_corners};
    use bevy_math::{DMat3, DVec2, DVec3};

    /// A marker 5 cm across, 60 cm away, turning about its vertical axis from 12 degrees one
    /// way through face on to 12 degrees the other, its corners seen with up to 0.4 px of
    /// noise: each frame's estimate and the true pose.
    fn turning_marker() -> Vec<(PoseEstimate, Pose)> {
        let camera = Intrinsics::pinhole([640, 480], 50.0);
        let mut seed = 12345u64;
        let mut noise = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.8
        };
        (0..=96)
            .map(|k| {
                let turn = (-12.0 + 0.25 * k as f64).to_radians();
                let truth = Pose { rotation: DMat3::from_rotation_y(turn), translation: DVec3::new(0.02, -0.01, 0.6) };
                let corners = marker_corners(0.05).map(|p| {
                    let pixel = camera.project(truth.apply(p)).unwrap();
                    pixel + DVec2::new(noise(), noise())
                });
                (estimate(&corners, 0.05, &camera).unwrap(), truth)
            })
            .collect()
    }

    #[test]
    fn a_marker_turning_through_face_on_flips_frame_by_frame_but_not_followed() {
        let frames = turning_marker();
        // Each frame's better fit alone: the pose turns over again and again.
        let mut best_flips = 0;
        for pair in frames.windows(2) {
            let (before, now) = (&pair[0].0, &pair[1].0);
            best_flips += usize::from(turned_over(&now.pose, &now.alternative, &before.pose));
        }
        assert!(best_flips >= 4, "the better fit alone flips {best_flips} times");
        // Followed: never, and nearer the truth than the better fits, at worst and on average.
        let mut follower = PoseFollower::default();
        let (mut best_off, mut shown_off) = (Vec::new(), Vec::new());
        for (estimate, truth) in &frames {
            let shown = follower.follow(estimate);
            best_off.push(estimate.pose.angle_to(truth).to_degrees());
            shown_off.push(shown.pose.angle_to(truth).to_degrees());
        }
        let worst = |off: &[f64]| off.iter().copied().fold(0.0, f64::max);
        let mean = |off: &[f64]| off.iter().sum::<f64>() / off.len() as f64;
        assert!(worst(&shown_off) < 0.6 * worst(&best_off), "{} against {}", worst(&shown_off), worst(&best_off));
        assert!(mean(&shown_off) < mean(&best_off), "{} against {}", mean(&shown_off), mean(&best_off));
        assert_eq!(follower.flips(), 0);
        assert!(follower.kept() > 0);
    }

    #[test]
    fn a_clearly_better_fit_wins_over_continuity() {
        let camera = Intrinsics::pinhole([640, 480], 50.0);
        let side = 0.1;
        // A large marker tilted 40 degrees: its mirror pose misses the corners by pixels.
        let truth = Pose { rotation: DMat3::from_rotation_x(0.7), translation: DVec3::new(0.0, 0.0, 0.4) };
        let corners = marker_corners(side).map(|p| camera.project(truth.apply(p)).unwrap());
        let estimate = estimate(&corners, side, &camera).unwrap();
        assert!(estimate.alternative_error_px > KEEP_FACTOR * estimate.error_px + KEEP_MARGIN_PX);
        // After a frame that showed the mirror pose, the true one is shown, and counted a flip.
        let mut follower = PoseFollower::default();
        let mirrored = PoseEstimate { pose: estimate.alternative, alternative: estimate.pose, ..estimate };
        follower.follow(&mirrored);
        let shown = follower.follow(&estimate);
        assert!(shown.pose.angle_to(&truth) < 1e-6 && shown.flipped && !shown.kept_alternative);
        assert_eq!(follower.flips(), 1);
        follower.forget();
        assert!(!follower.follow(&mirrored).flipped, "nothing to flip from after the marker was lost");
    }
}
