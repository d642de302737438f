//! Marker dictionaries of the user's, in the file OpenCV's `Dictionary::writeDictionary`
//! writes (YAML or JSON): `nmarkers`, `markersize`, `maxCorrectionBits`, and `marker_0`,
//! `marker_1`, ... each a string of `markersize * markersize` cells, `1` white, row by row
//! from the top-left.

use super::opencv_file::{read_mapping, untag};
use crate::foundation::yaml::{FileError, locate_key};
use canopy_vision::dictionary::{Dictionary, MAX_CUSTOM_MARKERS};
use std::path::Path;

/// The largest dictionary file read, bytes.
pub const MAX_DICTIONARY_BYTES: usize = 8 << 20;

/// Reads a dictionary file's bytes, naming the dictionary after the file; `path` names it in
/// errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Dictionary, FileError> {
    if bytes.len() > MAX_DICTIONARY_BYTES {
        return Err(FileError::whole_file(path, format!("{} bytes: a dictionary file is at most 8 MiB", bytes.len())));
    }
    let (text, fields) =
        read_mapping(path, bytes, "OpenCV's dictionary YAML or JSON with nmarkers, markersize and marker_0, ...")?;
    let at = |key: &str, message: String| locate_key(path, &text, key, 0, format!("{key}: {message}"));
    let whole = |key: &str, range: std::ops::RangeInclusive<u64>| -> Result<u64, FileError> {
        let value = fields.get(key).ok_or_else(|| FileError::whole_file(path, format!("missing {key}")))?;
        untag(value)
            .as_u64()
            .filter(|n| range.contains(n))
            .ok_or_else(|| at(key, format!("expected a whole number from {} to {}", range.start(), range.end())))
    };
    let count = whole("nmarkers", 1..=MAX_CUSTOM_MARKERS as u64)? as usize;
    let cells = whole("markersize", 2..=8)? as u32;
    let correction = match fields.get("maxCorrectionBits") {
        Some(_) => whole("maxCorrectionBits", 0..=u64::from(cells * cells / 2))? as u32,
        None => 0,
    };
    let codes = (0..count)
        .map(|id| {
            let key = format!("marker_{id}");
            let value = fields.get(key.as_str()).ok_or_else(|| {
                FileError::whole_file(path, format!("missing {key}: nmarkers says there are {count}"))
            })?;
            let bits = untag(value).as_str().ok_or_else(|| at(&key, "expected a string of 0s and 1s".into()))?;
            let length = (cells * cells) as usize;
            if bits.len() != length || !bits.bytes().all(|b| b == b'0' || b == b'1') {
                return Err(at(&key, format!("expected {length} characters, each 0 or 1, found \"{bits}\"")));
            }
            Ok(bits.bytes().fold(0u64, |code, bit| code << 1 | u64::from(bit == b'1')))
        })
        .collect::<Result<Vec<u64>, FileError>>()?;
    let name = path.file_stem().map_or_else(|| "custom".to_string(), |stem| stem.to_string_lossy().into_owned());
    Dictionary::custom(name, cells, codes, correction).map_err(|message| FileError::whole_file(path, message))
}

/// Reads a dictionary file.
pub fn read(path: &Path) -> Result<Dictionary, FileError> {
    let metadata = std::fs::metadata(path).map_err(|error| FileError::unreadable(path, error))?;
    if metadata.len() > MAX_DICTIONARY_BYTES as u64 {
        return Err(FileError::whole_file(
            path,
            format!("{} bytes: a dictionary file is at most 8 MiB", metadata.len()),
        ));
    }
    let bytes = std::fs::read(path).map_err(|error| FileError::unreadable(path, error))?;
    parse(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dictionary OpenCV 4.14's `extendDictionary(5, 4, randomSeed=7)` wrote.
    const OPENCV: &str = "%YAML:1.0\n---\nnmarkers: 5\nmarkersize: 4\nmaxCorrectionBits: 2\n\
        marker_0: \"1111010111000100\"\nmarker_1: \"1001101110110100\"\nmarker_2: \"0100101101001100\"\n\
        marker_3: \"0110111000101001\"\nmarker_4: \"0011100101000000\"\n";

    #[test]
    fn opencvs_dictionary_file_is_read_cell_for_cell() {
        let dictionary = parse(Path::new("mine.yml"), OPENCV.as_bytes()).unwrap();
        assert_eq!((dictionary.name.as_ref(), dictionary.len(), dictionary.cells), ("mine", 5, 4));
        assert_eq!(dictionary.max_correction_bits, 2);
        // Marker 2 as OpenCV draws it: rows 0100, 1011, 0100, 1100 (1 white).
        let cells: String = dictionary.cells_of(2).unwrap().iter().map(|&w| if w { '1' } else { '0' }).collect();
        assert_eq!(cells, "0100101101001100");
        let json = r#"{"nmarkers": 1, "markersize": 4, "marker_0": "1111010111000100"}"#;
        assert_eq!(parse(Path::new("one.json"), json.as_bytes()).unwrap().len(), 1);
    }

    #[test]
    fn bad_dictionaries_are_located() {
        let error = parse(Path::new("d.yml"), OPENCV.replace("0100101101001100", "01001").as_bytes()).unwrap_err();
        assert_eq!(error.location.map(|l| l.0), Some(8), "{error}");
        assert!(error.message.contains("marker_2: expected 16 characters"), "{error}");
        let error = parse(Path::new("d.yml"), OPENCV.replace("nmarkers: 5", "nmarkers: 6").as_bytes()).unwrap_err();
        assert!(error.message.contains("missing marker_5"), "{error}");
        let error = parse(Path::new("d.yml"), OPENCV.replace("markersize: 4", "markersize: 9").as_bytes()).unwrap_err();
        assert!(error.message.contains("markersize: expected a whole number from 2 to 8"), "{error}");
        let error =
            parse(Path::new("d.yml"), OPENCV.replace("maxCorrectionBits: 2", "maxCorrectionBits: 9").as_bytes())
                .unwrap_err();
        assert!(error.message.contains("maxCorrectionBits"), "{error}");
        assert!(parse(Path::new("d.yml"), b"- a list").unwrap_err().message.contains("expected a mapping"));
    }
}
