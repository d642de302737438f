//! Named parameters: one mechanism, built on `Reflect`, through which scripted timelines,
//! keyboard controls and the UI read and change the state of scene entities.
//!
//! A parameter name is `<entity>.<field path>`: the entity's name (or its kind, for unnamed
//! entities, which then addresses every unnamed entity of that kind), then a reflection path
//! into one of the entity's parameter components, for example `light.azimuth_deg` or
//! `ball.position.y`. Numbers (`f32`, `f64`, and `u32` counts, which take whole numbers), booleans and choices (enums of unit variants,
//! named in snake case, e.g. `render.shading: phong`) can be set.

use crate::foundation::entity::SceneEntity;
use bevy::ecs::reflect::ReflectComponent;
use bevy::prelude::*;
use bevy::reflect::enums::{DynamicEnum, DynamicVariant, VariantType};
use bevy::reflect::{GetPath, PartialReflect, ReflectRef, TypeInfo, TypeRegistry};
use serde::Deserialize;
use std::any::TypeId;
use std::fmt;

/// A parameter's value.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum ParamValue {
    /// A number.
    Number(f64),
    /// A switch.
    Bool(bool),
    /// One of a fixed set of names.
    Choice(String),
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Number(v) => write!(f, "{v}"),
            ParamValue::Bool(v) => write!(f, "{v}"),
            ParamValue::Choice(v) => write!(f, "{v}"),
        }
    }
}

/// The snake-case names of a unit-variant enum's variants, or `None` for other types.
fn choices(value: &dyn PartialReflect) -> Option<Vec<String>> {
    let Some(TypeInfo::Enum(info)) = value.get_represented_type_info() else { return None };
    info.iter()
        .all(|variant| variant.as_unit_variant().is_ok())
        .then(|| info.variant_names().iter().map(|n| snake_case(n)).collect())
}

/// `PascalCase` to `snake_case`.
fn snake_case(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// One parameter of an entity, as listed for the UI.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamEntry {
    /// The path inside the entity, e.g. `position.y`.
    pub path: String,
    /// Its current value.
    pub value: ParamValue,
    /// The names a choice accepts; empty for numbers and switches.
    pub choices: Vec<String>,
    /// A count: it takes whole numbers only.
    pub whole: bool,
}

/// Why a parameter could not be set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The name has no `.` separating entity and field.
    #[error("parameter `{0}`: expected `<entity>.<parameter>`")]
    Malformed(String),
    /// No entity has that name or kind.
    #[error("parameter `{name}`: no entity is named `{entity}` (entities: {known})")]
    NoEntity {
        /// The full parameter name.
        name: String,
        /// The entity part.
        entity: String,
        /// The names present.
        known: String,
    },
    /// The entity has no such parameter.
    #[error("parameter `{name}`: `{entity}` has no parameter `{path}` (it has: {known})")]
    NoParameter {
        /// The full parameter name.
        name: String,
        /// The entity part.
        entity: String,
        /// The path part.
        path: String,
        /// The entity's parameters.
        known: String,
    },
    /// The value does not fit the parameter.
    #[error("parameter `{name}`: cannot set {value}: expected {expected}")]
    BadValue {
        /// The full parameter name.
        name: String,
        /// The value given.
        value: ParamValue,
        /// What the parameter takes.
        expected: String,
    },
}

/// The component types whose reflected fields are parameters.
#[derive(Resource, Debug, Default)]
pub struct ParamComponents(Vec<TypeId>);

/// Registration of parameter components on the app.
pub trait RegisterParams {
    /// Makes the reflected fields of component `C` parameters of the entities holding it.
    fn register_params<C: Component + Reflect + bevy::reflect::GetTypeRegistration>(&mut self) -> &mut Self;
}

impl RegisterParams for App {
    fn register_params<C: Component + Reflect + bevy::reflect::GetTypeRegistration>(&mut self) -> &mut Self {
        self.register_type::<C>();
        let mut components = self.world_mut().get_resource_or_init::<ParamComponents>();
        if !components.0.contains(&TypeId::of::<C>()) {
            components.0.push(TypeId::of::<C>());
        }
        self
    }
}

