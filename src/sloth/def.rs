//! The `sloth:` entry of a scene file, and the kind that places it on the scene's trees
//! (once, while checking) and spawns it.

use super::biceps::Biceps;
use super::ccd::CcdSettings;
use super::gait::{self, StrideMode};
use super::locomotion::{Placement, Sloth, Tuning};
use super::rig::Proportions;
use super::supports::Supports;
use crate::foundation::values::{Color, Degrees, UnitInterval, checked_number};
use crate::muscle::ConfigFile;
use bevy::color::Srgba;
use bevy::prelude::Reflect;
use serde::{Deserialize, Serialize};

/// How far below its grips a body may hang, metres.
pub const HANG_RANGE: (f32, f32) = (0.1, 0.6);
/// The strides a sloth may be given: those the study measured, metres.
pub const STRIDE_RANGE: (f32, f32) = gait::ANIMAL_STRIDES;
/// The delays between steps a sloth stepping one foot at a time may be given, seconds.
pub const STEP_DELAY_RANGE: (f32, f32) = (0.0, 1.0);
/// The longest strides a sloth may be given, metres.
pub const MAX_STEP_RANGE: (f32, f32) = (0.1, 1.0);
/// The IK's tolerances, millimetres.
pub const IK_TOLERANCE_RANGE_MM: (f32, f32) = (0.01, 10.0);
/// The IK's sweeps for one solve.
pub const IK_SWEEPS_RANGE: (u32, u32) = (1, 256);

checked_number!(
    /// A walking speed in metres per second, within the gait's range.
    Speed(f32),
    "a speed in metres per second from 0.05 to 0.35",
    |v| (gait::SPEED_RANGE.0 as f64..=gait::SPEED_RANGE.1 as f64).contains(&v)
);

checked_number!(
    /// A size relative to the default 0.8 m animal.
    Scale(f32),
    "a scale from 0.5 to 2",
    |v| (0.5..=2.0).contains(&v)
);

checked_number!(
    /// How far below its grips a body hangs, metres.
    Hang(f32),
    "a distance in metres from 0.1 to 0.6",
    |v| (HANG_RANGE.0 as f64..=HANG_RANGE.1 as f64).contains(&v)
);

checked_number!(
    /// A stride in metres, within the range the study measured.
    StrideLength(f32),
    "a stride in metres from 0.21 to 0.83",
    |v| (STRIDE_RANGE.0 as f64..=STRIDE_RANGE.1 as f64).contains(&v)
);

checked_number!(
    /// Seconds from one foot's touch-down to the next foot's lift-off.
    StepDelay(f32),
    "a delay in seconds from 0 to 1",
    |v| (STEP_DELAY_RANGE.0 as f64..=STEP_DELAY_RANGE.1 as f64).contains(&v)
);

checked_number!(
    /// The longest stride the gait may take, metres.
    MaxStep(f32),
    "a distance in metres from 0.1 to 1",
    |v| (MAX_STEP_RANGE.0 as f64..=MAX_STEP_RANGE.1 as f64).contains(&v)
);

checked_number!(
    /// The distance from its target at which the IK stops, millimetres.
    IkTolerance(f32),
    "a distance in millimetres from 0.01 to 10",
    |v| (IK_TOLERANCE_RANGE_MM.0 as f64..=IK_TOLERANCE_RANGE_MM.1 as f64).contains(&v)
);

checked_number!(
    /// The most sweeps the IK takes for one solve.
    IkSweeps(u32),
    "a whole number of sweeps from 1 to 256",
    |v| v.fract() == 0.0 && (IK_SWEEPS_RANGE.0 as f64..=IK_SWEEPS_RANGE.1 as f64).contains(&v)
);

/// Which way along its support a sloth faces when placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Facing {
    /// Towards the support's end (its last point, or its tip for a fork).
    #[default]
    Forward,
    /// Towards the support's start.
    Backward,
}

/// Which way autorun walks.
#[derive(Reflect, Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WalkDirection {
    /// Head first (up, on a trunk).
    #[default]
    Forward,
    /// Tail first (down, on a trunk).
    Back,
}

impl WalkDirection {
    /// +1 forward, -1 back.
    pub fn sign(self) -> f32 {
        match self {
            WalkDirection::Forward => 1.0,
            WalkDirection::Back => -1.0,
        }
    }
}

