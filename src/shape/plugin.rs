//! The shape kind's plugin: its parameters and dump, spinning in the fixed step, and the
//! write-back of its transform and colour.

use super::def::ShapeDef;
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{SimSystems, WriteBackSystems};
use crate::foundation::values::{Angles, Color, MAX_METRES, Point, Size, srgb_channels, wrap_degrees};
use crate::raster::RasterMesh;
use crate::raster::primitives::Primitive;
use crate::spatial::SpatialSystems;
use crate::spatial::solid::{Collider, Solid};
use bevy::ecs::world::EntityRef;
use bevy::math::{EulerRot, Quat};
use bevy::prelude::*;
use serde_json::{Map, Value, json};

/// What a shape entity draws.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A primitive solid, drawn by the entity itself.
    Primitive(Primitive),
    /// A mesh file, drawn by the entity's children (one [`ShapePart`] each).
    Mesh {
        /// Triangles in all its parts.
        triangles: usize,
    },
}

/// One part of a mesh shape, a child of the shape's entity: its own colour (sRGB channels),
/// which the shape's colour multiplies.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct ShapePart {
    /// The part's colour as its file gives it.
    pub color: Vec3,
}

impl ShapePart {
    /// The part's colour multiplied by the shape's `tint`.
    pub fn tinted(&self, tint: Vec3) -> Vec3 {
        self.color * tint
    }
}

/// The live, editable state of a shape; the single source of its transform and colour.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct ShapeParams {
    /// Centre in metres.
    pub position: Vec3,
    /// Rotation in degrees about x, then y, then z, each kept in `[-180, 180)`.
    pub rotation_deg: Vec3,
    /// Extent in metres along each axis.
    pub size: Vec3,
    /// Surface colour (sRGB).
    pub color: Srgba,
    /// Rates of change of `rotation_deg`, degrees per second.
    pub spin_deg_per_s: Vec3,
}

impl From<&ShapeDef> for ShapeParams {
    fn from(def: &ShapeDef) -> Self {
        Self {
            position: def.position.0,
            rotation_deg: def.rotation_deg.0,
            size: def.size.0,
            color: def.color(),
            spin_deg_per_s: def.spin_deg_per_s.0,
        }
    }
}

/// The smallest size a shape may be edited down to, in metres.
const MIN_SIZE: f32 = 1e-3;

impl ShapeParams {
    /// The transform these parameters describe.
    pub fn transform(&self) -> Transform {
        let r = self.rotation_deg.map(f32::to_radians);
        Transform {
            translation: self.position,
            rotation: Quat::from_euler(EulerRot::XYZ, r.x, r.y, r.z),
            scale: self.size.max(Vec3::splat(MIN_SIZE)),
        }
    }

    /// The colour as the rasterizer takes it.
    pub fn color_channels(&self) -> Vec3 {
        srgb_channels(self.color)
    }
}

/// Brings `def` up to date with the shape's live parameters, each kept within what a scene file
/// holds. A spinning shape's rotation is where its spin has taken it, not an edit: the file's
/// rotation stays unless the shape stands still.
pub(super) fn save_live(def: &mut ShapeDef, entity: EntityRef) {
    let Some(params) = entity.get::<ShapeParams>() else { return };
    def.position = Point::nearest(params.position);
    def.size = Size(params.size.clamp(Vec3::splat(MIN_SIZE), Vec3::splat(MAX_METRES as f32)));
    let [red, green, blue] = [params.color.red, params.color.green, params.color.blue].map(|c| c.clamp(0.0, 1.0));
    let color = Srgba::rgb(red, green, blue);
    if def.color.is_some() || color != def.default_color() {
        def.color = Some(Color(color));
    }
    def.spin_deg_per_s = Angles::nearest(params.spin_deg_per_s);
    if params.spin_deg_per_s == Vec3::ZERO {
        def.rotation_deg = Angles::nearest(params.rotation_deg);
    }
}

