//! Where a lifted foot lands: the source's FindNextStep against the tree queries.
//!
//! The first candidate lies a full stride ahead along the foot's support; each retry tries
//! [`RETRY_STEP`] closer, a leading foot never closer than its pair's foot. A leading foot also
//! never lands more than `MAX_LEAD` strides ahead of its pair, which keeps the stagger such
//! that the pair can always overtake it again. A candidate is valid when
//! - it lies on the support, away from its free ends and outside every other support, on the
//!   limb's side (right limbs grip the right side of the branch, left limbs the left), half
//!   the branch's thickness from its axis;
//! - it moves the foot at least [`MIN_STEP`] the way the sloth is going;
//! - the leg order holds: a leading foot never lands behind its pair, a trailing foot never
//!   passes the leading foot on its side (hind feet stay behind fore feet walking forward);
//! - with the body where the feet will put it at touch-down, every limb still reaches its grip
//!   within its joint limits, and the stepping limb also at the end of the contact that
//!   follows (checked by solving the IK).
//!
//! While changing branch, a foot first looks for a grip on the new support beside its stride,
//! forelimbs first; hind limbs follow once both forelimbs hold the new support.

use super::body::{self, NearSupports};
use super::ccd;
use super::feet::{Foot, GRIP_TOLERANCE, Probe, Refusal, Step, in_wood, wood_at};
use super::locomotion::Sloth;
use super::rig::{BodyFrame, Limb, Proportions};
use super::supports::{SupportPath, Supports};
use crate::tree::SupportKind;
use bevy::math::{Quat, Vec3};

/// Shortest step, metres: a search that can only find shorter ones fails.
pub const MIN_STEP: f32 = 0.02;

/// How much closer each retry of the foothold search tries, metres.
pub const RETRY_STEP: f32 = 0.01;

/// How far the feet keep from a support's ends, metres.
pub const END_MARGIN: f32 = 0.06;

/// How far behind the leading foot on its side a trailing foot stays, metres.
const ORDER_GAP: f32 = 0.05;

/// How far, in strides, a leading foot may land ahead of its pair: enough for the usual
/// half-stride stagger, little enough that the pair can always overtake it again.
const MAX_LEAD: f32 = 0.75;

/// The leg order: a leading foot (a forefoot walking forward, a hind foot walking back) never
/// lands behind its pair, and a trailing foot stays [`ORDER_GAP`] behind the leading foot on
/// its side, so hind feet never pass fore feet. `pair_lead` is how far the step lies ahead of
/// the pair's foot, `side_lead` ahead of the foot on the same side, both in metres along the
/// motion. While changing branch a leading foot may land beside its pair.
fn keeps_leg_order(leading: bool, changing: bool, pair_lead: f32, side_lead: f32) -> bool {
    if leading { changing || pair_lead >= 0.0 } else { side_lead <= -ORDER_GAP }
}

/// Below this cosine between a branch and the body, the branch runs across the body.
const ACROSS: f32 = 0.3;

/// How far round a slender trunk from the side facing the body the grips lie, degrees.
const TRUNK_GRIP_DEG: f32 = 65.0;

/// How far to the side of the body's midline a grip on a trunk lies at most, in girdle
/// widths (twice [`Proportions::girdle_half_width`]): round a thick
/// trunk the limbs cannot reach [`TRUNK_GRIP_DEG`] round, so they grip its near face.
const TRUNK_GRIP_SPAN: f32 = 1.0;

/// How far round a trunk of `radius` metres from the side facing the body an animal of
/// `proportions` grips it, radians: [`TRUNK_GRIP_DEG`], or less where that would put the grip
/// more than [`TRUNK_GRIP_SPAN`] girdle widths to the side.
pub(super) fn trunk_grip_round(proportions: &Proportions, radius: f32) -> f32 {
    let span = TRUNK_GRIP_SPAN * 2.0 * proportions.girdle_half_width;
    (span / radius).min(1.0).asin().min(TRUNK_GRIP_DEG.to_radians())
}

/// How far round a branch, at most, a grip moves from its side to come clear of the wood of a
/// branch forking from it, degrees, and in how many steps either way.
const FORK_ROUND_DEG: f32 = 60.0;
const FORK_ROUND_STEPS: usize = 4;

