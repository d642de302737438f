//! The scene file format: serde types for the camera, the light, the background and the
//! entities, and the checks that span several fields.
//!
//! Every entity is a mapping with an optional `name` and exactly one kind key; the kind's
//! value is that kind's definition. The kinds are listed in [`EntityKind`].

use super::values::{Color, FieldOfView, Point, PositiveMetres, UnitInterval};
use crate::muscle::{ConfigFile, MuscleDef};
use crate::raster::Texture;
use crate::raster::settings::RenderDef;
use crate::shape::{ShapeDef, TextureDef};
use crate::sloth::{SlothDef, Supports};
use crate::tree::TreeDef;
use crate::yaml::{FileError, deserialize_str_with, parse_yaml};
use bevy::color::Srgba;
use bevy::math::Vec3;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;
use std::path::Path;
use std::sync::Arc;

/// The keys of an entity mapping: its name, then every kind.
const ENTITY_FIELDS: &[&str] = &["name", "shape", "muscle", "tree", "sloth"];

/// Names that refer to the scene's camera, light and render settings in parameter names and
/// dumps.
pub const RESERVED_NAMES: [&str; 3] = ["camera", "light", "render"];

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDef {
    /// The viewpoint; a default camera looks at the origin from the front and above.
    #[serde(default)]
    pub camera: CameraDef,
    /// The directional light; the default comes from above, in front and to the right.
    #[serde(default)]
    pub light: LightDef,
    /// Colour of pixels showing no surface (the sky); light blue by default.
    #[serde(default = "default_background")]
    pub background: Color,
    /// Shading mode and shadows; Gouraud with filtered shadows by default.
    #[serde(default)]
    pub render: RenderDef,
    /// What the scene holds, in order.
    #[serde(default)]
    pub entities: Vec<EntityDef>,
}

/// The camera of a scene file.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
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
}

impl Default for CameraDef {
    fn default() -> Self {
        Self {
            position: Point(Vec3::new(0.0, 2.0, 6.0)),
            look_at: Point(Vec3::ZERO),
            fov_deg: FieldOfView(60.0),
            near: PositiveMetres(0.1),
            far: PositiveMetres(1000.0),
        }
    }
}

/// The directional light of a scene file.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
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

/// One entity: an optional name and its kind.
#[derive(Debug, Clone, PartialEq)]
pub struct EntityDef {
    /// The name used in parameter names and dumps; unnamed entities go by their kind.
    pub name: Option<String>,
    /// What the entity is.
    pub kind: EntityKind,
}

/// The kinds of entity a scene can hold, one key each in the entity's mapping.
#[derive(Debug, Clone, PartialEq)]
pub enum EntityKind {
    /// A primitive solid (`shape:`).
    Shape(ShapeDef),
    /// A volume-preserving muscle on its arm (`muscle:`).
    Muscle(MuscleDef),
    /// Trunks and branches (`tree:`).
    Tree(TreeDef),
    /// A two-toed sloth on a support (`sloth:`).
    Sloth(SlothDef),
}

impl EntityKind {
    /// Every kind key, for messages.
    pub const KEYS: &'static [&'static str] = match ENTITY_FIELDS.split_first() {
        Some((_name, kinds)) => kinds,
        None => &[],
    };

    /// The kind's key in the file, which is also its name in dumps and parameters.
    pub fn key(&self) -> &'static str {
        match self {
            EntityKind::Shape(_) => "shape",
            EntityKind::Muscle(_) => "muscle",
            EntityKind::Tree(_) => "tree",
            EntityKind::Sloth(_) => "sloth",
        }
    }
}

impl EntityKind {
    /// The entity's texture, for kinds that take one.
    pub fn texture(&self) -> Option<&TextureDef> {
        match self {
            EntityKind::Shape(shape) => shape.texture.as_ref(),
            EntityKind::Tree(tree) => tree.texture.as_ref(),
            EntityKind::Muscle(_) | EntityKind::Sloth(_) => None,
        }
    }

    /// The entity's texture, to fill in its image.
    fn texture_mut(&mut self) -> Option<&mut TextureDef> {
        match self {
            EntityKind::Shape(shape) => shape.texture.as_mut(),
            EntityKind::Tree(tree) => tree.texture.as_mut(),
            EntityKind::Muscle(_) | EntityKind::Sloth(_) => None,
        }
    }
}

