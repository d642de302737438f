//! The muscle kind's plugin: its parameters and keys, the model following its flexion in the
//! fixed step, the write-back of its surface and rods, and its dump.

use super::carcass::Carcass;
use super::comparison::{REAL_BICEPS_RADII, growth_table, model_radii};
use super::def::{BuiltMuscle, MuscleDef, Scale};
use super::fit::GrowthFit;
use super::model::Muscle;
use super::surface;
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, SimSystems, WriteBackSystems};
use crate::foundation::values::{Angles, Point, srgb_channels, wrap_degrees};
use crate::raster::primitives::{Primitive, PrimitiveMeshes};
use crate::raster::{MeshData, RasterMesh};
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::math::{EulerRot, Quat};
use bevy::prelude::*;
use serde_json::{Map, Value, json};
use std::sync::Arc;

/// The live muscle: model, carcass and the surface mesh.
#[derive(Component, Debug, Clone)]
pub struct MuscleBody {
    /// The node model.
    pub model: Muscle,
    /// The arm.
    pub carcass: Carcass,
    /// Vertices around each ring.
    pub segments: usize,
    /// The flexion and length last applied, to tell which parameter the user changed.
    applied: (f64, f64),
    /// Why the last requested change was refused or clamped.
    pub message: Option<String>,
    /// Its growth fitted to the real biceps, for a model laid out as the measurements are.
    pub fit: Option<GrowthFit>,
    /// Whether the model grows with the fitted multipliers rather than the configured ones.
    pub fitted: bool,
}

impl MuscleBody {
    /// Grows the model with the fitted multipliers or the configured ones, at its current
    /// flexion when it can keep it (else at rest); nothing changes without a fit.
    pub fn use_fit(&mut self, fitted: bool) {
        let Some(fit) = &self.fit else { return };
        let mults = if fitted { &fit.mults } else { &fit.configured };
        let length = self.model.length();
        if let Ok(mut model) = self.model.with_mults(mults.clone()) {
            self.message = model.set_length(length).err().map(|refusal| refusal.to_string());
            (self.model, self.fitted) = (model, fitted);
        }
    }
}

/// The muscle's editable parameters.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct MuscleParams {
    /// Elbow flexion in degrees, 0 = straight arm.
    pub flexion_deg: f64,
    /// Muscle length in config units.
    pub length: f64,
}

/// Where the arm stands: the model's position, rotation and scale, editable like any
/// parameter (`<name>.position.x`, `<name>.rotation_deg.y`, `<name>.scale`, ...).
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct Placement {
    /// The elbow, metres.
    pub position: Vec3,
    /// Rotation in degrees about x, then y, then z.
    pub rotation_deg: Vec3,
    /// Metres per config unit.
    pub scale: f32,
}

impl Placement {
    /// The transform these values describe (a scale of at least 1e-6).
    pub fn transform(&self) -> Transform {
        let r = self.rotation_deg.map(f32::to_radians);
        Transform {
            translation: self.position,
            rotation: Quat::from_euler(EulerRot::XYZ, r.x, r.y, r.z),
            scale: Vec3::splat(self.scale.max(1e-6)),
        }
    }
}

/// Marks the entity drawing the muscle surface, a child of the muscle entity.
#[derive(Component)]
struct MuscleSurface;

/// Marks the entity drawing rod 1 or rod 2 of the carcass.
#[derive(Component)]
struct Rod(u8);

/// Brings `def` up to date with where the arm was moved, turned and scaled to, each kept within
/// what a scene file holds, and with whether it grows with the fitted multipliers.
pub(super) fn save_live(def: &mut MuscleDef, entity: EntityRef) {
    if let Some(body) = entity.get::<MuscleBody>()
        && body.fit.is_some()
    {
        def.fit_growth = body.fitted;
    }
    let Some(placement) = entity.get::<Placement>() else { return };
    def.position = Point::nearest(placement.position);
    def.rotation_deg = Angles::nearest(placement.rotation_deg);
    def.scale = Scale(placement.scale.clamp(1e-6, 1e6));
}

/// Spawns a muscle entity of `def`, whose model and carcass are `built`, and its drawn parts.
pub(super) fn spawn_muscle(entity: &mut EntityWorldMut, def: &MuscleDef, built: BuiltMuscle) {
    let BuiltMuscle { model, carcass, fit } = built;
    let mut body = MuscleBody {
        model,
        carcass,
        segments: def.segments.count(),
        applied: (f64::NAN, f64::NAN),
        message: None,
        fit,
        fitted: false,
    };
    if def.fit_growth {
        body.use_fit(true);
    }
    let (model, carcass) = (&body.model, &body.carcass);
    let length = model.length();
    let flexion_deg = carcass.flexion_from_length(length).value.to_degrees();
    let color = srgb_channels(def.color.0);
    let cylinder = entity.world().resource::<PrimitiveMeshes>().get(Primitive::Cylinder).clone();
    let placement = Placement { position: def.position.0, rotation_deg: def.rotation_deg.0, scale: def.scale.0 };
    entity.insert((placement.transform(), placement, MuscleParams { flexion_deg, length }, body)).with_children(
        |children| {
            children.spawn((MuscleSurface, RasterMesh::colored(Arc::new(MeshData::default()), color)));
            for index in 0..2 {
                let rod = RasterMesh::colored(cylinder.clone(), Vec3::splat(0.85));
                children.spawn((Rod(index), rod));
            }
        },
    );
}

