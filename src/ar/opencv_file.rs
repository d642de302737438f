//! OpenCV's `FileStorage` text files, YAML (with its `%YAML:1.0` header and `!!opencv-*`
//! tags) or JSON, read as a mapping with errors at their line.

use crate::foundation::yaml::FileError;
use serde_yaml::{Mapping, Value};
use std::path::Path;

/// The bytes of the file at `path`, refused (without reading them) if there are more than
/// `max_bytes`; `what` names the kind of file in that message.
pub fn read_bounded(path: &Path, max_bytes: usize, what: &str) -> Result<Vec<u8>, FileError> {
    let metadata = std::fs::metadata(path).map_err(|error| FileError::unreadable(path, error))?;
    if metadata.len() > max_bytes as u64 {
        let limit = format!("{} KiB", max_bytes >> 10);
        return Err(FileError::whole_file(path, format!("{} bytes: {what} is at most {limit}", metadata.len())));
    }
    std::fs::read(path).map_err(|error| FileError::unreadable(path, error))
}

/// The top-level mapping of an OpenCV file's bytes, and its text for locating keys; `what`
/// says what the file should hold, for errors.
pub fn read_mapping(path: &Path, bytes: &[u8], what: &str) -> Result<(String, Mapping), FileError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|_| FileError::whole_file(path, format!("not UTF-8 text: expected {what}")))?;
    // OpenCV's `%YAML:1.0` is not YAML's `%YAML 1.0`: blanked, keeping the line numbers.
    let cleaned: String =
        text.lines().map(|line| if line.starts_with("%YAML") { "" } else { line }).collect::<Vec<_>>().join("\n");
    let root: Value = serde_yaml::from_str(&cleaned).map_err(|error| match error.location() {
        Some(at) => FileError::at(path, at.line(), at.column(), format!("not valid YAML or JSON: {error}")),
        None => FileError::whole_file(path, format!("not valid YAML or JSON: {error}")),
    })?;
    match untag(&root) {
        Value::Mapping(fields) => Ok((text.to_string(), fields.clone())),
        _ => Err(FileError::whole_file(path, format!("expected a mapping: {what}"))),
    }
}

/// A tagged value's content (`!!opencv-matrix {..}` is its mapping).
pub fn untag(value: &Value) -> &Value {
    match value {
        Value::Tagged(tagged) => untag(&tagged.value),
        other => other,
    }
}
