//! Actions: what an entity can be told to do that no parameter holds, such as a list of
//! points to mark or a button to press. A kind registers the action type its entities take
//! (a serde type); timelines send actions to entities by name:
//!
//! ```yaml
//! - { at: 0.5, act: { torso: [{ mark: [0.0, 1.1, 0.12] }, apply] } }
//! ```
//!
//! An action is read from YAML by the kind's own type, so a timeline can be checked against
//! the loaded scene before it plays, and a wrong action is named with what was expected.

use crate::foundation::entity::SceneEntity;
use crate::foundation::kind::EntityKind;
use bevy::prelude::*;
use serde::de::DeserializeOwned;

/// Why an action could not be sent.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ActionError {
    /// No entity has that name.
    #[error("action for `{entity}`: no entity is named so (entities: {known})")]
    NoEntity {
        /// The name the action was sent to.
        entity: String,
        /// The names present.
        known: String,
    },
    /// The entity's kind takes no actions.
    #[error("action for `{entity}`: a {kind} takes no actions")]
    NoActions {
        /// The entity's name.
        entity: String,
        /// Its kind.
        kind: &'static str,
    },
    /// The action is not one the kind takes.
    #[error("action for `{entity}`: {message}")]
    Malformed {
        /// The entity's name.
        entity: String,
        /// What the kind's action type said.
        message: String,
    },
}

/// Reads an action from YAML and, when it reads and `run` is set, performs it on an entity.
type ActionFn = Box<dyn Fn(&mut World, Entity, &serde_yaml::Value, bool) -> Result<(), String> + Send + Sync>;

/// The action types of the kinds, by kind key.
#[derive(Resource, Default)]
pub struct ActionKinds(Vec<(&'static str, ActionFn)>);

/// Registration of a kind's actions on the app.
pub trait RegisterActions {
    /// Entities of kind `K` take actions of type `A`, performed by `perform`.
    fn register_actions<K: EntityKind, A: DeserializeOwned + 'static>(
        &mut self,
        perform: fn(&mut World, Entity, A),
    ) -> &mut Self;
}

impl RegisterActions for App {
    fn register_actions<K: EntityKind, A: DeserializeOwned + 'static>(
        &mut self,
        perform: fn(&mut World, Entity, A),
    ) -> &mut Self {
        let read: ActionFn = Box::new(move |world, entity, value, run| {
            // Enums as the one-entry mappings people write (`{ mark: .. }`), not YAML tags.
            let action: A = serde_yaml::with::singleton_map_recursive::deserialize(value.clone())
                .map_err(|error| error.to_string())?;
            if run {
                perform(world, entity, action);
            }
            Ok(())
        });
        self.world_mut().get_resource_or_init::<ActionKinds>().0.push((K::KEY, read));
        self
    }
}

/// Sends `actions` (one action, or a list of them done in order) to the entities named
/// `entity`; with `run` false it only checks that they would be taken.
pub fn act(world: &mut World, entity: &str, actions: &serde_yaml::Value, run: bool) -> Result<(), ActionError> {
    let mut query = world.query::<(Entity, &SceneEntity)>();
    let mut all: Vec<(usize, Entity, String, &'static str)> =
        query.iter(world).map(|(e, s)| (s.index, e, s.name.clone(), s.kind)).collect();
    all.sort_by_key(|(index, ..)| *index);
    let targets: Vec<(Entity, &'static str)> =
        all.iter().filter(|(_, _, name, _)| name == entity).map(|&(_, e, _, kind)| (e, kind)).collect();
    if targets.is_empty() {
        let known = all.iter().map(|(_, _, name, _)| name.as_str()).collect::<Vec<_>>().join(", ");
        return Err(ActionError::NoEntity { entity: entity.to_string(), known });
    }
    let list = match actions {
        serde_yaml::Value::Sequence(list) => list.clone(),
        one => vec![one.clone()],
    };
    world.resource_scope(|world, kinds: Mut<ActionKinds>| {
        for (target, kind) in targets {
            let Some((_, read)) = kinds.0.iter().find(|(k, _)| *k == kind) else {
                return Err(ActionError::NoActions { entity: entity.to_string(), kind });
            };
            for action in &list {
                read(world, target, action, run)
                    .map_err(|message| ActionError::Malformed { entity: entity.to_string(), message })?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Deserialize)]
    #[serde(rename_all = "snake_case", deny_unknown_fields)]
    enum Bell {
        Ring,
        RingTimes(u32),
    }

    #[derive(Component, Default)]
    struct Rings(u32);

    /// A kind whose entities take [`Bell`] actions.
    struct BellKind;

    #[derive(Default)]
    struct NoPlugin;

    impl Plugin for NoPlugin {
        fn build(&self, _: &mut App) {}
    }

    impl EntityKind for BellKind {
        const KEY: &'static str = "bell";
        type Def = ();
        type Built = ();
        type Plugin = NoPlugin;

        fn build(_: &(), _: &crate::foundation::kind::BuildContext) -> Result<(), crate::foundation::yaml::FileError> {
            Ok(())
        }

        fn spawn(_: &(), _: &(), _: &mut EntityWorldMut) {}
    }

    fn ring(world: &mut World, entity: Entity, bell: Bell) {
        let times = match bell {
            Bell::Ring => 1,
            Bell::RingTimes(n) => n,
        };
        world.get_mut::<Rings>(entity).unwrap().0 += times;
    }

    #[test]
    fn actions_are_checked_then_performed_in_order() {
        let mut app = App::new();
        app.init_resource::<ActionKinds>().register_actions::<BellKind, Bell>(ring);
        let bell = app.world_mut().spawn((SceneEntity { index: 0, name: "b".into(), kind: "bell" }, Rings(0))).id();
        app.world_mut().spawn(SceneEntity { index: 1, name: "lamp".into(), kind: "lamp" });
        let world = app.world_mut();
        let list: serde_yaml::Value = serde_yaml::from_str("[ring, {ring_times: 3}]").unwrap();
        act(world, "b", &list, false).unwrap();
        assert_eq!(world.get::<Rings>(bell).unwrap().0, 0, "a check performs nothing");
        act(world, "b", &list, true).unwrap();
        assert_eq!(world.get::<Rings>(bell).unwrap().0, 4);
        let bad: serde_yaml::Value = serde_yaml::from_str("knock").unwrap();
        let error = act(world, "b", &bad, false).unwrap_err().to_string();
        assert!(error.contains("unknown variant `knock`"), "{error}");
        let error = act(world, "lamp", &bad, false).unwrap_err().to_string();
        assert!(error.contains("a lamp takes no actions"), "{error}");
        let error = act(world, "c", &bad, false).unwrap_err().to_string();
        assert!(error.contains("no entity is named so (entities: b, lamp)"), "{error}");
    }
}
