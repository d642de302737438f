//! The scene file format: serde types for the camera, the light, the background and the
//! render settings, the entity list whose entries the kind registry reads, and the checks
//! that span several of these fields.
//!
//! Every entity is a mapping with an optional `name` and exactly one kind key; the kind's
//! value is that kind's definition (see [`super::kind_list`]).

use super::kind_list::{KindList, KindValue};
use crate::foundation::kind::{KindDef, Standalone};
use crate::foundation::values::{Color, FieldOfView, Point, PositiveMetres, UnitInterval};
use crate::foundation::yaml::{FileError, deserialize_str_with, locate_key as locate};
use bevy::color::Srgba;
use bevy::math::Vec3;
use bevy::prelude::{Component, Resource};
use canopy_raster::Shading;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeMap, SerializeSeq, SerializeStruct};
use serde::{Deserialize, Serialize, Serializer};
use std::collections::HashMap;
use std::fmt;
use std::marker::PhantomData;
use std::path::Path;

/// Names that refer to the scene's camera, light and render settings in parameter names and
/// dumps.
pub const RESERVED_NAMES: [&str; 3] = ["camera", "light", "render"];

/// A whole scene file, its entities' definitions as their kinds read them.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneDef {
    /// The viewpoint; a default camera looks at the origin from the front and above.
    pub camera: CameraDef,
    /// The directional light; the default comes from above, in front and to the right.
    pub light: LightDef,
    /// Colour of pixels showing no surface (the sky); light blue by default.
    pub background: Color,
    /// Shading mode and shadows; Gouraud with filtered shadows by default.
    pub render: RenderDef,
    /// What the scene holds, in order.
    pub entities: Vec<EntityDef>,
}

/// The camera of a scene file.
#[derive(Component, Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraDef {
    /// Eye position in metres.
    pub position: Point,
    /// The point looked at, in metres; must differ from `position`.
    pub look_at: Point,
    /// Vertical field of view in degrees.
    pub fov_deg: FieldOfView,
    /// Near clipping distance in metres.
    pub near: PositiveMetres,
    /// Far clipping distance in metres, beyond `near`.
    pub far: PositiveMetres,
    /// How fast Shift and the arrows fly the camera, metres per second.
    pub fly_speed_m_s: PositiveMetres,
    /// Whether the camera follows the scene's animal (its first sloth), keeping its offset
    /// from it; off by default (Home switches it).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub follow: bool,
}

impl Default for CameraDef {
    fn default() -> Self {
        Self {
            position: Point(Vec3::new(0.0, 2.0, 6.0)),
            look_at: Point(Vec3::ZERO),
            fov_deg: FieldOfView(60.0),
            near: PositiveMetres(0.1),
            far: PositiveMetres(1000.0),
            fly_speed_m_s: PositiveMetres(10.0),
            follow: false,
        }
    }
}

/// The directional light of a scene file.
#[derive(Component, Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightDef {
    /// The direction the light travels in (from the light into the scene); any non-zero
    /// length.
    pub direction: Point,
    /// Diffuse coefficient (light intensity times surface reflectance), 0 to 1.
    pub diffuse: UnitInterval,
    /// The least intensity any surface receives, 0 to 1.
    pub ambient: UnitInterval,
}

impl Default for LightDef {
    fn default() -> Self {
        Self { direction: Point(Vec3::new(-0.4, -1.0, -0.3)), diffuse: UnitInterval(0.85), ambient: UnitInterval(0.15) }
    }
}

fn default_background() -> Color {
    Color(Srgba::rgb(0.62, 0.76, 0.92))
}

/// The `render` section of a scene file.
#[derive(Component, Deserialize, Serialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDef {
    /// Shading mode: `flat`, `gouraud` (the default) or `phong`.
    pub shading: Shading,
    /// Whether the light casts shadows (on by default).
    pub shadows: bool,
    /// Whether shadow edges are filtered (on by default).
    pub pcf: bool,
    /// Distance fog; none by default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fog: Option<FogDef>,
    /// Shadows are cast within this many metres of the camera only, with the shadow map's
    /// detail spent there; by default the map covers all the camera sees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shadow_distance_m: Option<PositiveMetres>,
}

impl Default for RenderDef {
    fn default() -> Self {
        Self { shading: Shading::Gouraud, shadows: true, pcf: true, fog: None, shadow_distance_m: None }
    }
}

/// Distance fog in a scene's `render` section: surfaces fade into `color` (the background by
/// default) from `start_m` in front of the camera over `depth_m` more.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FogDef {
    /// Where the fog begins, metres in front of the camera.
    pub start_m: PositiveMetres,
    /// Over how many metres beyond `start_m` it thickens until it hides everything.
    pub depth_m: PositiveMetres,
    /// The colour far surfaces take; the background's by default, so that the end of the
    /// world fades into the sky.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Color>,
}