/// The grip on branch `path` (support `support`) at `s` on the side `towards`; where the wood
/// of a branch forking from it covers that grip, the nearest one round the branch clear of it,
/// if there is one within [`FORK_ROUND_DEG`]. Wood of any other support is left to the checks.
fn clear_of_forks(path: &SupportPath, support: usize, s: f32, towards: Vec3, supports: &Supports) -> Vec3 {
    let grip = path.surface_towards(s, towards);
    if wood_at(grip, supports).is_none_or(|wood| supports.paths[wood].parent != Some(support)) {
        return grip;
    }
    let tangent = path.at(s).tangent;
    (1..=FORK_ROUND_STEPS)
        .flat_map(|k| {
            let angle = (FORK_ROUND_DEG * k as f32 / FORK_ROUND_STEPS as f32).to_radians();
            [angle, -angle]
        })
        .map(|angle| path.surface_towards(s, Quat::from_axis_angle(tangent, angle) * towards))
        .find(|&grip| !in_wood(grip, supports))
        .unwrap_or(grip)
}

/// Arc a foot moves round a trunk in one side step, metres.
const SIDE_STEP: f32 = 0.04;

/// Farthest the body may be pushed out of the supports where a step would put it, metres.
const MAX_PUSH_AT_STEP: f32 = 0.03;

/// How far from the shoulders, sideways, a neighbouring branch is looked for, metres.
const NEIGHBOUR_REACH: f32 = 0.45;

impl Sloth {
    /// The next grip for `limb` moving in `direction` (+1 forward, -1 back), if there is one;
    /// every candidate tried goes into `probes`.
    pub fn find_next_step(
        &self,
        limb: Limb,
        direction: f32,
        supports: &Supports,
        probes: &mut Vec<Probe>,
    ) -> Option<Step> {
        let foot = &self.feet[limb.index()];
        let motion = self.frame.forward * direction;
        if let Some(target) = self.change_to
            && foot.support != target
            && (limb.is_fore()
                || Limb::ALL.iter().filter(|l| l.is_fore()).all(|l| self.feet[l.index()].support == target))
            && let Some(step) = self.step_onto(limb, target, motion, supports, probes)
        {
            return Some(step);
        }
        let path = &supports.paths[foot.support];
        let along = self.along(path, foot.s, direction);
        let pair = &self.feet[limb.pair().index()];
        let range = path.grip_range(END_MARGIN);
        let leading = limb.is_fore() == (direction > 0.0);
        let stride = self.timing().stride;
        let mut step = stride;
        let mut probe =
            |grip: Vec3, refusal: Option<Refusal>| probes.push(Probe { limb, from: foot.grip, grip, refusal });
        while step >= MIN_STEP {
            let s = foot.s + along * step;
            if !(range.0..=range.1).contains(&s) {
                probe(path.at(s.clamp(0.0, path.length())).point, Some(Refusal::OffSupport));
            } else {
                // Up and down a trunk a foot keeps its bearing round it: only side steps turn.
                let grip = match path.kind {
                    SupportKind::Trunk => path.surface_towards(s, foot.grip - path.at(foot.s).point),
                    SupportKind::Branch => clear_of_forks(path, foot.support, s, self.side_on(path, s, limb), supports),
                };
                let candidate = Step { support: foot.support, s, grip };
                let lead = ahead(&candidate, pair, along, motion);
                if leading && lead < 0.0 {
                    probe(grip, Some(Refusal::LegOrder));
                    break;
                }
                let checked = if leading && lead > MAX_LEAD * stride {
                    Err(Refusal::TooFarAhead)
                } else {
                    self.check(limb, &candidate, along, motion, false, supports)
                };
                probe(grip, checked.err());
                if checked.is_ok() {
                    return Some(candidate);
                }
            }
            step -= RETRY_STEP;
        }
        if leading && self.change_to.is_none() {
            return self.continuation(limb, motion, supports, probes);
        }
        None
    }

