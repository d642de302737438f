//! One sloth's locomotion, a fixed step at a time: the gait clock lifts each foot in turn, the
//! foothold search picks where it lands, the swing carries it there, the body follows the
//! grips, and every limb's IK reaches for its foot's target. Stopped at a trunk or below a
//! branch, a planned transfer (see [`super::transfer`]) takes over until it is done.

use super::body::{self, HEADING_EASE, NearSupports};
use super::ccd::{self, CcdSettings};
use super::feet::{Foot, GRIP_TOLERANCE, Probe, Step, Swing, in_wood};
use super::gait::{self, ANIMAL_STRIDES, GaitTiming, StrideMode, SwingArc};
use super::moves::Transfer;
use super::rig::{BodyFrame, JOINTS, Limb, LimbRig, Proportions, limb_rigs};
use super::supports::Supports;
use crate::foundation::random::Random;
use crate::tree::SupportKind;
use bevy::math::Vec3;

/// A foot touching down, for the gait record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footfall {
    /// Which foot.
    pub limb: Limb,
    /// Seconds since the sloth was placed.
    pub time: f32,
}

/// What the controls ask of the sloth this step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Drive {
    /// +1 forward (head first), -1 back, 0 stand.
    pub direction: f32,
    /// Change to the neighbouring branch on this side (+1 right, -1 left), asked this step.
    pub change: Option<f32>,
    /// On a trunk, with no `direction`: side-step round it, +1 to the right, -1 to the left.
    pub around: f32,
}

/// The longest stride the limbs of an animal of `proportions` comfortably take, metres: half
/// its torso's length and 0.1 m.
pub fn comfortable_stride(proportions: &Proportions) -> f32 {
    0.5 * (proportions.torso_length + 0.2)
}

/// What a person tunes of a sloth's walk while it walks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// Mean walking speed, metres per second.
    pub speed: f32,
    /// How the stride is chosen.
    pub stride_mode: StrideMode,
    /// The stride of [`StrideMode::Fixed`], metres.
    pub fixed_stride: f32,
    /// The seed of [`StrideMode::Random`]'s strides.
    pub stride_seed: u32,
    /// Seconds from one foot's touch-down to the next one's lift-off, when the feet step one at
    /// a time; `None` for the animal's overlapping swings.
    pub step_delay: Option<f32>,
    /// The longest stride, metres; `None` for what the limbs comfortably take.
    pub max_step: Option<f32>,
    /// How far the body hangs below its grips, metres.
    pub hang: f32,
    /// The limbs' IK.
    pub ccd: CcdSettings,
}

impl Tuning {
    /// The animal's own walk at `speed` (m/s) for a body of `proportions`: the stride from the
    /// speed, overlapping swings, the default IK.
    pub fn animal(speed: f32, proportions: &Proportions) -> Self {
        Self {
            speed,
            stride_mode: StrideMode::FromSpeed,
            fixed_stride: gait::DEFAULT_FIXED_STRIDE,
            stride_seed: 0,
            step_delay: None,
            max_step: None,
            hang: proportions.hang,
            ccd: CcdSettings::default(),
        }
    }
}

/// Where a sloth is placed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Index of the support in [`Supports::paths`].
    pub support: usize,
    /// Where along it, 0 to 1 of its length.
    pub fraction: f32,
    /// On a branch: +1 to face the way arc length grows, -1 the other way.
    pub facing: f32,
    /// On a trunk: where around it the body hangs, radians about +y from +z.
    pub around: f32,
}

/// Why a sloth could not be placed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlaceError {
    /// The named support does not exist.
    #[error("no support `{0}` in the scene")]
    UnknownSupport(String),
    /// The feet cannot all reach the support from a body hanging there.
    #[error("the sloth cannot hang at {fraction} along `{support}`: its feet do not reach the surface")]
    Unreachable {
        /// The support's label.
        support: String,
        /// Where along it.
        fraction: f32,
    },
    /// Near a junction, some foot finds no grip clear of the other support's wood.
    #[error("the sloth cannot hang at {fraction} along `{support}`: a foot's grips all sink into another support")]
    InWood {
        /// The support's label.
        support: String,
        /// Where along it.
        fraction: f32,
    },
}

