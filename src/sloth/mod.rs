//! The `sloth` entity kind: a two-toed sloth that hangs under branches, walks along them with
//! a diagonal-sequence gait, turns onto and changes between branches, climbs trunks head up,
//! transfers between a branch and its trunk, and stops where a branch ends.
//!
//! | module | what it holds |
//! |---|---|
//! | [`rig`] | the skeleton in metres: limbs of five hinge joints, limits from the range of motion |
//! | [`ccd`] | cyclic coordinate descent for one limb, within limits, never NaN |
//! | [`gait`] | stride and timing from speed, the footfall sequence, swing arcs |
//! | [`supports`] | every support of the scene as a path, with nearest-surface queries |
//! | [`foothold`] | the foothold search (the source's FindNextStep) |
//! | [`body`] | the body hanging from its grips, its heading and clearance |
//! | [`locomotion`] | one sloth, one fixed step at a time |
//! | [`transfer`] | planned moves between a branch and the trunk it grows from |
//! | [`mesh`] | the render mesh from the pose |
//!
//! All of these are pure and tested; this module adds the scene format, the parameters
//! `<name>.speed`, `<name>.autorun` and `<name>.direction`, the keys, and the state dump.

pub mod body;
pub mod ccd;
pub mod foothold;
pub mod gait;
pub mod locomotion;
pub mod mesh;
pub mod rig;
pub mod supports;
pub mod transfer;

pub use locomotion::{Drive, PlaceError, Placement, Sloth};
pub use supports::Supports;

use crate::controls::{KeyHelp, KeyScope, RegisterKeys};
use crate::dump::{DumpState, RegisterDump};
use crate::params::RegisterParams;
use crate::raster::{Material, RasterMesh, RenderSystems};
use crate::scene::SceneEntity;
use crate::scene::values::{Color, Degrees, UnitInterval, checked_number};
use crate::schedule::{ControlSystems, SimSystems};
use crate::tree::TreeBody;
use bevy::color::Srgba;
use bevy::prelude::*;
use rig::{JOINTS, Limb, Proportions};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};
use std::sync::Arc;

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
    |v| (0.1..=0.6).contains(&v)
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
    /// Fur colour; a greyish brown by default.
    #[serde(default = "fur")]
    pub color: Color,
}

fn middle() -> UnitInterval {
    UnitInterval(0.5)
}

fn no_turn() -> Degrees {
    Degrees(0.0)
}

fn free_speed() -> Speed {
    Speed(0.11)
}

fn unit_scale() -> Scale {
    Scale(1.0)
}

fn fur() -> Color {
    Color(Srgba::rgb(0.7, 0.63, 0.52))
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

    /// Places the sloth among `supports`.
    pub fn place(&self, supports: &Supports, speed: f32) -> Result<Sloth, String> {
        let placement = Placement {
            support: self.resolve(supports)?,
            fraction: self.at.0,
            facing: if self.facing == Facing::Forward { 1.0 } else { -1.0 },
            around: self.around_deg.0.to_radians(),
        };
        Sloth::place(supports, placement, self.proportions(), speed).map_err(|e| e.to_string())
    }
}

/// A sloth's parameters: `<name>.speed` (m/s), `<name>.autorun`, `<name>.direction`.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component)]
pub struct SlothParams {
    /// Mean walking speed, metres per second (clamped to 0.05-0.35).
    pub speed: f32,
    /// Walk without a key held, until no foothold is found.
    pub autorun: bool,
    /// Which way autorun walks.
    pub direction: WalkDirection,
}

/// What the keys ask of a sloth until the next fixed step.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct SlothInput {
    /// +1 while forward is held, -1 while back is held.
    pub hold: f32,
    /// A change of branch asked for: +1 right, -1 left.
    pub change: Option<f32>,
    /// +1 while right is held, -1 while left is held (side steps round a trunk).
    pub around: f32,
}

/// The scene's description of a sloth.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct SlothSource(pub SlothDef);

