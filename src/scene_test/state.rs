//! The state a scene test's expressions read at one step: the state dump (see
//! [`crate::foundation::dump`]) with every entity bound by its name, its parameters merged in
//! as the panel names them, and the clock.
//!
//! | variable | what |
//! |---|---|
//! | `<entity name>` | the entity's dump fields, and its parameters where the dump has no field of that name |
//! | `entities` | every entity by name, for names that are not CEL identifiers (`entities["tree-2"]`) |
//! | `time` | simulated seconds since the scene went live |
//! | `frame` | fixed steps taken |

use crate::foundation::dump::dump_state;
use crate::foundation::entity::SceneEntity;
use crate::foundation::params::{ParamValue, list_params};
use crate::scene_test::expr::to_cel;
use bevy::prelude::*;
use cel::Context;
use serde_json::{Map, Value as Json, json};

/// Names an entity cannot be reached by directly: CEL's reserved words and the scope's own.
const NOT_VARIABLES: &[&str] = &[
    "time",
    "frame",
    "entities",
    "math",
    "lists",
    "strings",
    "true",
    "false",
    "null",
    "in",
    "as",
    "break",
    "const",
    "continue",
    "else",
    "for",
    "function",
    "if",
    "import",
    "let",
    "loop",
    "package",
    "namespace",
    "return",
    "var",
    "void",
    "while",
];

/// The variables of one step.
#[derive(Debug, Clone, PartialEq)]
pub struct Scope {
    /// Variable name to value.
    pub variables: Map<String, Json>,
    /// The state dump it was made from, as written on a failure.
    pub dump: Json,
}

impl Scope {
    /// The scope of `world` as it is now.
    pub fn of(world: &mut World) -> Self {
        let dump = dump_state(world);
        let mut entities: Vec<(Entity, usize)> =
            world.query::<(Entity, &SceneEntity)>().iter(world).map(|(e, s)| (e, s.index)).collect();
        entities.sort_by_key(|(_, index)| *index);
        let mut by_name = Map::new();
        let listed = dump["entities"].as_array().into_iter().flatten();
        for ((entity, _), fields) in entities.iter().zip(listed) {
            let Some(name) = fields["name"].as_str() else { continue };
            if by_name.contains_key(name) {
                // Unnamed entities of one kind share their kind's name: the first answers.
                continue;
            }
            let mut fields = fields.as_object().cloned().unwrap_or_default();
            for param in list_params(world, *entity) {
                let value = match param.value {
                    ParamValue::Number(v) => json!(v),
                    ParamValue::Bool(v) => json!(v),
                    ParamValue::Choice(v) => json!(v),
                };
                merge(&mut fields, &param.path, value);
            }
            by_name.insert(name.to_string(), Json::Object(fields));
        }
        let mut variables = Map::new();
        for (name, fields) in &by_name {
            if is_identifier(name) && !NOT_VARIABLES.contains(&name.as_str()) {
                variables.insert(name.clone(), fields.clone());
            }
        }
        variables.insert("entities".into(), Json::Object(by_name));
        variables.insert("time".into(), dump["time"].clone());
        variables.insert("frame".into(), dump["frame"].clone());
        Self { variables, dump }
    }

    /// Binds the variables `roots` names in an inner scope of `root`.
    pub fn bind<'a, 'r>(
        &self,
        root: &'a Context<'static, 'static>,
        roots: impl IntoIterator<Item = &'r str>,
    ) -> Context<'a, 'static> {
        let mut context = root.new_inner_scope();
        for name in roots {
            if let Some(value) = self.variables.get(name) {
                context.add_variable_from_value(name, to_cel(value));
            }
        }
        context
    }
}

/// Puts a parameter at its dotted path into `fields`, unless a field already holds that
/// place: the dump's facts win over the parameter of the same name.
fn merge(fields: &mut Map<String, Json>, path: &str, value: Json) {
    match path.split_once('.') {
        None => {
            fields.entry(path.to_string()).or_insert(value);
        }
        Some((head, rest)) => {
            if let Json::Object(inner) = fields.entry(head.to_string()).or_insert_with(|| Json::Object(Map::new())) {
                merge(inner, rest, value);
            }
        }
    }
}

/// A CEL identifier: a letter or `_`, then letters, digits and `_`.
fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_fill_in_where_the_dump_is_silent() {
        let mut fields = Map::new();
        fields.insert("position".into(), json!([1.0, 2.0, 3.0]));
        merge(&mut fields, "position.y", json!(5.0));
        merge(&mut fields, "speed", json!(0.2));
        merge(&mut fields, "gait.delay_s", json!(0.2));
        assert_eq!(fields["position"], json!([1.0, 2.0, 3.0]));
        assert_eq!(fields["speed"], json!(0.2));
        assert_eq!(fields["gait"]["delay_s"], json!(0.2));
    }

    #[test]
    fn identifiers_are_what_cel_can_name() {
        assert!(is_identifier("plum_1"));
        assert!(is_identifier("_x"));
        assert!(!is_identifier("tree-2"));
        assert!(!is_identifier("2nd"));
        assert!(!is_identifier(""));
    }
}
