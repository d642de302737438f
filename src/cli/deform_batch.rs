//! The batch deformation behind `canopy deform`: a mesh file read and welded, a region
//! outlined on it, shrunk by a deformer, put back and written, with a report of what was done.

use crate::soft_body::deform::{Method, Settings, Variant};
use crate::soft_body::region::{Mark, RegionError};
use crate::soft_body::workbench::{ShrinkError, ShrinkReport, shrink};
use crate::spatial::mesh_io::{self, MeshError, MeshReport, TriangleMesh};
use crate::spatial::surface::{Surface, SurfaceError};
use bevy::math::Vec3;
use std::path::Path;

/// Why a batch deformation failed.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// The mesh file.
    #[error("{path}: {error}")]
    Mesh {
        /// The file.
        path: String,
        /// What is wrong.
        error: MeshError,
    },
    /// The marks.
    #[error("--region: {0}")]
    Marks(String),
    /// The region.
    #[error("--region: {0}")]
    Region(#[from] RegionError),
    /// The points to measure between.
    #[error("--measure: {0}")]
    Measure(String),
    /// The settings.
    #[error("{0}")]
    Settings(String),
    /// The mesh as a surface.
    #[error("{0}")]
    Surface(#[from] SurfaceError),
}

/// The marks of `text`: comma-separated vertex indices (`12,40,77`; of the mesh as read:
/// welded, and numbered as the file's reader numbers them, for OBJ by first use in the faces)
/// or points on the surface as `x:y:z` in metres (`0.1:0.05:0,-0.1:0.05:0,0:0.05:0.1`).
pub fn parse_marks(text: &str) -> Result<Vec<Mark>, BatchError> {
    text.split(',')
        .map(str::trim)
        .enumerate()
        .map(|(index, mark)| {
            if let Ok(vertex) = mark.parse::<u32>() {
                return Ok(Mark::Vertex(vertex));
            }
            let coordinates: Vec<f32> = mark.split(':').filter_map(|c| c.trim().parse().ok()).collect();
            match coordinates[..] {
                [x, y, z] if mark.split(':').count() == 3 && [x, y, z].iter().all(|c| c.is_finite()) => {
                    Ok(Mark::Point(Vec3::new(x, y, z)))
                }
                _ => Err(BatchError::Marks(format!(
                    "point {index}, `{mark}`: expected a vertex index or x:y:z in metres"
                ))),
            }
        })
        .collect()
}

/// The two points of `text` to measure between, written as the marks of [`parse_marks`].
pub fn parse_measure(text: &str) -> Result<[Mark; 2], BatchError> {
    let marks = parse_marks(text).map_err(|error| match error {
        BatchError::Marks(message) => BatchError::Measure(message),
        other => other,
    })?;
    <[Mark; 2]>::try_from(marks)
        .map_err(|marks| BatchError::Measure(format!("expected two points to measure between, found {}", marks.len())))
}

/// What a batch deformation did, as the command prints it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// Vertices of the mesh as welded.
    pub vertices: usize,
    /// Its triangles.
    pub triangles: usize,
    /// What reading it found.
    pub mesh: MeshReport,
    /// The region, the deformer and the facts of the result.
    #[serde(flatten)]
    pub shrink: ShrinkReport,
    /// Wall-clock milliseconds the deformer took.
    pub time_ms: f64,
}

/// Deforms the region of the mesh at `input` outlined by `marks` with `method` and
/// `settings`, measuring between the two points of `measure` before and after, writes the whole mesh to `output` (OBJ or PLY) and reports. Written in the
/// input's own format, the output is the input with only the moved vertices' positions (and
/// their normals) changed: the same vertices in the same order, faces, texture coordinates,
/// groups and materials.
pub fn run(
    input: &Path,
    marks: &[Mark],
    measure: Option<[Mark; 2]>,
    method: Method,
    settings: Settings,
    output: &Path,
) -> Result<Report, BatchError> {
    settings.check(method).map_err(|error| BatchError::Settings(format!("--k/--eps: {error}")))?;
    mesh_io::Format::of(output).map_err(located(output))?;
    fn located(path: &Path) -> impl Fn(MeshError) -> BatchError + '_ {
        move |error| BatchError::Mesh { path: path.display().to_string(), error }
    }
    let (mesh, read, source) = mesh_io::read_source(input).map_err(located(input))?;
    let movable = vec![true; mesh.positions.len()];
    let whole = Surface::new(mesh.positions, mesh.triangles, movable)?;
    let shrunk = shrink(&whole, marks, measure, method, settings).map_err(|error| match error {
        ShrinkError::Region(error) => BatchError::Region(error),
        ShrinkError::Measure(error) => BatchError::Measure(error.to_string()),
        ShrinkError::Settings(error) => BatchError::Settings(format!("--k/--eps: {error}")),
    })?;
    let (vertices, triangles) = (whole.positions.len(), whole.triangles.len());
    if mesh_io::Format::of(output).ok() == Some(source.format) {
        let bytes = source.written_back(&shrunk.positions, &whole.triangles, output).map_err(located(output))?;
        std::fs::write(output, bytes).map_err(|error| located(output)(MeshError::Io(error)))?;
    } else {
        let written = TriangleMesh { positions: shrunk.positions, triangles: whole.triangles };
        mesh_io::write(&written, output).map_err(located(output))?;
    }
    let time_ms = shrunk.report.time_ms;
    Ok(Report { vertices, triangles, mesh: read, shrink: shrunk.report, time_ms })
}

