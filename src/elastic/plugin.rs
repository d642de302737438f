//! The elastic body kind's plugin: the solids of the scene gathered for the bodies, the fixed
//! step, the keys, dragging with the mouse, actions, the write-back of the surface and the
//! dump.

use super::def::{Bending, Damping, ElasticBodyDef, ElasticBuilt, Friction, Modulus, Poisson, Substeps};
use super::xpbd::{Attachment, Body, World as Surroundings};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::entity::SceneEntity;
use crate::foundation::messages::{DragPhase, HandPlanted, SelectEntity, ViewDragged, ViewGrab};
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, SimSystems, WriteBackSystems};
use crate::foundation::values::srgb_channels;
use crate::raster::{MeshData, RasterMesh};
use crate::soft_body::draw::surface_mesh;
use crate::spatial::SpatialSystems;
use crate::spatial::pick::{Pickable, Picked, Pointer};
use crate::spatial::solid::{Collider, Solid};
use crate::spatial::tube::add_tube;
use crate::view::CameraParams;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::prelude::*;
use serde::Deserialize;
use serde_json::{Map, Value, json};
use std::sync::Arc;

/// Gravity, metres per second squared.
pub const GRAVITY: Vec3 = Vec3::new(0.0, -9.81, 0.0);

/// The colour of a stem, sRGB channels from 0 to 1.
const STEM_COLOR: Vec3 = Vec3::new(0.36, 0.42, 0.18);

/// Sides of a stem's tube.
const STEM_SIDES: usize = 6;

/// A stem's radius as a share of its body's lattice cell.
const STEM_RADIUS_SHARE: f32 = 0.3;

/// Marks the child entity that draws a body's stems.
#[derive(Component, Debug)]
struct StemMesh;

/// How soft the hand that drags a body is, as a natural frequency of the body's mass on it,
/// hertz: firm enough to follow the pointer, soft enough not to tear the body.
const HAND_HZ: f32 = 3.0;

/// The live state of an elastic body.
#[derive(Component, Debug, Clone)]
pub struct ElasticBody {
    /// The body now.
    pub body: Body,
    /// What it was built as: where a reset takes it back to.
    pub start: Arc<ElasticBuilt>,
    /// The body stands still (its own pause, apart from the simulation's).
    pub paused: bool,
    /// Its stems were released.
    pub dropped: bool,
    /// The plane a drag moves the hand in: a point of it and its normal.
    hand_plane: Option<(Vec3, Vec3)>,
    /// The grabbed particles' offsets from the hand.
    hand_offsets: Vec<Vec3>,
    /// The names of the solids of the last step, in the order of its contacts.
    solids: Arc<Vec<String>>,
    /// The surface where the tetrahedra carry it, for drawing and picking.
    surface: Vec<Vec3>,
}

impl ElasticBody {
    fn new(start: Arc<ElasticBuilt>) -> Self {
        let mut body = Self {
            body: start.body.clone(),
            start,
            paused: false,
            dropped: false,
            hand_plane: None,
            hand_offsets: Vec::new(),
            solids: Arc::default(),
            surface: Vec::new(),
        };
        body.place_surface();
        body
    }

    /// Places the surface where the particles carry it.
    fn place_surface(&mut self) {
        self.start.embedding.place(&self.body.rest, &self.body.positions, &mut self.surface);
    }

    /// Releases its stems: it falls.
    fn drop_from_stems(&mut self) {
        self.body.stems.clear();
        self.dropped = true;
    }

    /// Performs `action`; returns why it could not be, if it could not.
    pub fn perform(&mut self, action: &ElasticAction) -> Result<(), String> {
        match action {
            ElasticAction::Drop => self.drop_from_stems(),
            ElasticAction::Reset => {
                let params = self.body.material();
                *self = Self::new(self.start.clone());
                self.body.set_material(params);
            }
            ElasticAction::Pause => self.paused = true,
            ElasticAction::Resume => self.paused = false,
            ElasticAction::Grab(point) => {
                let point = Vec3::from_array(*point);
                self.grab(point, Vec3::Z);
            }
            ElasticAction::DragTo(point) => self.move_hand(Vec3::from_array(*point)),
            ElasticAction::LetGo => self.let_go(),
        }
        Ok(())
    }