/// How far a placed foot's grip moves at a time, metres, and in how many moves at most either
/// way, to come clear of another support's wood near a junction.
const WOOD_SHIFT_STEP: f32 = 0.02;
const WOOD_SHIFTS: usize = 15;

/// Where the gait clock stands with the feet as [`Sloth::place`] staggers them: the right hind
/// is about to lift.
const PLACED_PHASE: f32 = 1.0 - 1e-4;

/// How deep among the walks transfer plans try out transfers are still planned: the live sloth
/// plans its transfer, and the walk on that a plan tries out plans the next one it meets, but
/// that plan's own tried-out walks stop where a third would begin (nested without end, with
/// strides longer than the animal's default, plans overflowed the stack).
pub(super) const PLANNING_DEPTH: u8 = 2;

/// A sloth and everything its locomotion remembers.
#[derive(Debug, Clone, PartialEq)]
pub struct Sloth {
    /// Body proportions.
    pub proportions: Proportions,
    /// The limbs' rigs, indexed like [`Limb::ALL`].
    pub rigs: [LimbRig; 4],
    /// Mean walking speed asked for, metres per second.
    pub speed: f32,
    /// How the stride is chosen.
    pub stride_mode: StrideMode,
    /// The stride of [`StrideMode::Fixed`], metres.
    pub fixed_stride: f32,
    /// The seed `strides` was started from.
    pub stride_seed: u32,
    /// The stream [`StrideMode::Random`] draws its strides from.
    strides: Random,
    /// The stride [`StrideMode::Random`] drew for the current cycle, metres.
    pub drawn_stride: f32,
    /// Seconds from one foot's touch-down to the next one's lift-off, when the feet step one at
    /// a time; `None` for the animal's overlapping swings.
    pub step_delay: Option<f32>,
    /// The longest stride the gait takes, metres, when set; else from the torso's length.
    pub max_step: Option<f32>,
    /// The feet, indexed like [`Limb::ALL`].
    pub feet: [Foot; 4],
    /// The body's pose.
    pub frame: BodyFrame,
    /// Where in the gait cycle the clock is, 0 to 1.
    pub phase: f32,
    /// The support the sloth is changing to, if it is.
    pub change_to: Option<usize>,
    /// Whether each foot's last foothold search failed.
    pub stuck: [bool; 4],
    /// The direction in which neither leading foot found a foothold; the sloth waits until
    /// asked otherwise.
    pub blocked: Option<f32>,
    /// Every touch-down so far, in order.
    pub footfalls: Vec<Footfall>,
    /// Seconds since placing.
    pub time: f32,
    /// Seconds spent asked to move and not blocked.
    pub moving_time: f32,
    /// Path length of the body's centre, metres.
    pub distance: f32,
    /// Current distance from the body to the nearest support, metres.
    pub clearance: f32,
    /// Smallest `clearance` so far.
    pub min_clearance: f32,
    /// IK settings for all limbs.
    pub ccd: CcdSettings,
    /// Each limb's last foothold search: every grip it tried, and why each was refused.
    pub probes: [Vec<Probe>; 4],
    /// The transfer between a branch and a trunk under way, if one is.
    pub transfer: Option<Transfer>,
    /// Stopped going forward next to a support it may transfer onto, the sloth waits for its
    /// swinging feet to land before planning the transfer.
    transfer_pending: bool,
    /// How deep among the walks that transfer plans try out this sloth walks: 0 for the live
    /// one. Below [`PLANNING_DEPTH`] a transfer it waits for is planned; deeper, the walk ends
    /// where that transfer would begin.
    pub(super) trial_depth: u8,
    /// The support segments near the body, for its clearance.
    near: NearSupports,
}