/// A placed sloth and the supports it moves on.
#[derive(Component, Debug, Clone)]
pub struct SlothBody {
    /// Its locomotion state.
    pub sloth: Sloth,
    /// The scene's supports when it was placed.
    pub supports: Arc<Supports>,
}

/// Spawns a sloth entity's components; it is placed on its support once the trees exist.
pub fn spawn_sloth(entity: &mut EntityCommands, def: &SlothDef) {
    entity.insert((
        Transform::IDENTITY,
        RasterMesh { mesh: Arc::default(), material: Material::colored(Vec3::ONE) },
        SlothSource(def.clone()),
        SlothParams { speed: def.speed.0, autorun: def.autorun, direction: def.direction },
        SlothInput::default(),
    ));
}

/// Keys of the sloth kind, held or pressed.
const FORWARD_KEY: KeyCode = KeyCode::KeyW;
const BACK_KEY: KeyCode = KeyCode::KeyS;
const AUTORUN_KEY: KeyCode = KeyCode::KeyR;
const LEFT_KEY: KeyCode = KeyCode::KeyA;
const RIGHT_KEY: KeyCode = KeyCode::KeyD;

/// Registers the sloth kind: parameters, keys, placement, locomotion, mesh and dump.
pub struct SlothPlugin;

impl Plugin for SlothPlugin {
    fn build(&self, app: &mut App) {
        let scope = KeyScope::Kind("sloth");
        app.register_params::<SlothParams>()
            .register_dump::<SlothBody>()
            .register_keys(&[
                KeyHelp { key: FORWARD_KEY, action: "walk forward, or climb up a trunk (hold)", scope },
                KeyHelp { key: BACK_KEY, action: "walk back, or climb down a trunk (hold)", scope },
                KeyHelp { key: AUTORUN_KEY, action: "autorun on or off (stops where no foothold is found)", scope },
                KeyHelp {
                    key: LEFT_KEY,
                    action: "change to the branch on the left; on a trunk, hold to step round it",
                    scope,
                },
                KeyHelp {
                    key: RIGHT_KEY,
                    action: "change to the branch on the right; on a trunk, hold to step round it",
                    scope,
                },
            ])
            .add_systems(Update, sloth_keys.in_set(ControlSystems::Input))
            .add_systems(Update, place_sloths.in_set(ControlSystems::Apply))
            .add_systems(FixedUpdate, walk_sloths.in_set(SimSystems::Step))
            .add_systems(PostUpdate, draw_sloths.before(RenderSystems::Collect));
    }
}

fn sloth_keys(keys: Res<ButtonInput<KeyCode>>, mut sloths: Query<(&mut SlothInput, &mut SlothParams)>) {
    let hold = f32::from(keys.pressed(FORWARD_KEY)) - f32::from(keys.pressed(BACK_KEY));
    let around = f32::from(keys.pressed(RIGHT_KEY)) - f32::from(keys.pressed(LEFT_KEY));
    let change = if keys.just_pressed(LEFT_KEY) {
        Some(-1.0)
    } else if keys.just_pressed(RIGHT_KEY) {
        Some(1.0)
    } else {
        None
    };
    for (mut input, mut params) in &mut sloths {
        input.hold = hold;
        input.around = around;
        if change.is_some() {
            input.change = change;
        }
        if keys.just_pressed(AUTORUN_KEY) {
            params.autorun = !params.autorun;
        }
    }
}