    /// Grabs the particles nearest `point` with a hand that moves in the plane through it
    /// facing `normal`.
    fn grab(&mut self, point: Vec3, normal: Vec3) {
        let positions = &self.body.positions;
        let nearest = |a: &usize, b: &usize| positions[*a].distance(point).total_cmp(&positions[*b].distance(point));
        let Some(first) = (0..positions.len()).min_by(nearest) else { return };
        // Every particle within a cell of the nearest one: a hand, not a needle.
        let reach = positions[first].distance(point) + self.start.cell_m;
        let held: Vec<usize> = (0..positions.len()).filter(|&p| positions[p].distance(point) <= reach).collect();
        let compliance = hand_compliance(self.body.mass_kg(), held.len());
        self.hand_offsets = held.iter().map(|&p| positions[p] - point).collect();
        self.body.grab = held
            .iter()
            .map(|&p| Attachment { particle: p as u32, anchor: positions[p], length_m: 0.0, compliance })
            .collect();
        self.hand_plane = Some((point, normal));
    }

    /// Moves the hand to `point`.
    fn move_hand(&mut self, point: Vec3) {
        for (attachment, offset) in self.body.grab.iter_mut().zip(&self.hand_offsets) {
            attachment.anchor = point + *offset;
        }
    }

    /// Lets go of the body.
    fn let_go(&mut self) {
        self.body.grab.clear();
        self.hand_offsets.clear();
        self.hand_plane = None;
    }
}

/// The compliance of each of `held` attachments of a hand holding a body of `mass_kg`, so
/// that the body swings on it at [`HAND_HZ`].
fn hand_compliance(mass_kg: f32, held: usize) -> f32 {
    let omega = std::f32::consts::TAU * HAND_HZ;
    held as f32 / (mass_kg * omega * omega)
}

/// What an elastic body can be told to do from a timeline.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ElasticAction {
    /// Release the stems: the body falls.
    Drop,
    /// Back to its start, stems attached; its material parameters stay.
    Reset,
    /// Stand still.
    Pause,
    /// Move again.
    Resume,
    /// Grab it at the particles nearest this point, metres.
    Grab([f32; 3]),
    /// Move the hand to this point, metres.
    DragTo([f32; 3]),
    /// Let go.
    LetGo,
}

/// The live, editable material and stepping of an elastic body.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct ElasticParams {
    /// Young's modulus, pascals.
    pub young_modulus_pa: f32,
    /// Poisson's ratio, 0 to 0.5.
    pub poisson_ratio: f32,
    /// The share of velocity lost per second.
    pub damping_per_s: f32,
    /// The bending rigidity of its skin, newton metres (0: none).
    pub bending_rigidity_nm: f32,
    /// Friction with the solids it touches.
    pub friction: f32,
    /// Substeps a fixed step (a whole number; the panel's number is rounded).
    pub substeps: f32,
}

impl ElasticParams {
    /// The parameters kept in range.
    fn checked(&self) -> Self {
        Self {
            young_modulus_pa: self.young_modulus_pa.clamp(1.0, 1e9),
            poisson_ratio: self.poisson_ratio.clamp(0.0, 0.5),
            damping_per_s: self.damping_per_s.clamp(0.0, 100.0),
            bending_rigidity_nm: self.bending_rigidity_nm.clamp(0.0, 1e3),
            friction: self.friction.clamp(0.0, 10.0),
            substeps: self.substeps.round().clamp(1.0, 100.0),
        }
    }
}

/// The solids the bodies meet this step: every [`Solid`] of the scene, shapes first, then
/// grounds, then supports, each group in the scene's order, with the names of the entities
/// they are.
#[derive(Resource, Debug, Clone, Default)]
pub struct Solids {
    /// The solids.
    pub colliders: Arc<Vec<Collider>>,
    /// The entity each one is.
    pub names: Arc<Vec<String>>,
}

