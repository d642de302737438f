//! The `shape` entity kind: primitive solids (box, sphere, cylinder, plane) that give scenes
//! real 3D content, optionally spinning at a constant rate.
//!
//! Parameters (`<name>.<parameter>`, all from [`ShapeParams`]): `position.{x,y,z}` (metres),
//! `rotation_deg.{x,y,z}`, `size.{x,y,z}` (metres, > 0), `color.{red,green,blue}` (0 to 1),
//! `spin_deg_per_s.{x,y,z}`.
//!
//! A shape may carry a texture: a PNG or BMP file in the scene's folder, modulated by its
//! colour, read with nearest or bilinear filtering, repeated or clamped at its edges.

use crate::dump::{DumpState, RegisterDump};
use crate::params::RegisterParams;
use crate::raster::{Address, Filter, Material, MeshData, RasterMesh, Sampler, Texture};
use crate::scene::values::{Angles, Color, Point, Repeats, Size, inside_folder};
use crate::schedule::{ControlSystems, SimSystems};
use crate::yaml::deserialize_str_with;
use bevy::color::Srgba;
use bevy::math::{EulerRot, Quat, Vec3};
use bevy::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};
use std::sync::Arc;

/// Which solid a shape is. Each fits the box of its `size`: a sphere of size `[2, 1, 1]` is an
/// ellipsoid, a cylinder stands along y, a plane lies in xz facing +y.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Reflect)]
#[serde(rename_all = "snake_case")]
pub enum Primitive {
    /// A cuboid.
    Box,
    /// A sphere (ellipsoid for unequal sizes).
    Sphere,
    /// A cylinder along y with flat caps.
    Cylinder,
    /// A flat rectangle in xz facing +y; its y size is ignored.
    Plane,
}

impl Primitive {
    /// The name used in files and dumps.
    pub fn key(self) -> &'static str {
        match self {
            Primitive::Box => "box",
            Primitive::Sphere => "sphere",
            Primitive::Cylinder => "cylinder",
            Primitive::Plane => "plane",
        }
    }
}

/// A `shape` entity in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeDef {
    /// Which solid.
    pub primitive: Primitive,
    /// Extent along x, y and z in metres (one number for all three); 1 by default.
    #[serde(default = "unit_size")]
    pub size: Size,
    /// Centre in metres; the origin by default.
    #[serde(default = "origin")]
    pub position: Point,
    /// Rotation in degrees about x, then y, then z (intrinsic); none by default.
    #[serde(default = "no_angles")]
    pub rotation_deg: Angles,
    /// Surface colour; light grey by default.
    #[serde(default = "grey")]
    pub color: Color,
    /// Rates of change of `rotation_deg` in degrees per second; none by default.
    #[serde(default = "no_angles")]
    pub spin_deg_per_s: Angles,
    /// An image on the surface; none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureDef>,
}

/// A shape's texture in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDef {
    /// The image file.
    pub file: TexturePath,
    /// `nearest` or `bilinear` (the default).
    #[serde(default)]
    pub filter: Filter,
    /// `repeat` (the default) or `clamp`.
    #[serde(default)]
    pub address: Address,
    /// Repetitions across the surface along u and v; `[1, 1]` by default.
    #[serde(default = "once")]
    pub repeat: [Repeats; 2],
    /// The decoded image, filled in when the scene is resolved.
    #[serde(skip)]
    pub image: Option<Arc<Texture>>,
}

fn once() -> [Repeats; 2] {
    [Repeats(1.0); 2]
}

/// A path to a texture: relative, inside the scene's folder (no `..`), ending in `.png` or
/// `.bmp`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct TexturePath(pub String);

impl<'de> Deserialize<'de> for TexturePath {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize_str_with(deserializer, "a .png or .bmp file in the scene's folder", |path| {
            let lower = path.to_ascii_lowercase();
            if inside_folder(path) && (lower.ends_with(".png") || lower.ends_with(".bmp")) {
                Ok(TexturePath(path.to_string()))
            } else {
                Err(format!(
                    "expected a .png or .bmp file inside the scene's folder (relative, without `..`), found \"{path}\""
                ))
            }
        })
    }
}

impl ShapeDef {
    /// The material these settings describe, in the shape's current colour.
    fn material(&self, color: Srgba) -> Material {
        material(srgb_vec(color), self.texture.as_ref())
    }
}

/// A material of `color` (linear RGB) with an optional texture.
pub fn material(color: Vec3, texture: Option<&TextureDef>) -> Material {
    let mut material = Material::colored(color);
    if let Some(texture) = texture {
        material.texture = texture.image.clone();
        material.sampler = Sampler { filter: texture.filter, address: texture.address };
        material.uv_scale = Vec2::new(texture.repeat[0].0, texture.repeat[1].0);
    }
    material
}

fn unit_size() -> Size {
    Size(Vec3::ONE)
}

fn origin() -> Point {
    Point(Vec3::ZERO)
}

fn no_angles() -> Angles {
    Angles(Vec3::ZERO)
}

fn grey() -> Color {
    Color(Srgba::gray(0.8))
}

