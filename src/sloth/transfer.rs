//! Transfers between a branch and the trunk it grows from.
//!
//! Walking along a branch towards its trunk, the sloth stops when its head comes near the
//! trunk; climbing a trunk, when its head comes near a branch growing out above it on its
//! side. From there it moves onto the other support in three moves, the source's transfer:
//! 1. and 2. the left and then the right forelimb reach over to the new support while the body
//!    holds still or turns a little about its hips (fore limbs first; the hind limbs stay where
//!    they are while a fore limb is still on the old support);
//! 3. both hind limbs let go together and swing over while the body turns about its shoulders
//!    into its pose on the new support, its hips bowed out from the trunk by up to
//!    [`HIP_BOW`] (the hindquarters' offset), so that they swing round the trunk, not into it.
//!    Where rolling straight from one pose into the other would carry a hand across the body
//!    (beyond what its shoulder turns), the body rolls its belly towards the hands mid-move.
//!
//! The source also names the lateral sequence for these moves; its transfer rules (fore limbs
//! first, the hind limbs together) fix the order here, a lateral pair of forelimbs and then the
//! hind pair at once.
//!
//! On a trunk the sloth ends up head up below the branch, its head kept clear of the branch
//! all the way (ending a little round the trunk, or with the shoulders' path bowed aside, moves
//! the head aside from it); on a branch, facing out along it. The hind feet end where a
//! placement there would put them and the forefeet near that, the body where those grips hold
//! it, so the walk resumes as from a placement. Where the forefeet's grips leave them bunched
//! up against the hind feet, so that the walk would soon stop (onto a thick branch the
//! forelimbs reach only its base), two more moves step them out, the left and then the right,
//! to where the placement has them.
//!
//! A transfer is planned whole before it starts and checked at closely spaced moments of every
//! move: each planted foot reaches its grip within its joint limits, and the body keeps clear
//! of every support. Of the candidates tried (end poses nearest the junction first), the first
//! that passes is taken; if none does, the sloth stays where it stopped.

use super::body::{self, NearSupports};
use super::ccd;
use super::feet::{Foot, GRIP_TOLERANCE, Step, in_wood};
use super::foothold;
use super::locomotion::{Drive, Placement, Sloth};
use super::moves::{Move, SHOULDER_DELAY, Transfer};
use super::rig::{BodyFrame, Limb, Proportions};
use super::supports::Supports;
use crate::tree::SupportKind;
use bevy::math::{Quat, Vec3};

/// Greatest sideways bow of the hips away from the trunk in the body's move, metres.
pub const HIP_BOW: f32 = 0.15;

/// How far below the junction the body's centre may end on the trunk, metres: tried from the
/// nearest up, in [`TRY_STEP`] steps.
const TRUNK_DROP: (f32, f32) = (0.45, 1.0);

/// How far out along a branch from its start the forefeet may be for the sloth to transfer
/// onto the trunk, metres: the head reaches the trunk well before.
const TRUNK_NEAR: f32 = 0.8;

/// Where round the trunk the body may end, from the side the branch grows out of, degrees,
/// in the order tried: off to one side, the head turns aside from the branch.
const TRUNK_BEARING_DEG: [f32; 5] = [0.0, 30.0, -30.0, 60.0, -60.0];

/// How far out along the branch from the trunk's surface the body's centre may end, metres.
const BRANCH_OUT: (f32, f32) = (0.25, 0.9);

/// The time step of the walk tried on from a planned transfer's end, seconds.
const WALK_ON_STEP: f32 = 1.0 / 60.0;

/// Spacing of the end poses tried, metres.
const TRY_STEP: f32 = 0.05;

/// How the body may turn about its hips while the forelimbs reach for the new support,
/// degrees (positive: head towards the grips), in the order tried.
const REACH_PITCH_DEG: [f32; 9] = [0.0, -10.0, 10.0, -20.0, 20.0, -30.0, 30.0, -40.0, 40.0];

