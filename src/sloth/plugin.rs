//! The sloth kind's plugin: its parameters and keys, the walk in the fixed step, the
//! write-back of its mesh, and its dump.

use super::biceps::{BICEPS_LIMBS, Biceps, arm_points};
use super::ccd::CcdSettings;
use super::def::{
    HANG_RANGE, Hang, IK_SWEEPS_RANGE, IK_TOLERANCE_RANGE_MM, IkSweeps, IkTolerance, MAX_STEP_RANGE, MaxStep,
    STEP_DELAY_RANGE, STRIDE_RANGE, SlothDef, Speed, StepDelay, StrideLength, WalkDirection,
};
use super::gait;
use super::gait::StrideMode;
use super::gait_log::{GaitLog, LimbState};
use super::locomotion::{Drive, Sloth, Tuning, comfortable_stride};
use super::mesh;
use super::rig::{JOINTS, Limb};
use super::skin::Skin;
use super::supports::Supports;
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::entity::{FocusPoint, SceneEntity};
use crate::foundation::messages::HandPlanted;
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, SimSystems, WriteBackSystems};
use crate::foundation::values::srgb_channels;
use crate::raster::{Material, RasterMesh};
use crate::tree::TreeBody;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::prelude::*;
use serde_json::{Map, Value, json};
use std::sync::Arc;

/// A sloth's parameters, tuned while it walks: `<name>.speed` (m/s), `.autorun`, `.direction`,
/// `.stride_mode`, `.stride_m`, `.stride_seed`, `.one_at_a_time`, `.step_delay_s`, `.max_step_m`,
/// `.ik_tolerance_mm`, `.ik_sweeps`, `.hang_m`.
/// Each is kept within the range its scene-file field accepts.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component)]
pub struct SlothParams {
    /// Mean walking speed, metres per second (0.05-0.35).
    pub speed: f32,
    /// Walk without a key held, until no foothold is found.
    pub autorun: bool,
    /// Which way autorun walks.
    pub direction: WalkDirection,
    /// How the stride is chosen: from the speed, fixed at `stride_m`, or at random.
    pub stride_mode: StrideMode,
    /// The fixed stride, metres (0.21-0.83, the animal's range).
    pub stride_m: f32,
    /// The seed of the random strides.
    pub stride_seed: u32,
    /// The feet step one at a time, `step_delay_s` apart, as the source's animal did.
    pub one_at_a_time: bool,
    /// Seconds from one foot's touch-down to the next one's lift-off when stepping one at a
    /// time (0-1).
    pub step_delay_s: f32,
    /// The longest stride, metres (0.1-1).
    pub max_step_m: f32,
    /// Where each limb's IK stops short of its target, millimetres (0.01-10).
    pub ik_tolerance_mm: f32,
    /// The most IK sweeps for one solve (1-256).
    pub ik_sweeps: u32,
    /// How far the body hangs below its grips, metres (0.1-0.6).
    pub hang_m: f32,
}

impl SlothParams {
    /// The parameters of a sloth placed from `def`.
    fn of(def: &SlothDef, sloth: &Sloth) -> Self {
        let tuning = sloth.tuning();
        Self {
            speed: def.speed.0,
            autorun: def.autorun,
            direction: def.direction,
            stride_mode: tuning.stride_mode,
            stride_m: tuning.fixed_stride,
            stride_seed: tuning.stride_seed,
            one_at_a_time: tuning.step_delay.is_some(),
            step_delay_s: tuning.step_delay.unwrap_or(SOURCE_STEP_DELAY),
            max_step_m: sloth.max_stride(),
            ik_tolerance_mm: tuning.ccd.tolerance * 1e3,
            ik_sweeps: tuning.ccd.max_sweeps,
            hang_m: tuning.hang,
        }
    }