/// Spawns an elastic body's components; its surface is drawn in world coordinates.
pub(super) fn spawn_elastic_body(entity: &mut EntityWorldMut, def: &ElasticBodyDef, built: Arc<ElasticBuilt>) {
    let params = ElasticParams {
        young_modulus_pa: def.young_modulus_pa.0,
        poisson_ratio: def.poisson_ratio.0,
        damping_per_s: def.damping_per_s.0,
        bending_rigidity_nm: def.bending_rigidity_nm.0,
        friction: def.friction.0,
        substeps: def.substeps.0 as f32,
    };
    entity
        .insert((
            Transform::IDENTITY,
            RasterMesh::colored(Arc::default(), srgb_channels(def.color.0)),
            ElasticBody::new(built),
            params,
        ))
        .with_children(|children| {
            children.spawn((StemMesh, RasterMesh::colored(Arc::default(), STEM_COLOR)));
        });
}

/// Brings the definition's material and stepping up to date with the live parameters.
pub(super) fn save_live(def: &mut ElasticBodyDef, entity: EntityRef) {
    let Some(params) = entity.get::<ElasticParams>().map(ElasticParams::checked) else { return };
    def.young_modulus_pa = Modulus(params.young_modulus_pa);
    def.poisson_ratio = Poisson(params.poisson_ratio);
    def.damping_per_s = Damping(params.damping_per_s);
    def.bending_rigidity_nm = Bending(params.bending_rigidity_nm);
    def.friction = Friction(params.friction);
    def.substeps = Substeps(params.substeps as u32);
}

impl DumpState for ElasticBody {
    fn dump(&self, out: &mut Map<String, Value>) {
        let body = &self.body;
        let contacts: Map<String, Value> = self
            .solids
            .iter()
            .zip(body.contacts())
            .filter(|(_, n)| **n > 0)
            .map(|(name, n)| (name.clone(), json!(n)))
            .collect();
        out.insert("particles".into(), json!(body.positions.len()));
        out.insert("tetrahedra".into(), json!(body.tet_count()));
        out.insert("mass_kg".into(), json!(body.mass_kg()));
        out.insert("centre_of_mass".into(), json!(body.centre_of_mass().to_array()));
        out.insert("volume_ratio".into(), json!(body.volume_ratio()));
        out.insert("max_strain".into(), json!(body.max_strain()));
        out.insert("kinetic_energy_j".into(), json!(body.kinetic_energy()));
        out.insert("elastic_energy_j".into(), json!(body.elastic_energy()));
        out.insert("lowest".into(), json!(body.lowest().to_array()));
        out.insert("contacts".into(), Value::Object(contacts));
        out.insert("inverted".into(), json!(body.inverted()));
        out.insert("recoveries".into(), json!(body.recoveries()));
        out.insert("stems".into(), json!(body.stems.len()));
        out.insert("held".into(), json!(!body.grab.is_empty()));
        out.insert("dropped".into(), json!(self.dropped));
        out.insert("paused".into(), json!(self.paused));
    }
}

/// Every system of the elastic body kind, in whichever phase it runs: a handle for ordering
/// other plugins' systems before or after the elastic bodies'.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ElasticSystems;

/// Elastic body keys: (key, action).
pub(super) const ELASTIC_KEYS: [(KeyCode, &str); 3] = [
    (KeyCode::KeyO, "drop the elastic bodies from their stems"),
    (KeyCode::KeyB, "put the elastic bodies back where they started"),
    (KeyCode::KeyP, "pause or resume the elastic bodies"),
];

/// Runs elastic bodies: parameters, the solids, the fixed step, keys, dragging, actions, the
/// write-back of their surfaces, the dump and the panel section.
#[derive(Default)]
pub struct ElasticPlugin;