impl Sloth {
    /// The longest stride the gait takes, metres: [`Sloth::max_step`], or
    /// [`comfortable_stride`].
    pub fn max_stride(&self) -> f32 {
        self.max_step.unwrap_or_else(|| comfortable_stride(&self.proportions))
    }

    /// What is tuned of its walk.
    pub fn tuning(&self) -> Tuning {
        Tuning {
            speed: self.speed,
            stride_mode: self.stride_mode,
            fixed_stride: self.fixed_stride,
            stride_seed: self.stride_seed,
            step_delay: self.step_delay,
            max_step: self.max_step,
            hang: self.proportions.hang,
            ccd: self.ccd,
        }
    }

    /// Walks on as `tuning` says from the next step.
    pub fn tune(&mut self, tuning: Tuning) {
        self.speed = tuning.speed;
        self.stride_mode = tuning.stride_mode;
        self.fixed_stride = tuning.fixed_stride;
        if tuning.stride_seed != self.stride_seed {
            self.stride_seed = tuning.stride_seed;
            self.strides = Random::new(tuning.stride_seed.into());
            self.draw_stride();
        }
        self.step_delay = tuning.step_delay;
        self.max_step = tuning.max_step;
        self.proportions.hang = tuning.hang;
        self.ccd = tuning.ccd;
    }

    /// The gait at the current speed.
    pub fn timing(&self) -> GaitTiming {
        let timing = match self.stride_mode {
            StrideMode::FromSpeed => GaitTiming::at(self.speed, self.max_stride()),
            StrideMode::Fixed => GaitTiming::with_stride(self.speed, self.fixed_stride, self.max_stride()),
            StrideMode::Random => GaitTiming::with_stride(self.speed, self.drawn_stride, self.max_stride()),
        };
        match self.step_delay {
            Some(delay) => timing.with_step_delay(delay),
            None => timing,
        }
    }

    /// Draws the next cycle's stride of [`StrideMode::Random`].
    fn draw_stride(&mut self) {
        self.drawn_stride = self.strides.between(ANIMAL_STRIDES.0, ANIMAL_STRIDES.1);
    }