    /// The walk these parameters ask for, each kept within its range.
    fn tuning(&self) -> Tuning {
        Tuning {
            speed: self.speed.clamp(gait::SPEED_RANGE.0, gait::SPEED_RANGE.1),
            stride_mode: self.stride_mode,
            fixed_stride: self.stride_m.clamp(STRIDE_RANGE.0, STRIDE_RANGE.1),
            stride_seed: self.stride_seed,
            step_delay: self.one_at_a_time.then(|| self.step_delay_s.clamp(STEP_DELAY_RANGE.0, STEP_DELAY_RANGE.1)),
            max_step: Some(self.max_step_m.clamp(MAX_STEP_RANGE.0, MAX_STEP_RANGE.1)),
            hang: self.hang_m.clamp(HANG_RANGE.0, HANG_RANGE.1),
            ccd: CcdSettings {
                tolerance: self.ik_tolerance_mm.clamp(IK_TOLERANCE_RANGE_MM.0, IK_TOLERANCE_RANGE_MM.1) * 1e-3,
                max_sweeps: self.ik_sweeps.clamp(IK_SWEEPS_RANGE.0, IK_SWEEPS_RANGE.1),
            },
        }
    }
}

/// The source's delay between steps, seconds: what `step_delay_s` starts at when the file
/// leaves the feet's swings overlapping.
const SOURCE_STEP_DELAY: f32 = 0.2;

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

/// The sloth's muscles: the left and right forelimbs' biceps, following the elbows.
#[derive(Component, Debug, Clone)]
pub struct SlothMuscles {
    /// The biceps of [`Limb::LeftFore`] and [`Limb::RightFore`].
    pub biceps: [Biceps; 2],
}

/// A sloth's gait as measured since it was last placed (a new log with each placing).
#[derive(Component, Debug, Clone, Default)]
pub struct SlothGait(pub GaitLog);

/// The feet of `sloth` as the gait log watches them.
fn limb_states(sloth: &Sloth) -> [LimbState; 4] {
    sloth.feet.map(|foot| LimbState { planted: foot.planted(), position: foot.position, angles: foot.angles })
}

/// A sloth's skin, made once for its proportions and posed by its rig every frame.
#[derive(Component, Debug, Clone)]
pub struct SlothSkin(pub Arc<Skin>);

/// Spawns a sloth entity of `def`, placed as `sloth` among `supports`, with its `biceps`.
pub(super) fn spawn_sloth(
    entity: &mut EntityWorldMut,
    def: &SlothDef,
    sloth: Sloth,
    supports: Arc<Supports>,
    mut biceps: [Biceps; 2],
) {
    for (muscle, limb) in biceps.iter_mut().zip(BICEPS_LIMBS) {
        muscle.follow(&arm_points(&sloth, limb));
    }
    entity.insert((
        SlothMuscles { biceps },
        SlothSkin(Arc::new(Skin::new(&sloth.proportions, &sloth.rigs))),
        Transform::IDENTITY,
        RasterMesh { mesh: Arc::default(), material: Material::colored(Vec3::ONE) },
        SlothSource(def.clone()),
        SlothParams::of(def, &sloth),
        SlothInput::default(),
        FocusPoint(sloth.frame.centre),
        SlothGait(GaitLog::new(&limb_states(&sloth))),
        SlothBody { sloth, supports },
    ));
}

/// Brings `def` up to date with the parameters set while it ran (the panel's and the
/// timelines'); a tuning left as the file had it is left out of the file as it was.
pub(super) fn save_live(def: &mut SlothDef, entity: EntityRef) {
    let (Some(params), Some(body)) = (entity.get::<SlothParams>(), entity.get::<SlothBody>()) else { return };
    let tuning = params.tuning();
    let filed = def.tuning(tuning.speed);
    def.speed = Speed(tuning.speed);
    def.autorun = params.autorun;
    def.direction = params.direction;
    if tuning.stride_mode != filed.stride_mode {
        def.stride_mode = Some(tuning.stride_mode);
    }
    if tuning.fixed_stride != filed.fixed_stride {
        def.stride_m = Some(StrideLength(tuning.fixed_stride));
    }
    if tuning.stride_seed != filed.stride_seed {
        def.stride_seed = Some(tuning.stride_seed);
    }
    if tuning.step_delay != filed.step_delay {
        def.step_delay_s = tuning.step_delay.map(StepDelay);
    }
    // The default longest stride follows the animal's size: written only when changed.
    let default_max = filed.max_step.unwrap_or_else(|| comfortable_stride(&body.sloth.proportions));
    if let Some(max_step) = tuning.max_step.filter(|m| (m - default_max).abs() > 1e-6) {
        def.max_step_m = Some(MaxStep(max_step));
    }
    if tuning.ccd.tolerance != filed.ccd.tolerance {
        def.ik_tolerance_mm = Some(IkTolerance(tuning.ccd.tolerance * 1e3));
    }
    if tuning.ccd.max_sweeps != filed.ccd.max_sweeps {
        def.ik_sweeps = Some(IkSweeps(tuning.ccd.max_sweeps));
    }
    if (tuning.hang - filed.hang).abs() > 1e-6 {
        def.hang = Some(Hang(tuning.hang));
    }
}

