//! Gait timing: stride, cycle, contact and swing from the walking speed, the footfall
//! sequence, and the arc a foot swings along.
//!
//! The source's data: free speed 0.11 +- 0.04 m/s; strides of 0.21-0.83 m (mean about 0.6 m);
//! contact about twice as long as swing; at 0.2-0.3 m/s the forelimbs' contact lasts 1.50 s and
//! swing 0.84 s, the hindlimbs' 1.66 s and 0.67 s. Stride grows with speed here as
//! `0.15 m + 1.5 s * speed`, within the measured range and capped by what the limbs reach; the
//! cycle is stride over speed, and a third of it is swing. At 0.25 m/s that gives a 0.525 m
//! stride, 1.4 s of contact and 0.7 s of swing; at 0.11 m/s 0.315 m, 1.9 s and 0.95 s.

use super::rig::Limb;
use bevy::math::Vec3;
use bevy::reflect::Reflect;
use serde::{Deserialize, Serialize};

/// The animal's free walking speed, metres per second (0.11 +- 0.04 measured).
pub const FREE_SPEED: f32 = 0.11;

/// The slowest and fastest walking speeds the gait accepts, metres per second.
pub const SPEED_RANGE: (f32, f32) = (0.05, 0.35);

/// The strides the study measured, shortest and longest, metres.
pub const ANIMAL_STRIDES: (f32, f32) = (0.21, 0.83);

/// Shortest stride the source measured, metres.
pub const MIN_STRIDE: f32 = ANIMAL_STRIDES.0;

/// The shortest swing of feet stepping one at a time, seconds: a longer delay between steps
/// lengthens the cycle rather than hurry the swing further.
pub const MIN_SEQUENTIAL_SWING: f32 = 0.25;

/// Part of a cycle a foot swings: contact lasts twice as long.
pub const SWING_FRACTION: f32 = 1.0 / 3.0;

/// How the stride is chosen.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StrideMode {
    /// Growing with the speed (see [`GaitTiming::at`]).
    #[default]
    FromSpeed,
    /// The same at every speed; the cycle is what makes the speed.
    Fixed,
    /// Drawn anew for every cycle within the animal's [`ANIMAL_STRIDES`] (and the longest
    /// stride allowed), from a seeded stream: the same seed walks the same strides.
    Random,
}

/// The stride of [`StrideMode::Fixed`] when none is given, metres.
pub const DEFAULT_FIXED_STRIDE: f32 = 0.45;

/// A measure of the study's, as mean and standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// Mean.
    pub mean: f32,
    /// Standard deviation.
    pub sd: f32,
}

impl Measured {
    /// Whether `value` lies within one standard deviation of the mean.
    pub fn within(&self, value: f32) -> bool {
        (value - self.mean).abs() <= self.sd
    }
}

/// One limb pair's figures in the study's Table 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudyGait {
    /// Contact, seconds.
    pub contact_s: Measured,
    /// Swing, seconds.
    pub swing_s: Measured,
    /// Stride, metres.
    pub stride_m: Measured,
}

/// The study's steady-state walk at 0.2-0.3 m/s on its 40 mm pole (Table 1), forelimbs then
/// hindlimbs.
pub const STEADY_STATE: [StudyGait; 2] = [
    StudyGait {
        contact_s: Measured { mean: 1.50, sd: 0.20 },
        swing_s: Measured { mean: 0.84, sd: 0.20 },
        stride_m: Measured { mean: 0.59, sd: 0.05 },
    },
    StudyGait {
        contact_s: Measured { mean: 1.66, sd: 0.25 },
        swing_s: Measured { mean: 0.67, sd: 0.15 },
        stride_m: Measured { mean: 0.60, sd: 0.05 },
    },
];

/// The timing of one gait.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaitTiming {
    /// How far each foot moves per cycle, metres.
    pub stride: f32,
    /// One full cycle, seconds.
    pub cycle: f32,
    /// One swing, seconds.
    pub swing: f32,
}

impl GaitTiming {
    /// The timing at `speed` (m/s, clamped to [`SPEED_RANGE`]) for limbs that comfortably step
    /// at most `max_stride` metres.
    pub fn at(speed: f32, max_stride: f32) -> Self {
        let speed = speed.clamp(SPEED_RANGE.0, SPEED_RANGE.1);
        Self::with_stride(speed, 0.15 + 1.5 * speed, max_stride)
    }

    /// The timing at `speed` with strides of `stride` metres (kept within what the limbs
    /// comfortably step, `max_stride`).
    pub fn with_stride(speed: f32, stride: f32, max_stride: f32) -> Self {
        let speed = speed.clamp(SPEED_RANGE.0, SPEED_RANGE.1);
        let stride = stride.clamp(MIN_STRIDE.min(max_stride), max_stride);
        let cycle = stride / speed;
        Self { stride, cycle, swing: cycle * SWING_FRACTION }
    }