    /// A sloth placed as `placement` says, walking as `tuning` says, with its feet staggered
    /// as in the middle of a diagonal-sequence walk. On a trunk it always faces up.
    pub fn place(
        supports: &Supports,
        placement: Placement,
        proportions: Proportions,
        tuning: Tuning,
    ) -> Result<Self, PlaceError> {
        let Placement { support, fraction, facing, around } = placement;
        let path = supports.paths.get(support).ok_or_else(|| PlaceError::UnknownSupport(format!("#{support}")))?;
        let rigs = limb_rigs(&proportions);
        let s0 = fraction.clamp(0.0, 1.0) * path.length();
        let axis = path.at(s0);
        let (forward, up) = match path.kind {
            SupportKind::Trunk => {
                let forward = if axis.tangent.y >= 0.0 { axis.tangent } else { -axis.tangent };
                let outward = Vec3::new(around.sin(), 0.0, around.cos());
                (forward, body::perpendicular_towards(-outward, forward))
            }
            SupportKind::Branch => {
                let forward = axis.tangent * if facing < 0.0 { -1.0 } else { 1.0 };
                (forward, body::perpendicular_towards(Vec3::Y, forward))
            }
        };
        let frame = BodyFrame { centre: axis.point - up * proportions.hang, forward, up };
        let mut sloth = Self {
            proportions,
            rigs,
            speed: tuning.speed,
            stride_mode: StrideMode::FromSpeed,
            fixed_stride: gait::DEFAULT_FIXED_STRIDE,
            stride_seed: 0,
            strides: Random::new(0),
            drawn_stride: 0.0,
            step_delay: None,
            max_step: None,
            feet: [Foot { support, s: s0, grip: axis.point, swing: None, angles: [0.0; JOINTS], position: axis.point };
                4],
            frame,
            phase: PLACED_PHASE,
            change_to: None,
            stuck: [false; 4],
            blocked: None,
            footfalls: Vec::new(),
            time: 0.0,
            moving_time: 0.0,
            distance: 0.0,
            clearance: f32::INFINITY,
            min_clearance: f32::INFINITY,
            ccd: CcdSettings::default(),
            probes: Default::default(),
            transfer: None,
            transfer_pending: false,
            trial_depth: 0,
            near: NearSupports::default(),
        };
        sloth.draw_stride();
        sloth.tune(tuning);
        // Feet where a steady walk at the animal's own stride for the speed would have them when
        // the right hind is about to lift: any stride the gait then takes walks on from there
        // (a stagger of a stride near the shortest would leave a leading foot no grip between
        // its pair and the most it may lead by).
        let stride = GaitTiming::at(sloth.speed, sloth.max_stride()).stride;
        let stagger = [-0.5, -0.125, 0.25, 0.5];
        for limb in Limb::ALL {
            let rig = &sloth.rigs[limb.index()];
            let staggered = s0 + facing.signum() * (rig.neutral_reach() + stagger[limb.index()] * stride);
            // Near a junction the grip moves along its support to the nearest place clear of
            // the other support's wood.
            let grip_at = |s: f32| {
                let s = s.clamp(0.0, path.length());
                (s, path.surface_towards(s, sloth.side_on(path, s, limb)))
            };
            let shifts = (0..=WOOD_SHIFTS).flat_map(|k| [k as f32, -(k as f32)]).map(|k| k * WOOD_SHIFT_STEP);
            let (s, grip) = shifts
                .map(|shift| grip_at(staggered + shift))
                .find(|&(_, grip)| !in_wood(grip, supports))
                .ok_or_else(|| PlaceError::InWood { support: path.label.clone(), fraction })?;
            let foot = &mut sloth.feet[limb.index()];
            (foot.s, foot.grip, foot.angles) = (s, grip, rig.rest);
        }
        sloth.settle(supports, 0.0);
        let unreachable = sloth.feet.iter().any(|f| f.position.distance(f.grip) > GRIP_TOLERANCE);
        if unreachable {
            return Err(PlaceError::Unreachable { support: path.label.clone(), fraction });
        }
        sloth.min_clearance = sloth.clearance;
        Ok(sloth)
    }

    /// The support the forelimbs lead on.
    pub fn support(&self) -> usize {
        self.feet[Limb::RightFore.index()].support
    }

    /// Advances one fixed step of `dt` seconds.
    pub fn step(&mut self, dt: f32, drive: Drive, supports: &Supports) {
        self.time += dt;
        if let Some(side) = drive.change {
            self.change_to = self.neighbour(side, supports);
            if self.change_to.is_some() {
                self.blocked = None;
                self.stuck = [false; 4];
            }
        }
        // (`f32::signum` would make 0 forward.)
        let direction = if drive.direction > 0.0 {
            1.0
        } else if drive.direction < 0.0 {
            -1.0
        } else {
            0.0
        };
        if direction != 0.0 && self.blocked.is_some_and(|b| b != direction) {
            self.blocked = None;
            self.stuck = [false; 4];
        }
        if self.transfer.is_some() {
            self.step_transfer(dt, supports);
            return;
        }
        let on_trunk = supports.paths[self.support()].kind == SupportKind::Trunk;
        if direction != 0.0 && self.blocked.is_none() && !self.transfer_pending {
            self.moving_time += dt;
            self.advance_clock(dt, direction, supports, None);
        } else if drive.around != 0.0 && on_trunk && self.change_to.is_none() {
            self.advance_clock(dt, 1.0, supports, Some(drive.around));
        }
        self.advance_swings(dt);
        // A transfer waits for every foot to hold on, and is dropped if asked to go back.
        if self.transfer_pending && direction < 0.0 {
            self.transfer_pending = false;
        }
        if self.transfer_pending && self.trial_depth < PLANNING_DEPTH && self.feet.iter().all(Foot::planted) {
            self.transfer_pending = false;
            self.transfer = self.plan_transfer(supports);
            if self.transfer.is_none() {
                self.blocked = Some(1.0);
            }
        }
        if let Some(target) = self.change_to
            && self.feet.iter().all(|f| f.support == target)
        {
            self.change_to = None;
        }
        self.settle(supports, dt);
    }

