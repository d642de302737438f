//! The `sloth` entity kind: a two-toed sloth that hangs under branches, walks along them with
//! a diagonal-sequence gait, turns onto and changes between branches, climbs trunks head up,
//! transfers between a branch and its trunk, and stops where a branch ends
//! (`../shared/spec/sloth.md` is the source's model).
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`SlothKind`], which places the sloth once while checking, spawns and saves it; its keys |
//! | [`def`] | the `sloth:` entry of a scene file |
//! | [`plugin`] | [`SlothPlugin`] and its set [`SlothSystems`]: parameters `<name>.speed`, `.autorun`, `.direction`, keys, the walk, mesh write-back, dump |
//! | [`rig`] | the skeleton in metres: limbs of five hinge joints, limits from the range of motion |
//! | [`debug`] | the debug view: foothold probes and why each was refused, targets, limb chains, body frame, a transfer's path |
//! | [`ccd`] | cyclic coordinate descent for one limb, within limits, never NaN |
//! | [`fabrik`] | FABRIK with the same limits, for the comparison with CCD |
//! | [`gait`] | stride and timing from speed, the footfall sequence, swing arcs |
//! | [`gait_log`] | the gait measured: contact, swing, duty factor, stride, footfall order, joint excursions, foot slip |
//! | [`supports`] | every support of the scene as a path, with nearest-surface queries |
//! | [`survey`] | which of a tree's boughs a sloth walks from end to end, and why it stops |
//! | [`foothold`] | where a lifted foot lands (the source's FindNextStep): the step rules and the leg order |
//! | [`body`] | the body hanging from its grips, its heading and clearance |
//! | [`feet`] | how each foot stands or swings, where one lands, whether a grip sinks into wood |
//! | [`locomotion`] | one sloth, one fixed step at a time |
//! | [`moves`] | a transfer's moves and their playback |
//! | [`transfer`] | planned moves between a branch and the trunk it grows from |
//! | [`biceps`] | each forelimb's biceps: the muscle kind's node model, its length set by the elbow |
//! | [`skin`] | one smooth surface over body and limbs, made once and posed by the rig (linear blend skinning), with its coat and face |
//! | [`mesh`] | the render mesh from the pose: skin, claws, biceps |
//! | [`panel`] | the panel section: where it is and what it does, limbs, joints against their limits, the footfall diagram, the gait measured |
//!
//! Where the source's rules live: the diagonal sequence and its timing in [`gait`]; the leg
//! order ("hind feet never ahead of fore feet") with the step lengths and margins it works
//! with in [`foothold`]; the joint limits in [`rig`]; trunks climbed head up, and the
//! transfer between a branch and its trunk, in [`transfer`].
//!
//! The pure modules are tested and benchmarked without a world.

pub mod biceps;
pub mod body;
pub mod ccd;
pub mod debug;
pub mod def;
pub mod fabrik;
pub mod feet;
pub mod foothold;
pub mod gait;
pub mod gait_log;
pub mod kind;
pub mod locomotion;
pub mod mesh;
pub mod moves;
pub mod panel;
pub mod plugin;
pub mod rig;
pub mod skin;
pub mod supports;
pub mod survey;
pub mod transfer;

pub use def::{Facing, SlothDef, WalkDirection};
pub use kind::SlothKind;
pub use locomotion::{Drive, PlaceError, Placement, Sloth, Tuning};
pub use plugin::{
    SlothBody, SlothGait, SlothInput, SlothMuscles, SlothParams, SlothPlugin, SlothSkin, SlothSource, SlothSystems,
};
pub use supports::Supports;
