//! TreeQSM's text export: one cylinder per line, values separated by tabs (or spaces), in metres.
//!
//! - Version 2.3 (`cyl_data_*.txt`): no header, 15 columns: radius, length, start x y z, axis
//!   x y z, parent, extension, branch, branch order, position in branch, added, unmodified
//!   radius.
//! - Version 2.4 (`cylinder_*.txt`): a header of 13 names (`start_point` and `axis_direction`
//!   stand for three columns each), then 17 columns: as 2.3 with `mad` and `SurfCov` before
//!   `added`.
//! - aRchi's copies: no header, 15 columns in the MATLAB structure's order (radius, length,
//!   start, axis, parent, extension, added, unmodified radius, branch, ...). A branch is never
//!   0, so a 0 in the eleventh column tells this order from 2.3's.
//!
//! Parents, extensions and branches are 1-based row numbers, 0 for none.

use super::{QsmError, Row, RowPlace, branch_number, one_based};
use bevy::math::DVec3;

/// Where the columns a model needs lie in a row (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Columns {
    /// Values in a row.
    count: usize,
    /// The branch's column.
    branch: usize,
}

/// Radius, length, start (3), axis (3), parent and extension lead every layout.
const RADIUS: usize = 0;
const LENGTH: usize = 1;
const START: usize = 2;
const AXIS: usize = 5;
const PARENT: usize = 8;
const EXTENSION: usize = 9;

const VERSION_2_3: Columns = Columns { count: 15, branch: 10 };
const VERSION_2_4: Columns = Columns { count: 17, branch: 10 };
const ARCHI: Columns = Columns { count: 15, branch: 12 };

/// A line split into its values, each with its 1-based column.
fn fields(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let base = line.as_ptr() as usize;
    line.split(['\t', ' ', ',']).filter(|f| !f.is_empty()).map(move |f| (f.as_ptr() as usize - base + 1, f))
}

