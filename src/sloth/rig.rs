//! The skeleton of a two-toed sloth, in metres: a torso, neck and head, and four limbs of four
//! bones each (girdle, upper, lower, hand or foot, the last one ending in the claws' grip point).
//!
//! Each limb has five hinge joints. The first swings the limb's plane out from the body about
//! the body's long axis (abduction); the other four flex the girdle, upper, lower and hand
//! bones inside that plane. Consecutive flexion joints rest bent in opposite directions, as in
//! the animal.
//!
//! ## Joint limits
//! The source's range-of-motion table gives each flexion joint's *amplitude during the contact
//! phase*. Swing and uneven supports need more than one contact phase shows, so each joint may
//! move its full amplitude to either side of its rest angle:
//! `min = rest - amplitude`, `max = rest + amplitude`. Abduction is not in the table (its
//! studies measured the sagittal plane); it gets [`ABDUCTION_AMPLITUDE_DEG`] either side.

use bevy::math::Vec3;

/// Joints per limb: abduction, then the four flexion joints.
pub const JOINTS: usize = 5;

/// Abduction's allowed swing either side of rest, degrees (not measured by the source).
pub const ABDUCTION_AMPLITUDE_DEG: f32 = 40.0;

/// The four limbs in the order of the diagonal-sequence gait: right hind, left fore, left hind,
/// right fore.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Limb {
    /// Right hind leg.
    RightHind,
    /// Left foreleg.
    LeftFore,
    /// Left hind leg.
    LeftHind,
    /// Right foreleg.
    RightFore,
}

impl Limb {
    /// All limbs, in diagonal-sequence footfall order.
    pub const ALL: [Limb; 4] = [Limb::RightHind, Limb::LeftFore, Limb::LeftHind, Limb::RightFore];

    /// Position in [`Limb::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The short name used in dumps: `rh`, `lf`, `lh`, `rf`.
    pub fn key(self) -> &'static str {
        match self {
            Limb::RightHind => "rh",
            Limb::LeftFore => "lf",
            Limb::LeftHind => "lh",
            Limb::RightFore => "rf",
        }
    }

    /// A foreleg?
    pub fn is_fore(self) -> bool {
        matches!(self, Limb::LeftFore | Limb::RightFore)
    }

    /// +1 for right limbs, -1 for left ones.
    pub fn side(self) -> f32 {
        if matches!(self, Limb::RightHind | Limb::RightFore) { 1.0 } else { -1.0 }
    }

    /// The other limb of the same girdle.
    pub fn pair(self) -> Limb {
        match self {
            Limb::RightHind => Limb::LeftHind,
            Limb::LeftHind => Limb::RightHind,
            Limb::LeftFore => Limb::RightFore,
            Limb::RightFore => Limb::LeftFore,
        }
    }

    /// The limb on the same side of the other girdle.
    pub fn same_side(self) -> Limb {
        match self {
            Limb::RightHind => Limb::RightFore,
            Limb::RightFore => Limb::RightHind,
            Limb::LeftHind => Limb::LeftFore,
            Limb::LeftFore => Limb::LeftHind,
        }
    }

    /// The names of the limb's joints, as in dumps.
    pub fn joint_names(self) -> [&'static str; JOINTS] {
        if self.is_fore() {
            ["abduction", "shoulder_blade", "upper_arm", "forearm", "hand"]
        } else {
            ["abduction", "pelvis", "thigh", "lower_leg", "foot"]
        }
    }
}

/// The sloth's body proportions, metres. The defaults make a 0.8 m animal whose limbs reach
/// about 0.45 m from the girdle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proportions {
    /// Hip joint to shoulder joint along the spine.
    pub torso_length: f32,
    /// Torso thickness (radius).
    pub torso_radius: f32,
    /// Shoulder to the back of the head.
    pub neck_length: f32,
    /// Head radius.
    pub head_radius: f32,
    /// Forelimb bones: shoulder blade, upper arm, forearm, hand (to the claws' grip point).
    pub fore_bones: [f32; 4],
    /// Hindlimb bones: pelvis, thigh, lower leg, foot (to the claws' grip point).
    pub hind_bones: [f32; 4],
    /// Claw length: the grip point lies this far beyond the palm.
    pub claw: f32,
    /// Half the distance between left and right limb roots.
    pub girdle_half_width: f32,
    /// How far the feet's mean lies above the body's centre while hanging.
    pub hang: f32,
}

impl Default for Proportions {
    fn default() -> Self {
        Self {
            torso_length: 0.4,
            torso_radius: 0.085,
            neck_length: 0.09,
            head_radius: 0.06,
            fore_bones: [0.06, 0.17, 0.16, 0.09],
            hind_bones: [0.05, 0.15, 0.14, 0.08],
            claw: 0.05,
            girdle_half_width: 0.06,
            hang: 0.28,
        }
    }
}

impl Proportions {
    /// Nose to tail, metres: the torso, the neck and the head.
    pub fn body_length(&self) -> f32 {
        self.torso_length + 2.0 * self.torso_radius + self.neck_length + 2.0 * self.head_radius
    }

