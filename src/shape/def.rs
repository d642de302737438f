//! The `shape:` entry of a scene file, and the kind that reads, spawns and saves it.

use super::mesh::MeshParts;
use crate::foundation::values::{Angles, Color, FolderFile, Point, Size};
use crate::raster::Material;
use crate::raster::primitives::Primitive;
use crate::raster::texture::{TextureDef, material};
use crate::spatial::mesh_io::MeshFile;
use bevy::color::{Gray, Srgba};
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A `shape` entity in a scene file: a primitive solid, or a mesh file drawn as a prop.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeDef {
    /// Which solid, for a primitive shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub primitive: Option<Primitive>,
    /// The mesh file drawn, for a mesh shape: OBJ, PLY or STL in one colour, or glTF with its
    /// nodes' placements, materials' base colours and base colour textures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<FolderFile<MeshFile>>,
    /// A primitive's extent along x, y and z in metres, a mesh's scale (one number for all
    /// three); 1 by default.
    #[serde(default = "unit_size")]
    pub size: Size,
    /// Centre in metres; the origin by default.
    #[serde(default = "origin")]
    pub position: Point,
    /// Rotation in degrees about x, then y, then z (intrinsic); none by default.
    #[serde(default = "no_angles")]
    pub rotation_deg: Angles,
    /// Surface colour, multiplying a mesh's own; light grey for a primitive and white for a
    /// mesh by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Color>,
    /// Rates of change of `rotation_deg` in degrees per second; none by default.
    #[serde(default = "no_angles")]
    pub spin_deg_per_s: Angles,
    /// An image on the surface; none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureDef>,
    /// The mesh's parts as drawn, filled in when the scene is resolved.
    #[serde(skip)]
    pub drawn: Option<Arc<MeshParts>>,
}

impl ShapeDef {
    /// The material these settings describe, in `color` (sRGB channels).
    pub fn material(&self, color: Vec3) -> Material {
        material(color, self.texture.as_ref())
    }

    /// The colour the file gives, or the default for a primitive or a mesh.
    pub fn color(&self) -> Srgba {
        self.color.map_or_else(|| self.default_color(), |color| color.0)
    }

    /// The colour of a shape whose file names none: light grey for a primitive, white (the
    /// mesh's own colours) for a mesh.
    pub fn default_color(&self) -> Srgba {
        match self.mesh {
            Some(_) => Srgba::WHITE,
            None => Srgba::gray(0.8),
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{Address, Filter, Sampler};
    use bevy::math::Vec2;

    #[test]
    fn shape_defaults_and_unknown_primitives() {
        let def: ShapeDef = serde_yaml::from_str("primitive: sphere").unwrap();
        assert_eq!(def.size.0, Vec3::ONE);
        assert_eq!(def.position.0, Vec3::ZERO);
        assert_eq!(def.color(), Srgba::gray(0.8));
        let error = serde_yaml::from_str::<ShapeDef>("primitive: cone").unwrap_err().to_string();
        assert!(error.contains("unknown variant `cone`, expected one of"), "{error}");
        let def: ShapeDef = serde_yaml::from_str("mesh: props/rock.gltf").unwrap();
        assert_eq!((def.primitive, def.color()), (None, Srgba::WHITE));
        let error = serde_yaml::from_str::<ShapeDef>("mesh: rock.fbx").unwrap_err().to_string();
        assert!(error.contains("an .obj, .ply, .stl, .gltf or .glb file"), "{error}");
    }

    #[test]
    fn texture_settings_parse_with_defaults_and_paths_stay_inside() {
        let def: ShapeDef = serde_yaml::from_str("{primitive: plane, texture: {file: textures/checker.png}}").unwrap();
        let texture = def.texture.unwrap();
        assert_eq!((texture.filter, texture.address), (Filter::Trilinear, Address::Repeat));
        let def: ShapeDef = serde_yaml::from_str(
            "{primitive: box, texture: {file: a.bmp, filter: nearest, address: clamp, repeat: [2, 3]}}",
        )
        .unwrap();
        let material = def.material(Vec3::ONE);
        assert_eq!(material.sampler, Sampler { filter: Filter::Nearest, address: Address::Clamp });
        assert_eq!(material.uv_scale, Vec2::new(2.0, 3.0));
        for bad in ["../up.png", "/abs.png", "image.jpg"] {
            let yaml = format!("{{primitive: box, texture: {{file: \"{bad}\"}}}}");
            let error = serde_yaml::from_str::<ShapeDef>(&yaml).unwrap_err().to_string();
            assert!(error.contains("expected a .png or .bmp file inside the scene's folder"), "{error}");
        }
    }
}