impl EntityDef {
    /// The name parameters and dumps use: the given name, else the kind.
    pub fn display_name(&self) -> &str {
        self.name.as_deref().unwrap_or(self.kind.key())
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

impl Serialize for EntityDef {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(None)?;
        if let Some(name) = &self.name {
            map.serialize_entry("name", name)?;
        }
        match &self.kind {
            EntityKind::Shape(shape) => map.serialize_entry("shape", shape)?,
            EntityKind::Muscle(muscle) => map.serialize_entry("muscle", muscle)?,
            EntityKind::Tree(tree) => map.serialize_entry("tree", tree)?,
            EntityKind::Sloth(sloth) => map.serialize_entry("sloth", sloth)?,
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for EntityDef {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct EntityVisitor;

        impl<'de> Visitor<'de> for EntityVisitor {
            type Value = EntityDef;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "an entity: a mapping with an optional `name` and one kind ({})", EntityKind::KEYS.join(", "))
            }

            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<EntityDef, A::Error> {
                let mut name: Option<String> = None;
                let mut kind: Option<EntityKind> = None;
                while let Some(key) = map.next_key::<String>()? {
                    let value = match key.as_str() {
                        "name" => {
                            if name.is_some() {
                                return Err(de::Error::duplicate_field("name"));
                            }
                            name = Some(map.next_value::<EntityName>()?.0);
                            continue;
                        }
                        "shape" => EntityKind::Shape(map.next_value()?),
                        "muscle" => EntityKind::Muscle(map.next_value()?),
                        "tree" => EntityKind::Tree(map.next_value()?),
                        "sloth" => EntityKind::Sloth(map.next_value()?),
                        other => return Err(de::Error::unknown_field(other, ENTITY_FIELDS)),
                    };
                    if let Some(first) = &kind {
                        return Err(de::Error::custom(format_args!(
                            "an entity has exactly one kind, found both `{}` and `{}`",
                            first.key(),
                            value.key()
                        )));
                    }
                    kind = Some(value);
                }
                let kind = kind.ok_or_else(|| {
                    de::Error::custom(format_args!("an entity needs a kind: one of {}", EntityKind::KEYS.join(", ")))
                })?;
                Ok(EntityDef { name, kind })
            }
        }

        deserializer.deserialize_map(EntityVisitor)
    }
}

impl SceneDef {
    /// Reads and checks a scene file.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        let bytes = std::fs::read(path).map_err(|error| FileError::unreadable(path, error))?;
        Self::parse(path, &bytes)
    }