impl Plugin for ElasticPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Solids>()
            .register_params::<ElasticParams>()
            .register_dump::<ElasticBody>()
            .add_systems(
                RunFixedMainLoop,
                (act_on_keys, drag_with_the_mouse).in_set(ControlSystems::Input).in_set(ElasticSystems),
            )
            .add_systems(RunFixedMainLoop, apply_params.in_set(ControlSystems::Apply).in_set(ElasticSystems))
            .add_systems(
                FixedUpdate,
                (shake_loose, gather_solids, step_bodies).chain().in_set(SimSystems::Dynamics).in_set(ElasticSystems),
            )
            .add_systems(PostUpdate, write_back_surfaces.in_set(WriteBackSystems).in_set(ElasticSystems))
            .add_systems(PostUpdate, publish_surfaces.in_set(SpatialSystems::Publish).in_set(ElasticSystems));
    }
}

/// Performs a timeline's action on the body `entity`.
pub(super) fn perform_action(world: &mut World, entity: Entity, action: ElasticAction) {
    let Some(mut body) = world.get_mut::<ElasticBody>(entity) else { return };
    if let Err(error) = body.perform(&action) {
        warn!("{error}");
    }
}

/// Drops the bodies hanging on a stem that shakes loose when a hand takes hold within its reach
/// of the anchor (sent by the animals' locomotion, earlier in the step).
fn shake_loose(mut hands: MessageReader<HandPlanted>, mut bodies: Query<&mut ElasticBody>) {
    for hand in hands.read() {
        for mut body in &mut bodies {
            let Some((anchor, reach)) = body.start.shaken_loose else { continue };
            if !body.dropped && hand.point.distance(anchor) <= reach {
                body.drop_from_stems();
            }
        }
    }
}

/// Gathers the solids as their kinds last wrote them.
fn gather_solids(mut solids: ResMut<Solids>, scene: Query<(&SceneEntity, &Solid)>) {
    let mut found: Vec<(&SceneEntity, &Collider)> =
        scene.iter().map(|(entity, Solid(collider))| (entity, collider)).collect();
    found.sort_by_key(|(entity, collider)| (collider.rank(), entity.index));
    let names = found.iter().map(|(entity, _)| entity.name.clone()).collect();
    let colliders = found.into_iter().map(|(_, collider)| collider.clone()).collect();
    *solids = Solids { colliders: Arc::new(colliders), names: Arc::new(names) };
}

/// Steps every body that is not paused by the fixed step, bodies in parallel.
fn step_bodies(time: Res<Time>, solids: Res<Solids>, mut bodies: Query<(&mut ElasticBody, &ElasticParams)>) {
    let dt = time.delta_secs();
    bodies.par_iter_mut().for_each(|(mut elastic, params)| {
        if elastic.paused {
            return;
        }
        let world = Surroundings {
            gravity: GRAVITY,
            colliders: &solids.colliders,
            friction: params.friction,
            substeps: params.substeps as u32,
        };
        elastic.body.step(dt, world);
        elastic.solids = solids.names.clone();
        elastic.place_surface();
    });
}

/// Writes changed parameters into their bodies.
fn apply_params(mut bodies: Query<(&mut ElasticBody, &mut ElasticParams), Changed<ElasticParams>>) {
    for (mut elastic, mut params) in &mut bodies {
        let checked = params.checked();
        if checked != *params {
            *params = checked.clone();
        }
        let mut material = elastic.body.material();
        material.young_modulus_pa = checked.young_modulus_pa;
        material.poisson_ratio = checked.poisson_ratio;
        material.damping_per_s = checked.damping_per_s;
        material.bending_rigidity_nm = checked.bending_rigidity_nm;
        if material != elastic.body.material() {
            elastic.body.set_material(material);
        }
    }
}

/// The elastic body keys, acting on every elastic body.
fn act_on_keys(keys: Res<ButtonInput<KeyCode>>, mut bodies: Query<&mut ElasticBody>) {
    let action = if keys.just_pressed(KeyCode::KeyO) {
        Some(ElasticAction::Drop)
    } else if keys.just_pressed(KeyCode::KeyB) {
        Some(ElasticAction::Reset)
    } else {
        None
    };
    let toggle = keys.just_pressed(KeyCode::KeyP);
    for mut elastic in &mut bodies {
        if let Some(action) = &action {
            let _ = elastic.perform(action);
        }
        if toggle {
            elastic.paused = !elastic.paused;
        }
    }
}

