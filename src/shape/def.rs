//! The `shape:` entry of a scene file, and the kind that reads, spawns and saves it.

use crate::foundation::values::{Angles, Color, Point, Size};
use crate::raster::Material;
use crate::raster::primitives::Primitive;
use crate::raster::texture::{TextureDef, material};
use bevy::color::{Gray, Srgba};
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};

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

impl ShapeDef {
    /// The material these settings describe, in `color` (sRGB channels).
    pub fn material(&self, color: Vec3) -> Material {
        material(color, self.texture.as_ref())
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

fn grey() -> Color {
    Color(Srgba::gray(0.8))
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
        let error = serde_yaml::from_str::<ShapeDef>("primitive: cone").unwrap_err().to_string();
        assert!(error.contains("unknown variant `cone`, expected one of"), "{error}");
        let error = serde_yaml::from_str::<ShapeDef>("size: 1").unwrap_err().to_string();
        assert!(error.contains("missing field `primitive`"), "{error}");
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