/// Every system of the muscle kind, in whichever phase it runs: a handle for ordering other
/// plugins' systems before or after the muscles'.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MuscleSystems;

/// Runs muscles: parameters, keys, the model in the fixed step, write-back, dump and panel.
#[derive(Default)]
pub struct MusclePlugin;

/// Flexion speed of the hold keys, degrees per second.
const FLEX_DEG_PER_S: f64 = 30.0;
/// Flexion step of the step keys, degrees.
const FLEX_STEP_DEG: f64 = 15.0;
/// Muscle keys: (key, action, hold rate sign, step sign).
pub(super) const MUSCLE_KEYS: [(KeyCode, &str, f64, f64); 4] = [
    (KeyCode::KeyW, "contract the muscle (flex the elbow)", 1.0, 0.0),
    (KeyCode::KeyS, "stretch the muscle (extend the elbow)", -1.0, 0.0),
    (KeyCode::KeyE, "flex the elbow 15 degrees more", 0.0, 1.0),
    (KeyCode::KeyQ, "flex the elbow 15 degrees less", 0.0, -1.0),
];
/// Turning speed of the model, degrees per second.
const TURN_DEG_PER_S: f32 = 45.0;
/// Moving speed of the model, metres per second.
const MOVE_M_PER_S: f32 = 0.5;
/// Scaling speed of the model: the scale changes by this factor per second.
const SCALE_PER_S: f32 = 1.5;
/// Placement keys: (key, action, turn about y, move along x, move along y, scale exponent).
pub(super) const PLACEMENT_KEYS: [(KeyCode, &str, f32, f32, f32, f32); 8] = [
    (KeyCode::KeyR, "turn the arm left", 1.0, 0.0, 0.0, 0.0),
    (KeyCode::KeyF, "turn the arm right", -1.0, 0.0, 0.0, 0.0),
    (KeyCode::KeyA, "move the arm left", 0.0, -1.0, 0.0, 0.0),
    (KeyCode::KeyD, "move the arm right", 0.0, 1.0, 0.0, 0.0),
    (KeyCode::KeyT, "move the arm up", 0.0, 0.0, 1.0, 0.0),
    (KeyCode::KeyG, "move the arm down", 0.0, 0.0, -1.0, 0.0),
    (KeyCode::KeyX, "make the arm larger", 0.0, 0.0, 0.0, 1.0),
    (KeyCode::KeyZ, "make the arm smaller", 0.0, 0.0, 0.0, -1.0),
];

impl Plugin for MusclePlugin {
    fn build(&self, app: &mut App) {
        app.register_params::<MuscleParams>()
            .register_params::<Placement>()
            .register_dump::<MuscleBody>()
            .add_systems(
                RunFixedMainLoop,
                (flex_with_keys, place_with_keys).in_set(ControlSystems::Input).in_set(MuscleSystems),
            )
            .add_systems(RunFixedMainLoop, apply_placement.in_set(ControlSystems::Apply).in_set(MuscleSystems))
            .add_systems(FixedUpdate, follow_flexion.in_set(SimSystems::Deform).in_set(MuscleSystems))
            .add_systems(PostUpdate, write_back_muscles.in_set(WriteBackSystems).in_set(MuscleSystems));
    }
}

fn flex_with_keys(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut muscles: Query<&mut MuscleParams>) {
    let mut change = 0.0;
    for (key, _, rate, step) in MUSCLE_KEYS {
        if keys.pressed(key) {
            change += rate * FLEX_DEG_PER_S * time.delta_secs_f64();
        }
        if keys.just_pressed(key) {
            change += step * FLEX_STEP_DEG;
        }
    }
    if change != 0.0 {
        for mut params in &mut muscles {
            params.flexion_deg = (params.flexion_deg + change).clamp(0.0, 180.0);
        }
    }
}

fn place_with_keys(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut placements: Query<&mut Placement>) {
    let dt = time.delta_secs();
    let (mut turn, mut shift, mut grow) = (0.0, Vec3::ZERO, 0.0);
    for (key, _, t, x, y, s) in PLACEMENT_KEYS {
        if keys.pressed(key) {
            (turn, shift, grow) = (turn + t, shift + Vec3::new(x, y, 0.0), grow + s);
        }
    }
    if (turn, shift, grow) == (0.0, Vec3::ZERO, 0.0) {
        return;
    }
    for mut placement in &mut placements {
        placement.rotation_deg.y = wrap_degrees(placement.rotation_deg.y + turn * TURN_DEG_PER_S * dt);
        placement.position += shift * MOVE_M_PER_S * dt;
        placement.scale *= SCALE_PER_S.powf(grow * dt);
    }
}

fn apply_placement(mut placements: Query<(&Placement, &mut Transform), Changed<Placement>>) {
    for (placement, mut transform) in &mut placements {
        *transform = placement.transform();
    }
}