/// Reads a leaf value.
fn read_leaf(value: &dyn PartialReflect) -> Option<ParamValue> {
    if let Some(v) = value.try_downcast_ref::<f32>() {
        Some(ParamValue::Number(*v as f64))
    } else if let Some(v) = value.try_downcast_ref::<f64>() {
        Some(ParamValue::Number(*v))
    } else if let Some(v) = value.try_downcast_ref::<u32>() {
        Some(ParamValue::Number(f64::from(*v)))
    } else if let Some(v) = value.try_downcast_ref::<bool>() {
        Some(ParamValue::Bool(*v))
    } else if let (ReflectRef::Enum(e), Some(_)) = (value.reflect_ref(), choices(value)) {
        Some(ParamValue::Choice(snake_case(e.variant_name())))
    } else {
        None
    }
}

/// Lists the settable leaves under `value`, depth first in field order.
fn collect_leaves(value: &dyn PartialReflect, prefix: &str, out: &mut Vec<ParamEntry>) {
    if let Some(leaf) = read_leaf(value) {
        let (choices, whole) = (choices(value).unwrap_or_default(), value.try_downcast_ref::<u32>().is_some());
        out.push(ParamEntry { path: prefix.to_string(), value: leaf, choices, whole });
        return;
    }
    if let ReflectRef::Struct(fields) = value.reflect_ref() {
        for index in 0..fields.field_len() {
            let (Some(name), Some(field)) = (fields.name_at(index), fields.field_at(index)) else {
                continue;
            };
            let path = if prefix.is_empty() { name.to_string() } else { format!("{prefix}.{name}") };
            collect_leaves(field, &path, out);
        }
    }
}

/// The parameters of `entity`, in component registration and field order.
pub fn list_params(world: &World, entity: Entity) -> Vec<ParamEntry> {
    let (Some(components), Some(registry)) =
        (world.get_resource::<ParamComponents>(), world.get_resource::<AppTypeRegistry>())
    else {
        return Vec::new();
    };
    let registry = registry.read();
    let Ok(entity_ref) = world.get_entity(entity) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for reflect in components.0.iter().filter_map(|id| registry.get_type_data::<ReflectComponent>(*id)) {
        if let Some(component) = reflect.reflect(entity_ref) {
            collect_leaves(component.as_partial_reflect(), "", &mut out);
        }
    }
    out
}

/// The entities a parameter's entity part addresses.
fn addressed(world: &mut World, entity: &str) -> (Vec<Entity>, Vec<String>) {
    let mut query = world.query::<(Entity, &SceneEntity)>();
    let mut all: Vec<(usize, Entity, String)> = query.iter(world).map(|(e, s)| (s.index, e, s.name.clone())).collect();
    all.sort_by_key(|(index, ..)| *index);
    let matching = all.iter().filter(|(_, _, name)| name == entity).map(|(_, e, _)| *e).collect();
    (matching, all.into_iter().map(|(_, _, name)| name).collect())
}

/// Checks that `name` addresses a parameter that takes `value`, without setting it.
pub fn check_param(world: &mut World, name: &str, value: ParamValue) -> Result<(), ParamError> {
    let (entity_name, path) = name.split_once('.').ok_or_else(|| ParamError::Malformed(name.to_string()))?;
    let (targets, known) = addressed(world, entity_name);
    let Some(&first) = targets.first() else {
        return Err(ParamError::NoEntity {
            name: name.to_string(),
            entity: entity_name.to_string(),
            known: known.join(", "),
        });
    };
    let params = list_params(world, first);
    let Some(entry) = params.iter().find(|p| p.path == path) else {
        return Err(ParamError::NoParameter {
            name: name.to_string(),
            entity: entity_name.to_string(),
            path: path.to_string(),
            known: params.iter().map(|p| p.path.as_str()).collect::<Vec<_>>().join(", "),
        });
    };
    fits(&entry.value, &entry.choices, entry.whole, &value).map_err(|expected| ParamError::BadValue {
        name: name.to_string(),
        value,
        expected,
    })
}