/// How far the body may draw back along itself while the forelimbs reach, metres (negative:
/// on towards the new support, as below a thick branch), in the order tried.
const REACH_BACK: [f32; 5] = [0.0, 0.05, 0.1, -0.05, -0.1];

/// The least clearance a plan keeps between the body and the supports, metres. The body
/// follows the plan exactly (it is not pushed out to [`BODY_MARGIN`](body::BODY_MARGIN) on the
/// way), so this is what it keeps.
const PLAN_CLEARANCE: f32 = 0.002;

/// How closely a plan's planted feet must reach their grips, metres.
const PLAN_REACH: f32 = 1.5 * GRIP_TOLERANCE;

/// How far along its support a forelimb's grip may move from where a placement puts it,
/// metres (negative: back towards the junction, down to the base of a thick branch, all that
/// a forelimb reaching from the trunk gets to), in the order tried.
const GRIP_SHIFTS: [f32; 14] = [0.0, -0.05, 0.05, -0.1, 0.1, -0.15, 0.15, -0.2, -0.25, -0.3, -0.35, -0.4, -0.45, -0.5];

/// How far round a trunk from the side facing the body a forelimb may grip, as parts of how
/// far round it grips walking ([`foothold::trunk_grip_round`]), in the order tried.
const TRUNK_GRIP_ROUND: [f32; 4] = [1.0, 0.77, 0.54, 0.31];

/// How far the shoulders may bow out from the trunk (negative: in towards it) and to the
/// body's right (negative: left) in the body's turn, metres, in the order tried: the head
/// moves aside from the support above it.
const SHOULDER_BOW: [(f32, f32); 9] = [
    (0.0, 0.0),
    (0.05, 0.0),
    (-0.05, 0.0),
    (0.0, 0.05),
    (0.0, -0.05),
    (0.05, 0.05),
    (0.05, -0.05),
    (0.0, 0.1),
    (0.0, -0.1),
];

/// By what part of the body's move onto the new support it has turned into its end pose, in
/// the order tried: all through the move, or early, rolling over while its head still points
/// at its hands (which a thick trunk's grips, all on its near face, need).
const TURNED_BY: [f32; 2] = [1.0, 1.0 - SHOULDER_DELAY];

/// How much farther than its grip a forelimb must reach from the reaching body, metres: a
/// grip at the edge of its reach is lost as soon as the body turns.
const REACH_SPARE: f32 = 0.03;

/// Grips tried per forelimb, of those it reaches.
const GRIPS_TRIED: usize = 3;

/// Moments checked per move of a plan, after a first look at [`COARSE_CHECKS`].
const CHECKS_PER_MOVE: usize = 24;

/// Moments of the first, coarse check of a move.
const COARSE_CHECKS: usize = 6;

/// How far above the shoulders the junction of a branch may be for the sloth on the trunk to
/// transfer onto it, metres (below them when a rising branch leaves room), and how far round
/// from the side the body hangs on, as a cosine.
const BRANCH_ABOVE: (f32, f32) = (-0.3, 0.8);
const BRANCH_BEARING_COS: f32 = 0.5;

/// The feet of `limbs` swinging to where `feet` grip, indexed like [`Limb::ALL`].
fn swinging_to(feet: &[Foot; 4], limbs: &[Limb]) -> [Option<Step>; 4] {
    let mut swings = [None; 4];
    for &limb in limbs {
        let foot = &feet[limb.index()];
        swings[limb.index()] = Some(Step { support: foot.support, s: foot.s, grip: foot.grip });
    }
    swings
}

/// Where a transfer ends: the support, a sloth placed there, and the way out from the trunk
/// (the way the hips bow).
struct Ending {
    target: usize,
    placed: Sloth,
    out: Vec3,
}