    /// At the end of its support, a leading foot looks for another support of the same kind
    /// ahead within half a stride (a branch it turns onto, or the one it grows from) and steps
    /// onto it. Between a branch and a trunk the sloth transfers instead.
    fn continuation(&self, limb: Limb, motion: Vec3, supports: &Supports, probes: &mut Vec<Probe>) -> Option<Step> {
        let foot = &self.feet[limb.index()];
        let half_stride = self.timing().stride * 0.5;
        let probe = foot.grip + motion * half_stride;
        let kind = supports.paths[foot.support].kind;
        let mut candidates: Vec<(usize, f32)> = supports
            .others_near(probe, half_stride, foot.support)
            .into_iter()
            .filter(|&index| supports.paths[index].kind == kind)
            .map(|index| (index, supports.paths[index].distance(probe)))
            .collect();
        candidates.sort_by(|a, b| a.1.total_cmp(&b.1));
        candidates.iter().find_map(|&(index, _)| self.step_onto(limb, index, motion, supports, probes))
    }

    /// A grip for `limb` on the support it is changing to, beside its stride or closer.
    fn step_onto(
        &self,
        limb: Limb,
        target: usize,
        motion: Vec3,
        supports: &Supports,
        probes: &mut Vec<Probe>,
    ) -> Option<Step> {
        let foot = &self.feet[limb.index()];
        let path = &supports.paths[target];
        let stride = self.timing().stride;
        let range = path.grip_range(END_MARGIN);
        let direction = if motion.dot(self.frame.forward) >= 0.0 { 1.0 } else { -1.0 };
        (0..=8).rev().find_map(|k| {
            let (_, s) = path.nearest(foot.grip + motion * (stride * k as f32 / 8.0));
            if !(range.0..=range.1).contains(&s) {
                return None;
            }
            let along = self.along(path, s, direction);
            let grip = path.surface_towards(s, self.side_on(path, s, limb));
            let candidate = Step { support: target, s, grip };
            let checked = self.check(limb, &candidate, along, motion, true, supports);
            probes.push(Probe { limb, from: foot.grip, grip, refusal: checked.err() });
            checked.is_ok().then_some(candidate)
        })
    }

    /// Whether `step` keeps the leg order and lies within the limb's reach (else why not); a change of branch
    /// may step sideways without moving ahead, and a leading foot may land beside its pair.
    /// `along` is the way arc length grows in the direction of motion on the step's support.
    fn check(
        &self,
        limb: Limb,
        step: &Step,
        along: f32,
        motion: Vec3,
        changing: bool,
        supports: &Supports,
    ) -> Result<(), Refusal> {
        let foot = &self.feet[limb.index()];
        // Where a branch grows out of another, its grips must not sink into the other's wood.
        if in_wood(step.grip, supports) {
            return Err(Refusal::InWood);
        }
        if ahead(step, foot, along, motion) < if changing { 0.0 } else { MIN_STEP } {
            return Err(Refusal::TooShort);
        }
        let leading = limb.is_fore() == (motion.dot(self.frame.forward) > 0.0);
        let pair_lead = ahead(step, &self.feet[limb.pair().index()], along, motion);
        let side_lead = ahead(step, &self.feet[limb.same_side().index()], along, motion);
        if !keeps_leg_order(leading, changing, pair_lead, side_lead) {
            return Err(Refusal::LegOrder);
        }
        // With the body where the feet will put it at touch-down, every foot must still reach
        // its grip; and the stepping foot also at the end of the contact that follows.
        let mut feet = self.feet;
        feet[limb.index()] = Foot { support: step.support, s: step.s, grip: step.grip, swing: None, ..*foot };
        let grips = feet.map(|f| f.grip);
        let mut touchdown = self.pose(&feet, &grips, supports, 0.0);
        let near = NearSupports::around(&touchdown, &self.proportions, supports);
        let hanging = touchdown.centre;
        body::push_clear(&mut touchdown, &self.proportions, &near);
        // A step that would press the body into a support (its head into the trunk ahead, say)
        // is not taken: the sloth stops there.
        if touchdown.centre.distance(hanging) > MAX_PUSH_AT_STEP {
            return Err(Refusal::PressesBody);
        }
        let timing = self.timing();
        let later = BodyFrame { centre: touchdown.centre + motion * (self.speed * timing.contact()), ..touchdown };
        let reaches = |l: Limb, frame: &BodyFrame| {
            let mut angles = feet[l.index()].angles;
            ccd::solve(&self.rigs[l.index()], frame, &mut angles, grips[l.index()], &self.ccd).error <= GRIP_TOLERANCE
        };
        // The stepping limb first: it is the one most often out of reach.
        let reached = reaches(limb, &touchdown)
            && reaches(limb, &later)
            && Limb::ALL.iter().filter(|&&l| l != limb).all(|&l| reaches(l, &touchdown));
        if reached { Ok(()) } else { Err(Refusal::OutOfReach) }
    }