/// Moves the model to the length or flexion the parameters ask for; a refusal keeps the last
/// valid state and is reported.
fn follow_flexion(mut muscles: Query<(&mut MuscleParams, &mut MuscleBody), Changed<MuscleParams>>) {
    for (mut params, mut body) in &mut muscles {
        let body = &mut *body;
        let flexion_changed = params.flexion_deg != body.applied.0;
        let (length, clamp_note) = if flexion_changed {
            let clamped = body.carcass.length_from_flexion(params.flexion_deg.to_radians());
            (clamped.value, clamped.note)
        } else {
            (params.length, None)
        };
        body.message = match body.model.set_length(length) {
            Ok(()) => clamp_note.map(str::to_string),
            Err(refusal) => Some(refusal.to_string()),
        };
        if let Some(message) = &body.message {
            warn!("muscle: {message}");
        }
        let length = body.model.length();
        let flexion = body.carcass.flexion_from_length(length).value.to_degrees();
        body.applied = (flexion, length);
        let params = params.bypass_change_detection();
        params.flexion_deg = flexion;
        params.length = length;
    }
}

/// The drawn surface of a muscle, apart from its rods.
type SurfaceParts<'w, 's> =
    Query<'w, 's, (&'static mut RasterMesh, &'static mut Transform), (With<MuscleSurface>, Without<Rod>)>;

/// Rebuilds the surface and places the surface and rods for the current state.
fn write_back_muscles(
    muscles: Query<(&MuscleBody, &Children), Changed<MuscleBody>>,
    mut surfaces: SurfaceParts,
    mut rods: Query<(&Rod, &mut Transform), Without<MuscleSurface>>,
) {
    for (body, children) in &muscles {
        let carcass = &body.carcass;
        let flexion = carcass.flexion_from_length(body.model.length()).value;
        // The elbow is the origin; rod 1 lies along -x, rod 2 turns up by the flexion.
        let forearm = Vec3::new(flexion.cos() as f32, flexion.sin() as f32, 0.0);
        let attachment_1 = Vec3::new(-carcass.b1 as f32, 0.0, 0.0);
        let attachment_2 = forearm * carcass.a2 as f32;
        let ends = [
            (Vec3::new(-(carcass.a1 + carcass.b1) as f32, 0.0, 0.0), Vec3::ZERO),
            (Vec3::ZERO, forearm * (carcass.a2 + carcass.b2) as f32),
        ];
        for child in children.iter() {
            if let Ok((mut mesh, mut transform)) = surfaces.get_mut(child) {
                let muscle_mesh = Arc::make_mut(&mut mesh.mesh);
                surface::build_surface(body.model.radii(), body.model.node_spacing(), body.segments, muscle_mesh);
                let axis = attachment_2 - attachment_1;
                *transform = Transform::from_translation(attachment_1)
                    .with_rotation(Quat::from_rotation_arc(Vec3::X, axis.normalize_or(Vec3::X)));
            } else if let Ok((rod, mut transform)) = rods.get_mut(child) {
                let (start, end) = ends[rod.0 as usize];
                let thickness = carcass.thickness as f32;
                *transform = Transform {
                    translation: (start + end) / 2.0,
                    rotation: Quat::from_rotation_arc(Vec3::Y, (end - start).normalize_or(Vec3::Y)),
                    scale: Vec3::new(thickness, (end - start).length(), thickness),
                };
            }
        }
    }
}

impl DumpState for MuscleBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let model = &self.model;
        out.insert("radii".into(), json!(model.radii()));
        out.insert("length".into(), json!(model.length()));
        out.insert("flexion_deg".into(), json!(self.carcass.flexion_from_length(model.length()).value.to_degrees()));
        out.insert("volume".into(), json!(model.volume()));
        out.insert("rest_volume".into(), json!(model.rest_volume()));
        out.insert("node_spacing".into(), json!(model.node_spacing()));
        if let Some(table) = growth_table(model, &self.carcass) {
            let rows: Vec<Value> = table
                .iter()
                .map(|row| json!({"node": row.node, "real": row.real, "model": row.model, "ratio": row.ratio}))
                .collect();
            out.insert("growth_table".into(), Value::Array(rows));
        }
        // Tables 4.1 and 4.2: the real radii of the measured nodes and the model's radii of
        // every node (null where the arm cannot reach the flexion), at each flexion measured.
        let radius_table: Vec<Value> = REAL_BICEPS_RADII
            .iter()
            .zip(model_radii(model, &self.carcass))
            .map(|((flexion, real), radii)| json!({"flexion_deg": flexion, "real": real, "model": radii}))
            .collect();
        out.insert("radius_table".into(), Value::Array(radius_table));
        if let Some(fit) = &self.fit {
            out.insert(
                "growth_fit".into(),
                json!({
                    "fitted": self.fitted,
                    "configured_mults": fit.configured,
                    "fitted_mults": fit.mults,
                    "rms_configured": fit.rms_before,
                    "rms_fitted": fit.rms_after,
                    "gap_closed": fit.gap_closed(),
                }),
            );
        }
    }
}
