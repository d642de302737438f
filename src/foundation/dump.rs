//! State dumps: the measurable facts of every scene entity as JSON,
//! `{"frame": N, "time": seconds, "entities": [{"name": .., "kind": .., ...}]}`.
//!
//! Each domain contributes fields by implementing [`DumpState`] for its components and
//! registering them with [`RegisterDump::register_dump`]. Entities appear in scene order and
//! object keys are sorted, so a dump is byte-for-byte reproducible.

use crate::foundation::entity::SceneEntity;
use crate::foundation::schedule::SimClock;
use bevy::prelude::*;
use serde_json::{Map, Value, json};

/// A component that adds fields to its entity's dump.
pub trait DumpState: Component {
    /// Inserts this component's facts into the entity's JSON object.
    fn dump(&self, out: &mut Map<String, Value>);
}

type DumpFn = fn(&World, Entity, &mut Map<String, Value>);

/// The registered dump contributors, in registration order.
#[derive(Resource, Default)]
pub struct DumpRegistry(Vec<DumpFn>);

/// Registration of dump contributors on the app.
pub trait RegisterDump {
    /// Adds component `C`'s [`DumpState`] fields to the dump of every entity holding it.
    fn register_dump<C: DumpState>(&mut self) -> &mut Self;
}

impl RegisterDump for App {
    fn register_dump<C: DumpState>(&mut self) -> &mut Self {
        fn contribute<C: DumpState>(world: &World, entity: Entity, out: &mut Map<String, Value>) {
            if let Some(component) = world.get::<C>(entity) {
                component.dump(out);
            }
        }
        self.world_mut().get_resource_or_init::<DumpRegistry>().0.push(contribute::<C>);
        self
    }
}

/// Writes a dump to a JSON file, pretty-printed, with a final newline.
pub fn write_dump(path: &std::path::Path, dump: &Value) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(dump).expect("a JSON value always serializes");
    std::fs::write(path, text + "\n")
}

/// The dump of the whole scene as it is now.
pub fn dump_state(world: &mut World) -> Value {
    let entities: Vec<Value> = dump_entities(world, |_| true).into_iter().map(|(_, dump)| dump).collect();
    let clock = world.get_resource::<SimClock>().copied().unwrap_or_default();
    json!({ "frame": clock.frame, "time": clock.elapsed.as_secs_f64(), "entities": entities })
}

/// The dumps of the scene entities that `wanted` accepts, in scene order, each with its
/// entity: what [`dump_state`] lists, for a reader that needs only some.
pub fn dump_entities(world: &mut World, wanted: impl Fn(&SceneEntity) -> bool) -> Vec<(Entity, Value)> {
    let mut entities: Vec<(Entity, SceneEntity)> = world
        .query::<(Entity, &SceneEntity)>()
        .iter(world)
        .filter(|(_, scene)| wanted(scene))
        .map(|(e, s)| (e, s.clone()))
        .collect();
    entities.sort_by_key(|(_, scene)| scene.index);
    let registry = world.get_resource::<DumpRegistry>().map(|r| r.0.clone()).unwrap_or_default();
    entities
        .into_iter()
        .map(|(entity, scene)| {
            let mut out = Map::new();
            out.insert("name".into(), json!(scene.name));
            out.insert("kind".into(), json!(scene.kind));
            for contribute in &registry {
                contribute(world, entity, &mut out);
            }
            (entity, Value::Object(out))
        })
        .collect()
}
