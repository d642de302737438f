//! Where a value sits in a YAML text, found by its path (`expect[2].that`), so that a problem
//! found after the file was read (an expression naming a field the scene lacks) still points
//! at its line and column.
//!
//! The text is read again with a seed that walks to the value and refuses it there: the YAML
//! reader marks the refusal with the value's position, as it marks every error.

use serde::de::{self, DeserializeSeed, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// One step of a path into a YAML document.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step<'a> {
    /// A mapping's key.
    Key(&'a str),
    /// A sequence's element.
    Index(usize),
}

/// The 1-based line and column where the value at `path` starts, or `None` when the text has
/// no such value.
pub fn locate(text: &str, path: &[Step]) -> Option<(usize, usize)> {
    let error = Seek(path).deserialize(serde_yaml::Deserializer::from_str(text)).err()?;
    let location = error.location()?;
    Some((location.line(), location.column()))
}

/// Walks down `path`; refuses the value at its end.
struct Seek<'p, 'a>(&'p [Step<'a>]);

impl<'de> DeserializeSeed<'de> for Seek<'_, '_> {
    type Value = ();

    fn deserialize<D: de::Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        deserializer.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Seek<'_, '_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("the value looked for")
    }

    // Every scalar at the end of the path is refused by the default `visit_*` methods, whose
    // errors carry the value's position; a scalar before the end ends the search.
    fn visit_bool<E: de::Error>(self, _: bool) -> Result<(), E> {
        self.scalar()
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> Result<(), E> {
        self.scalar()
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> Result<(), E> {
        self.scalar()
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> Result<(), E> {
        self.scalar()
    }
    fn visit_str<E: de::Error>(self, _: &str) -> Result<(), E> {
        self.scalar()
    }
    fn visit_unit<E: de::Error>(self) -> Result<(), E> {
        self.scalar()
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let Some((Step::Index(wanted), rest)) = self.0.split_first() else { return self.here() };
        let mut index = 0;
        while index < *wanted {
            if seq.next_element::<IgnoredAny>()?.is_none() {
                return Ok(());
            }
            index += 1;
        }
        seq.next_element_seed(Seek(rest))?;
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(())
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let Some((Step::Key(wanted), rest)) = self.0.split_first() else { return self.here() };
        while let Some(key) = map.next_key::<serde_yaml::Value>()? {
            if key.as_str() == Some(*wanted) {
                map.next_value_seed(Seek(rest))?;
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(())
    }
}

impl Seek<'_, '_> {
    fn here<E: de::Error>(&self) -> Result<(), E> {
        Err(E::custom("found"))
    }

    fn scalar<E: de::Error>(&self) -> Result<(), E> {
        if self.0.is_empty() { self.here() } else { Ok(()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "scene: a.yaml\nexpect:\n  - at: 10\n    that: sloth.x > 0.8\n  - { always: \"b\" }\n";

    #[test]
    fn finds_scalars_in_blocks_and_flows() {
        let that = [Step::Key("expect"), Step::Index(0), Step::Key("that")];
        assert_eq!(locate(TEXT, &that), Some((4, 11)));
        let always = [Step::Key("expect"), Step::Index(1), Step::Key("always")];
        assert_eq!(locate(TEXT, &always), Some((5, 15)));
        assert_eq!(locate(TEXT, &[Step::Key("scene")]), Some((1, 8)));
    }

    #[test]
    fn finds_collections_and_misses_what_is_not_there() {
        assert_eq!(locate(TEXT, &[Step::Key("expect"), Step::Index(1)]), Some((5, 5)));
        assert_eq!(locate(TEXT, &[Step::Key("expect"), Step::Index(2)]), None);
        assert_eq!(locate(TEXT, &[Step::Key("nothing")]), None);
        assert_eq!(locate(TEXT, &[Step::Key("scene"), Step::Key("deeper")]), None);
    }
}