    /// The limb's side of `path` at `s`: its right for right limbs. Along a branch that is
    /// the right of the way the body faces along it, so a foot keeps its side round a turn;
    /// across a branch it is the body's own right, the two blending by how much the branch runs
    /// along the body. On a trunk the grip lies [`trunk_grip_round`] round from the side
    /// facing the body, so the grips hold the body's bearing round the trunk.
    pub fn side_on(&self, path: &SupportPath, s: f32, limb: Limb) -> Vec3 {
        let axis = path.at(s);
        let tangent = axis.tangent;
        let across = self.frame.right() - tangent * self.frame.right().dot(tangent);
        if path.kind == SupportKind::Trunk {
            let towards_body = body::perpendicular_towards(self.frame.centre - axis.point, tangent);
            let (sin, cos) = trunk_grip_round(&self.proportions, axis.radius).sin_cos();
            return towards_body * cos + across.normalize_or(towards_body.cross(tangent)) * (sin * limb.side());
        }
        let lengthwise = tangent.dot(self.frame.forward);
        let facing = if lengthwise >= 0.0 { tangent } else { -tangent };
        let walked = self.frame.up.cross(facing);
        (walked * lengthwise.abs() + across * (1.0 - lengthwise.abs())).normalize_or(walked) * limb.side()
    }

    /// Which way arc length grows on `path` at `s` as the sloth moves in `direction`: on a
    /// trunk, up is forward (it climbs head up); on a branch, the way the motion points along
    /// it, or out towards the tip where the branch runs across the body (just reached from the
    /// trunk it grows from).
    pub fn along(&self, path: &SupportPath, s: f32, direction: f32) -> f32 {
        let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
        let tangent = path.at(s).tangent;
        match path.kind {
            SupportKind::Trunk => sign(tangent.y) * direction,
            SupportKind::Branch => {
                let lengthwise = tangent.dot(self.frame.forward * direction);
                if lengthwise.abs() < ACROSS && path.parent.is_some() { direction } else { sign(lengthwise) }
            }
        }
    }

    /// A side step of `limb` around its trunk, towards the body's right if `around` is positive:
    /// the grip turns about the trunk's axis by up to `SIDE_STEP` of arc, less if the limb
    /// cannot reach that far.
    pub fn find_side_step(&self, limb: Limb, around: f32, supports: &Supports) -> Option<Step> {
        let foot = &self.feet[limb.index()];
        let path = &supports.paths[foot.support];
        if path.kind != SupportKind::Trunk {
            return None;
        }
        let axis = path.at(foot.s);
        let radial = body::perpendicular_towards(foot.grip - axis.point, axis.tangent);
        let towards = if axis.tangent.cross(radial).dot(self.frame.right() * around) >= 0.0 { 1.0 } else { -1.0 };
        let full = SIDE_STEP / axis.radius.max(0.05);
        [1.0, 0.75, 0.5, 0.25].into_iter().find_map(|fraction| {
            let turn = Quat::from_axis_angle(axis.tangent, towards * full * fraction);
            let grip = path.surface_towards(foot.s, turn * radial);
            let candidate = Step { support: foot.support, s: foot.s, grip };
            let rig = &self.rigs[limb.index()];
            // The body follows the feet round, about half this turn by touch-down.
            let half = Quat::from_axis_angle(axis.tangent, towards * full * fraction * 0.5);
            let turned = BodyFrame {
                centre: axis.point + half * (self.frame.centre - axis.point),
                forward: self.frame.forward,
                up: half * self.frame.up,
            };
            [self.frame, turned]
                .iter()
                .all(|frame| {
                    let mut angles = foot.angles;
                    ccd::solve(rig, frame, &mut angles, grip, &self.ccd).error <= GRIP_TOLERANCE
                })
                .then_some(candidate)
        })
    }

