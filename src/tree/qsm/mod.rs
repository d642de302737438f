//! Quantitative structure models (QSM) of scanned trees: the cylinders that TreeQSM, SimpleForest
//! and aRchi fit to terrestrial laser scans, read from their files and turned into supports.
//!
//! | module | what it holds |
//! |---|---|
//! | [`text`] | TreeQSM's text export (`cyl_data_*.txt`, `cylinder_*.txt`) and aRchi's variant of it |
//! | [`csv`] | SimpleForest's and rTwig's CSV, and aRchi's |
//! | [`mat`] | TreeQSM's MATLAB files (`qsm.cylinder`, versions 2.3-2.4, and 2.0's flat variables) |
//! | [`build`] | cylinders to supports: chains along the branches, forks where they leave, y up |
//!
//! Every reader checks every value it keeps (finite, in range, parents that exist) and reports a
//! bad one at its line and column, or for a MATLAB file at its variable and row.

pub mod build;
pub mod csv;
pub mod mat;
pub mod text;

use bevy::math::{DVec3, Vec3};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The most cylinders a model may hold.
pub const MAX_CYLINDERS: usize = 2_000_000;

/// The largest file read, bytes.
pub const MAX_FILE_BYTES: usize = 512 << 20;

/// The thickest cylinder accepted, metres of radius.
pub const MAX_RADIUS_M: f64 = 10.0;

/// The longest cylinder accepted, metres.
pub const MAX_LENGTH_M: f64 = 100.0;

/// The farthest a coordinate may lie from the file's origin, metres (georeferenced scans lie
/// hundreds of kilometres from it).
pub const MAX_COORDINATE_M: f64 = 1e8;

/// The kinds of file a model comes in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum QsmFormat {
    /// TreeQSM's MATLAB file (`.mat`, version 7).
    TreeqsmMat,
    /// TreeQSM's text export: tab-separated cylinders, with a header from version 2.4.
    TreeqsmText,
    /// SimpleForest's CSV (and rTwig's copies of it): `ID, parentID, startX, ..., radius`.
    SimpleforestCsv,
    /// aRchi's CSV: `startX, ..., cyl_ID, parent_ID, extension_ID, radius_cyl, ...`.
    ArchiCsv,
}

impl QsmFormat {
    /// The format of a file from its contents: a MATLAB header, a CSV header naming its
    /// columns, or else TreeQSM's text.
    pub fn of(bytes: &[u8]) -> Self {
        if bytes.starts_with(b"MATLAB") {
            return QsmFormat::TreeqsmMat;
        }
        let first_line = bytes.split(|&b| b == b'\n').next().unwrap_or_default();
        let first_line = String::from_utf8_lossy(first_line);
        let names: Vec<&str> = first_line.split(',').map(str::trim).collect();
        if names.contains(&"cyl_ID") {
            QsmFormat::ArchiCsv
        } else if names.contains(&"parentID") {
            QsmFormat::SimpleforestCsv
        } else {
            QsmFormat::TreeqsmText
        }
    }
}

impl fmt::Display for QsmFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            QsmFormat::TreeqsmMat => "TreeQSM MATLAB file",
            QsmFormat::TreeqsmText => "TreeQSM text export",
            QsmFormat::SimpleforestCsv => "SimpleForest CSV",
            QsmFormat::ArchiCsv => "aRchi CSV",
        })
    }
}

/// One cylinder of a model, in the file's frame (z up) less the model's origin, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// The centre of its base.
    pub start: Vec3,
    /// Unit direction from base to top.
    pub axis: Vec3,
    /// Metres from base to top.
    pub length: f32,
    /// Metres.
    pub radius: f32,
    /// The cylinder it grows from, by index; `None` at a root.
    pub parent: Option<usize>,
    /// The cylinder that continues it along its branch, when the format says.
    pub extension: Option<usize>,
    /// The branch it belongs to, when the format says.
    pub branch: Option<u32>,
}

impl Cylinder {
    /// The centre of its top.
    pub fn end(&self) -> Vec3 {
        self.start + self.axis * self.length
    }
}

/// A model as read from its file.
#[derive(Debug, Clone, PartialEq)]
pub struct Qsm {
    /// The cylinders, in the file's order.
    pub cylinders: Vec<Cylinder>,
    /// Where the first cylinder starts in the file's coordinates (z up), metres: every
    /// cylinder's `start` is relative to it, which keeps a georeferenced scan's precision.
    pub origin: DVec3,
    /// What it was read from.
    pub format: QsmFormat,
}

/// A problem with a model's file: where, when it has a place, and what.
#[derive(Debug, Clone, PartialEq)]
pub struct QsmError {
    /// 1-based line and column in a text file.
    pub location: Option<(usize, usize)>,
    /// What is wrong, naming the column, field or variable.
    pub message: String,
}

impl QsmError {
    /// A problem at `line` and `column` (1-based).
    pub fn at(line: usize, column: usize, message: impl Into<String>) -> Self {
        Self { location: Some((line, column)), message: message.into() }
    }

    /// A problem with the file as a whole, or with a MATLAB variable.
    pub fn whole(message: impl Into<String>) -> Self {
        Self { location: None, message: message.into() }
    }
}

