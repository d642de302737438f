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

use crate::foundation::dump::dump_entities;
use crate::foundation::entity::SceneEntity;
use crate::foundation::params::{ParamValue, list_params};
use crate::foundation::schedule::SimClock;
use crate::scene_test::expr::{NAMESPACES, to_cel};
use bevy::prelude::*;
use cel::Context;
use serde_json::{Map, Value as Json, json};
use std::collections::{BTreeMap, BTreeSet};

/// Names an entity cannot be reached by directly: the scope's own, the extensions' namespaces
/// ([`NAMESPACES`]) and CEL's reserved words.
const SCOPE_NAMES: &[&str] = &["time", "frame", "entities"];
const RESERVED_WORDS: &[&str] = &[
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
}

impl Scope {
    /// The scope of `world` as it is now: every variable, or (with `roots`) only those
    /// named, dumping no more entities than they need.
    pub fn of(world: &mut World, roots: Option<&[String]>) -> Self {
        let all = roots.is_none_or(|roots| roots.iter().any(|root| root == "entities"));
        let wanted = |scene: &SceneEntity| all || roots.is_some_and(|roots| roots.contains(&scene.name));
        let mut by_name = Map::new();
        for (entity, fields) in dump_entities(world, wanted) {
            let Json::Object(mut fields) = fields else { continue };
            let Some(name) = fields.get("name").and_then(Json::as_str).map(str::to_string) else { continue };
            if by_name.contains_key(&name) {
                // Unnamed entities of one kind share their kind's name: the first answers.
                continue;
            }
            for param in list_params(world, entity) {
                let value = match param.value {
                    ParamValue::Number(v) => json!(v),
                    ParamValue::Bool(v) => json!(v),
                    ParamValue::Choice(v) => json!(v),
                };
                merge(&mut fields, &param.path, value);
            }
            by_name.insert(name, Json::Object(fields));
        }
        let variable = |name: &str| {
            is_identifier(name) && ![SCOPE_NAMES, NAMESPACES, RESERVED_WORDS].iter().any(|names| names.contains(&name))
        };
        let mut variables = Map::new();
        if all {
            // Each entity both by its name and under `entities`.
            for (name, fields) in by_name.iter().filter(|(name, _)| variable(name)) {
                variables.insert(name.clone(), fields.clone());
            }
            variables.insert("entities".into(), Json::Object(by_name));
        } else {
            variables.extend(by_name.into_iter().filter(|(name, _)| variable(name)));
        }
        let clock = world.get_resource::<SimClock>().copied().unwrap_or_default();
        variables.insert("time".into(), json!(clock.elapsed.as_secs_f64()));
        variables.insert("frame".into(), json!(clock.frame));
        Self { variables }
    }

    /// Binds the variables `reads` needs in an inner scope of `root`.
    pub fn bind<'a>(&self, root: &'a Context<'static, 'static>, reads: &Reads) -> Context<'a, 'static> {
        let mut context = root.new_inner_scope();
        for (name, fields) in &reads.0 {
            let Some(value) = self.variables.get(name) else { continue };
            let value = match (fields, value) {
                (Some(fields), Json::Object(all)) => {
                    let map = fields.iter().filter_map(|f| all.get(f).map(|v| (f.clone(), v.clone()))).collect();
                    to_cel(&Json::Object(map))
                }
                _ => to_cel(value),
            };
            context.add_variable_from_value(name, value);
        }
        context
    }
}

/// What a test's expressions read of each variable: the fields selected from it, or all of
/// it (`None`) where a variable is used whole, so that a step converts no more of the state
/// than is read.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Reads(BTreeMap<String, Option<BTreeSet<String>>>);

impl Reads {
    /// Adds a path read: a variable and the fields selected from it.
    pub fn add(&mut self, path: &[String]) {
        let Some((root, fields)) = path.split_first() else { return };
        let entry = self.0.entry(root.clone()).or_insert_with(|| Some(BTreeSet::new()));
        match (entry, fields.first()) {
            (Some(selected), Some(field)) => {
                selected.insert(field.clone());
            }
            (entry, _) => *entry = None,
        }
    }

    /// The variables read.
    pub fn roots(&self) -> Vec<String> {
        self.0.keys().cloned().collect()
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
    fn a_step_binds_only_the_fields_read_unless_a_variable_is_used_whole() {
        let path = |p: &str| p.split('.').map(str::to_string).collect::<Vec<_>>();
        let mut reads = Reads::default();
        reads.add(&path("sloth.feet.lf"));
        reads.add(&path("sloth.support"));
        reads.add(&path("plum"));
        reads.add(&path("plum.dropped"));
        assert_eq!(reads.roots(), ["plum", "sloth"]);
        let sloth: BTreeSet<String> = ["feet", "support"].map(String::from).into();
        assert_eq!(reads.0["sloth"], Some(sloth));
        assert_eq!(reads.0["plum"], None);
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