/// Whether `value` can be given to a parameter holding `current` (whose names are `choices`
/// when it is a choice, and which takes only whole numbers when `whole`); what the parameter
/// takes when it cannot.
fn fits(current: &ParamValue, choices: &[String], whole: bool, value: &ParamValue) -> Result<(), String> {
    match (current, value) {
        (ParamValue::Number(_), ParamValue::Number(v))
            if whole && !(v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(v)) =>
        {
            Err(format!("a whole number from 0 to {}", u32::MAX))
        }
        (ParamValue::Number(_), ParamValue::Number(v)) if v.is_finite() && v.abs() <= f32::MAX as f64 => Ok(()),
        (ParamValue::Number(_), ParamValue::Number(_)) => Err("a finite number".into()),
        (ParamValue::Number(_), _) => Err("a number".into()),
        (ParamValue::Bool(_), ParamValue::Bool(_)) => Ok(()),
        (ParamValue::Bool(_), _) => Err("true or false".into()),
        (ParamValue::Choice(_), ParamValue::Choice(choice)) if choices.contains(choice) => Ok(()),
        (ParamValue::Choice(_), _) => Err(format!("one of {}", choices.join(", "))),
    }
}

/// Sets the parameter `name` to `value` on every entity it addresses.
pub fn set_param(world: &mut World, name: &str, value: ParamValue) -> Result<(), ParamError> {
    let (entity_name, path) = name.split_once('.').ok_or_else(|| ParamError::Malformed(name.to_string()))?;
    let (targets, known) = addressed(world, entity_name);
    if targets.is_empty() {
        return Err(ParamError::NoEntity {
            name: name.to_string(),
            entity: entity_name.to_string(),
            known: known.join(", "),
        });
    }
    let registry = world.resource::<AppTypeRegistry>().clone();
    let components = world.get_resource::<ParamComponents>().map(|c| c.0.clone()).unwrap_or_default();
    for target in targets {
        if !set_on_entity(world, &registry.read(), &components, target, path, name, &value)? {
            let known = list_params(world, target).into_iter().map(|p| p.path).collect::<Vec<_>>();
            return Err(ParamError::NoParameter {
                name: name.to_string(),
                entity: entity_name.to_string(),
                path: path.to_string(),
                known: known.join(", "),
            });
        }
    }
    Ok(())
}