impl DumpState for ShapeParams {
    fn dump(&self, out: &mut Map<String, Value>) {
        out.insert("position".into(), json!(self.position.to_array()));
        out.insert("rotation_deg".into(), json!(self.rotation_deg.to_array()));
        out.insert("size".into(), json!(self.size.to_array()));
        out.insert("color".into(), json!([self.color.red, self.color.green, self.color.blue]));
        out.insert("spin_deg_per_s".into(), json!(self.spin_deg_per_s.to_array()));
    }
}

impl DumpState for Shape {
    fn dump(&self, out: &mut Map<String, Value>) {
        match self {
            Shape::Primitive(primitive) => out.insert("primitive".into(), json!(primitive.key())),
            Shape::Mesh { triangles } => out.insert("mesh_triangles".into(), json!(triangles)),
        };
    }
}

/// Every system of the shape kind, in whichever phase it runs: a handle for ordering other
/// plugins' systems before or after the shapes'.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ShapeSystems;

/// Runs shapes: their parameters and dump fields, spinning, and their write-back.
#[derive(Default)]
pub struct ShapePlugin;

impl Plugin for ShapePlugin {
    fn build(&self, app: &mut App) {
        app.register_params::<ShapeParams>()
            .register_dump::<Shape>()
            .register_dump::<ShapeParams>()
            .add_systems(FixedUpdate, spin_shapes.in_set(SimSystems::Deform).in_set(ShapeSystems))
            .add_systems(PostUpdate, write_back_shapes.in_set(WriteBackSystems).in_set(ShapeSystems))
            .add_systems(PostUpdate, publish_solids.in_set(SpatialSystems::Publish).in_set(ShapeSystems));
    }
}

/// Advances the rotation of spinning shapes by one fixed step.
fn spin_shapes(time: Res<Time>, mut shapes: Query<&mut ShapeParams>) {
    let dt = time.delta_secs();
    for mut params in &mut shapes {
        if params.spin_deg_per_s != Vec3::ZERO {
            let spin = params.spin_deg_per_s;
            params.rotation_deg = (params.rotation_deg + spin * dt).map(wrap_degrees);
        }
    }
}

/// What writing a shape's parameters back changes: its transform, and the colour of its mesh or
/// of its parts.
type ShapeOutputs =
    (&'static ShapeParams, &'static mut Transform, Option<&'static mut RasterMesh>, Option<&'static Children>);

/// Writes edited or spun shape parameters into the transform and the colour of the mesh, or
/// of a mesh shape's parts.
fn write_back_shapes(
    mut shapes: Query<ShapeOutputs, Changed<ShapeParams>>,
    mut parts: Query<(&ShapePart, &mut RasterMesh), Without<ShapeParams>>,
) {
    for (params, mut transform, mesh, children) in &mut shapes {
        *transform = params.transform();
        let tint = params.color_channels();
        if let Some(mut mesh) = mesh {
            mesh.material.color = tint;
        }
        for child in children.into_iter().flatten() {
            if let Ok((part, mut mesh)) = parts.get_mut(*child) {
                mesh.material.color = part.tinted(tint);
            }
        }
    }
}

/// Every primitive shape is a solid where it stands now (a mesh shape is drawn, not solid).
fn publish_solids(shapes: Query<(Entity, &Shape, &GlobalTransform), Changed<GlobalTransform>>, mut commands: Commands) {
    for (entity, shape, placed) in &shapes {
        if let Shape::Primitive(primitive) = shape {
            commands.entity(entity).insert(Solid(Collider::shape(*primitive, placed.affine())));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_scales_by_size_and_rotates_in_degrees() {
        let def: ShapeDef =
            serde_yaml::from_str("{primitive: box, size: [2, 3, 4], rotation_deg: [0, 90, 0], position: [1, 0, 0]}")
                .unwrap();
        let transform = ShapeParams::from(&def).transform();
        assert_eq!(transform.scale, Vec3::new(2.0, 3.0, 4.0));
        assert!((transform.rotation * Vec3::X - Vec3::NEG_Z).length() < 1e-6);
        assert_eq!(transform.translation, Vec3::X);
    }
}
