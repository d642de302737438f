//! Comma-separated models, read by their header's column names (their order and any other
//! columns vary between versions):
//!
//! - SimpleForest (and rTwig's copies): `ID, parentID, startX, startY, startZ, endX, endY, endZ,
//!   radius`, optionally `branchID`; IDs from 0, `parentID` -1 at the root.
//! - aRchi: `startX, ..., endZ, cyl_ID, parent_ID, extension_ID, radius_cyl`, optionally
//!   `axis_ID` (its branch); IDs from 1, 0 for none.
//!
//! A cylinder runs from its start to its end point.

use super::{QsmError, Row, RowPlace};
use bevy::math::DVec3;
use std::collections::HashMap;

/// Which program wrote the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// SimpleForest or rTwig.
    SimpleForest,
    /// aRchi.
    Archi,
}

impl Layout {
    /// The names of the identity, parent, extension, radius and branch columns; the
    /// extension and branch columns may be missing, and SimpleForest has no extension.
    fn names(self) -> [&'static str; 5] {
        match self {
            Layout::SimpleForest => ["ID", "parentID", "", "radius", "branchID"],
            Layout::Archi => ["cyl_ID", "parent_ID", "extension_ID", "radius_cyl", "axis_ID"],
        }
    }
}

const ENDS: [&str; 6] = ["startX", "startY", "startZ", "endX", "endY", "endZ"];

/// Reads the rows of a CSV model.
pub fn read(bytes: &[u8], layout: Layout) -> Result<Vec<Row>, QsmError> {
    let text = std::str::from_utf8(bytes).map_err(|error| {
        let line = bytes[..error.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        QsmError::at(line, 1, "the file is not text (is it a CSV file?)")
    })?;
    let mut lines = text.lines().enumerate().map(|(i, line)| (i + 1, line.trim_end_matches('\r')));
    let Some((_, header)) = lines.next() else { return Err(QsmError::whole("the file is empty")) };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let column = |name: &str| names.iter().position(|n| *n == name);
    let required = |name: &'static str| {
        column(name).ok_or_else(|| {
            QsmError::at(1, 1, format!("the header has no `{name}` column ({} expected)", expected(layout)))
        })
    };
    let [id, parent, extension, radius, branch] = layout.names();
    let ends = ENDS.map(required);
    let ends: Vec<usize> = ends.into_iter().collect::<Result<_, _>>()?;
    let (id, parent, radius) = (required(id)?, required(parent)?, required(radius)?);
    // SimpleForest has no extension column (a header's trailing comma names an empty one).
    let extension = (!extension.is_empty()).then(|| column(extension)).flatten();
    let branch = column(branch);

    struct Read {
        line: usize,
        id: i64,
        parent: i64,
        extension: Option<i64>,
        start: DVec3,
        end: DVec3,
        radius: f64,
        branch: Option<u32>,
    }
    let mut read_rows = Vec::new();
    for (line, text) in lines.filter(|(_, text)| !text.trim().is_empty()) {
        let base = text.as_ptr() as usize;
        let fields: Vec<(usize, &str)> = text.split(',').map(|f| (f.as_ptr() as usize - base + 1, f.trim())).collect();
        let value = |at: usize| -> Result<f64, QsmError> {
            let (column, field) = fields.get(at).copied().ok_or_else(|| {
                QsmError::at(
                    line,
                    text.len() + 1,
                    format!("missing the `{}` column ({} values)", names[at], fields.len()),
                )
            })?;
            field
                .parse::<f64>()
                .map_err(|_| QsmError::at(line, column, format!("{}: `{field}` is not a number", names[at])))
        };
        let whole = |at: usize| -> Result<i64, QsmError> {
            let v = value(at)?;
            if v.fract() != 0.0 || v.abs() > 1e15 {
                return Err(QsmError::at(
                    line,
                    fields[at].0,
                    format!("{}: expected a whole number, found {v}", names[at]),
                ));
            }
            Ok(v as i64)
        };
        let point = |first: usize| -> Result<DVec3, QsmError> {
            Ok(DVec3::new(value(ends[first])?, value(ends[first + 1])?, value(ends[first + 2])?))
        };
        let branch_id = branch.map(whole).transpose()?;
        read_rows.push(Read {
            line,
            id: whole(id)?,
            parent: whole(parent)?,
            extension: extension.map(whole).transpose()?,
            start: point(0)?,
            end: point(3)?,
            radius: value(radius)?,
            // SimpleForest counts branches from 0: stored from 1, as TreeQSM does.
            branch: branch_id.and_then(|b| u32::try_from(b + i64::from(layout == Layout::SimpleForest)).ok()),
        });
        if read_rows.len() > super::MAX_CYLINDERS {
            return Err(QsmError::at(line, 1, format!("more than {} cylinders", super::MAX_CYLINDERS)));
        }
    }
    let mut by_id: HashMap<i64, usize> = HashMap::with_capacity(read_rows.len());
    for (index, row) in read_rows.iter().enumerate() {
        if by_id.insert(row.id, index).is_some() {
            return Err(QsmError::at(
                row.line,
                fields_column(text, row.line, id),
                format!("the ID {} is used twice", row.id),
            ));
        }
    }
    // IDs that name no cylinder: the root's parent (-1 or 0), an end's extension.
    let none = |value: i64| match layout {
        Layout::SimpleForest => value < 0,
        Layout::Archi => value == 0,
    };
    read_rows
        .iter()
        .map(|row| {
            let parent = if none(row.parent) {
                None
            } else {
                let message = format!("{}: no cylinder has the ID {}", names[parent], row.parent);
                Some(
                    *by_id
                        .get(&row.parent)
                        .ok_or_else(|| QsmError::at(row.line, fields_column(text, row.line, parent), message))?,
                )
            };
            let axis = row.end - row.start;
            let result = Row {
                start: row.start,
                axis,
                length: axis.length(),
                radius: row.radius,
                parent,
                extension: row.extension.filter(|&e| !none(e)).and_then(|e| by_id.get(&e).copied()),
                branch: row.branch,
                place: RowPlace::Line(row.line),
            };
            result.check().map_err(|(field, message)| QsmError::at(row.line, 1, format!("{field}: {message}")))?;
            Ok(result)
        })
        .collect()
}