    /// Parses and checks scene text read from `path`, reading referenced files next to it.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Self, FileError> {
        let mut scene = Self::parse_unresolved(path, bytes)?;
        let folder = path.parent().unwrap_or(Path::new(""));
        for file in scene.references() {
            let referenced = folder.join(&file);
            let contents = std::fs::read(&referenced).map_err(|error| FileError::unreadable(&referenced, error))?;
            scene.resolve(&file, &referenced, &contents)?;
        }
        scene.check(path, &String::from_utf8_lossy(bytes))?;
        Ok(scene)
    }

    /// The files the scene refers to (muscle configurations and textures), relative to its
    /// folder.
    pub fn references(&self) -> Vec<String> {
        let mut files: Vec<String> = self
            .entities
            .iter()
            .filter_map(|entity| match &entity.kind {
                EntityKind::Muscle(muscle) => muscle.file.as_ref().map(|f| f.0.clone()),
                EntityKind::Shape(_) | EntityKind::Tree(_) => entity.kind.texture().map(|t| t.file.0.clone()),
                EntityKind::Sloth(_) => None,
            })
            .collect();
        // Each file is read once, however many entities refer to it.
        files.sort();
        files.dedup();
        files
    }

    /// Fills every entity referring to `file` from its `contents`, read from `shown_path`.
    pub fn resolve(&mut self, file: &str, shown_path: &Path, contents: &[u8]) -> Result<(), FileError> {
        let textured: Vec<usize> = (0..self.entities.len())
            .filter(|&index| self.entities[index].kind.texture().is_some_and(|t| t.file.0 == file))
            .collect();
        if let Some(&first) = textured.first() {
            let texture = Texture::decode(contents).map_err(|error| {
                let kind = self.entities[first].kind.key();
                FileError::whole_file(shown_path, format!("entities[{first}].{kind}.texture.file: {error}"))
            })?;
            let texture = Arc::new(texture);
            for index in textured {
                if let Some(def) = self.entities[index].kind.texture_mut() {
                    def.image = Some(texture.clone());
                }
            }
            return Ok(());
        }
        let config: ConfigFile = parse_yaml(shown_path, contents, "a muscle configuration")?;
        // The node model is checked here, where its errors can point into its own file.
        if let Err(error) = config.muscle_config.model(1.0, 1.0) {
            let text = String::from_utf8_lossy(contents);
            return Err(locate(shown_path, &text, "muscle_config", 0, format!("muscle_config: {error}")));
        }
        for entity in &mut self.entities {
            if let EntityKind::Muscle(muscle) = &mut entity.kind
                && muscle.file.as_ref().is_some_and(|f| f.0 == file)
            {
                muscle.fill_from(config.clone());
            }
        }
        Ok(())
    }

    /// The scene as YAML text, as a file holds it. Referenced muscle configurations stay
    /// references; textures stay file names.
    pub fn to_yaml(&self) -> Result<String, serde_yaml::Error> {
        let mut scene = self.clone();
        for entity in &mut scene.entities {
            if let EntityKind::Muscle(muscle) = &mut entity.kind
                && muscle.file.is_some()
            {
                muscle.muscle_config = None;
                muscle.carcass_config = None;
            }
        }
        let text = serde_yaml::to_string(&scene)?;
        Ok(format!("# Saved by Canopy; the scene format is described in the README (\"Scene files\").\n{text}"))
    }

    /// Parses scene text read from `path`, leaving references to other files unread; the
    /// result still needs [`Self::resolve`] for each of [`Self::references`] and checking.
    ///
    /// A file whose top level is the source program's muscle configuration (`muscle_config`
    /// and `carcass_config`) is a scene too: that muscle, named `muscle`, seen from a camera
    /// that frames its arm.
    pub fn parse_unresolved(path: &Path, bytes: &[u8]) -> Result<Self, FileError> {
        let text = String::from_utf8_lossy(bytes);
        if text.lines().any(|line| line.starts_with("muscle_config:")) {
            return Ok(Self::of_muscle(parse_yaml(path, bytes, "a muscle configuration")?));
        }
        let scene: Self = parse_yaml(path, bytes, "a scene")?;
        for (index, entity) in scene.entities.iter().enumerate() {
            if let EntityKind::Muscle(muscle) = &entity.kind
                && muscle.file.is_some()
                && (muscle.muscle_config.is_some() || muscle.carcass_config.is_some())
            {
                let message = format!(
                    "entities[{index}].muscle.file: give the configuration either inline or from a file, not both"
                );
                return Err(locate(path, &text, "file", 0, message));
            }
        }
        Ok(scene)
    }

    /// A scene holding one muscle, framed from the front.
    fn of_muscle(muscle: MuscleDef) -> Self {
        let camera = CameraDef {
            position: Point(Vec3::new(-0.2, 0.7, 2.4)),
            look_at: Point(Vec3::new(-0.2, 0.1, 0.0)),
            fov_deg: FieldOfView(45.0),
            ..CameraDef::default()
        };
        Self {
            camera,
            light: LightDef::default(),
            background: default_background(),
            render: RenderDef::default(),
            entities: vec![EntityDef { name: None, kind: EntityKind::Muscle(muscle) }],
        }
    }

    /// The checks that involve several fields, located by their key in `text`.
    pub fn check(&self, path: &Path, text: &str) -> Result<(), FileError> {
        let at_key = |key: &str, nth: usize, message: String| locate(path, text, key, nth, message);
        let camera = &self.camera;
        if (camera.position.0 - camera.look_at.0).length() < 1e-6 {
            return Err(at_key("look_at", 0, "camera.look_at: expected a point different from camera.position".into()));
        }
        if camera.far.0 <= camera.near.0 {
            return Err(at_key(
                "far",
                0,
                format!(
                    "camera.far: expected a distance beyond camera.near ({}), found {}",
                    camera.near.0, camera.far.0
                ),
            ));
        }
        if self.light.direction.0.length() < 1e-6 {
            return Err(at_key("direction", 0, "light.direction: expected a non-zero vector".into()));
        }
        self.check_trees(path, text)?;
        self.check_sloths(path, text)?;
        let muscles = self.entities.iter().enumerate().filter_map(|(index, entity)| match &entity.kind {
            EntityKind::Muscle(muscle) => Some((index, muscle)),
            _ => None,
        });
        // Inline configurations are located by their key; the nth inline muscle has the nth
        // `muscle_config` of the file.
        let mut inline = 0;
        for (index, muscle) in muscles {
            let result = muscle.build();
            if muscle.file.is_some() {
                if let Err(error) = result {
                    return Err(FileError::whole_file(path, format!("entities[{index}].muscle: {error}")));
                }
                continue;
            }
            if let Err(error) = result {
                return Err(at_key(
                    "muscle_config",
                    inline,
                    format!("entities[{index}].muscle.muscle_config: {error}"),
                ));
            }
            inline += 1;
        }
        let mut seen: Vec<&str> = Vec::new();
        for (index, entity) in self.entities.iter().enumerate() {
            let Some(name) = entity.name.as_deref() else { continue };
            if seen.contains(&name) {
                // The key of this entity's name is the nth `name:` of the file.
                let nth = self.entities[..index].iter().filter(|e| e.name.is_some()).count();
                return Err(at_key(
                    "name",
                    nth,
                    format!(
                        "entities[{index}].name: the name \"{name}\" is used by an earlier entity; names must be unique"
                    ),
                ));
            }
            seen.push(name);
        }
        Ok(())
    }
}