    /// Scales every length by `factor` (a smaller or larger animal of the same shape).
    pub fn scaled(&self, factor: f32) -> Self {
        let scale = |b: [f32; 4]| b.map(|l| l * factor);
        Self {
            torso_length: self.torso_length * factor,
            torso_radius: self.torso_radius * factor,
            neck_length: self.neck_length * factor,
            head_radius: self.head_radius * factor,
            fore_bones: scale(self.fore_bones),
            hind_bones: scale(self.hind_bones),
            claw: self.claw * factor,
            girdle_half_width: self.girdle_half_width * factor,
            hang: self.hang * factor,
        }
    }
}

/// Where the body is and which way it faces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyFrame {
    /// Centre of the torso, metres.
    pub centre: Vec3,
    /// Unit vector from the hips to the shoulders.
    pub forward: Vec3,
    /// Unit vector from the body towards its grips (the belly side: the animal hangs back
    /// down), perpendicular to `forward`.
    pub up: Vec3,
}

impl BodyFrame {
    /// The animal's right: it hangs back down, so this is `up x forward`.
    pub fn right(&self) -> Vec3 {
        self.up.cross(self.forward)
    }

    /// The shoulder (or hip) end of the spine.
    pub fn shoulders(&self, proportions: &Proportions) -> Vec3 {
        self.centre + self.forward * (proportions.torso_length * 0.5)
    }

    /// The hip end of the spine.
    pub fn hips(&self, proportions: &Proportions) -> Vec3 {
        self.centre - self.forward * (proportions.torso_length * 0.5)
    }

    /// Centre of the head: beyond the shoulders by the neck, a little towards the grips.
    pub fn head(&self, proportions: &Proportions) -> Vec3 {
        self.shoulders(proportions)
            + self.forward * (proportions.torso_radius + proportions.neck_length + proportions.head_radius * 0.5)
            + self.up * (proportions.torso_radius * 0.3)
    }
}

/// One limb's geometry: root, bones, rest pose and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbRig {
    /// Which limb.
    pub limb: Limb,
    /// Root (girdle joint) in the body frame: along forward, right, up, metres.
    pub root: Vec3,
    /// Bone lengths from the girdle out, the last one to the grip point, metres.
    pub bones: [f32; 4],
    /// Rest angles, radians: abduction, then each flexion joint relative to the bone before.
    pub rest: [f32; JOINTS],
    /// Lowest angle of each joint, radians.
    pub min: [f32; JOINTS],
    /// Highest angle of each joint, radians.
    pub max: [f32; JOINTS],
}

/// Contact-phase amplitudes from the source's range-of-motion table, degrees: girdle, upper,
/// lower, hand/foot.
pub const FORE_AMPLITUDE_DEG: [f32; 4] = [41.5, 98.1, 92.3, 36.8];
/// The hindlimb's, likewise: pelvis, thigh, lower leg, foot.
pub const HIND_AMPLITUDE_DEG: [f32; 4] = [8.5, 75.7, 53.4, 17.8];

/// Rest angles, degrees: abduction (outwards), then flexion of each bone relative to the one
/// before, measured from the limb's reach direction towards the head.
const FORE_REST_DEG: [f32; JOINTS] = [5.0, -20.0, 80.0, -110.0, 55.0];
const HIND_REST_DEG: [f32; JOINTS] = [5.0, 20.0, -80.0, 110.0, -55.0];

impl LimbRig {
    /// The rig of `limb` for `proportions`.
    pub fn new(limb: Limb, proportions: &Proportions) -> Self {
        let (bones, amplitude, rest_deg, along) = if limb.is_fore() {
            (proportions.fore_bones, FORE_AMPLITUDE_DEG, FORE_REST_DEG, proportions.torso_length * 0.5)
        } else {
            (proportions.hind_bones, HIND_AMPLITUDE_DEG, HIND_REST_DEG, -proportions.torso_length * 0.5)
        };
        let amplitude_deg = [ABDUCTION_AMPLITUDE_DEG, amplitude[0], amplitude[1], amplitude[2], amplitude[3]];
        let rest = rest_deg.map(f32::to_radians);
        let min = std::array::from_fn(|j| rest[j] - amplitude_deg[j].to_radians());
        let max = std::array::from_fn(|j| rest[j] + amplitude_deg[j].to_radians());
        let root = Vec3::new(along, limb.side() * proportions.girdle_half_width, proportions.torso_radius * 0.6);
        Self { limb, root, bones, rest, min, max }
    }

    /// The root in the world.
    pub fn root_in(&self, frame: &BodyFrame) -> Vec3 {
        frame.centre + frame.forward * self.root.x + frame.right() * self.root.y + frame.up * self.root.z
    }

    /// The limb plane's reach direction for abduction `abduction` (radians, outwards).
    pub fn reach(&self, frame: &BodyFrame, abduction: f32) -> Vec3 {
        let (sin, cos) = abduction.sin_cos();
        frame.up * cos + frame.right() * (self.limb.side() * sin)
    }

