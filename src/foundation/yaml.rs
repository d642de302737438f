//! Reading user-written YAML files with errors that point at the file, line, column and field.

use serde::de::DeserializeOwned;
use std::fmt;
use std::path::{Path, PathBuf};

/// A user file that could not be read or is not valid: the message names the field and what
/// was expected, the location points into the file (1-based line and column).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct FileError {
    /// The file, as the user named it.
    pub path: PathBuf,
    /// 1-based line and column, when the problem has a place in the file.
    pub location: Option<(usize, usize)>,
    /// What is wrong, naming the field and what was expected.
    pub message: String,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some((line, column)) => write!(f, "{}:{line}:{column}: {}", self.path.display(), self.message),
            None => write!(f, "{}: {}", self.path.display(), self.message),
        }
    }
}

impl FileError {
    /// An error about the whole file.
    pub fn whole_file(path: &Path, message: impl Into<String>) -> Self {
        Self { path: path.to_path_buf(), location: None, message: message.into() }
    }

    /// The file could not be read at all.
    pub fn unreadable(path: &Path, error: impl fmt::Display) -> Self {
        Self::whole_file(path, format!("cannot read the file: {error}"))
    }

    /// An error at a 1-based line and column.
    pub fn at(path: &Path, line: usize, column: usize, message: impl Into<String>) -> Self {
        Self { path: path.to_path_buf(), location: Some((line, column)), message: message.into() }
    }
}

/// Reads and parses a YAML file; `what` names the expected content for an empty file.
pub fn read_yaml_file<T: DeserializeOwned>(path: &Path, what: &str) -> Result<T, FileError> {
    let bytes = std::fs::read(path).map_err(|error| FileError::unreadable(path, error))?;
    parse_yaml(path, &bytes, what)
}

/// Parses YAML bytes read from `path`; `what` names the expected content for an empty file.
pub fn parse_yaml<T: DeserializeOwned>(path: &Path, bytes: &[u8], what: &str) -> Result<T, FileError> {
    let text = std::str::from_utf8(bytes).map_err(|error| {
        let (line, column) = line_column(bytes, error.valid_up_to());
        FileError::at(path, line, column, "the file is not UTF-8 text (is it a YAML file?)")
    })?;
    if text.lines().all(|line| line.trim().is_empty() || line.trim_start().starts_with('#')) {
        return Err(FileError::whole_file(path, format!("the file is empty: expected {what}")));
    }
    serde_yaml::from_str(text).map_err(|error| yaml_error(path, text, &error))
}

/// Converts a `serde_yaml` error into a [`FileError`], moving "unknown field" errors from the
/// start of their mapping to the line of the offending key.
fn yaml_error(path: &Path, text: &str, error: &serde_yaml::Error) -> FileError {
    let full = error.to_string();
    let Some(location) = error.location() else {
        return FileError::whole_file(path, full);
    };
    let (mut line, mut column) = (location.line(), location.column());
    // serde_yaml puts " at line L column C" into its messages; the location is kept apart.
    let message = full.replacen(&format!(" at line {line} column {column}"), "", 1);
    if let Some(key) = unknown_field(&message)
        && let Some(offset) = key_offsets(text, key).find(|&at| at >= location.index())
    {
        (line, column) = line_column(text.as_bytes(), offset);
    }
    FileError::at(path, line, column, message)
}

/// The field name in a serde "unknown field `name`" message.
fn unknown_field(message: &str) -> Option<&str> {
    let rest = &message[message.find("unknown field `")? + "unknown field `".len()..];
    Some(&rest[..rest.find('`')?])
}

/// Deserializes a string and converts it with `parse`, inside the deserializer, so that a
/// refused value is reported at its own line and column with its field path. `expecting`
/// describes a valid value.
pub fn deserialize_str_with<'de, D, T>(
    deserializer: D,
    expecting: &'static str,
    parse: fn(&str) -> Result<T, String>,
) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
{
    struct StrVisitor<T> {
        expecting: &'static str,
        parse: fn(&str) -> Result<T, String>,
    }

    impl<T> serde::de::Visitor<'_> for StrVisitor<T> {
        type Value = T;

        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(self.expecting)
        }

        fn visit_str<E: serde::de::Error>(self, value: &str) -> Result<T, E> {
            (self.parse)(value).map_err(E::custom)
        }
    }

    deserializer.deserialize_str(StrVisitor { expecting, parse })
}