/// Reads the rows of a TreeQSM text export.
pub fn read(bytes: &[u8]) -> Result<Vec<Row>, QsmError> {
    let text = std::str::from_utf8(bytes).map_err(|error| {
        let line = bytes[..error.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        QsmError::at(line, 1, "the file is not text (is it a TreeQSM text export?)")
    })?;
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.trim_end_matches('\r')))
        .filter(|(_, line)| !line.trim().is_empty())
        .collect();
    let Some(&(_, first)) = lines.first() else { return Err(QsmError::whole("the file holds no cylinders")) };
    let header = first.chars().any(|c| c.is_ascii_alphabetic() && !matches!(c, 'e' | 'E'));
    let data = if header { &lines[1..] } else { &lines[..] };
    let parsed = data
        .iter()
        .map(|&(line, text)| {
            fields(text)
                .map(|(column, field)| {
                    field.parse::<f64>().map_err(|_| QsmError::at(line, column, format!("`{field}` is not a number")))
                })
                .collect::<Result<Vec<f64>, QsmError>>()
                .map(|values| (line, values))
        })
        .collect::<Result<Vec<_>, QsmError>>()?;
    let columns = match (header, parsed.first().map(|(_, values)| values.len())) {
        (true, _) => VERSION_2_4,
        // A 0 where 2.3 keeps the branch (never 0) marks aRchi's order.
        (false, _) if parsed.iter().any(|(_, v)| v.get(VERSION_2_3.branch) == Some(&0.0)) => ARCHI,
        _ => VERSION_2_3,
    };
    let count = parsed.len();
    parsed
        .iter()
        .map(|(line, values)| {
            let line = *line;
            if values.len() < columns.count {
                let message = format!("expected {} values, found {}", columns.count, values.len());
                return Err(QsmError::at(line, 1, message));
            }
            let index = |column: usize, name: &str, required: bool| {
                one_based(values[column], count, required)
                    .map_err(|message| QsmError::at(line, 1, format!("column {} ({name}): {message}", column + 1)))
            };
            let vector = |at: usize| DVec3::new(values[at], values[at + 1], values[at + 2]);
            let row = Row {
                start: vector(START),
                axis: vector(AXIS),
                length: values[LENGTH],
                radius: values[RADIUS],
                parent: index(PARENT, "parent", true)?,
                extension: index(EXTENSION, "extension", false)?,
                branch: branch_number(values[columns.branch]),
                place: RowPlace::Line(line),
            };
            row.check().map_err(|(field, message)| QsmError::at(line, 1, format!("{field}: {message}")))?;
            Ok(row)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_layouts_are_told_apart_and_read() {
        // Version 2.4: a header of 13 names over 17 values (TreeQSM's own layout).
        let v24 = "radius (m)\tlength (m)\tstart_point\taxis_direction\tparent\textension\tbranch\tbranch_order\tposition_in_branch\tmad\tSurfCov\tadded\tUnmodRadius (m)\n\
                   0.06\t0.5\t1\t2\t3\t0\t0\t1\t0\t2\t1\t0\t1\t0.001\t1\t0\t0.06\n\
                   0.05\t0.4\t1\t2\t3.5\t0\t0\t1\t1\t0\t1\t0\t2\t0.001\t1\t0\t0.05\n";
        let rows = read(v24.as_bytes()).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!((rows[0].parent, rows[0].extension, rows[0].branch), (None, Some(1), Some(1)));
        assert_eq!((rows[1].parent, rows[1].start.z, rows[1].radius), (Some(0), 3.5, 0.05));
        assert_eq!(rows[1].place, RowPlace::Line(3));
        // Version 2.3: no header, 15 values, CRLF line ends (MATLAB's text mode on Windows).
        let v23 = "0.06\t0.5\t1\t2\t3\t0\t0\t1\t0\t2\t1\t0\t1\t0\t0.06\r\n0.05\t0.4\t1\t2\t3.5\t0\t0\t1\t1\t0\t1\t0\t2\t0\t0.05\r\n";
        let rows = read(v23.as_bytes()).unwrap();
        assert_eq!((rows[1].parent, rows[1].branch, rows[0].extension), (Some(0), Some(1), Some(1)));
        // aRchi's order: added and the unmodified radius before the branch (whose column in
        // 2.3's order then holds the unmodified radius, here 0 for an added cylinder).
        let archi =
            "0.06\t0.5\t1\t2\t3\t0\t0\t1\t0\t2\t0\t0\t1\t0\t1\n0.05\t0.4\t1\t2\t3.5\t0\t0\t1\t1\t0\t1\t0\t7\t1\t2\n";
        let rows = read(archi.as_bytes()).unwrap();
        assert_eq!((rows[0].branch, rows[1].branch), (Some(1), Some(7)));
    }

    #[test]
    fn a_bad_value_is_reported_at_its_line_and_column() {
        let text = "0.06\t0.5\t1\t2\t3\t0\t0\t1\t0\t2\t1\t0\t1\t0\t0.06\n0.05\t0.4\t1\tx2\t3.5\t0\t0\t1\t1\t0\t1\t0\t2\t0\t0.05\n";
        assert_eq!(read(text.as_bytes()).unwrap_err(), QsmError::at(2, 12, "`x2` is not a number"));
        let negative = text.replace("x2", "2").replace("0.05\t0.4", "-0.05\t0.4");
        let error = read(negative.as_bytes()).unwrap_err();
        assert_eq!(error.location, Some((2, 1)));
        assert!(error.message.starts_with("radius:"), "{error}");
        let short = "0.06\t0.5\t1\t2\t3\n";
        assert_eq!(read(short.as_bytes()).unwrap_err(), QsmError::at(1, 1, "expected 15 values, found 5"));
        let parent_beyond = text.replace("x2", "2").replace("\t1\t0\t1\t0\t2\t0\t0.05", "\t9\t0\t1\t0\t2\t0\t0.05");
        let error = read(parent_beyond.as_bytes()).unwrap_err();
        assert!(error.message.contains("parent"), "{error}");
    }
}
