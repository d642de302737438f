//! Feet: how each stands or swings, where one will land and the grips the search tried on the
//! way, and whether a grip holds on the wood or sinks into another support's.

use super::gait::SwingArc;
use super::rig::{JOINTS, Limb};
use super::supports::Supports;
use bevy::math::Vec3;

/// How a foot stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Foot {
    /// The support it grips (or will grip, while swinging): index into [`Supports::paths`].
    pub support: usize,
    /// Arc length of its grip along that support, metres.
    pub s: f32,
    /// The grip point on the support's surface, metres.
    pub grip: Vec3,
    /// The swing in progress, if any.
    pub swing: Option<Swing>,
    /// The limb's joint angles, radians.
    pub angles: [f32; JOINTS],
    /// Where the limb's grip point is (forward kinematics of `angles`), metres.
    pub position: Vec3,
}

impl Foot {
    /// Where the limb's IK aims: the grip, or the point of the swing arc.
    pub fn target(&self) -> Vec3 {
        self.swing.map_or(self.grip, |swing| swing.arc.at(swing.elapsed / swing.duration))
    }

    /// Planted (not swinging)?
    pub fn planted(&self) -> bool {
        self.swing.is_none()
    }
}

/// A swing in progress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Swing {
    /// The path of the foot.
    pub arc: SwingArc,
    /// Seconds since lift-off.
    pub elapsed: f32,
    /// Seconds from lift-off to touch-down.
    pub duration: f32,
}

/// Largest distance, metres, between an IK grip point and its grip that still counts as
/// holding on: the foothold search only accepts grips the limb reaches this closely.
pub const GRIP_TOLERANCE: f32 = 0.004;

/// Whether a grip at `grip` sinks into some support's wood (where one grows out of another).
pub(super) fn in_wood(grip: Vec3, supports: &Supports) -> bool {
    wood_at(grip, supports).is_some()
}

/// The support whose wood a grip at `grip` sinks into, if it sinks into one.
pub(super) fn wood_at(grip: Vec3, supports: &Supports) -> Option<usize> {
    supports.nearest(grip, GRIP_TOLERANCE).filter(|hit| hit.surface.distance < -GRIP_TOLERANCE).map(|hit| hit.support)
}

/// Where a foot will land.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Index of the support.
    pub support: usize,
    /// Arc length along it, metres.
    pub s: f32,
    /// The grip point on its surface, metres.
    pub grip: Vec3,
}

/// Why the foothold search refused a candidate grip.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// Beyond the support's ends (less the margin the feet keep from them).
    OffSupport,
    /// Less than [`MIN_STEP`](super::foothold::MIN_STEP) the way the sloth is going.
    TooShort,
    /// It would break the leg order: a leading foot behind its pair, a trailing foot past the
    /// leading foot on its side.
    LegOrder,
    /// A leading foot more than `MAX_LEAD` strides ahead of its pair.
    TooFarAhead,
    /// It sinks into another support's wood.
    InWood,
    /// The body hanging from it would be pressed into a support.
    PressesBody,
    /// Some limb would not reach its grip within its joint limits.
    OutOfReach,
}

impl Refusal {
    /// The reason in a few words.
    pub fn reason(self) -> &'static str {
        match self {
            Refusal::OffSupport => "off the support",
            Refusal::TooShort => "too short",
            Refusal::LegOrder => "leg order",
            Refusal::TooFarAhead => "too far ahead of its pair",
            Refusal::InWood => "in another support's wood",
            Refusal::PressesBody => "presses the body into a support",
            Refusal::OutOfReach => "out of reach",
        }
    }
}

/// A candidate grip the foothold search tried (the source drew these as its debug traces).
/// Grips are made on the limb's own side of the support, so none is ever on the wrong side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probe {
    /// The limb it was for.
    pub limb: Limb,
    /// Where the foot stood, metres.
    pub from: Vec3,
    /// The grip tried, metres.
    pub grip: Vec3,
    /// Why it was refused; `None` for the grip taken.
    pub refusal: Option<Refusal>,
}
