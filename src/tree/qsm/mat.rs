//! TreeQSM's MATLAB files (version 7, the format MATLAB saves by default), read with the `matrw`
//! crate.
//!
//! Versions 2.3-2.4 save a structure (named `qsm`, `QSM`, `QSMs`, `OptQSM`, ...; a structure
//! array holds one model per element, the first is taken) whose `cylinder` field holds column
//! arrays: `radius`, `length`, `start` and `axis` (N x 3), `parent`, `extension`, `branch`, ...
//! Version 2.0 saves flat variables instead: `Rad`, `Len`, `Sta`, `Axe`, `CPar`, `CExt`.
//! Whole numbers are often stored as smaller integer types; every numeric type is read.

use super::{QsmError, Row, RowPlace, branch_number, one_based};
use bevy::math::DVec3;
use matrw::{MatVariable, MatlabType};

/// The names of the columns a model needs, in a 2.3-2.4 `cylinder` structure and as 2.0's
/// variables: radius, length, start, axis, parent, extension, and the branch (2.3-2.4 only).
const STRUCTURE_FIELDS: [&str; 7] = ["radius", "length", "start", "axis", "parent", "extension", "branch"];
const FLAT_VARIABLES: [&str; 6] = ["Rad", "Len", "Sta", "Axe", "CPar", "CExt"];

/// Reads the rows of a TreeQSM MATLAB file.
pub fn read(bytes: &[u8]) -> Result<Vec<Row>, QsmError> {
    // The crate indexes what the file declares; a malformed file must be an error, never a
    // panic of the app.
    let file = std::panic::catch_unwind(|| matrw::load_matfile_from_u8(bytes))
        .map_err(|_| QsmError::whole("the MATLAB file is malformed"))?
        .map_err(|error| QsmError::whole(format!("not a MATLAB version 7 file this reader can read: {error}")))?;
    let variables: Vec<(&String, &MatVariable)> = file.iter().collect();
    // A model structure: the first variable (or first element of a structure array) with a
    // `cylinder` field.
    let cylinder = variables.iter().find_map(|(_, variable)| {
        let model = match variable {
            MatVariable::StructureArray(_) => &variable[0],
            _ => variable,
        };
        matches!(model["cylinder"], MatVariable::Structure(_)).then(|| &model["cylinder"])
    });
    if let Some(cylinder) = cylinder {
        let [radius, length, start, axis, parent, extension, branch] =
            STRUCTURE_FIELDS.map(|name| (format!("cylinder.{name}"), &cylinder[name]));
        return rows([radius, length, start, axis, parent, extension], Some(branch));
    }
    let flat = FLAT_VARIABLES.map(|name| {
        let found = variables.iter().find(|(variable, _)| *variable == name).map_or(&MatVariable::Null, |(_, v)| *v);
        (name.to_string(), found)
    });
    if !matches!(flat[0].1, MatVariable::Null) {
        return rows(flat, None);
    }
    let names: Vec<&str> = variables.iter().map(|(name, _)| name.as_str()).collect();
    Err(QsmError::whole(format!(
        "no TreeQSM model in the file: no structure with a `cylinder` field, nor a `Rad` variable (variables: {})",
        if names.is_empty() { "none".into() } else { names.join(", ") }
    )))
}