/// Keys of the sloth kind, held or pressed.
const FORWARD_KEY: KeyCode = KeyCode::KeyW;
const BACK_KEY: KeyCode = KeyCode::KeyS;
const AUTORUN_KEY: KeyCode = KeyCode::KeyR;
const LEFT_KEY: KeyCode = KeyCode::KeyA;
const RIGHT_KEY: KeyCode = KeyCode::KeyD;
/// Switches the debug view (see [`super::debug`]).
pub(super) const DEBUG_KEY: KeyCode = KeyCode::F3;

/// The sloth's keys and what they do, for the key help.
pub(super) const SLOTH_KEYS: [(KeyCode, &str); 6] = [
    (FORWARD_KEY, "walk forward, or climb up a trunk (hold)"),
    (BACK_KEY, "walk back, or climb down a trunk (hold)"),
    (AUTORUN_KEY, "autorun on or off (stops where no foothold is found)"),
    (LEFT_KEY, "change to the branch on the left; on a trunk, hold to step round it"),
    (RIGHT_KEY, "change to the branch on the right; on a trunk, hold to step round it"),
    (DEBUG_KEY, "the debug view on or off: foothold probes, targets, limb chains, body frame"),
];

/// Every system of the sloth kind, in whichever phase it runs: a handle for ordering other
/// plugins' systems before or after the sloths'.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SlothSystems;

/// Runs sloths: parameters, keys, placement after tree edits, locomotion, mesh and dump.
#[derive(Default)]
pub struct SlothPlugin;