/// An error at the `nth` (from 0) occurrence of mapping key `key` in `text`, read from
/// `path`, or about the whole file when the key cannot be found.
pub fn locate_key(path: &Path, text: &str, key: &str, nth: usize, message: String) -> FileError {
    match find_nth_key(text, key, nth) {
        Some((line, column)) => FileError::at(path, line, column, message),
        None => FileError::whole_file(path, message),
    }
}

/// An error at the `nth` (from 0) mapping key `key` after the `anchor_nth` occurrence of the
/// mapping key `anchor` (an entity's kind key, say), or about the whole file when either
/// cannot be found.
pub fn locate_key_after(
    path: &Path,
    text: &str,
    (anchor, anchor_nth): (&str, usize),
    key: &str,
    nth: usize,
    message: String,
) -> FileError {
    let found = key_offsets(text, anchor)
        .nth(anchor_nth)
        .and_then(|start| key_offsets(text, key).filter(|&at| at >= start).nth(nth))
        .map(|at| line_column(text.as_bytes(), at));
    match found {
        Some((line, column)) => FileError::at(path, line, column, message),
        None => FileError::whole_file(path, message),
    }
}

/// The 1-based line and column of the `nth` (from 0) mapping key `key` in `text`.
pub fn find_nth_key(text: &str, key: &str, nth: usize) -> Option<(usize, usize)> {
    key_offsets(text, key).nth(nth).map(|at| line_column(text.as_bytes(), at))
}

/// Byte offsets of every place `key` stands as a mapping key (`key:` in block or flow style).
fn key_offsets<'a>(text: &'a str, key: &'a str) -> impl Iterator<Item = usize> + 'a {
    text.match_indices(key).map(|(at, _)| at).filter(move |&at| {
        let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
        let in_comment = text[line_start..at].contains('#');
        let before = text[..at].chars().next_back();
        let after = text[at + key.len()..].trim_start_matches([' ', '"', '\'']);
        !in_comment
            && matches!(before, None | Some(' ' | '\n' | '{' | ',' | '"' | '\'' | '-'))
            && after.starts_with(':')
    })
}

/// The 1-based line and column of byte `offset`.
pub fn line_column(bytes: &[u8], offset: usize) -> (usize, usize) {
    let before = &bytes[..offset.min(bytes.len())];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Outer {
        inner: Inner,
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Inner {
        alpha: f32,
        beta: f32,
    }

    fn parse(text: &str) -> FileError {
        parse_yaml::<Outer>(Path::new("t.yaml"), text.as_bytes(), "an outer").unwrap_err()
    }

    #[test]
    fn unknown_fields_point_at_their_key() {
        let error = parse("inner:\n  alpha: 1\n  betta: 2\n");
        assert_eq!(error.location, Some((3, 3)), "{error}");
        assert!(error.message.contains("inner: unknown field `betta`"), "{error}");
    }

    #[test]
    fn type_errors_name_the_path_and_place() {
        let error = parse("inner:\n  alpha: one\n  beta: 2\n");
        assert_eq!(error.location, Some((2, 10)), "{error}");
        assert!(error.message.starts_with("inner.alpha: invalid type"), "{error}");
        assert_eq!(error.to_string().split(':').take(3).collect::<Vec<_>>(), ["t.yaml", "2", "10"]);
    }

    #[test]
    fn empty_and_binary_files_are_clear_errors() {
        assert!(parse("").message.contains("the file is empty: expected an outer"));
        assert!(parse("# only a comment\n\n").message.contains("empty"));
        let error = parse_yaml::<Outer>(Path::new("b.yaml"), b"inner:\n\xff\xfe", "x").unwrap_err();
        assert_eq!(error.location, Some((2, 1)));
        assert!(error.message.contains("not UTF-8"));
    }

    #[test]
    fn deep_nesting_is_refused_without_overflowing_the_stack() {
        let text = format!("{}{}", "[".repeat(5_000), "]".repeat(5_000));
        let error = parse_yaml::<serde_yaml::Value>(Path::new("d.yaml"), text.as_bytes(), "x").unwrap_err();
        assert!(error.message.contains("recursion limit exceeded"), "{error}");
    }
}