/// A numeric array's values as `f64`, whatever type the file stored them in.
fn numbers(variable: &MatVariable) -> Option<Vec<f64>> {
    Some(match variable.numeric_type()? {
        MatlabType::U8(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::I8(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::U16(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::I16(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::U32(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::I32(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::U64(v) => v.iter().map(|&x| x as f64).collect(),
        MatlabType::I64(v) => v.iter().map(|&x| x as f64).collect(),
        MatlabType::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
        MatlabType::F64(v) => v.clone(),
        MatlabType::BOOL(v) => v.iter().map(|&x| f64::from(u8::from(x))).collect(),
        MatlabType::UTF8(_) | MatlabType::UTF16(_) => return None,
    })
}

/// The rows of the columns `[radius, length, start, axis, parent, extension]` and the optional
/// `branch`, each with its name for messages.
fn rows(columns: [(String, &MatVariable); 6], branch: Option<(String, &MatVariable)>) -> Result<Vec<Row>, QsmError> {
    let column = |(name, variable): &(String, &MatVariable), per_row: usize| -> Result<Vec<f64>, QsmError> {
        numbers(variable).ok_or_else(|| QsmError::whole(format!("`{name}`: expected a numeric array"))).and_then(
            |values| {
                if per_row == 3 && values.len() % 3 != 0 {
                    return Err(QsmError::whole(format!("`{name}`: expected N x 3 values, found {}", values.len())));
                }
                Ok(values)
            },
        )
    };
    let [radius, length, start, axis, parent, extension] = &columns;
    let radius_values = column(radius, 1)?;
    let count = radius_values.len();
    if count > super::MAX_CYLINDERS {
        return Err(QsmError::whole(format!("{count} cylinders, more than {}", super::MAX_CYLINDERS)));
    }
    let same_count = |(name, _): &(String, &MatVariable), values: Vec<f64>, per_row: usize| {
        if values.len() == count * per_row {
            Ok(values)
        } else {
            let message = format!(
                "`{name}`: expected {} values, one per cylinder of `{}`, found {}",
                count * per_row,
                radius.0,
                values.len()
            );
            Err(QsmError::whole(message))
        }
    };
    let length_values = same_count(length, column(length, 1)?, 1)?;
    let start_values = same_count(start, column(start, 3)?, 3)?;
    let axis_values = same_count(axis, column(axis, 3)?, 3)?;
    let parent_values = same_count(parent, column(parent, 1)?, 1)?;
    let extension_values = same_count(extension, column(extension, 1)?, 1)?;
    let branch_values = match &branch {
        Some(branch @ (_, variable)) if !matches!(variable, MatVariable::Null) => {
            Some(same_count(branch, column(branch, 1)?, 1)?)
        }
        _ => None,
    };
    // MATLAB stores N x 3 arrays column by column.
    let vector = |values: &[f64], i: usize| DVec3::new(values[i], values[count + i], values[2 * count + i]);
    (0..count)
        .map(|i| {
            let at = |name: &str, message: String| QsmError::whole(format!("cylinder {} (`{name}`): {message}", i + 1));
            let index =
                |value: f64, name: &str, required: bool| one_based(value, count, required).map_err(|e| at(name, e));
            let row = Row {
                start: vector(&start_values, i),
                axis: vector(&axis_values, i),
                length: length_values[i],
                radius: radius_values[i],
                parent: index(parent_values[i], &parent.0, true)?,
                extension: index(extension_values[i], &extension.0, false)?,
                branch: branch_values.as_ref().and_then(|b| branch_number(b[i])),
                place: RowPlace::Index(i + 1),
            };
            row.check().map_err(|(field, message)| at(field, message))?;
            Ok(row)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model shipped with the tests (TreeQSM files from the ITSMe project).
    fn model(name: &str) -> Vec<u8> {
        std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/qsm").join(name)).unwrap()
    }

    #[test]
    fn treeqsm_files_of_each_version_are_read() {
        // 2.4 (`QSM`), 2.3 (`QSMs`, a structure and a 1 x 4 structure array) and 2.0's flat
        // variables, with their cylinder counts as TreeQSM wrote them.
        for (name, count) in [
            ("itsme_qsm_tree_v240_notria.mat", 66),
            ("itsme_qsm_tree_v230.mat", 88),
            ("itsme_qsms_tree_v230.mat", 110),
            ("itsme_qsm_tree_v200.mat", 115),
        ] {
            let rows = read(&model(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(rows.len(), count, "{name}");
            assert_eq!(rows[0].parent, None, "{name}");
            assert!(rows.iter().skip(1).any(|r| r.parent.is_some()), "{name}");
            assert!(rows.iter().all(|r| r.radius > 0.0 && (r.axis.length() - 1.0).abs() < 1e-3), "{name}");
        }
    }

    #[test]
    fn a_truncated_or_foreign_file_is_an_error() {
        let whole = model("itsme_qsm_tree_v230.mat");
        for cut in [10, 128, 200, whole.len() / 2, whole.len() - 3] {
            assert!(read(&whole[..cut]).is_err(), "cut at {cut}");
        }
        let error = read(b"MATLAB 5.0 MAT-file, but nothing after").unwrap_err();
        assert!(error.message.contains("MATLAB"), "{error}");
    }
}