/// Sets `path` in the first parameter component of `entity` that has it; false if none has.
fn set_on_entity(
    world: &mut World,
    registry: &TypeRegistry,
    components: &[TypeId],
    entity: Entity,
    path: &str,
    name: &str,
    value: &ParamValue,
) -> Result<bool, ParamError> {
    for reflect in components.iter().filter_map(|id| registry.get_type_data::<ReflectComponent>(*id)) {
        let Ok(entity_mut) = world.get_entity_mut(entity) else { return Ok(false) };
        let Some(mut component) = reflect.reflect_mut(entity_mut) else { continue };
        let Ok(field) = component.bypass_change_detection().reflect_path_mut(path) else { continue };
        let Some(current) = read_leaf(field) else { continue };
        let names = choices(field).unwrap_or_default();
        let bad = |expected: String| ParamError::BadValue { name: name.to_string(), value: value.clone(), expected };
        fits(&current, &names, field.try_downcast_ref::<u32>().is_some(), value).map_err(bad)?;
        match value {
            &ParamValue::Number(v) => {
                if let Some(target) = field.try_downcast_mut::<f32>() {
                    *target = v as f32;
                } else if let Some(target) = field.try_downcast_mut::<f64>() {
                    *target = v;
                } else if let Some(target) = field.try_downcast_mut::<u32>() {
                    *target = v as u32;
                }
            }
            &ParamValue::Bool(v) => {
                if let Some(target) = field.try_downcast_mut::<bool>() {
                    *target = v;
                }
            }
            ParamValue::Choice(choice) => {
                let Some(TypeInfo::Enum(info)) = field.get_represented_type_info() else { continue };
                let Some(variant) = names.iter().position(|n| n == choice).and_then(|i| info.variant_at(i)) else {
                    continue;
                };
                debug_assert_eq!(variant.variant_type(), VariantType::Unit);
                field
                    .try_apply(&DynamicEnum::new(variant.name(), DynamicVariant::Unit))
                    .map_err(|error| bad(format!("one of {} ({error})", names.join(", "))))?;
            }
        }
        component.set_changed();
        return Ok(true);
    }
    Ok(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Reflect, Default, Debug, PartialEq)]
    enum Mode {
        #[default]
        Quiet,
        VeryLoud,
    }

    #[derive(Component, Reflect, Default)]
    #[reflect(Component)]
    struct Knobs {
        gain: f32,
        offset: Vec3,
        enabled: bool,
        mode: Mode,
        count: u32,
    }

    fn world_with(names: &[&str]) -> (App, Vec<Entity>) {
        let mut app = App::new();
        app.register_params::<Knobs>();
        let entities = names
            .iter()
            .enumerate()
            .map(|(index, name)| {
                app.world_mut()
                    .spawn((SceneEntity { index, name: name.to_string(), kind: "knobs" }, Knobs::default()))
                    .id()
            })
            .collect();
        (app, entities)
    }

    #[test]
    fn lists_leaves_with_their_paths() {
        let (app, entities) = world_with(&["a"]);
        let paths: Vec<String> = list_params(app.world(), entities[0]).into_iter().map(|p| p.path).collect();
        assert_eq!(paths, ["gain", "offset.x", "offset.y", "offset.z", "enabled", "mode", "count"]);
    }

    #[test]
    fn sets_numbers_and_switches_by_name() {
        let (mut app, entities) = world_with(&["a", "b"]);
        set_param(app.world_mut(), "b.offset.y", ParamValue::Number(2.5)).unwrap();
        set_param(app.world_mut(), "b.enabled", ParamValue::Bool(true)).unwrap();
        set_param(app.world_mut(), "b.mode", ParamValue::Choice("very_loud".into())).unwrap();
        let b = app.world().get::<Knobs>(entities[1]).unwrap();
        assert_eq!((b.offset.y, b.enabled, &b.mode), (2.5, true, &Mode::VeryLoud));
        set_param(app.world_mut(), "b.count", ParamValue::Number(12.0)).unwrap();
        let listed = list_params(app.world(), entities[1]);
        assert_eq!(listed[5].value, ParamValue::Choice("very_loud".into()));
        assert_eq!((listed[6].value.clone(), listed[6].whole), (ParamValue::Number(12.0), true));
        assert_eq!(app.world().get::<Knobs>(entities[0]).unwrap().offset.y, 0.0);
    }

    #[test]
    fn every_entity_sharing_a_name_is_set() {
        let (mut app, entities) = world_with(&["knobs", "knobs"]);
        set_param(app.world_mut(), "knobs.gain", ParamValue::Number(0.5)).unwrap();
        for entity in entities {
            assert_eq!(app.world().get::<Knobs>(entity).unwrap().gain, 0.5);
        }
    }

    #[test]
    fn errors_say_what_exists() {
        let (mut app, _) = world_with(&["a"]);
        let world = app.world_mut();
        assert!(matches!(set_param(world, "gain", ParamValue::Number(1.0)), Err(ParamError::Malformed(_))));
        let error = set_param(world, "z.gain", ParamValue::Number(1.0)).unwrap_err().to_string();
        assert!(error.contains("no entity is named `z` (entities: a)"), "{error}");
        let error = set_param(world, "a.gian", ParamValue::Number(1.0)).unwrap_err().to_string();
        assert!(error.contains("has no parameter `gian` (it has: gain, offset.x"), "{error}");
        let error = set_param(world, "a.enabled", ParamValue::Number(1.0)).unwrap_err().to_string();
        assert!(error.contains("expected true or false"), "{error}");
        let error = set_param(world, "a.gain", ParamValue::Number(f64::NAN)).unwrap_err().to_string();
        assert!(error.contains("expected a finite number"), "{error}");
        let error = set_param(world, "a.mode", ParamValue::Choice("loud".into())).unwrap_err().to_string();
        assert!(error.contains("expected one of quiet, very_loud"), "{error}");
        let error = check_param(world, "a.mode", ParamValue::Choice("loud".into())).unwrap_err().to_string();
        assert!(error.contains("expected one of quiet, very_loud"), "{error}");
        assert!(check_param(world, "a.mode", ParamValue::Choice("quiet".into())).is_ok());
        for count in [2.5, -1.0, 5e9] {
            let error = check_param(world, "a.count", ParamValue::Number(count)).unwrap_err().to_string();
            assert!(error.contains("expected a whole number from 0"), "{error}");
            assert!(set_param(world, "a.count", ParamValue::Number(count)).is_err());
        }
    }
}