    /// The joint axes: abduction turns about the body's long axis, flexion about the normal of
    /// the limb's plane; a positive angle turns the limb by the right-hand rule about these.
    pub fn axes(&self, frame: &BodyFrame, abduction: f32) -> (Vec3, Vec3) {
        let reach = self.reach(frame, abduction);
        let abduct = frame.forward * -self.limb.side();
        (abduct, reach.cross(frame.forward))
    }

    /// Forward kinematics: the root, the end of each bone (the last one is the grip point).
    pub fn points(&self, frame: &BodyFrame, angles: &[f32; JOINTS]) -> [Vec3; JOINTS] {
        let reach = self.reach(frame, angles[0]);
        let mut points = [self.root_in(frame); JOINTS];
        let mut bend = 0.0;
        for bone in 0..4 {
            bend += angles[bone + 1];
            let (sin, cos) = bend.sin_cos();
            points[bone + 1] = points[bone] + (reach * cos + frame.forward * sin) * self.bones[bone];
        }
        points
    }

    /// The grip point for `angles`.
    pub fn effector(&self, frame: &BodyFrame, angles: &[f32; JOINTS]) -> Vec3 {
        self.points(frame, angles)[JOINTS - 1]
    }

    /// The pivot of joint `joint`: abduction and the girdle turn at the root, the others at the
    /// end of the bone before.
    pub fn pivot(points: &[Vec3; JOINTS], joint: usize) -> Vec3 {
        points[joint.saturating_sub(1)]
    }

    /// Whether every angle lies within its limits (up to `slack` radians).
    pub fn within_limits(&self, angles: &[f32; JOINTS], slack: f32) -> bool {
        (0..JOINTS).all(|j| angles[j] >= self.min[j] - slack && angles[j] <= self.max[j] + slack)
    }

    /// How far ahead of the body's centre the grip point rests, along the body, metres.
    pub fn neutral_reach(&self) -> f32 {
        let frame = BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y };
        self.effector(&frame, &self.rest).x
    }
}

/// The four limb rigs of an animal, indexed like [`Limb::ALL`].
pub fn limb_rigs(proportions: &Proportions) -> [LimbRig; 4] {
    Limb::ALL.map(|limb| LimbRig::new(limb, proportions))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> BodyFrame {
        BodyFrame { centre: Vec3::ZERO, forward: Vec3::X, up: Vec3::Y }
    }

    #[test]
    fn the_default_animal_measures_like_a_two_toed_sloth() {
        let proportions = Proportions::default();
        // Body length 0.78-0.87 m; limbs reaching about 0.4 m, as the source's.
        assert!((0.75..=0.87).contains(&proportions.body_length()), "{}", proportions.body_length());
        let fore: f32 = proportions.fore_bones.iter().sum();
        assert!((0.38..=0.5).contains(&fore), "{fore}");
        assert!((proportions.scaled(1.1).body_length() - 1.1 * proportions.body_length()).abs() < 1e-5);
    }

    #[test]
    fn bones_keep_their_lengths_in_any_pose() {
        let rig = LimbRig::new(Limb::LeftFore, &Proportions::default());
        let angles = [0.3, -0.2, 1.1, -1.5, 0.7];
        let points = rig.points(&frame(), &angles);
        for bone in 0..4 {
            assert!((points[bone].distance(points[bone + 1]) - rig.bones[bone]).abs() < 1e-6);
        }
    }

    #[test]
    fn limbs_sit_on_their_sides_and_rest_reaching_towards_the_grips() {
        let proportions = Proportions::default();
        for rig in limb_rigs(&proportions) {
            let root = rig.root_in(&frame());
            let grip = rig.effector(&frame(), &rig.rest);
            // Right is -z for an animal facing +x with its belly up.
            assert_eq!(root.z.signum(), -rig.limb.side());
            assert!(grip.y > root.y + 0.1, "{:?} rests reaching up: {grip}", rig.limb);
            assert_eq!(root.x > 0.0, rig.limb.is_fore());
        }
    }

    #[test]
    fn limits_span_twice_the_measured_amplitude_about_rest() {
        let rig = LimbRig::new(Limb::RightHind, &Proportions::default());
        assert!((rig.max[2] - rig.min[2] - 2.0 * 75.7f32.to_radians()).abs() < 1e-5);
        assert!((rig.max[0] - rig.rest[0] - ABDUCTION_AMPLITUDE_DEG.to_radians()).abs() < 1e-5);
        assert!(rig.within_limits(&rig.rest, 0.0));
    }

    #[test]
    fn positive_angles_turn_by_the_right_hand_rule_about_the_axes() {
        let rig = LimbRig::new(Limb::RightFore, &Proportions::default());
        let pose = rig.rest;
        let points = rig.points(&frame(), &pose);
        let (abduct, flex) = rig.axes(&frame(), pose[0]);
        for joint in 0..JOINTS {
            let mut turned = pose;
            turned[joint] += 1e-3;
            let moved = rig.effector(&frame(), &turned) - points[JOINTS - 1];
            let axis = if joint == 0 { abduct } else { flex };
            let lever = points[JOINTS - 1] - LimbRig::pivot(&points, joint);
            let expected = axis.cross(lever) * 1e-3;
            assert!(moved.distance(expected) < 1e-5, "joint {joint}: {moved} vs {expected}");
        }
    }
}