/// The colour of pixels showing no surface, from the scene's `background`.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct Background(pub Srgba);

impl Default for Background {
    fn default() -> Self {
        Self(Srgba::BLACK)
    }
}

/// One entity: an optional name, its kind's key and the kind's definition.
#[derive(Debug, Clone)]
pub struct EntityDef {
    /// The name used in parameter names and dumps; unnamed entities go by their kind.
    pub name: Option<String>,
    /// The kind's key in the file.
    pub key: &'static str,
    /// The kind's definition.
    pub def: Box<dyn KindDef>,
}

impl PartialEq for EntityDef {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name && self.key == other.key && self.def.eq_def(&*other.def)
    }
}

impl EntityDef {
    /// The name parameters and dumps use: the given name, else the kind.
    pub fn display_name(&self) -> &str {
        self.name.as_deref().unwrap_or(self.key)
    }

    /// The definition, if this entity is of the kind whose definition type is `D`.
    pub fn def<D: 'static>(&self) -> Option<&D> {
        self.def.as_any().downcast_ref()
    }

    /// The definition, if this entity is of the kind whose definition type is `D`.
    pub fn def_mut<D: 'static>(&mut self) -> Option<&mut D> {
        self.def.as_any_mut().downcast_mut()
    }
}

/// An entity name: letters, digits, `_` and `-` (a `.` would split parameter names), not one
/// of [`RESERVED_NAMES`].
struct EntityName(String);

impl<'de> Deserialize<'de> for EntityName {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize_str_with(deserializer, "a name of 1 to 64 letters, digits, `_` or `-`", |name| {
            let valid_chars = name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if name.is_empty() || name.len() > 64 || !valid_chars {
                Err(format!("expected a name of 1 to 64 letters, digits, `_` or `-`, found \"{name}\""))
            } else if RESERVED_NAMES.contains(&name) {
                Err(format!("the name \"{name}\" is reserved for the scene's {name}"))
            } else {
                Ok(EntityName(name.to_string()))
            }
        })
    }
}

/// A scene file as serde reads and writes it, its entities through the kinds of `L`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, bound = "L: KindList", rename = "SceneDef")]
pub(super) struct SceneFile<L> {
    #[serde(default)]
    camera: CameraDef,
    #[serde(default)]
    light: LightDef,
    #[serde(default = "default_background")]
    background: Color,
    #[serde(default)]
    render: RenderDef,
    #[serde(default)]
    entities: EntityList<L>,
}

impl<L> From<SceneFile<L>> for SceneDef {
    fn from(file: SceneFile<L>) -> Self {
        let SceneFile { camera, light, background, render, entities } = file;
        Self { camera, light, background, render, entities: entities.0 }
    }
}

/// Writes a [`SceneDef`] as [`SceneFile`] reads it.
pub(super) struct WriteScene<'a, L>(pub &'a SceneDef, pub PhantomData<L>);

impl<L: KindList> Serialize for WriteScene<'_, L> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let scene = self.0;
        let mut file = serializer.serialize_struct("SceneDef", 5)?;
        file.serialize_field("camera", &scene.camera)?;
        file.serialize_field("light", &scene.light)?;
        file.serialize_field("background", &scene.background)?;
        file.serialize_field("render", &scene.render)?;
        file.serialize_field("entities", &WriteEntities::<L>(&scene.entities, PhantomData))?;
        file.end()
    }
}

struct WriteEntities<'a, L>(&'a [EntityDef], PhantomData<L>);

impl<L: KindList> Serialize for WriteEntities<'_, L> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut list = serializer.serialize_seq(Some(self.0.len()))?;
        for entity in self.0 {
            list.serialize_element(&WriteEntity::<L>(entity, PhantomData))?;
        }
        list.end()
    }
}

struct WriteEntity<'a, L>(&'a EntityDef, PhantomData<L>);

impl<L: KindList> Serialize for WriteEntity<'_, L> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let entity = self.0;
        let mut map = serializer.serialize_map(None)?;
        if let Some(name) = &entity.name {
            map.serialize_entry("name", name)?;
        }
        L::serialize_entry(entity.key, &*entity.def, &mut map)
            .unwrap_or_else(|| Err(serde::ser::Error::custom(format_args!("no entity kind `{}`", entity.key))))?;
        map.end()
    }
}

/// The entity list of a scene file, each entry read by its kind in `L`.
pub(super) struct EntityList<L>(Vec<EntityDef>, PhantomData<L>);

impl<L> Default for EntityList<L> {
    fn default() -> Self {
        Self(Vec::new(), PhantomData)
    }
}