/// The method named on the command line: `edge`, `edge-sum` or `area`, with `variant` one of
/// [`Variant`]'s names for the last two.
pub fn method(name: &str, variant: &str) -> Result<Method, BatchError> {
    let Some(variant) = Variant::ALL.into_iter().find(|known| known.name() == variant) else {
        let names: Vec<&str> = Variant::ALL.iter().map(|known| known.name()).collect();
        return Err(BatchError::Settings(format!(
            "--variant: expected one of {}, found `{variant}`",
            names.join(", ")
        )));
    };
    match name {
        "edge" => Ok(Method::EdgeLengths),
        "edge-sum" => Ok(Method::EdgeSum(variant)),
        "area" => Ok(Method::Area(variant)),
        other => Err(BatchError::Settings(format!("--method: expected edge, edge-sum or area, found `{other}`"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::soft_body::sample;

    #[test]
    fn marks_are_vertex_indices_or_points_and_anything_else_is_named() {
        assert_eq!(parse_marks("3, 7,12").unwrap(), vec![Mark::Vertex(3), Mark::Vertex(7), Mark::Vertex(12)]);
        assert_eq!(parse_marks("0.5:0:-1").unwrap(), vec![Mark::Point(Vec3::new(0.5, 0.0, -1.0))]);
        let error = parse_marks("3,x:1,5").unwrap_err().to_string();
        assert!(error.contains("point 1, `x:1`"), "{error}");
        assert!(parse_marks("1:2:3:4").is_err() && parse_marks("nan:0:0").is_err());
    }

    #[test]
    fn a_belly_from_a_file_is_shrunk_and_written_with_its_outline_held() {
        let folder = tempfile::tempdir().unwrap();
        let belly = sample::belly(25);
        let (input, output) = (folder.path().join("belly.obj"), folder.path().join("shrunk.ply"));
        let mesh = TriangleMesh { positions: belly.positions.clone(), triangles: belly.triangles.clone() };
        mesh_io::write(&mesh, &input).unwrap();
        // The corners as points: the file's reader numbers vertices its own way.
        let corner = |(i, j): (u32, u32)| {
            let p = belly.positions[(j * 25 + i) as usize];
            format!("{}:{}:{}", p.x, p.y, p.z)
        };
        let marks = parse_marks(&[(6, 6), (18, 6), (18, 18), (6, 18)].map(corner).join(",")).unwrap();
        let settings = Settings { k: 0.95, eps: 1e-5, max_iterations: 2000 };
        // Two landmarks either side of the region, measured across it.
        let measure = parse_measure(&[(2, 12), (22, 12)].map(corner).join(",")).unwrap();
        let report = run(&input, &marks, Some(measure), Method::Area(Variant::Projection), settings, &output).unwrap();
        let shrink = &report.shrink;
        let measured = shrink.measure.unwrap();
        // They do not move, and the way between them over the shrunk belly is shorter.
        assert_eq!(measured.before.straight_m, measured.after.straight_m);
        let (before, after) = (measured.before.along_m.unwrap(), measured.after.along_m.unwrap());
        assert!(after < before && before > measured.before.straight_m, "{measured:?}");
        assert!(parse_measure("1,2,3").unwrap_err().to_string().contains("two points"));
        assert_eq!((shrink.region_vertices, shrink.outline_vertices), (11 * 11, 48));
        assert!(shrink.facts.fixed_unchanged && (shrink.facts.area_ratio - 0.95).abs() < 1e-4, "{report:?}");
        let (written, _) = mesh_io::read(&output).unwrap();
        assert_eq!(written.triangles.len(), belly.triangles.len());
        // The reader numbers vertices by first use: compare positions, not indices.
        let before: std::collections::HashSet<[u32; 3]> =
            mesh.positions.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
        let moved = written.positions.iter().filter(|p| !before.contains(&p.to_array().map(f32::to_bits))).count();
        assert!(moved > 0 && moved <= 11 * 11, "only the region's inside moved: {moved}");
    }

    #[test]
    fn a_mesh_written_back_is_its_file_with_only_the_moved_positions_and_their_normals_changed() {
        let folder = tempfile::tempdir().unwrap();
        let belly = sample::belly(25);
        // An artist's OBJ: a material library, an object, a group, a material, texture
        // coordinates and normals on every corner, a vertex with a colour after its position.
        let mut text = String::from("# a belly\nmtllib belly.mtl\no belly\n");
        for (i, p) in belly.positions.iter().enumerate() {
            let colour = if i == 0 { " 0.5 0.4 0.3" } else { "" };
            text.push_str(&format!("v {} {} {}{colour}\n", p.x, p.y, p.z));
        }
        for p in &belly.positions {
            text.push_str(&format!("vt {} {}\nvn 0 1 0\n", p.x, p.z));
        }
        text.push_str("g skin\nusemtl fur\ns 1\n");
        for t in &belly.triangles {
            let [a, b, c] = t.map(|v| v + 1);
            text.push_str(&format!("f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n"));
        }
        let input = folder.path().join("belly.obj");
        std::fs::write(&input, &text).unwrap();
        let corners = [(6, 6), (18, 6), (18, 18), (6, 18)].map(|(i, j)| Mark::Vertex(j * 25 + i));
        let deform = |method: Method, k: f32, name: &str| {
            let output = folder.path().join(name);
            let settings = Settings { k, eps: 1e-5, max_iterations: 2000 };
            run(&input, &corners, None, method, settings, &output).unwrap();
            std::fs::read_to_string(output).unwrap()
        };
        // Edges kept at their length (k = 1): the file back, byte for byte.
        assert_eq!(deform(Method::EdgeLengths, 1.0, "same.obj"), text);
        // Shrunk: line for line the same file but for the region's positions and normals.
        let shrunk = deform(Method::Area(Variant::Projection), 0.95, "shrunk.obj");
        let (before, after): (Vec<&str>, Vec<&str>) = (text.lines().collect(), shrunk.lines().collect());
        assert_eq!(before.len(), after.len());
        let changed: Vec<(&str, &str)> =
            before.iter().zip(&after).filter(|(a, b)| a != b).map(|(a, b)| (*a, *b)).collect();
        let moved = changed.iter().filter(|(a, _)| a.starts_with("v ")).count();
        let turned = changed.iter().filter(|(a, _)| a.starts_with("vn ")).count();
        assert!(changed.iter().all(|(a, _)| a.starts_with("v ") || a.starts_with("vn ")), "{changed:?}");
        assert!(moved > 50 && moved <= 11 * 11, "the region's inside moved: {moved}");
        assert_eq!(turned, moved, "the normal of each moved corner is recomputed");
        // The vertices keep their order: the file's vertex k is still vertex k.
        let (read_back, _) = mesh_io::read(&folder.path().join("shrunk.obj")).unwrap();
        assert_eq!(read_back.positions.len(), belly.positions.len());
        let outside = belly.positions[0];
        assert_eq!(read_back.positions[0], outside);
        assert!(after[3].ends_with(" 0.5 0.4 0.3"), "the colour after a position is kept: {}", after[3]);
    }

    #[test]
    fn bad_settings_and_files_are_errors_that_say_which() {
        let folder = tempfile::tempdir().unwrap();
        let missing = folder.path().join("missing.obj");
        let marks = parse_marks("0,1,2").unwrap();
        let settings = Settings { k: 0.9, eps: 1e-5, max_iterations: 10 };
        let out = folder.path().join("out.obj");
        let error = run(&missing, &marks, None, Method::EdgeLengths, settings, &out).unwrap_err().to_string();
        assert!(error.contains("missing.obj"), "{error}");
        let k = Settings { k: 1.0, ..settings };
        let error = run(&missing, &marks, None, Method::Area(Variant::Projection), k, &out).unwrap_err().to_string();
        assert!(error.contains("--k") && error.contains("below 1"), "{error}");
        assert!(method("bend", "projection").is_err() && method("area", "guess").is_err());
        assert_eq!(method("edge-sum", "source").unwrap(), Method::EdgeSum(Variant::Source));
    }
}