    /// Moves the gait clock and lifts each foot whose turn it is, if it has somewhere to go.
    ///
    /// Walking back runs the clock backwards: each foot swings back over the part of the cycle
    /// it swings in going forward (lifting where it would land), so the footfall sequence is the
    /// forward one reversed, and the stagger of the feet survives any change of direction.
    ///
    /// With `around`, each foot whose turn it is side-steps round its trunk instead.
    fn advance_clock(&mut self, dt: f32, direction: f32, supports: &Supports, around: Option<f32>) {
        let timing = self.timing();
        let before = self.phase;
        let after = (self.phase + direction * dt / timing.cycle).rem_euclid(1.0);
        self.phase = after;
        let wrapped = if direction > 0.0 { after < before } else { after > before };
        if wrapped && self.stride_mode == StrideMode::Random {
            self.draw_stride();
        }
        for limb in Limb::ALL {
            let offset = gait::lift_phase(limb);
            let lift = if direction > 0.0 { offset } else { (offset + timing.swing_fraction()).fract() };
            // Whether the clock passed `lift` going from `before` to `after` in `direction`.
            let (from, to) = if direction > 0.0 { (before, after) } else { (after, before) };
            let crossed = if from <= to { lift > from && lift <= to } else { lift > from || lift <= to };
            if !crossed || !self.feet[limb.index()].planted() {
                continue;
            }
            let step = match around {
                Some(around) => self.find_side_step(limb, around, supports),
                None => {
                    let mut probes = std::mem::take(&mut self.probes[limb.index()]);
                    probes.clear();
                    let step = self.find_next_step(limb, direction, supports, &mut probes);
                    self.probes[limb.index()] = probes;
                    step
                }
            };
            self.stuck[limb.index()] = step.is_none();
            if let Some(step) = step {
                self.lift(limb, step, timing.swing, supports);
            }
            let leading = Limb::ALL.into_iter().filter(|l| l.is_fore() == (direction > 0.0));
            if around.is_none() && leading.into_iter().all(|l| self.stuck[l.index()]) {
                // Stopped going forward at the trunk its branch grows from, or below a branch
                // growing from its trunk: over onto it, if that can be done.
                if direction > 0.0 && self.transfer_in_reach(supports) {
                    self.transfer_pending = true;
                } else {
                    self.blocked = Some(direction);
                }
            }
        }
    }

    /// Starts `limb`'s swing to `step`; a step onto another support makes the others follow.
    fn lift(&mut self, limb: Limb, step: Step, duration: f32, supports: &Supports) {
        if step.support != self.feet[limb.index()].support && self.change_to.is_none() {
            self.change_to = Some(step.support);
        }
        let foot = &mut self.feet[limb.index()];
        let path = &supports.paths[foot.support];
        let axis = path.at(foot.s).point;
        let outward = (foot.grip - axis).normalize_or_zero();
        let clear = (outward - self.frame.up).normalize_or_zero();
        let height = path.at(foot.s).radius + 0.03;
        let arc = SwingArc { from: foot.grip, to: step.grip, clear, height };
        foot.swing = Some(Swing { arc, elapsed: 0.0, duration });
        foot.support = step.support;
        foot.s = step.s;
        foot.grip = step.grip;
    }

    fn advance_swings(&mut self, dt: f32) {
        for limb in Limb::ALL {
            let foot = &mut self.feet[limb.index()];
            if let Some(swing) = &mut foot.swing {
                swing.elapsed += dt;
                if swing.elapsed >= swing.duration {
                    foot.swing = None;
                    self.footfalls.push(Footfall { limb, time: self.time });
                }
            }
        }
    }