impl SceneDef {
    /// Builds every tree; an error is located at its support's field, the nth occurrence of
    /// that key among the supports of the file.
    fn check_trees(&self, path: &Path, text: &str) -> Result<(), FileError> {
        let trees: Vec<(usize, &TreeDef)> = self
            .entities
            .iter()
            .enumerate()
            .filter_map(|(index, entity)| match &entity.kind {
                EntityKind::Tree(tree) => Some((index, tree)),
                _ => None,
            })
            .collect();
        for (position, &(index, tree)) in trees.iter().enumerate() {
            let Err(error) = tree.build() else { continue };
            let message = format!("entities[{index}].tree.{error}");
            let Some(support) = error.support else {
                // About the tree as a whole: at its `generate` key, or else its `tree` key.
                let earlier = &trees[..position];
                return Err(match error.field {
                    "generate" => {
                        let nth = earlier.iter().filter(|(_, t)| t.generate.is_some()).count();
                        locate(path, text, "generate", nth, message)
                    }
                    _ => locate(path, text, "tree", earlier.len(), message),
                });
            };
            // Supports of earlier trees, and earlier supports of this one, holding the key.
            let earlier = trees[..position].iter().flat_map(|(_, t)| &t.supports).chain(&tree.supports[..support]);
            let mut nth = earlier.filter(|s| s.has_field(error.field)).count();
            if error.field == "name" {
                // Entity names come before their kinds' supports in the file.
                nth += self.entities[..=index].iter().filter(|e| e.name.is_some()).count();
            }
            return Err(locate(path, text, error.field, nth, message));
        }
        Ok(())
    }
}

impl SceneDef {
    /// Places every sloth on the scene's (already checked) trees; an error is located at the
    /// sloth's `support` key.
    fn check_sloths(&self, path: &Path, text: &str) -> Result<(), FileError> {
        let sloths: Vec<(usize, &SlothDef)> = self
            .entities
            .iter()
            .enumerate()
            .filter_map(|(index, entity)| match &entity.kind {
                EntityKind::Sloth(sloth) => Some((index, sloth)),
                _ => None,
            })
            .collect();
        if sloths.is_empty() {
            return Ok(());
        }
        let trees: Vec<(&str, crate::tree::Tree)> = self
            .entities
            .iter()
            .filter_map(|entity| match &entity.kind {
                EntityKind::Tree(tree) => tree.build().ok().map(|built| (entity.display_name(), built)),
                _ => None,
            })
            .collect();
        let supports = Supports::new(trees.iter().map(|(name, tree)| (*name, tree)));
        for (nth, (index, sloth)) in sloths.into_iter().enumerate() {
            if let Err(error) = sloth.place(&supports, sloth.speed.0) {
                return Err(locate(path, text, "support", nth, format!("entities[{index}].sloth.support: {error}")));
            }
        }
        Ok(())
    }
}

/// An error at the `nth` (from 0) occurrence of mapping key `key` in `text`, or about the
/// whole file when the key cannot be found.
fn locate(path: &Path, text: &str, key: &str, nth: usize, message: String) -> FileError {
    match crate::yaml::find_nth_key(text, key, nth) {
        Some((line, column)) => FileError::at(path, line, column, message),
        None => FileError::whole_file(path, message),
    }
}