    /// The nearest other support on `side` (+1 right, -1 left) that the forelimbs could reach.
    pub fn neighbour(&self, side: f32, supports: &Supports) -> Option<usize> {
        let shoulders = self.frame.shoulders(&self.proportions);
        let sideways = self.frame.right() * side;
        let grips = shoulders + self.frame.up * self.proportions.hang;
        supports
            .others_near(grips, NEIGHBOUR_REACH, self.support())
            .into_iter()
            .filter_map(|index| {
                let (surface, _) = supports.paths[index].nearest(grips + sideways * 0.1);
                let beside = (surface.point - grips).dot(sideways);
                (beside > 0.05).then_some((index, surface.point.distance(grips)))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(index, _)| index)
    }
}

/// How far `step` lies ahead of `foot` in the direction of motion: along the support when both
/// are on the same one (round bends count in full), else along `motion`.
fn ahead(step: &Step, foot: &Foot, along: f32, motion: Vec3) -> f32 {
    if step.support == foot.support { (step.s - foot.s) * along } else { (step.grip - foot.grip).dot(motion) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_leading_foot_never_lands_behind_its_pair_unless_changing_branch() {
        assert!(keeps_leg_order(true, false, 0.0, 0.3));
        assert!(!keeps_leg_order(true, false, -0.01, 0.3));
        assert!(keeps_leg_order(true, true, -0.01, 0.3));
    }

    #[test]
    fn a_trailing_foot_stays_the_gap_behind_the_leading_foot_on_its_side() {
        assert!(keeps_leg_order(false, false, 1.0, -ORDER_GAP));
        assert!(!keeps_leg_order(false, false, 1.0, -ORDER_GAP + 0.001));
        assert!(!keeps_leg_order(false, true, -1.0, 0.0));
    }

    #[test]
    fn round_a_thick_trunk_the_grips_keep_to_its_near_face() {
        let proportions = Proportions::default();
        let span = TRUNK_GRIP_SPAN * 2.0 * proportions.girdle_half_width;
        // A slender trunk is gripped well round it, inside the span.
        let slender = 0.08;
        assert!((trunk_grip_round(&proportions, slender).to_degrees() - TRUNK_GRIP_DEG).abs() < 1e-4);
        assert!(slender * TRUNK_GRIP_DEG.to_radians().sin() < span);
        // Thicker ones at the span to the side, so less far round the thicker they are.
        let rounds = [0.15, 0.25, 0.35].map(|radius| {
            let round = trunk_grip_round(&proportions, radius);
            assert!((radius * round.sin() - span).abs() < 1e-5, "{radius} m: {round} rad");
            round
        });
        assert!(rounds[0] > rounds[1] && rounds[1] > rounds[2]);
    }

    #[test]
    fn a_grip_under_a_forks_wood_moves_round_the_branch_clear_of_it() {
        use crate::tree::{Shape, SupportSpec, Tree};
        // A level branch along +x and a fork leaving its middle 60 degrees below level, off to
        // one side: where a sloth hanging under the branch grips it.
        let branch = Shape::Polyline { points: vec![Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0)], radii: vec![0.08, 0.06] };
        let fork = Shape::Fork {
            parent: "branch".into(),
            at: 0.5,
            yaw_deg: 0.0,
            pitch_deg: -60.0,
            length: 1.5,
            radius: [0.04, 0.02],
            bend_deg: [0.0, 0.0],
            sections: 1,
        };
        let spec = |name: &str, shape| SupportSpec { name: name.into(), shape, kind: None };
        let tree = Tree::build(&[spec("branch", branch), spec("fork", fork)]).unwrap();
        let supports = Supports::new([("t", &tree)]);
        let index = supports.find("t/branch").unwrap();
        let path = &supports.paths[index];
        let fork_side = supports.paths[supports.find("t/fork").unwrap()].at(0.5).point - Vec3::new(2.0, 0.0, 0.0);
        let towards = fork_side.normalize();
        let covered = path.surface_towards(2.0, towards);
        assert!(in_wood(covered, &supports), "the grip on the fork's side at its foot is in its wood");
        let moved = clear_of_forks(path, index, 2.0, towards, &supports);
        assert!(!in_wood(moved, &supports) && moved.distance(covered) > 0.01, "{moved} from {covered}");
        let round = (moved - path.at(2.0).point).normalize().angle_between(towards).to_degrees();
        assert!(round <= FORK_ROUND_DEG + 1e-3, "{round} deg round");
        // Away from the fork the grip stays where it was.
        let clear = path.surface_towards(0.6, towards);
        assert_eq!(clear_of_forks(path, index, 0.6, towards, &supports), clear);
    }
}