    /// One step of the transfer under way. Once begun, a transfer runs to its end (and counts
    /// as moving) whatever the controls ask.
    fn step_transfer(&mut self, dt: f32, supports: &Supports) {
        let Some(transfer) = &mut self.transfer else { return };
        let step = transfer.advance(dt, self.proportions.torso_length * 0.5);
        for (limb, to, duration) in step.lifts {
            self.lift(limb, to, duration, supports);
        }
        self.moving_time += dt;
        self.advance_swings(dt);
        let targets = self.feet.map(|f| f.target());
        self.hang(step.frame, &targets, false, supports, dt);
        if step.done {
            self.transfer = None;
            self.change_to = None;
            self.phase = PLACED_PHASE;
            self.stuck = [false; 4];
        }
    }

    /// Places the body under the feet and solves every limb's IK.
    fn settle(&mut self, supports: &Supports, dt: f32) {
        let targets = self.feet.map(|f| f.target());
        let frame = self.pose(&self.feet, &targets, supports, dt);
        self.hang(frame, &targets, true, supports, dt);
    }

    /// Puts the body at `frame` (pushed clear of the supports if `push`, else as planned) and
    /// solves every limb's IK for its foot's target of `targets`.
    fn hang(&mut self, mut frame: BodyFrame, targets: &[Vec3; 4], push: bool, supports: &Supports, dt: f32) {
        self.near.refresh(&frame, &self.proportions, supports);
        self.clearance = if push {
            body::push_clear(&mut frame, &self.proportions, &self.near)
        } else {
            body::clearance(&frame, &self.proportions, &self.near)
        };
        if dt > 0.0 {
            self.distance += frame.centre.distance(self.frame.centre);
        }
        self.frame = frame;
        for limb in Limb::ALL {
            let rig = &self.rigs[limb.index()];
            let foot = &mut self.feet[limb.index()];
            ccd::solve(rig, &self.frame, &mut foot.angles, targets[limb.index()], &self.ccd);
            foot.position = rig.effector(&self.frame, &foot.angles);
        }
        self.min_clearance = self.min_clearance.min(self.clearance);
    }

    /// Where the body hangs from feet aiming at `targets`, its heading eased over `dt` seconds
    /// from the current one (taken as is when `dt` is 0), before any clearance push.
    pub fn pose(&self, feet: &[Foot; 4], targets: &[Vec3; 4], supports: &Supports, dt: f32) -> BodyFrame {
        let [rh, lf, lh, rf] = *targets;
        // On one trunk the body stays upright along it, turning only about its axis; elsewhere it
        // heads along the feet.
        let trunk = feet[0].support;
        let on_trunk = supports.paths[trunk].kind == SupportKind::Trunk && feet.iter().all(|f| f.support == trunk);
        let wanted = if on_trunk {
            let mean_s = feet.iter().map(|f| f.s).sum::<f32>() / 4.0;
            let tangent = supports.paths[trunk].at(mean_s).tangent;
            if tangent.y >= 0.0 { tangent } else { -tangent }
        } else {
            body::heading_of(rh, rf, lh, lf).unwrap_or(self.frame.forward)
        };
        let forward = if dt > 0.0 { body::ease_towards(self.frame.forward, wanted, dt, HEADING_EASE) } else { wanted };
        // Each foot pulls the body's belly towards its support: up for a branch, from its grip
        // towards the axis for a trunk (the grips, round the side facing the body, then agree).
        let pull: Vec3 = feet
            .iter()
            .map(|foot| {
                let path = &supports.paths[foot.support];
                match path.kind {
                    SupportKind::Branch => Vec3::Y,
                    SupportKind::Trunk => {
                        let axis = path.at(foot.s);
                        body::perpendicular_towards(axis.point - foot.grip, axis.tangent)
                    }
                }
            })
            .sum();
        let up = body::perpendicular_towards(pull, forward);
        let mean = targets.iter().copied().sum::<Vec3>() / 4.0;
        BodyFrame { centre: mean - up * self.proportions.hang, forward, up }
    }