    /// The same strides with the feet stepping one at a time, as the source's animal did:
    /// each foot lifts `delay` seconds after the one before it touched down. The swing takes
    /// what is left of a quarter cycle, and no less than [`MIN_SEQUENTIAL_SWING`] (the cycle,
    /// and with it the speed made, gives way when a long delay leaves too little).
    pub fn with_step_delay(self, delay: f32) -> Self {
        let delay = delay.max(0.0);
        let swing = (0.25 * self.cycle - delay).max(MIN_SEQUENTIAL_SWING);
        Self { stride: self.stride, cycle: 4.0 * (swing + delay), swing }
    }

    /// Contact time, seconds.
    pub fn contact(&self) -> f32 {
        self.cycle - self.swing
    }

    /// The part of a cycle a foot swings.
    pub fn swing_fraction(&self) -> f32 {
        self.swing / self.cycle
    }
}

/// When in the cycle (0 to 1) `limb` lifts off in the diagonal sequence: right hind, left
/// fore, left hind, right fore, a quarter cycle apart.
pub fn lift_phase(limb: Limb) -> f32 {
    limb.index() as f32 * 0.25
}

/// A foot on its way from one grip to the next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwingArc {
    /// Where it lifted off, metres.
    pub from: Vec3,
    /// Where it lands, metres.
    pub to: Vec3,
    /// Unit direction it bulges out to clear the support.
    pub clear: Vec3,
    /// How far it bulges at mid-swing, metres.
    pub height: f32,
}

impl SwingArc {
    /// The foot at `t` (0 lift-off to 1 touch-down): eased along the chord, bulging out on a
    /// half sine, so it leaves and lands at rest.
    pub fn at(&self, t: f32) -> Vec3 {
        let t = t.clamp(0.0, 1.0);
        let eased = t * t * (3.0 - 2.0 * t);
        self.from.lerp(self.to, eased) + self.clear * (self.height * (std::f32::consts::PI * t).sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_lasts_twice_the_swing_and_speed_is_stride_per_cycle() {
        for speed in [0.07, 0.11, 0.2, 0.3] {
            let gait = GaitTiming::at(speed, 0.6);
            assert!((gait.contact() - 2.0 * gait.swing).abs() < 1e-5);
            assert!((gait.stride / gait.cycle - speed).abs() < 1e-6);
            assert!((MIN_STRIDE..=0.83).contains(&gait.stride));
        }
        let steady = GaitTiming::at(0.25, 0.6);
        assert!((1.3..=1.8).contains(&steady.contact()) && (0.6..=0.9).contains(&steady.swing));
    }

    #[test]
    fn faster_walking_takes_longer_strides_in_shorter_cycles() {
        let (slow, fast) = (GaitTiming::at(0.08, 0.6), GaitTiming::at(0.28, 0.6));
        assert!(fast.stride > slow.stride && fast.cycle < slow.cycle);
        assert_eq!(GaitTiming::at(0.3, 0.3).stride, 0.3);
    }

    #[test]
    fn stepping_one_at_a_time_leaves_the_delay_between_touch_down_and_the_next_lift() {
        let overlapping = GaitTiming::with_stride(0.11, 0.27, 0.3);
        let sequential = overlapping.with_step_delay(0.2);
        // Lifts stay a quarter cycle apart; the swing ends `delay` before the next lift.
        assert!((0.25 * sequential.cycle - sequential.swing - 0.2).abs() < 1e-6);
        assert_eq!(sequential.cycle, overlapping.cycle);
        assert!(sequential.swing < overlapping.swing);
        // Too long a delay for the cycle: the swing keeps its least and the cycle grows.
        let slow = overlapping.with_step_delay(0.9);
        assert_eq!(slow.swing, MIN_SEQUENTIAL_SWING);
        assert!((slow.cycle - 4.0 * (MIN_SEQUENTIAL_SWING + 0.9)).abs() < 1e-6);
        assert!(slow.cycle > overlapping.cycle);
    }

    #[test]
    fn the_diagonal_sequence_is_rh_lf_lh_rf() {
        let mut limbs = Limb::ALL;
        limbs.sort_by(|a, b| lift_phase(*a).total_cmp(&lift_phase(*b)));
        assert_eq!(limbs, [Limb::RightHind, Limb::LeftFore, Limb::LeftHind, Limb::RightFore]);
        assert_eq!(lift_phase(Limb::RightFore), 0.75);
    }

    #[test]
    fn a_swing_starts_and_ends_on_its_grips_and_clears_in_between() {
        let arc = SwingArc { from: Vec3::ZERO, to: Vec3::X * 0.3, clear: Vec3::NEG_Y, height: 0.05 };
        assert_eq!(arc.at(0.0), Vec3::ZERO);
        assert!(arc.at(1.0).distance(Vec3::X * 0.3) < 1e-6);
        assert!((arc.at(0.5).y + 0.05).abs() < 1e-6);
    }
}