impl Ending {
    /// The body where the grips of `feet` hold the placed sloth, pushed clear of the supports,
    /// if it keeps [`PLAN_CLEARANCE`] from them.
    fn held_by(&self, feet: &[Foot; 4], proportions: &Proportions, supports: &Supports) -> Option<BodyFrame> {
        let mut frame = self.placed.pose(feet, &feet.map(|f| f.grip), supports, 0.0);
        let near = NearSupports::around(&frame, proportions, supports);
        (body::push_clear(&mut frame, proportions, &near) >= PLAN_CLEARANCE).then_some(frame)
    }

    /// Whether the sloth, its body at `frame` and its feet on `feet`, walks on forward from
    /// there for two gait cycles without stopping, every planted foot holding its grip (a forefoot
    /// may find its first grip and the walk still stop a few steps on, the feet's order
    /// bunching them up).
    fn walks_on_from(&self, frame: BodyFrame, feet: &[Foot; 4], supports: &Supports) -> bool {
        let mut after = self.placed.clone();
        (after.frame, after.feet) = (frame, *feet);
        let drive = Drive { direction: 1.0, ..Drive::default() };
        let steps = (2.0 * after.timing().cycle / WALK_ON_STEP).ceil() as usize;
        (0..steps).all(|_| {
            after.step(WALK_ON_STEP, drive, supports);
            let holding = after.feet.iter().filter(|f| f.planted()).all(|f| f.position.distance(f.grip) <= PLAN_REACH);
            after.blocked.is_none() && holding
        })
    }
}

impl Sloth {
    /// A transfer from where the sloth stopped, moving forward, onto the trunk its branch grows
    /// from or onto a branch growing from its trunk above it; `None` if there is no such
    /// support nearby or no transfer onto it passes the checks.
    pub fn plan_transfer(&self, supports: &Supports) -> Option<Transfer> {
        // The hind feet may still hold a branch beside the forefeet's, where two leave the
        // trunk side by side: they hold on there until they swing over.
        let support = self.support();
        if !self.feet.iter().all(Foot::planted) || self.feet[Limb::LeftFore.index()].support != support {
            return None;
        }
        let (target, ends, out) = self.transfer_ends(supports)?;
        let reaching = self.reaching_poses(supports);
        ends.into_iter().find_map(|placement| self.plan_onto(target, placement, &reaching, out, supports))
    }

    /// Whether there is a support nearby to transfer onto (whether a transfer onto it passes
    /// the checks is another matter).
    pub fn transfer_in_reach(&self, supports: &Supports) -> bool {
        self.transfer_ends(supports).is_some()
    }

    /// The support to transfer onto from the one the forelimbs lead on, the placements to end
    /// in there, nearest the junction first, and the way out from the trunk.
    fn transfer_ends(&self, supports: &Supports) -> Option<(usize, Vec<Placement>, Vec3)> {
        let support = self.support();
        match supports.paths[support].kind {
            SupportKind::Branch => self.trunk_ends(support, supports),
            SupportKind::Trunk => self.branch_ends(support, supports),
        }
    }

    /// The trunk the branch `branch` grows from, if the sloth is heading in to it near the
    /// junction, with the placements to end in there (head up below the branch) and the way
    /// out from the trunk.
    fn trunk_ends(&self, branch: usize, supports: &Supports) -> Option<(usize, Vec<Placement>, Vec3)> {
        let path = &supports.paths[branch];
        let trunk = path.parent.filter(|&p| supports.paths[p].kind == SupportKind::Trunk)?;
        let start = path.at(0.0);
        let fore_s = self.feet[Limb::RightFore.index()].s.min(self.feet[Limb::LeftFore.index()].s);
        if self.frame.forward.dot(start.tangent) > 0.0 || fore_s > TRUNK_NEAR {
            return None;
        }
        let trunk_path = &supports.paths[trunk];
        let (_, junction) = trunk_path.nearest(start.point);
        // The body hangs on the side of the trunk the branch grows out of, or off to a side.
        let out = Vec3::new(start.tangent.x, 0.0, start.tangent.z).try_normalize()?;
        let around = out.x.atan2(out.z);
        let drops = ((TRUNK_DROP.1 - TRUNK_DROP.0) / TRY_STEP).round() as usize;
        let ends = TRUNK_BEARING_DEG
            .into_iter()
            .flat_map(|bearing| {
                (0..=drops).map(move |k| Placement {
                    support: trunk,
                    fraction: (junction - TRUNK_DROP.0 - k as f32 * TRY_STEP) / trunk_path.length(),
                    facing: 1.0,
                    around: around + bearing.to_radians(),
                })
            })
            .collect();
        Some((trunk, ends, out))
    }