/// Places sloths not yet placed, and every sloth again when the trees change.
fn place_sloths(
    mut commands: Commands,
    trees: Query<(&SceneEntity, &TreeBody)>,
    changed: Query<(), Changed<TreeBody>>,
    sloths: Query<(Entity, &SceneEntity, &SlothSource, &SlothParams, Has<SlothBody>)>,
) {
    let rebuild = !changed.is_empty();
    if !rebuild && sloths.iter().all(|(.., placed)| placed) {
        return;
    }
    let mut named: Vec<(&SceneEntity, &TreeBody)> = trees.iter().collect();
    named.sort_by_key(|(entity, _)| entity.index);
    let supports = Arc::new(Supports::new(named.iter().map(|(entity, body)| (entity.name.as_str(), &body.tree))));
    for (entity, scene_entity, source, params, placed) in &sloths {
        if placed && !rebuild {
            continue;
        }
        match source.0.place(&supports, params.speed) {
            Ok(sloth) => {
                commands.entity(entity).insert(SlothBody { sloth, supports: supports.clone() });
            }
            Err(error) => {
                error!("sloth `{}` not placed: {error}", scene_entity.name);
                commands.entity(entity).remove::<SlothBody>();
            }
        }
    }
}

fn walk_sloths(time: Res<Time>, mut sloths: Query<(&mut SlothBody, &mut SlothParams, &mut SlothInput)>) {
    let dt = time.delta_secs();
    for (mut body, mut params, mut input) in &mut sloths {
        let direction = if input.hold != 0.0 {
            input.hold
        } else if params.autorun {
            params.direction.sign()
        } else {
            0.0
        };
        let drive = Drive { direction, change: input.change.take(), around: input.around };
        let SlothBody { sloth, supports } = &mut *body;
        sloth.speed = params.speed;
        sloth.step(dt, drive, supports);
        if params.autorun && input.hold == 0.0 && sloth.blocked.is_some() {
            params.autorun = false;
        }
    }
}

fn draw_sloths(mut sloths: Query<(&SlothBody, &SlothSource, &mut RasterMesh), Changed<SlothBody>>) {
    for (body, source, mut raster) in &mut sloths {
        let fur = source.0.color.0;
        raster.mesh = Arc::new(mesh::sloth_mesh(&body.sloth, Vec3::new(fur.red, fur.green, fur.blue)));
    }
}

fn vec3(v: Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

impl DumpState for SlothBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let sloth = &self.sloth;
        let label = |index: usize| self.supports.paths[index].label.clone();
        let mut feet = Map::new();
        let mut joints = Map::new();
        for limb in Limb::ALL {
            let foot = &sloth.feet[limb.index()];
            let rig = &sloth.rigs[limb.index()];
            feet.insert(
                limb.key().into(),
                json!({
                    "position": vec3(foot.position),
                    "planted": foot.planted(),
                    "support": label(foot.support),
                    "surface_distance": self.supports.paths[foot.support].distance(foot.position),
                }),
            );
            let limb_joints: Map<String, Value> = (0..JOINTS)
                .map(|j| {
                    let joint = json!({
                        "angle_deg": foot.angles[j].to_degrees(),
                        "min_deg": rig.min[j].to_degrees(),
                        "max_deg": rig.max[j].to_degrees(),
                    });
                    (limb.joint_names()[j].to_string(), joint)
                })
                .collect();
            joints.insert(limb.key().into(), Value::Object(limb_joints));
        }
        let footfalls: Vec<Value> =
            sloth.footfalls.iter().map(|f| json!({ "limb": f.limb.key(), "time": f.time })).collect();
        out.insert("body_position".into(), vec3(sloth.frame.centre));
        out.insert("heading".into(), vec3(sloth.frame.forward));
        out.insert("support".into(), json!(label(sloth.support())));
        out.insert("changing_to".into(), json!(sloth.change_to.map(label)));
        out.insert("blocked".into(), json!(sloth.blocked.is_some()));
        out.insert("feet".into(), Value::Object(feet));
        out.insert("joints".into(), Value::Object(joints));
        out.insert("footfalls".into(), json!(footfalls));
        out.insert("distance_travelled".into(), json!(sloth.distance));
        out.insert("mean_speed".into(), json!(sloth.mean_speed()));
        out.insert("body_clearance".into(), json!(sloth.clearance));
        out.insert("min_body_clearance".into(), json!(sloth.min_clearance));
    }
}