    /// Mean speed while moving, metres per second.
    pub fn mean_speed(&self) -> f32 {
        if self.moving_time > 0.0 { self.distance / self.moving_time } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::{Shape, SupportSpec, Tree};

    /// A sloth `tuning` walks forward for `seconds` along a level pole like the study's, 40 mm
    /// thick; `watch` sees it after every 60 Hz step.
    fn walk(tuning: impl Fn(Tuning) -> Tuning, seconds: f32, mut watch: impl FnMut(&Sloth)) -> Sloth {
        let pole = Shape::Polyline { points: vec![Vec3::ZERO, Vec3::new(6.0, 0.0, 0.0)], radii: vec![0.02, 0.02] };
        let tree = Tree::build(&[SupportSpec { name: "pole".into(), shape: pole, kind: None }]).unwrap();
        let supports = Supports::new([("t", &tree)]);
        let placement = Placement { support: 0, fraction: 0.1, facing: 1.0, around: 0.0 };
        let proportions = Proportions::default();
        let mut sloth =
            Sloth::place(&supports, placement, proportions, tuning(Tuning::animal(0.11, &proportions))).unwrap();
        let forward = Drive { direction: 1.0, ..Drive::default() };
        for _ in 0..(seconds * 60.0) as usize {
            sloth.step(1.0 / 60.0, forward, &supports);
            watch(&sloth);
        }
        sloth
    }

    #[test]
    fn feet_stepping_one_at_a_time_wait_the_delay_between_steps() {
        let delay = 0.2;
        let mut most_swinging = 0;
        let mut touchdowns = Vec::new();
        let mut lifts = Vec::new();
        let mut planted = [true; 4];
        let sloth = walk(
            |t| Tuning { step_delay: Some(delay), ..t },
            12.0,
            |sloth| {
                most_swinging = most_swinging.max(sloth.feet.iter().filter(|f| !f.planted()).count());
                for (was, foot) in planted.iter_mut().zip(&sloth.feet) {
                    match (*was, foot.planted()) {
                        (true, false) => lifts.push(sloth.time),
                        (false, true) => touchdowns.push(sloth.time),
                        _ => {}
                    }
                    *was = foot.planted();
                }
            },
        );
        assert_eq!(most_swinging, 1, "one foot in the air at a time");
        assert!(touchdowns.len() >= 12, "{} steps", touchdowns.len());
        // Each lift follows the touch-down before it by the delay, to a fixed step.
        for touchdown in &touchdowns {
            if let Some(next) = lifts.iter().find(|&&lift| lift > *touchdown) {
                assert!((next - touchdown - delay).abs() <= 1.5 / 60.0, "lift {next} after touch-down {touchdown}");
            }
        }
        assert!(sloth.distance > 0.8, "walked {} m", sloth.distance);
    }

    #[test]
    fn random_strides_vary_within_the_animals_range_and_follow_from_the_seed() {
        let strides = |seed| {
            let mut drawn = Vec::new();
            let tuning = |t| Tuning { stride_mode: StrideMode::Random, stride_seed: seed, max_step: Some(0.9), ..t };
            walk(tuning, 20.0, |sloth| {
                if drawn.last() != Some(&sloth.drawn_stride) {
                    drawn.push(sloth.drawn_stride);
                }
            });
            drawn
        };
        let first = strides(7);
        assert!(first.len() >= 3, "{first:?}");
        assert!(first.iter().all(|s| (ANIMAL_STRIDES.0..ANIMAL_STRIDES.1).contains(s)), "{first:?}");
        assert!(first.windows(2).all(|pair| pair[0] != pair[1]), "{first:?}");
        assert_eq!(strides(7), first);
        assert_ne!(strides(8), first);
    }
}