impl Plugin for SlothPlugin {
    fn build(&self, app: &mut App) {
        app.register_params::<SlothParams>()
            .register_dump::<SlothBody>()
            .register_dump::<SlothMuscles>()
            .register_dump::<SlothGait>()
            .add_systems(RunFixedMainLoop, sloth_keys.in_set(ControlSystems::Input).in_set(SlothSystems))
            .add_systems(RunFixedMainLoop, place_sloths.in_set(ControlSystems::Apply).in_set(SlothSystems))
            .add_systems(
                FixedUpdate,
                (walk_sloths, (flex_biceps, record_gaits)).chain().in_set(SimSystems::Locomotion).in_set(SlothSystems),
            )
            .add_systems(PostUpdate, write_back_sloths.in_set(WriteBackSystems).in_set(SlothSystems));
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

/// Places every sloth again when a tree was edited (sloths are placed when they are spawned),
/// and any sloth an earlier placement left without a body.
fn place_sloths(
    mut commands: Commands,
    trees: Query<(&SceneEntity, Ref<TreeBody>)>,
    sloths: Query<(Entity, &SceneEntity, &SlothSource, &SlothParams, Has<SlothBody>)>,
) {
    let rebuild = trees.iter().any(|(_, body)| body.is_changed() && !body.is_added());
    if !rebuild && sloths.iter().all(|(.., placed)| placed) {
        return;
    }
    let mut named: Vec<(&SceneEntity, Ref<TreeBody>)> = trees.iter().collect();
    named.sort_by_key(|(entity, _)| entity.index);
    let supports = Arc::new(Supports::new(named.iter().map(|(entity, body)| (entity.name.as_str(), &body.tree))));
    for (entity, scene_entity, source, params, placed) in &sloths {
        if placed && !rebuild {
            continue;
        }
        match source.0.place(&supports, params.speed) {
            Ok(sloth) => {
                let gait = SlothGait(GaitLog::new(&limb_states(&sloth)));
                commands.entity(entity).insert((gait, SlothBody { sloth, supports: supports.clone() }));
            }
            Err(error) => {
                error!("sloth `{}` not placed: {error}", scene_entity.name);
                commands.entity(entity).remove::<SlothBody>();
            }
        }
    }
}

fn walk_sloths(
    time: Res<Time>,
    mut sloths: Query<(&mut SlothBody, &mut SlothParams, &mut SlothInput, &mut FocusPoint)>,
    mut hands: MessageWriter<HandPlanted>,
) {
    let dt = time.delta_secs();
    for (mut body, mut params, mut input, mut focus) in &mut sloths {
        let direction = if input.hold != 0.0 {
            input.hold
        } else if params.autorun {
            params.direction.sign()
        } else {
            0.0
        };
        let drive = Drive { direction, change: input.change.take(), around: input.around };
        let SlothBody { sloth, supports } = &mut *body;
        sloth.tune(params.tuning());
        let footfalls = sloth.footfalls.len();
        sloth.step(dt, drive, supports);
        // Each hand that took hold in this step may shake loose what hangs near it.
        for footfall in &sloth.footfalls[footfalls..] {
            if matches!(footfall.limb, Limb::LeftFore | Limb::RightFore) {
                hands.write(HandPlanted { point: sloth.feet[footfall.limb.index()].grip });
            }
        }
        focus.0 = sloth.frame.centre;
        if params.autorun && input.hold == 0.0 && sloth.blocked.is_some() {
            params.autorun = false;
        }
    }
}

/// Takes each sloth's feet into its gait log.
fn record_gaits(mut sloths: Query<(&SlothBody, &mut SlothGait)>) {
    for (body, mut gait) in &mut sloths {
        gait.0.observe(body.sloth.time, &limb_states(&body.sloth));
    }
}

/// Sets each biceps' length from the elbow the walk left, keeping its volume.
fn flex_biceps(mut sloths: Query<(&SlothBody, &mut SlothMuscles), Changed<SlothBody>>) {
    for (body, mut muscles) in &mut sloths {
        for (biceps, limb) in muscles.biceps.iter_mut().zip(BICEPS_LIMBS) {
            biceps.follow(&arm_points(&body.sloth, limb));
            if let Some(refusal) = &biceps.refusal {
                warn!("sloth biceps ({}): {refusal}", limb.key());
            }
        }
    }
}

/// Meshes sloths whose pose changed.
fn write_back_sloths(
    mut sloths: Query<(&SlothBody, &SlothSkin, &SlothSource, &SlothMuscles, &mut RasterMesh), Changed<SlothBody>>,
) {
    for (body, skin, source, muscles, mut raster) in &mut sloths {
        let fur = srgb_channels(source.0.color.0);
        raster.mesh = Arc::new(mesh::sloth_mesh(&body.sloth, &skin.0, &muscles.biceps, fur));
    }
}

fn vec3(v: Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

impl DumpState for SlothMuscles {
    fn dump(&self, out: &mut Map<String, Value>) {
        let biceps: Map<String, Value> = self
            .biceps
            .iter()
            .zip(BICEPS_LIMBS)
            .map(|(muscle, limb)| {
                let value = json!({
                    "length_m": muscle.length_m(),
                    "flexion_deg": muscle.flexion.to_degrees(),
                    "volume_relative_error": muscle.relative_volume_error(),
                    "radii_m": muscle.model.radii().iter().map(|r| r * muscle.metres_per_unit).collect::<Vec<_>>(),
                    "refused": muscle.refusal.map(|refusal| refusal.to_string()),
                });
                (limb.key().to_string(), value)
            })
            .collect();
        out.insert("biceps".into(), Value::Object(biceps));
    }
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

impl DumpState for SlothGait {
    fn dump(&self, out: &mut Map<String, Value>) {
        let figures = self.0.figures(0.0);
        let limbs: Map<String, Value> = Limb::ALL
            .into_iter()
            .zip(&figures.limbs)
            .map(|(limb, f)| {
                let excursions: Map<String, Value> = limb
                    .joint_names()
                    .into_iter()
                    .zip(f.excursion_deg)
                    .map(|(name, e)| (name.to_string(), json!(e)))
                    .collect();
                let value = json!({
                    "contacts": f.contacts,
                    "contact_s": f.contact_s,
                    "swing_s": f.swing_s,
                    "duty_factor": f.duty_factor,
                    "stride_m": f.stride_m,
                    "excursion_deg": excursions,
                    "slip_max_m": f.slip_max_m,
                });
                (limb.key().to_string(), value)
            })
            .collect();
        out.insert(
            "gait".into(),
            json!({ "limbs": limbs, "diagonal_share": figures.diagonal_share, "footfalls": figures.footfalls.len() }),
        );
    }
}