impl fmt::Display for QsmError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some((line, column)) => write!(f, "{line}:{column}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

/// Reads a model from `bytes`, in `format` or, when `None`, the format its contents show.
pub fn read(bytes: &[u8], format: Option<QsmFormat>) -> Result<Qsm, QsmError> {
    if bytes.len() > MAX_FILE_BYTES {
        return Err(QsmError::whole(format!("the file is {} bytes, more than {MAX_FILE_BYTES}", bytes.len())));
    }
    let format = format.unwrap_or_else(|| QsmFormat::of(bytes));
    let rows = match format {
        QsmFormat::TreeqsmMat => mat::read(bytes)?,
        QsmFormat::TreeqsmText => text::read(bytes)?,
        QsmFormat::SimpleforestCsv => csv::read(bytes, csv::Layout::SimpleForest)?,
        QsmFormat::ArchiCsv => csv::read(bytes, csv::Layout::Archi)?,
    };
    Qsm::from_rows(rows, format)
}

/// A 1-based row number of a model of `count` rows, 0 for none, as a 0-based index: `None` for
/// 0 and, unless `required`, for a number beyond the rows (TreeQSM writes one for a branch's
/// last extension now and then); an error for anything else.
pub fn one_based(value: f64, count: usize, required: bool) -> Result<Option<usize>, String> {
    if value == 0.0 {
        return Ok(None);
    }
    if value.fract() != 0.0 || value < 0.0 || (required && value > count as f64) {
        return Err(format!("expected a row number from 0 to {count}, found {value}"));
    }
    Ok((value <= count as f64).then(|| value as usize - 1))
}

/// A branch number (from 1), or `None` for anything else.
pub fn branch_number(value: f64) -> Option<u32> {
    (value >= 1.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX)).then_some(value as u32)
}

/// A cylinder as a reader found it, in the file's coordinates, before the model is checked
/// as a whole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Centre of the base, file coordinates, metres.
    pub start: DVec3,
    /// Direction from base to top (any length but zero).
    pub axis: DVec3,
    /// Metres.
    pub length: f64,
    /// Metres.
    pub radius: f64,
    /// The parent's index among the rows; `None` at a root.
    pub parent: Option<usize>,
    /// The extension's index among the rows, when given (one out of range counts as none).
    pub extension: Option<usize>,
    /// The branch, when given.
    pub branch: Option<u32>,
    /// Where the row is, for messages: its line in a text file, its index in a MATLAB file.
    pub place: RowPlace,
}

/// Where a row came from, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowPlace {
    /// A line of a text file (1-based).
    Line(usize),
    /// A row of a MATLAB file's arrays (1-based, as MATLAB counts).
    Index(usize),
}

impl Row {
    /// The row's checks that need no other row: finite values, radius and length in range, a
    /// direction; `column` names what is at fault for a message.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let finite = |v: DVec3| v.is_finite() && v.abs().max_element() <= MAX_COORDINATE_M;
        if !finite(self.start) {
            return Err(("start", format!("expected finite coordinates within {MAX_COORDINATE_M} m")));
        }
        if !self.axis.is_finite() || self.axis.length() < 1e-9 {
            return Err(("axis", "expected a direction, found a zero or non-finite vector".into()));
        }
        if !(self.radius > 0.0 && self.radius <= MAX_RADIUS_M) {
            return Err((
                "radius",
                format!("expected a radius above 0 and at most {MAX_RADIUS_M} m, found {}", self.radius),
            ));
        }
        if !(self.length > 0.0 && self.length <= MAX_LENGTH_M) {
            return Err((
                "length",
                format!("expected a length above 0 and at most {MAX_LENGTH_M} m, found {}", self.length),
            ));
        }
        Ok(())
    }
}

impl Qsm {
    /// The model of `rows`, checked as a whole: at least one cylinder, at most
    /// [`MAX_CYLINDERS`], parents within the model and no cylinder its own ancestor.
    pub fn from_rows(rows: Vec<Row>, format: QsmFormat) -> Result<Self, QsmError> {
        let place = |row: &Row| match row.place {
            RowPlace::Line(line) => (Some((line, 1)), format!("line {line}")),
            RowPlace::Index(index) => (None, format!("cylinder {index}")),
        };
        let Some(first) = rows.first() else { return Err(QsmError::whole("the file holds no cylinders")) };
        if rows.len() > MAX_CYLINDERS {
            return Err(QsmError::whole(format!("{} cylinders, more than {MAX_CYLINDERS}", rows.len())));
        }
        if let Some(row) = rows.iter().find(|row| row.parent.is_some_and(|p| p >= rows.len())) {
            let (location, at) = place(row);
            let message = format!("{at}: the parent is not a cylinder of the file");
            return Err(QsmError { location, message });
        }
        // Walking up from each cylinder reaches a root within as many steps as there are
        // cylinders, or the parents form a cycle (marks make the walks linear overall).
        let mut state = vec![0u8; rows.len()]; // 0 unseen, 1 on the current walk, 2 reaches a root
        for start in 0..rows.len() {
            let mut walk = Vec::new();
            let mut at = Some(start);
            while let Some(index) = at {
                match state[index] {
                    2 => break,
                    1 => {
                        let (location, at) = place(&rows[index]);
                        let message = format!("{at}: the cylinder's parents lead back to it");
                        return Err(QsmError { location, message });
                    }
                    _ => {
                        state[index] = 1;
                        walk.push(index);
                        at = rows[index].parent;
                    }
                }
            }
            walk.into_iter().for_each(|index| state[index] = 2);
        }
        let origin = first.start;
        let cylinders = rows
            .iter()
            .enumerate()
            .map(|(index, row)| Cylinder {
                start: (row.start - origin).as_vec3(),
                axis: row.axis.normalize().as_vec3(),
                length: row.length as f32,
                radius: row.radius as f32,
                parent: row.parent,
                // An extension must grow from this cylinder; one that does not counts as none.
                extension: row.extension.filter(|&e| rows.get(e).is_some_and(|next| next.parent == Some(index))),
                branch: row.branch,
            })
            .collect();
        Ok(Self { cylinders, origin, format })
    }
}