    /// The nearest branch growing from the trunk `trunk` above the shoulders on the body's
    /// side, with the placements to end in on it (facing out along it) and the way out from
    /// the trunk.
    fn branch_ends(&self, trunk: usize, supports: &Supports) -> Option<(usize, Vec<Placement>, Vec3)> {
        let trunk_path = &supports.paths[trunk];
        let shoulders = self.frame.shoulders(&self.proportions);
        let (_, shoulders_s) = trunk_path.nearest(shoulders);
        let axis = trunk_path.at(shoulders_s);
        let out = body::perpendicular_towards(shoulders - axis.point, axis.tangent);
        let (branch, junction) = (0..supports.paths.len())
            .filter(|&i| supports.paths[i].parent == Some(trunk) && supports.paths[i].kind == SupportKind::Branch)
            .filter_map(|i| {
                let start = supports.paths[i].at(0.0);
                let (_, junction) = trunk_path.nearest(start.point);
                let above = (junction - shoulders_s) * axis.tangent.y.signum();
                let bearing = body::perpendicular_towards(start.tangent, axis.tangent).dot(out);
                ((BRANCH_ABOVE.0..BRANCH_ABOVE.1).contains(&above) && bearing > BRANCH_BEARING_COS)
                    .then_some((i, junction))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let path = &supports.paths[branch];
        let surface = trunk_path.at(junction).radius;
        let outs = ((BRANCH_OUT.1 - BRANCH_OUT.0) / TRY_STEP).round() as usize;
        let ends = (0..=outs)
            .map(|k| Placement {
                support: branch,
                fraction: (surface + BRANCH_OUT.0 + k as f32 * TRY_STEP) / path.length(),
                facing: 1.0,
                around: 0.0,
            })
            .collect();
        Some((branch, ends, out))
    }

    /// The poses the body may hold while the forelimbs move over, with the move into each:
    /// turned about the hips and drawn back along the body, each checked with the hind feet
    /// and the right forefoot still on the old support (the left forefoot swinging).
    fn reaching_poses(&self, supports: &Supports) -> Vec<BodyFrame> {
        let left_swinging = swinging_to(&self.feet, &[Limb::LeftFore]);
        let mut poses = Vec::new();
        for pitch in REACH_PITCH_DEG {
            for back in REACH_BACK {
                let turn = Quat::from_axis_angle(self.frame.right(), -pitch.to_radians());
                let hips = self.frame.hips(&self.proportions) - self.frame.forward * back;
                let forward = turn * self.frame.forward;
                let centre = hips + forward * (self.proportions.torso_length * 0.5);
                let pose = BodyFrame { centre, forward, up: turn * self.frame.up };
                let reach = Move::plain(self.frame, pose, left_swinging, 1.0);
                if self.move_holds(&reach, &self.feet, supports) {
                    poses.push(pose);
                }
            }
        }
        poses
    }

    /// The three moves onto the sloth placed as `placement` says, if some way of making them
    /// passes the checks; `out` points away from the trunk, the way the hips bow.
    fn plan_onto(
        &self,
        target: usize,
        placement: Placement,
        reaching: &[BodyFrame],
        out: Vec3,
        supports: &Supports,
    ) -> Option<Transfer> {
        if !(0.0..=1.0).contains(&placement.fraction) {
            return None;
        }
        // Placements whose grips near the junction cannot come clear of the other support's
        // wood are refused by `place`.
        let mut placed = Sloth::place(supports, placement, self.proportions, self.tuning()).ok()?;
        placed.trial_depth = self.trial_depth + 1;
        let ending = Ending { target, placed, out };
        reaching.iter().find_map(|&pose| {
            let [lefts, rights] =
                [Limb::LeftFore, Limb::RightFore].map(|limb| self.fore_grips(limb, &pose, &ending.placed, supports));
            let pairs = lefts.iter().flat_map(|&left| rights.iter().map(move |&right| (left, right)));
            pairs.into_iter().find_map(|(left, right)| self.moves_onto(&ending, pose, [left, right], supports))
        })
    }

    /// Up to [`GRIPS_TRIED`] grips for forelimb `limb` on the new support, nearest the placed
    /// sloth's first: each reached from the placed body, and from the reaching body `pose` with
    /// [`REACH_SPARE`] to spare (that body turns on from there).
    fn fore_grips(&self, limb: Limb, pose: &BodyFrame, placed: &Sloth, supports: &Supports) -> Vec<Step> {
        let rig = &self.rigs[limb.index()];
        let length: f32 = rig.bones.iter().sum();
        let reaches = |frame: &BodyFrame, target: Vec3| {
            // Beyond the limb's length nothing is reached: no need to solve.
            let mut angles = rig.rest;
            target.distance(rig.root_in(frame)) <= length
                && ccd::solve(rig, frame, &mut angles, target, &self.ccd).error <= GRIP_TOLERANCE
        };
        let reached = |step: &Step| {
            let beyond = step.grip + (step.grip - rig.root_in(pose)).normalize_or_zero() * REACH_SPARE;
            reaches(pose, step.grip) && reaches(pose, beyond) && reaches(&placed.frame, step.grip)
        };
        let grips = placed.grip_variations(limb, supports).into_iter().filter(|step| !in_wood(step.grip, supports));
        grips.filter(reached).take(GRIPS_TRIED).collect()
    }

    /// The transfer whose forelimbs reach from the body at `pose` to the grips `fore` (left,
    /// right) and whose body then turns into the pose those grips and the placed sloth's hind
    /// grips hold, if one of the shoulder paths tried passes the checks.
    fn moves_onto(&self, ending: &Ending, pose: BodyFrame, fore: [Step; 2], supports: &Supports) -> Option<Transfer> {
        let [left, right] = fore;
        // The body ends where the grips put it, as it will once walking resumes.
        let mut feet = ending.placed.feet;
        let mut holding = self.feet;
        for (limb, step) in [(Limb::LeftFore, left), (Limb::RightFore, right)] {
            for foot in [&mut feet[limb.index()], &mut holding[limb.index()]] {
                (foot.support, foot.s, foot.grip) = (step.support, step.s, step.grip);
            }
        }
        let end = ending.held_by(&feet, &self.proportions, supports)?;
        let swing = self.timing().swing;
        let swinging = |limbs: &[Limb]| swinging_to(&feet, limbs);
        let still = |swings| Move::plain(pose, pose, swings, swing);
        let reach = Move { from: self.frame, ..still(swinging(&[Limb::LeftFore])) };
        let hind = swinging(&[Limb::RightHind, Limb::LeftHind]);
        let grips = (left.grip + right.grip) * 0.5;
        let paths = [None, Some(grips)].into_iter().flat_map(|belly_towards| {
            TURNED_BY.into_iter().flat_map(move |turned_by| SHOULDER_BOW.map(|bow| (belly_towards, turned_by, bow)))
        });
        let turn = paths.into_iter().find_map(|(belly_towards, turned_by, (outwards, sideways))| {
            let front_bow = ending.out * outwards + pose.right() * sideways;
            let bow = ending.out * HIP_BOW;
            let turn = Move {
                from: pose,
                to: end,
                swings: hind,
                bow,
                front_bow,
                turned_by,
                belly_towards,
                duration: 2.0 * swing,
            };
            self.move_holds(&turn, &holding, supports).then_some(turn)
        })?;
        let mut moves = vec![reach, still(swinging(&[Limb::RightFore])), turn];
        if !ending.walks_on_from(end, &feet, supports) {
            moves.extend(self.stepping_out(ending, end, &feet, supports)?);
        }
        Some(Transfer::new(ending.target, moves))
    }

    /// The forefeet stepping on from their grips in `feet`, the left and then the right, to
    /// where the placed sloth has them, the body moving from `end` into the placed pose: two
    /// moves, if they pass the checks.
    fn stepping_out(
        &self,
        ending: &Ending,
        end: BodyFrame,
        feet: &[Foot; 4],
        supports: &Supports,
    ) -> Option<[Move; 2]> {
        let placed = &ending.placed;
        let mut halfway = *feet;
        halfway[Limb::LeftFore.index()] = placed.feet[Limb::LeftFore.index()];
        let middle = ending.held_by(&halfway, &self.proportions, supports)?;
        let swing = self.timing().swing;
        let step = |limb, from, to| Move::plain(from, to, swinging_to(&placed.feet, &[limb]), swing);
        let moves = [step(Limb::LeftFore, end, middle), step(Limb::RightFore, middle, placed.frame)];
        (self.move_holds(&moves[0], feet, supports) && self.move_holds(&moves[1], &halfway, supports)).then_some(moves)
    }

    /// Whether, all through `current`, every foot of `feet` not swinging in it reaches its
    /// grip and the body keeps clear of the supports: first at a few moments, which rejects
    /// most candidates cheaply, then at [`CHECKS_PER_MOVE`].
    fn move_holds(&self, current: &Move, feet: &[Foot; 4], supports: &Supports) -> bool {
        [COARSE_CHECKS, CHECKS_PER_MOVE].into_iter().all(|checks| self.holds_at(current, feet, checks, supports))
    }

    /// [`Sloth::move_holds`] at `checks + 1` evenly spaced moments.
    fn holds_at(&self, current: &Move, feet: &[Foot; 4], checks: usize, supports: &Supports) -> bool {
        let half_torso = self.proportions.torso_length * 0.5;
        let mut angles = feet.map(|f| f.angles);
        let mut near = NearSupports::default();
        (0..=checks).all(|k| {
            let frame = current.frame_at(k as f32 / checks as f32, half_torso);
            near.refresh(&frame, &self.proportions, supports);
            body::clearance(&frame, &self.proportions, &near) >= PLAN_CLEARANCE
                && Limb::ALL.into_iter().filter(|l| current.swings[l.index()].is_none()).all(|limb| {
                    let i = limb.index();
                    ccd::solve(&self.rigs[i], &frame, &mut angles[i], feet[i].grip, &self.ccd).error <= PLAN_REACH
                })
        })
    }

    /// Grips for `limb` near the one it holds, nearest first: on a trunk a little higher or
    /// lower and less far round, on a branch a little along it either way.
    fn grip_variations(&self, limb: Limb, supports: &Supports) -> Vec<Step> {
        let foot = &self.feet[limb.index()];
        let path = &supports.paths[foot.support];
        let (low, high) = path.grip_range(0.0);
        let mut steps = Vec::new();
        for along in GRIP_SHIFTS {
            let s = foot.s + along;
            if !(low..=high).contains(&s) {
                continue;
            }
            match path.kind {
                SupportKind::Branch => steps.push(Step {
                    support: foot.support,
                    s,
                    grip: path.surface_towards(s, self.side_on(path, s, limb)),
                }),
                SupportKind::Trunk => {
                    let axis = path.at(s);
                    let facing = body::perpendicular_towards(self.frame.centre - axis.point, axis.tangent);
                    let side = axis.tangent.cross(facing) * -limb.side();
                    let walking = foothold::trunk_grip_round(&self.proportions, axis.radius);
                    for part in TRUNK_GRIP_ROUND {
                        let (sin, cos) = (walking * part).sin_cos();
                        steps.push(Step {
                            support: foot.support,
                            s,
                            grip: path.surface_towards(s, facing * cos + side * sin),
                        });
                    }
                }
            }
        }
        steps
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sloth::locomotion::{Drive, PLANNING_DEPTH, PlaceError, Tuning};
    use crate::sloth::rig::Proportions;
    use crate::tree::{Shape, SupportSpec, Tree};

    /// A vertical trunk with a branch growing from it at `angle` degrees to the trunk below.
    fn tree(angle: f32) -> Tree {
        junction(vec![0.15, 0.13, 0.1], angle, 2.0)
    }

    /// A vertical trunk 4 m tall with `radii` at its foot, middle and top, and a branch
    /// `length` metres long growing from its middle at `angle` degrees to the trunk below.
    fn junction(radii: Vec<f32>, angle: f32, length: f32) -> Tree {
        let trunk =
            Shape::Polyline { points: vec![Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 4.0, 0.0)], radii };
        let limb = Shape::Fork {
            parent: "trunk".into(),
            at: 0.5,
            yaw_deg: 90.0,
            pitch_deg: angle - 90.0,
            length,
            radius: [0.06, 0.035],
            bend_deg: [0.0, 0.0],
            sections: 1,
        };
        let spec = |name: &str, shape| SupportSpec { name: name.into(), shape, kind: None };
        Tree::build(&[spec("trunk", trunk), spec("limb", limb)]).unwrap()
    }

    #[test]
    fn a_move_starts_and_ends_at_its_poses_and_keeps_the_torso_whole() {
        let from = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y };
        let to = BodyFrame { centre: Vec3::new(0.3, -0.2, 0.0), forward: Vec3::Y, up: Vec3::NEG_X };
        let bow = Vec3::new(0.0, 0.0, HIP_BOW);
        let moving = Move {
            from,
            to,
            swings: [None; 4],
            bow,
            front_bow: Vec3::ZERO,
            turned_by: 1.0,
            belly_towards: None,
            duration: 1.0,
        };
        // Turning the belly towards a point below the body changes neither end of the move.
        let grips = Vec3::new(0.2, -1.0, 0.0);
        let towards_grips = Move { belly_towards: Some(grips), ..moving };
        let half = 0.2;
        for moving in [moving, towards_grips] {
            for (t, expected) in [(0.0, from), (1.0, to)] {
                let frame = moving.frame_at(t, half);
                assert!(
                    frame.centre.distance(expected.centre) < 1e-5 && frame.forward.distance(expected.forward) < 1e-5
                );
                assert!(frame.up.distance(expected.up) < 1e-5, "{t}: {frame:?}");
            }
            for k in 0..=20 {
                let frame = moving.frame_at(k as f32 / 20.0, half);
                assert!((frame.forward.length() - 1.0).abs() < 1e-5 && frame.forward.dot(frame.up).abs() < 1e-5);
            }
            // Mid-move the hips bow out sideways.
            let middle = moving.frame_at(0.5, half);
            assert!((middle.centre - middle.forward * half).z > 0.1);
        }
        // Mid-move the belly faces the point, square to the long axis.
        let middle = towards_grips.frame_at(0.5, half);
        let shoulders = middle.centre + middle.forward * half;
        let towards = body::perpendicular_towards(grips - shoulders, middle.forward);
        assert!(middle.up.dot(towards) > 0.999, "{middle:?}");
        assert!(moving.frame_at(0.5, half).up.dot(towards) < 0.9, "without it the belly faces elsewhere");
    }

    #[test]
    fn walking_in_to_the_trunk_it_stops_and_transfers_head_up_keeping_every_grip() {
        let tree = tree(110.0);
        let supports = Supports::new([("t", &tree)]);
        let (trunk, limb) = (supports.find("t/trunk").unwrap(), supports.find("t/limb").unwrap());
        let placement = Placement { support: limb, fraction: 0.6, facing: -1.0, around: 0.0 };
        let mut sloth =
            Sloth::place(&supports, placement, Proportions::default(), Tuning::animal(0.11, &Proportions::default()))
                .unwrap();
        let mut transferred = false;
        for _ in 0..60 * 20 {
            sloth.step(1.0 / 60.0, Drive { direction: 1.0, ..Drive::default() }, &supports);
            transferred |= sloth.transfer.is_some();
            for foot in sloth.feet.iter().filter(|f| f.planted()) {
                assert!(supports.paths[foot.support].distance(foot.position).abs() < 0.01);
            }
            assert!(sloth.clearance >= 0.0);
            if transferred && sloth.transfer.is_none() {
                break;
            }
        }
        assert!(transferred);
        assert!(sloth.feet.iter().all(|f| f.support == trunk), "{:?}", sloth.feet.map(|f| f.support));
        assert!(sloth.frame.forward.y > 0.95, "head up: {}", sloth.frame.forward);
        let head = sloth.frame.head(&sloth.proportions);
        assert!(head.y < 2.0, "the head stays below the branch: {head}");
    }

    #[test]
    fn a_walk_tried_out_deep_among_plans_stops_at_the_next_junction_without_planning_there() {
        let tree = tree(110.0);
        let supports = Supports::new([("t", &tree)]);
        let limb = supports.find("t/limb").unwrap();
        let placement = Placement { support: limb, fraction: 0.6, facing: -1.0, around: 0.0 };
        let mut sloth =
            Sloth::place(&supports, placement, Proportions::default(), Tuning::animal(0.11, &Proportions::default()))
                .unwrap();
        sloth.trial_depth = PLANNING_DEPTH;
        let mut distances = Vec::new();
        for _ in 0..60 * 20 {
            sloth.step(1.0 / 60.0, Drive { direction: 1.0, ..Drive::default() }, &supports);
            assert!(sloth.transfer.is_none(), "no transfer planned");
            distances.push(sloth.distance);
        }
        assert!(sloth.blocked.is_none(), "waiting at the junction, not blocked");
        assert!(distances[60 * 5] > 0.3, "walked in: {} m", distances[60 * 5]);
        assert_eq!(distances[60 * 15], sloth.distance, "and stopped there");
    }

    #[test]
    fn a_sloth_is_not_placed_where_a_foot_finds_no_grip_clear_of_the_other_supports_wood() {
        // A trunk a metre thick: the first metre of the branch growing from it is inside it.
        let tree = junction(vec![1.0, 1.0, 1.0], 90.0, 4.0);
        let supports = Supports::new([("t", &tree)]);
        let limb = supports.find("t/limb").unwrap();
        let place = |fraction| {
            let placement = Placement { support: limb, fraction, facing: -1.0, around: 0.0 };
            Sloth::place(&supports, placement, Proportions::default(), Tuning::animal(0.11, &Proportions::default()))
        };
        assert!(matches!(place(0.02), Err(PlaceError::InWood { .. })), "{:?}", place(0.02).err());
        let placed = place(0.7).expect("clear of the trunk");
        assert!(placed.feet.iter().all(|f| !in_wood(f.grip, &supports)));
    }

    #[test]
    fn there_is_nothing_to_transfer_onto_from_a_branch_that_grows_from_no_trunk() {
        let shape = Shape::Polyline { points: vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)], radii: vec![0.05, 0.05] };
        let tree = Tree::build(&[SupportSpec { name: "b".into(), shape, kind: None }]).unwrap();
        let supports = Supports::new([("t", &tree)]);
        let placement = Placement { support: 0, fraction: 0.5, facing: 1.0, around: 0.0 };
        let sloth =
            Sloth::place(&supports, placement, Proportions::default(), Tuning::animal(0.11, &Proportions::default()))
                .unwrap();
        assert!(!sloth.transfer_in_reach(&supports));
        assert!(sloth.plan_transfer(&supports).is_none());
    }
}