impl<'de, L: KindList> Deserialize<'de> for EntityList<L> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct ListVisitor<L>(PhantomData<L>);

        impl<'de, L: KindList> Visitor<'de> for ListVisitor<L> {
            type Value = EntityList<L>;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a sequence")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<EntityList<L>, A::Error> {
                let mut entities = Vec::new();
                while let Some(ReadEntity(entity, _)) = seq.next_element::<ReadEntity<L>>()? {
                    entities.push(entity);
                }
                Ok(EntityList(entities, PhantomData))
            }
        }

        deserializer.deserialize_seq(ListVisitor(PhantomData))
    }
}

/// One entity as its kind in `L` reads it.
struct ReadEntity<L>(EntityDef, PhantomData<L>);

impl<'de, L: KindList> Deserialize<'de> for ReadEntity<L> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct EntityVisitor<L>(PhantomData<L>);

        impl<'de, L: KindList> Visitor<'de> for EntityVisitor<L> {
            type Value = ReadEntity<L>;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "an entity: a mapping with an optional `name` and one kind ({})", L::keys().join(", "))
            }

            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<ReadEntity<L>, A::Error> {
                let mut name: Option<String> = None;
                let mut kind: Option<KindValue> = None;
                while let Some(key) = map.next_key::<String>()? {
                    if key == "name" {
                        if name.is_some() {
                            return Err(de::Error::duplicate_field("name"));
                        }
                        name = Some(map.next_value::<EntityName>()?.0);
                        continue;
                    }
                    let Some(value) = L::next_value(&key, &mut map) else {
                        // As serde words it for a struct's fields, which yaml.rs locates.
                        let kinds = L::keys();
                        let expected = if kinds.is_empty() {
                            "`name`".to_string()
                        } else {
                            format!("one of `name`, `{}`", kinds.join("`, `"))
                        };
                        return Err(de::Error::custom(format_args!("unknown field `{key}`, expected {expected}")));
                    };
                    let value = value?;
                    if let Some((first, _)) = &kind {
                        return Err(de::Error::custom(format_args!(
                            "an entity has exactly one kind, found both `{first}` and `{}`",
                            value.0
                        )));
                    }
                    kind = Some(value);
                }
                let (key, def) = kind.ok_or_else(|| {
                    de::Error::custom(format_args!("an entity needs a kind: one of {}", L::keys().join(", ")))
                })?;
                Ok(ReadEntity(EntityDef { name, key, def }, PhantomData))
            }
        }

        deserializer.deserialize_map(EntityVisitor(PhantomData))
    }
}

impl SceneDef {
    /// For every entity, in file order, how many entities of its kind come before it.
    pub fn kind_indices(&self) -> Vec<usize> {
        let mut seen: HashMap<&str, usize> = HashMap::new();
        self.entities
            .iter()
            .map(|entity| {
                let count = seen.entry(entity.key).or_default();
                *count += 1;
                *count - 1
            })
            .collect()
    }

    /// A scene holding one kind's standalone configuration, framed by its view.
    pub(super) fn of_standalone(key: &'static str, standalone: Standalone<Box<dyn KindDef>>) -> Self {
        let view = standalone.view;
        let camera = CameraDef {
            position: Point(view.position),
            look_at: Point(view.look_at),
            fov_deg: FieldOfView(view.fov_deg),
            ..CameraDef::default()
        };
        Self {
            camera,
            light: LightDef::default(),
            background: default_background(),
            render: RenderDef::default(),
            entities: vec![EntityDef { name: None, key, def: standalone.def }],
        }
    }

    /// The checks of the camera and the light, located by their key in `text`.
    pub(super) fn check_view(&self, path: &Path, text: &str) -> Result<(), FileError> {
        let camera = &self.camera;
        if (camera.position.0 - camera.look_at.0).length() < 1e-6 {
            let message = "camera.look_at: expected a point different from camera.position".into();
            return Err(locate(path, text, "look_at", 0, message));
        }
        if camera.far.0 <= camera.near.0 {
            let message = format!(
                "camera.far: expected a distance beyond camera.near ({}), found {}",
                camera.near.0, camera.far.0
            );
            return Err(locate(path, text, "far", 0, message));
        }
        if self.light.direction.0.length() < 1e-6 {
            return Err(locate(path, text, "direction", 0, "light.direction: expected a non-zero vector".into()));
        }
        Ok(())
    }

    /// Refuses a name used twice, at the second use.
    pub(super) fn check_names(&self, path: &Path, text: &str) -> Result<(), FileError> {
        let mut seen: Vec<&str> = Vec::new();
        for (index, entity) in self.entities.iter().enumerate() {
            let Some(name) = entity.name.as_deref() else { continue };
            if seen.contains(&name) {
                // The key of this entity's name is the nth `name:` of the file.
                let nth = self.entities[..index].iter().filter(|e| e.name.is_some()).count();
                let message = format!(
                    "entities[{index}].name: the name \"{name}\" is used by an earlier entity; names must be unique"
                );
                return Err(locate(path, text, "name", nth, message));
            }
            seen.push(name);
        }
        Ok(())
    }
}