/// A `sloth` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SlothDef {
    /// The support it hangs from: `tree/support`, or just the support's name when only one
    /// tree has a support of that name.
    pub support: String,
    /// Where along the support, 0 to 1 of its length; 0.5 by default.
    #[serde(default = "middle")]
    pub at: UnitInterval,
    /// On a branch, which way it faces: `forward` (towards the support's end, the default) or
    /// `backward`. On a trunk it always faces up.
    #[serde(default)]
    pub facing: Facing,
    /// On a trunk, where around it the body hangs: degrees about +y from +z (0, the default,
    /// puts the sloth on the trunk's +z side).
    #[serde(default = "no_turn")]
    pub around_deg: Degrees,
    /// Mean walking speed, metres per second; 0.11 by default.
    #[serde(default = "free_speed")]
    pub speed: Speed,
    /// Whether it walks by itself from the start (it stops where it finds no foothold).
    #[serde(default)]
    pub autorun: bool,
    /// Which way autorun walks: `forward` (the default) or `back`.
    #[serde(default)]
    pub direction: WalkDirection,
    /// Size relative to the default animal of 0.8 m; 1 by default.
    #[serde(default = "unit_scale")]
    pub scale: Scale,
    /// How far the body hangs below its grips, metres; 0.28 times `scale` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hang: Option<Hang>,
    /// How the stride is chosen: `from_speed` (the default) or `fixed` at `stride_m`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stride_mode: Option<StrideMode>,
    /// The stride of `stride_mode: fixed`, metres; 0.45 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stride_m: Option<StrideLength>,
    /// The seed of `stride_mode: random`'s strides; 0 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stride_seed: Option<u32>,
    /// Feet step one at a time, each lifting this many seconds after the one before landed
    /// (the source's 0.2 s); absent, the animal's swings overlap (contact twice the swing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step_delay_s: Option<StepDelay>,
    /// The longest stride, metres; half the torso's length and 0.1 m by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step_m: Option<MaxStep>,
    /// The distance from its target at which each limb's IK stops, millimetres; 0.5 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ik_tolerance_mm: Option<IkTolerance>,
    /// The most sweeps of the IK for one solve; 16 by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ik_sweeps: Option<IkSweeps>,
    /// Fur colour; a greyish brown by default.
    #[serde(default = "fur")]
    pub color: Color,
    /// Each forelimb's biceps: a `muscle_config` and `carcass_config` as the muscle kind
    /// reads them, the carcass's rod 1 scaled onto the upper arm; the source program's first
    /// configuration when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub biceps: Option<ConfigFile>,
}

fn middle() -> UnitInterval {
    UnitInterval(0.5)
}

fn no_turn() -> Degrees {
    Degrees(0.0)
}

fn free_speed() -> Speed {
    Speed(gait::FREE_SPEED)
}

fn unit_scale() -> Scale {
    Scale(1.0)
}

fn fur() -> Color {
    Color(Srgba::rgb(0.56, 0.45, 0.33))
}

impl SlothDef {
    /// The body proportions this definition asks for.
    pub fn proportions(&self) -> Proportions {
        let mut proportions = Proportions::default().scaled(self.scale.0);
        if let Some(hang) = self.hang {
            proportions.hang = hang.0;
        }
        proportions
    }

    /// The left and right forelimbs' biceps, or why the configuration cannot follow the elbow.
    pub fn biceps(&self) -> Result<[Biceps; 2], String> {
        let config = self.biceps.clone().unwrap_or_else(ConfigFile::source_first);
        let bones = self.proportions().fore_bones;
        let biceps = Biceps::new(&config, bones[1], bones[2])?;
        Ok([biceps.clone(), biceps])
    }

    /// The index of the support it names among `supports`, or why there is none.
    pub fn resolve(&self, supports: &Supports) -> Result<usize, String> {
        if let Some(index) = supports.find(&self.support) {
            return Ok(index);
        }
        let suffix = format!("/{}", self.support);
        let matching: Vec<usize> =
            (0..supports.paths.len()).filter(|&i| supports.paths[i].label.ends_with(&suffix)).collect();
        match matching.as_slice() {
            [index] => Ok(*index),
            [] if supports.ungripped.iter().any(|label| *label == self.support || label.ends_with(&suffix)) => {
                Err(format!("`{}` is drawn but never gripped: thinner than its tree's grip_min_radius_m", self.support))
            }
            [] => {
                let known: Vec<&str> = supports.paths.iter().map(|p| p.label.as_str()).take(12).collect();
                Err(format!("no support named `{}`; the scene has: {}", self.support, known.join(", ")))
            }
            several => Err(format!(
                "`{}` names a support in {} trees; write it as `tree/support`",
                self.support,
                several.len()
            )),
        }
    }

    /// What is tuned of its walk at `speed` (m/s), as the file says or by default.
    pub fn tuning(&self, speed: f32) -> Tuning {
        let animal = Tuning::animal(speed, &self.proportions());
        Tuning {
            stride_mode: self.stride_mode.unwrap_or(animal.stride_mode),
            fixed_stride: self.stride_m.map_or(animal.fixed_stride, |s| s.0),
            stride_seed: self.stride_seed.unwrap_or(animal.stride_seed),
            step_delay: self.step_delay_s.map(|d| d.0).or(animal.step_delay),
            max_step: self.max_step_m.map(|m| m.0).or(animal.max_step),
            ccd: CcdSettings {
                tolerance: self.ik_tolerance_mm.map_or(animal.ccd.tolerance, |t| t.0 * 1e-3),
                max_sweeps: self.ik_sweeps.map_or(animal.ccd.max_sweeps, |s| s.0),
            },
            ..animal
        }
    }

    /// Places the sloth among `supports`, walking at `speed` (m/s) as the file tunes it.
    pub fn place(&self, supports: &Supports, speed: f32) -> Result<Sloth, String> {
        let placement = Placement {
            support: self.resolve(supports)?,
            fraction: self.at.0,
            facing: if self.facing == Facing::Forward { 1.0 } else { -1.0 },
            around: self.around_deg.0.to_radians(),
        };
        Sloth::place(supports, placement, self.proportions(), self.tuning(speed)).map_err(|e| e.to_string())
    }
}
