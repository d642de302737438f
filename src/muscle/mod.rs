//! The `muscle` entity kind: a volume-preserving biceps on a two-rod arm
//! (`../shared/spec/muscle.md` is the source's model).
//!
//! | module | what it holds |
//! |---|---|
//! | [`kind`] | [`MuscleKind`]: the source's configuration files as scenes, the model built while checking, spawned and saved; its panel and keys |
//! | [`def`] | the `muscle:` entry of a scene file, the source's two configurations |
//! | [`plugin`] | [`MusclePlugin`] and its set [`MuscleSystems`]: parameters, keys, the model in the fixed step, write-back, dump |
//! | [`model`] | the node model: frusta-chain volume, exact volume-preserving length changes |
//! | [`carcass`] | the arm: flexion from muscle length and back (law of cosines) |
//! | [`comparison`] | the real biceps' measurements, the model's radii at the same flexions, the source's Table 4.3 |
//! | [`fit`] | growth multipliers fitted to the real biceps in least squares, the volume still exact |
//! | [`surface`] | the revolved surface with smooth profile normals |
//! | [`panel`] | the window's muscle section: figures, node editor, model vs real plot, Table 4.3 |
//!
//! Where the source's rules live: the frustum volume and the quadratic whose root keeps the
//! volume when the length changes (its `A` coefficient included) in [`model`]; the law of
//! cosines between muscle length and elbow flexion in [`carcass`].
//!
//! Parameters: `<name>.flexion_deg` (elbow flexion, 0 = straight arm) and `<name>.length`
//! (muscle length in config units); setting either moves the other. Keys: W contracts
//! (flexes), S stretches, Q / E step the flexion by 15 degrees.

pub mod carcass;
pub mod comparison;
pub mod def;
pub mod fit;
pub mod kind;
pub mod model;
pub mod panel;
pub mod plugin;
pub mod surface;

pub use def::{BuiltMuscle, CarcassConfig, ConfigFile, MuscleConfig, MuscleDef};
pub use kind::MuscleKind;
pub use plugin::{MuscleBody, MuscleParams, MusclePlugin, MuscleSystems, Placement};