/// Which primitive a shape entity draws.
#[derive(Component, Debug, Clone, Copy)]
pub struct Shape(pub Primitive);

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
            color: def.color.0,
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
        out.insert("primitive".into(), json!(self.0.key()));
    }
}

/// The primitive meshes, built once and shared by every shape.
#[derive(Resource)]
pub struct PrimitiveMeshes {
    cube: Arc<MeshData>,
    sphere: Arc<MeshData>,
    cylinder: Arc<MeshData>,
    plane: Arc<MeshData>,
}

impl Default for PrimitiveMeshes {
    fn default() -> Self {
        Self {
            cube: Arc::new(MeshData::cube()),
            sphere: Arc::new(MeshData::sphere(24, 48)),
            cylinder: Arc::new(MeshData::cylinder(48)),
            plane: Arc::new(MeshData::plane(16)),
        }
    }
}

impl PrimitiveMeshes {
    /// The shared mesh of a primitive, sized 1 along every axis.
    pub fn get(&self, primitive: Primitive) -> &Arc<MeshData> {
        match primitive {
            Primitive::Box => &self.cube,
            Primitive::Sphere => &self.sphere,
            Primitive::Cylinder => &self.cylinder,
            Primitive::Plane => &self.plane,
        }
    }
}

/// Spawns the components of a shape entity onto `entity`.
pub fn spawn_shape(entity: &mut EntityCommands, def: &ShapeDef, meshes: &PrimitiveMeshes) {
    let params = ShapeParams::from(def);
    entity.insert((
        Shape(def.primitive),
        params.transform(),
        RasterMesh { mesh: meshes.get(def.primitive).clone(), material: def.material(params.color) },
        params,
    ));
}

fn srgb_vec(color: Srgba) -> Vec3 {
    Vec3::new(color.red, color.green, color.blue).clamp(Vec3::ZERO, Vec3::ONE)
}

/// Registers the shape kind: its parameters, dump fields and systems.
pub struct ShapePlugin;

impl Plugin for ShapePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<PrimitiveMeshes>()
            .register_params::<ShapeParams>()
            .register_dump::<Shape>()
            .register_dump::<ShapeParams>()
            .add_systems(FixedUpdate, spin_shapes.in_set(SimSystems::Step))
            .add_systems(Update, apply_shape_params.in_set(ControlSystems::Apply));
    }
}

/// Advances the rotation of spinning shapes by one fixed step.
fn spin_shapes(time: Res<Time>, mut shapes: Query<&mut ShapeParams>) {
    let dt = time.delta_secs();
    for mut params in &mut shapes {
        if params.spin_deg_per_s != Vec3::ZERO {
            let spin = params.spin_deg_per_s;
            params.rotation_deg = (params.rotation_deg + spin * dt + 180.0).rem_euclid(Vec3::splat(360.0)) - 180.0;
        }
    }
}

/// Writes edited shape parameters into the transform and the mesh colour.
fn apply_shape_params(mut shapes: Query<(&ShapeParams, &mut Transform, &mut RasterMesh), Changed<ShapeParams>>) {
    for (params, mut transform, mut mesh) in &mut shapes {
        *transform = params.transform();
        mesh.material.color = srgb_vec(params.color);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_defaults_and_unknown_primitives() {
        let def: ShapeDef = serde_yaml::from_str("primitive: sphere").unwrap();
        assert_eq!(def.size.0, Vec3::ONE);
        assert_eq!(def.position.0, Vec3::ZERO);
        let error = serde_yaml::from_str::<ShapeDef>("primitive: cone").unwrap_err().to_string();
        assert!(error.contains("unknown variant `cone`, expected one of"), "{error}");
        let error = serde_yaml::from_str::<ShapeDef>("size: 1").unwrap_err().to_string();
        assert!(error.contains("missing field `primitive`"), "{error}");
    }

    #[test]
    fn texture_settings_parse_with_defaults_and_paths_stay_inside() {
        let def: ShapeDef = serde_yaml::from_str("{primitive: plane, texture: {file: textures/checker.png}}").unwrap();
        let texture = def.texture.unwrap();
        assert_eq!((texture.filter, texture.address), (Filter::Bilinear, Address::Repeat));
        let def: ShapeDef = serde_yaml::from_str(
            "{primitive: box, texture: {file: a.bmp, filter: nearest, address: clamp, repeat: [2, 3]}}",
        )
        .unwrap();
        let material = def.material(Srgba::WHITE);
        assert_eq!(material.sampler, Sampler { filter: Filter::Nearest, address: Address::Clamp });
        assert_eq!(material.uv_scale, Vec2::new(2.0, 3.0));
        for bad in ["../up.png", "/abs.png", "image.jpg"] {
            let yaml = format!("{{primitive: box, texture: {{file: \"{bad}\"}}}}");
            let error = serde_yaml::from_str::<ShapeDef>(&yaml).unwrap_err().to_string();
            assert!(error.contains("expected a .png or .bmp file inside the scene's folder"), "{error}");
        }
    }

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