/// The columns a layout needs, for messages.
fn expected(layout: Layout) -> String {
    let [id, parent, _, radius, _] = layout.names();
    format!("{id}, {parent}, {}, {radius}", ENDS.join(", "))
}

/// The 1-based column where field `at` of line `line` (1-based) of `text` begins.
fn fields_column(text: &str, line: usize, at: usize) -> usize {
    let line = text.lines().nth(line - 1).unwrap_or_default();
    line.split(',').take(at).map(|f| f.len() + 1).sum::<usize>() + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simpleforest_and_archi_columns_are_found_by_name() {
        // rTwig's copy of a SimpleForest file: a space before the first name, IDs from 0.
        let simpleforest = " ID, parentID, startX, startY, startZ, endX, endY, endZ, radius, length, branchID\n\
                            0,-1,0.76,-16.35,253.88,0.76,-16.35,253.98,0.047,0.1,0\n\
                            1,0,0.76,-16.35,253.98,0.77,-16.35,254.08,0.045,0.1,0\n\
                            2,1,0.77,-16.35,254.08,0.97,-16.35,254.1,0.02,0.2,1\n";
        let rows = read(simpleforest.as_bytes(), Layout::SimpleForest).unwrap();
        assert_eq!(rows.iter().map(|r| r.parent).collect::<Vec<_>>(), [None, Some(0), Some(1)]);
        assert_eq!(rows.iter().map(|r| r.branch).collect::<Vec<_>>(), [Some(1), Some(1), Some(2)]);
        assert!((rows[0].length - 0.1).abs() < 1e-9 && (rows[2].axis.x - 0.2).abs() < 1e-9);
        // aRchi: IDs from 1, 0 for none, an extension column.
        let archi = "startX,startY,startZ,endX,endY,endZ,cyl_ID,parent_ID,extension_ID,radius_cyl,length,axis_ID\n\
                     0,0,0,0,0,1,1,0,2,0.1,1,1\n0,0,1,0,0,2,2,1,0,0.08,1,1\n";
        let rows = read(archi.as_bytes(), Layout::Archi).unwrap();
        assert_eq!(
            (rows[0].parent, rows[0].extension, rows[1].parent, rows[1].extension),
            (None, Some(1), Some(0), None)
        );
    }

    #[test]
    fn a_missing_column_or_an_unknown_parent_is_located() {
        let missing = "ID, parentID, startX, startY, startZ, endX, endY, endZ\n0,-1,0,0,0,0,0,1\n";
        let error = read(missing.as_bytes(), Layout::SimpleForest).unwrap_err();
        assert_eq!(error.location, Some((1, 1)));
        assert!(error.message.contains("no `radius` column"), "{error}");
        let orphan =
            "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1,0.1\n1,7,0,0,1,0,0,2,0.1\n";
        let error = read(orphan.as_bytes(), Layout::SimpleForest).unwrap_err();
        assert_eq!(error, QsmError::at(3, 3, "parentID: no cylinder has the ID 7"));
        let short = "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n0,-1,0,0,0,0,0,1\n";
        let error = read(short.as_bytes(), Layout::SimpleForest).unwrap_err();
        assert_eq!(error.location, Some((2, 17)));
        assert!(error.message.contains("missing the `radius` column"), "{error}");
    }
}