/// Grabs the body a drag's start picked, moves the hand in the plane facing the camera through
/// the point grabbed as the pointer moves, and lets go when the drag ends.
fn drag_with_the_mouse(
    mut picks: MessageReader<Picked>,
    mut drags: MessageReader<ViewDragged>,
    cameras: Query<&CameraParams>,
    mut bodies: Query<(&mut ElasticBody, &SceneEntity)>,
    mut grab: ResMut<ViewGrab>,
    mut selections: MessageWriter<SelectEntity>,
) {
    let Some(camera) = cameras.iter().next().map(CameraParams::camera) else { return };
    for picked in picks.read().filter(|picked| picked.pointer == Pointer::Grab) {
        let Ok((mut elastic, scene)) = bodies.get_mut(picked.hit.entity) else { continue };
        let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        elastic.grab(picked.hit.point, forward);
        selections.write(SelectEntity(scene.name.clone()));
        grab.held = true;
    }
    for drag in drags.read() {
        let (origin, direction) = camera.ray(drag.ndc, drag.aspect);
        match drag.phase {
            // Grabs come picked, above.
            DragPhase::Start => {}
            DragPhase::Move => {
                for (mut elastic, _) in &mut bodies {
                    let Some((point, normal)) = elastic.hand_plane else { continue };
                    let along = direction.dot(normal);
                    if along.abs() < 1e-6 {
                        continue;
                    }
                    let distance = (point - origin).dot(normal) / along;
                    if distance > 0.0 {
                        elastic.move_hand(origin + direction * distance);
                    }
                }
            }
            DragPhase::End => {
                for (mut elastic, _) in &mut bodies {
                    if elastic.hand_plane.is_some() {
                        elastic.let_go();
                    }
                }
                grab.held = false;
            }
        }
    }
}

/// A body that moved can be grabbed where its surface is now.
fn publish_surfaces(bodies: Query<(Entity, &ElasticBody), Changed<ElasticBody>>, mut commands: Commands) {
    for (entity, elastic) in &bodies {
        let positions = Arc::new(elastic.surface.clone());
        commands.entity(entity).insert(Pickable::Mesh { positions, triangles: elastic.start.triangles.clone() });
    }
}

/// The bodies that moved, with their surfaces' meshes and their children.
type MovedBodies<'w, 's> = Query<
    'w,
    's,
    (&'static ElasticBody, &'static mut RasterMesh, &'static Children),
    (Changed<ElasticBody>, Without<StemMesh>),
>;

/// Draws each body's surface where its tetrahedra carry it, and its stems.
fn write_back_surfaces(mut bodies: MovedBodies, mut stems: Query<&mut RasterMesh, With<StemMesh>>) {
    for (elastic, mut raster, children) in &mut bodies {
        raster.mesh = Arc::new(surface_mesh(&elastic.surface, &elastic.start.triangles, Vec::new()));
        let mut drawn = stems.iter_many_mut(children);
        while let Some(mut stem) = drawn.fetch_next() {
            if !(stem.mesh.positions.is_empty() && elastic.body.stems.is_empty()) {
                stem.mesh = Arc::new(stem_mesh(&elastic.body, STEM_RADIUS_SHARE * elastic.start.cell_m));
            }
        }
    }
}

/// A tube of `radius_m` from each stem's anchor to the middle of the particles it holds
/// (nothing for a body without stems).
fn stem_mesh(body: &Body, radius_m: f32) -> MeshData {
    let mut mesh = MeshData::default();
    let mut stems: Vec<&Attachment> = body.stems.iter().collect();
    while let Some(first) = stems.first().copied() {
        let (held, rest): (Vec<&Attachment>, Vec<&Attachment>) = stems.iter().partition(|a| a.anchor == first.anchor);
        let end = held.iter().map(|a| body.positions[a.particle as usize]).sum::<Vec3>() / held.len() as f32;
        add_tube(&mut mesh, &[first.anchor, end], &[radius_m, radius_m], STEM_SIDES);
        stems = rest;
    }
    mesh
}
