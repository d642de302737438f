//! Triangle meshes in files: OBJ (its vertex and face lines, in file order), PLY (ASCII or
//! binary), STL and glTF 2.0 (see [`gltf`]) read, OBJ and PLY written; every mesh read is welded (vertices at the same
//! position become one), so that a surface from STL, which repeats its vertices per triangle,
//! deforms as one piece. Faces that collapse and edges shared by more than two faces are
//! counted, not refused. A mesh read from OBJ, PLY or glTF can be written back over its own
//! file's contents with only its positions changed (see [`Source`]).

mod gltf;

use crate::foundation::values::FileType;
use bevy::math::{Vec2, Vec3};
use gltf::GltfFile;
use std::collections::HashMap;
use std::io::{Cursor, Write};
use std::path::Path;

/// The most vertices or triangles a mesh file may hold, so that no file can exhaust memory.
pub const MAX_ELEMENTS: usize = 4_000_000;

/// The largest mesh file read, bytes.
pub const MAX_FILE_BYTES: u64 = 512 << 20;

/// A mesh file's format, by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// STL (read only).
    Stl,
    /// glTF 2.0 as text, its buffers in data URIs or in files beside it.
    Gltf,
    /// Binary glTF 2.0.
    Glb,
}

impl Format {
    /// The format of `path`'s extension.
    pub fn of(path: &Path) -> Result<Self, MeshError> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("obj") => Ok(Self::Obj),
            Some("ply") => Ok(Self::Ply),
            Some("stl") => Ok(Self::Stl),
            Some("gltf") => Ok(Self::Gltf),
            Some("glb") => Ok(Self::Glb),
            _ => Err(MeshError::Format(path.display().to_string())),
        }
    }
}

/// Mesh files in a scene's folder: OBJ, PLY, STL or glTF (`.obj`, `.ply`, `.stl`, `.gltf`,
/// `.glb`, in any case).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshFile;

impl FileType for MeshFile {
    const EXTENSIONS: &'static [&'static str] = &[".obj", ".ply", ".stl", ".gltf", ".glb"];
    const EXPECTING: &'static str = "an .obj, .ply, .stl, .gltf or .glb file in the scene's folder";
    const FILES: &'static str = "an .obj, .ply, .stl, .gltf or .glb file";
}

/// Why a mesh could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// Not a format the project reads.
    #[error("{0}: expected an .obj, .ply, .stl, .gltf or .glb file")]
    Format(String),
    /// The file could not be read or written.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The file's contents are not a mesh of its format.
    #[error("not a valid {format} mesh: {message}")]
    Parse {
        /// The format.
        format: &'static str,
        /// What the reader said.
        message: String,
    },
    /// Too large a mesh.
    #[error("{what} of {count} is more than the {MAX_ELEMENTS} a mesh may have")]
    TooLarge {
        /// What there are too many of.
        what: &'static str,
        /// How many.
        count: usize,
    },
    /// A position that is not a finite number.
    #[error("vertex {0} (counting from 0) has a position that is not a finite number")]
    NotFinite(usize),
    /// A face names a vertex that does not exist.
    #[error("face {face} names vertex {vertex}, but there are {count} vertices")]
    IndexOutOfRange {
        /// The face.
        face: usize,
        /// The index it names.
        vertex: i64,
        /// Vertices there are.
        count: usize,
    },
}

/// A triangle mesh.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Index triples.
    pub triangles: Vec<[u32; 3]>,
}

/// One piece of a mesh as drawn: a glTF file's triangle primitive as a node of its scene
/// places it, or the whole of a mesh from another format.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// Vertex positions, metres.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position, or empty where the file has none.
    pub normals: Vec<Vec3>,
    /// Texture coordinates of the base colour texture, one per position, or empty.
    pub uvs: Vec<Vec2>,
    /// Linear RGB vertex colours, one per position, or empty.
    pub colors: Vec<Vec3>,
    /// Index triples into `positions`, wound counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// The material's base colour factor, linear RGB.
    pub base_color: Vec3,
    /// The base colour texture: its image (an index into [`Drawing::images`]) and whether
    /// it is clamped at its edges rather than repeated.
    pub texture: Option<(usize, bool)>,
}

/// What drawing a mesh file needs: its parts and the encoded images they use (PNG or JPEG).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Drawing {
    /// Its pieces, each with its own material.
    pub parts: Vec<Part>,
    /// The file's images by index, encoded; `None` for an image no part uses.
    pub images: Vec<Option<Vec<u8>>>,
}

/// What reading a mesh found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct MeshReport {
    /// Vertices merged into another at the same position.
    pub welded: usize,
    /// Faces dropped because two of their corners became one.
    pub degenerate: usize,
    /// Edges shared by more than two faces.
    pub non_manifold_edges: usize,
}

/// Reads the mesh at `path`, welded.
pub fn read(path: &Path) -> Result<(TriangleMesh, MeshReport), MeshError> {
    let (bytes, format) = read_file(path)?;
    parse(&bytes, format, folder_of(path))
}

/// Reads the mesh at `path`, welded, with what writing it back needs.
pub fn read_source(path: &Path) -> Result<(TriangleMesh, MeshReport, Source), MeshError> {
    let (bytes, format) = read_file(path)?;
    parse_source(bytes, format, folder_of(path))
}

/// The folder a file's relative references are found in.
pub fn folder_of(path: &Path) -> &Path {
    path.parent().filter(|folder| !folder.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// The contents of the mesh file at `path` (at most [`MAX_FILE_BYTES`]) and its format.
fn read_file(path: &Path) -> Result<(Vec<u8>, Format), MeshError> {
    let format = Format::of(path)?;
    let size = std::fs::metadata(path)?.len();
    if size > MAX_FILE_BYTES {
        return Err(MeshError::TooLarge { what: "a file of bytes", count: size as usize });
    }
    Ok((std::fs::read(path)?, format))
}

/// The mesh in `bytes` of `format`, welded; a glTF file's references are found in `folder`.
pub fn parse(bytes: &[u8], format: Format, folder: &Path) -> Result<(TriangleMesh, MeshReport), MeshError> {
    parse_in_order(bytes, format, folder).map(|(mesh, report, _)| (mesh, report))
}

/// The mesh in `bytes` of `format`, welded, with what writing it back needs (which keeps
/// `bytes`); a glTF file's references are found in `folder`.
pub fn parse_source(
    bytes: Vec<u8>,
    format: Format,
    folder: &Path,
) -> Result<(TriangleMesh, MeshReport, Source), MeshError> {
    let (mesh, report, file_vertices) = parse_in_order(&bytes, format, folder)?;
    Ok((mesh, report, Source { format, bytes, folder: folder.to_path_buf(), file_vertices }))
}

/// What drawing the mesh in `bytes` of `format` needs: a glTF file's every primitive as the
/// nodes of its scene place them, with their materials and images; another format's mesh,
/// welded, as one white part.
pub fn drawing(bytes: &[u8], format: Format, folder: &Path) -> Result<Drawing, MeshError> {
    match format {
        Format::Gltf | Format::Glb => GltfFile::open(bytes, folder)?.drawing(),
        Format::Obj | Format::Ply | Format::Stl => {
            let (mesh, _) = parse(bytes, format, folder)?;
            let part = Part {
                positions: mesh.positions,
                normals: Vec::new(),
                uvs: Vec::new(),
                colors: Vec::new(),
                triangles: mesh.triangles,
                base_color: Vec3::ONE,
                texture: None,
            };
            Ok(Drawing { parts: vec![part], images: Vec::new() })
        }
    }
}

/// The mesh in `bytes` of `format`, welded, and the welded vertex of each of the file's
/// vertices in file order.
fn parse_in_order(
    bytes: &[u8],
    format: Format,
    folder: &Path,
) -> Result<(TriangleMesh, MeshReport, Vec<u32>), MeshError> {
    let (positions, faces) = match format {
        Format::Obj => parse_obj(bytes)?,
        Format::Ply => parse_ply(bytes)?,
        Format::Stl => parse_stl(bytes)?,
        Format::Gltf | Format::Glb => GltfFile::open(bytes, folder)?.triangles()?,
    };
    for (what, count) in [("a vertex count", positions.len()), ("a face count", faces.len())] {
        if count > MAX_ELEMENTS {
            return Err(MeshError::TooLarge { what, count });
        }
    }
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(MeshError::NotFinite(bad));
    }
    let count = positions.len();
    let triangles = faces
        .iter()
        .enumerate()
        .map(|(face, corners)| {
            let index = |v: i64| match u32::try_from(v).ok().filter(|&v| (v as usize) < count) {
                Some(v) => Ok(v),
                None => Err(MeshError::IndexOutOfRange { face, vertex: v, count }),
            };
            Ok([index(corners[0])?, index(corners[1])?, index(corners[2])?])
        })
        .collect::<Result<Vec<_>, MeshError>>()?;
    Ok(weld(positions, triangles))
}

/// `positions` and `triangles` with the vertices at one position merged (bit for bit), the
/// faces that collapse dropped, what was found, and the merged vertex of each given one.
fn weld(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> (TriangleMesh, MeshReport, Vec<u32>) {
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let mut kept = Vec::with_capacity(positions.len());
    let remap: Vec<u32> = positions
        .iter()
        .map(|p| {
            // -0.0 and 0.0 are one position.
            let key = p.to_array().map(|c| (c + 0.0).to_bits());
            *first.entry(key).or_insert_with(|| {
                kept.push(*p);
                (kept.len() - 1) as u32
            })
        })
        .collect();
    let welded = positions.len() - kept.len();
    let mapped: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|v| remap[v as usize])).collect();
    let triangles: Vec<[u32; 3]> = mapped.iter().copied().filter(|[a, b, c]| a != b && b != c && c != a).collect();
    let degenerate = mapped.len() - triangles.len();
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for &[a, b, c] in &triangles {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            *uses.entry((u.min(v), u.max(v))).or_default() += 1;
        }
    }
    let non_manifold_edges = uses.values().filter(|&&n| n > 2).count();
    (TriangleMesh { positions: kept, triangles }, MeshReport { welded, degenerate, non_manifold_edges }, remap)
}

/// Positions in file order and faces (polygons split into fans) of an OBJ file's `v` and `f`
/// lines; every other line (texture coordinates, normals, groups, materials) is left to the
/// file, where writing back keeps it.
fn parse_obj(bytes: &[u8]) -> Result<(Vec<Vec3>, Vec<[i64; 3]>), MeshError> {
    let text = String::from_utf8_lossy(bytes);
    let (mut positions, mut faces) = (Vec::new(), Vec::new());
    for (number, line) in text.lines().enumerate() {
        let error =
            |message: String| MeshError::Parse { format: "OBJ", message: format!("line {}: {message}", number + 1) };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => positions.push(obj_position(line).ok_or_else(|| error("expected `v x y z`".into()))?),
            Some("f") => {
                let corners = words
                    .map(|word| {
                        let index: i64 = word
                            .split('/')
                            .next()
                            .unwrap_or_default()
                            .parse()
                            .map_err(|_| error(format!("`{word}` is not a vertex index")))?;
                        // OBJ counts from 1; negative indices count back from the last vertex so far.
                        match index {
                            0 => Err(error("vertex index 0 (OBJ counts from 1)".into())),
                            i if i > 0 => Ok(i - 1),
                            i => Ok(positions.len() as i64 + i),
                        }
                    })
                    .collect::<Result<Vec<i64>, MeshError>>()?;
                faces.extend((1..corners.len().saturating_sub(1)).map(|k| [corners[0], corners[k], corners[k + 1]]));
            }
            _ => {}
        }
        if positions.len() > MAX_ELEMENTS || faces.len() > MAX_ELEMENTS {
            return Err(MeshError::TooLarge { what: "an element count", count: positions.len().max(faces.len()) });
        }
    }
    Ok((positions, faces))
}

/// The position of an OBJ `v` line (its first three numbers; a weight or a colour may follow).
fn obj_position(line: &str) -> Option<Vec3> {
    let mut numbers = line.split_whitespace().skip(1).map(|w| w.parse::<f32>());
    let mut next = || numbers.next()?.ok();
    Some(Vec3::new(next()?, next()?, next()?))
}

/// Positions and faces (fans of triangles) of a PLY file.
fn parse_ply(bytes: &[u8]) -> Result<(Vec<Vec3>, Vec<[i64; 3]>), MeshError> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let error = |message: String| MeshError::Parse { format: "PLY", message };
    let ply = Parser::<DefaultElement>::new().read_ply(&mut Cursor::new(bytes)).map_err(|e| error(e.to_string()))?;
    let number = |property: Option<&Property>| -> Option<f64> {
        Some(match property? {
            Property::Float(v) => f64::from(*v),
            Property::Double(v) => *v,
            Property::Char(v) => f64::from(*v),
            Property::UChar(v) => f64::from(*v),
            Property::Short(v) => f64::from(*v),
            Property::UShort(v) => f64::from(*v),
            Property::Int(v) => f64::from(*v),
            Property::UInt(v) => f64::from(*v),
            _ => return None,
        })
    };
    let vertices = ply.payload.get("vertex").ok_or_else(|| error("no `vertex` element".into()))?;
    let positions = vertices
        .iter()
        .enumerate()
        .map(|(index, vertex)| {
            let [x, y, z] = ["x", "y", "z"].map(|axis| number(vertex.get(axis)));
            match (x, y, z) {
                (Some(x), Some(y), Some(z)) => Ok(Vec3::new(x as f32, y as f32, z as f32)),
                _ => Err(error(format!("vertex {index} lacks a numeric x, y or z"))),
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut faces = Vec::new();
    for (index, face) in ply.payload.get("face").into_iter().flatten().enumerate() {
        let list = face.get("vertex_indices").or_else(|| face.get("vertex_index"));
        let corners: Vec<i64> = match list {
            Some(Property::ListInt(v)) => v.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListUInt(v)) => v.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListShort(v)) => v.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListUShort(v)) => v.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListChar(v)) => v.iter().map(|&i| i64::from(i)).collect(),
            Some(Property::ListUChar(v)) => v.iter().map(|&i| i64::from(i)).collect(),
            _ => return Err(error(format!("face {index} lacks an integer list `vertex_indices`"))),
        };
        // A polygon as a fan from its first corner.
        faces.extend((1..corners.len().saturating_sub(1)).map(|k| [corners[0], corners[k], corners[k + 1]]));
    }
    Ok((positions, faces))
}

/// Positions and faces of an STL file (ASCII or binary).
fn parse_stl(bytes: &[u8]) -> Result<(Vec<Vec3>, Vec<[i64; 3]>), MeshError> {
    let mesh = stl_io::read_stl(&mut Cursor::new(bytes))
        .map_err(|e| MeshError::Parse { format: "STL", message: e.to_string() })?;
    let positions = mesh.vertices.iter().map(|v| Vec3::from_array(v.0)).collect();
    let faces = mesh.faces.iter().map(|f| f.vertices.map(|v| v as i64)).collect();
    Ok((positions, faces))
}

/// A mesh file as read, for writing it back changed only where its vertices moved.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// Its format.
    pub format: Format,
    /// Its contents.
    pub bytes: Vec<u8>,
    /// Its folder, where a glTF file's references are found.
    pub folder: std::path::PathBuf,
    /// The welded vertex of each of the file's vertices, in file order.
    pub file_vertices: Vec<u32>,
}

impl Source {
    /// The file's contents, for writing to `to`, with each vertex at `positions` (indexed like
    /// the welded mesh read from it): every line or value of a vertex that did not move, and
    /// everything that is not a position, kept as it was; the normals of moved vertices
    /// recomputed (OBJ `vn` lines used by a moved corner, PLY `nx ny nz`), a glTF position
    /// accessor's bounds kept true (and a glTF file's buffers and images in files beside it
    /// taken into it where `to` is in another folder). STL files are read, not written.
    pub fn written_back(&self, positions: &[Vec3], triangles: &[[u32; 3]], to: &Path) -> Result<Vec<u8>, MeshError> {
        let file_positions: Vec<Vec3> = self.file_vertices.iter().map(|&v| positions[v as usize]).collect();
        match self.format {
            Format::Obj => Ok(obj_written_back(&self.bytes, &file_positions)),
            Format::Ply => ply_written_back(&self.bytes, &file_positions, &self.file_vertices, positions, triangles),
            Format::Gltf | Format::Glb => {
                let folder = |path: &Path| std::fs::canonicalize(path).ok();
                let elsewhere = folder(folder_of(to)).is_none_or(|to| Some(to) != folder(&self.folder));
                GltfFile::open(&self.bytes, &self.folder)?.written_back(&self.bytes, &file_positions, elsewhere)
            }
            Format::Stl => Err(MeshError::Format("an STL file (STL is read, not written)".into())),
        }
    }
}

/// Whether two positions are the same, bit for bit (so that a vertex that did not move keeps
/// its text).
fn same(a: Vec3, b: Vec3) -> bool {
    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
}

/// An OBJ file's text with the `v` lines of moved vertices rewritten (a weight or colour after
/// the position kept) and the `vn` normals their corners use recomputed from the faces that use
/// them; every other byte kept.
fn obj_written_back(bytes: &[u8], positions: &[Vec3]) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    // The file's vertices, and which of them moved.
    let mut moved = Vec::with_capacity(positions.len());
    for line in &lines {
        if line.split_whitespace().next() == Some("v") {
            let index = moved.len();
            moved.push(obj_position(line).is_some_and(|p| positions.get(index).is_some_and(|&q| !same(p, q))));
        }
    }
    // Normals used by a corner of a moved vertex: each the sum of the (area-weighted) normals
    // of the faces whose corners use it.
    let (mut vertices, mut normals_seen) = (0i64, 0i64);
    let mut recomputed: HashMap<usize, Vec3> = HashMap::new();
    let mut touched: Vec<usize> = Vec::new();
    for line in &lines {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => vertices += 1,
            Some("vn") => normals_seen += 1,
            Some("f") => {
                let resolve = |i: i64, count: i64| if i > 0 { i - 1 } else { count + i };
                let corners: Vec<(usize, Option<usize>)> = words
                    .filter_map(|word| {
                        let mut parts = word.split('/');
                        let v = resolve(parts.next()?.parse().ok()?, vertices);
                        let n = parts.nth(1).and_then(|n| n.parse().ok()).map(|n| resolve(n, normals_seen));
                        Some((usize::try_from(v).ok()?, n.and_then(|n| usize::try_from(n).ok())))
                    })
                    .collect();
                if corners.iter().any(|&(v, _)| v >= positions.len()) || corners.len() < 3 {
                    continue;
                }
                let corner = |k: usize| positions[corners[k].0];
                let face_normal: Vec3 = (1..corners.len() - 1)
                    .map(|k| (corner(k) - corner(0)).cross(corner(k + 1) - corner(0)))
                    .sum::<Vec3>()
                    * 0.5;
                for &(v, n) in &corners {
                    if let Some(n) = n {
                        *recomputed.entry(n).or_default() += face_normal;
                        if moved.get(v) == Some(&true) {
                            touched.push(n);
                        }
                    }
                }
            }
            _ => {}
        }
    }
    let touched: std::collections::HashSet<usize> = touched.into_iter().collect();
    let (mut vertex, mut normal) = (0usize, 0usize);
    let mut out = String::with_capacity(text.len());
    for line in lines {
        let body = line.trim_end_matches(['\n', '\r']);
        let ending = &line[body.len()..];
        let indent = &body[..body.len() - body.trim_start().len()];
        let words: Vec<&str> = body.split_whitespace().collect();
        match words.first() {
            Some(&"v") => {
                if moved.get(vertex) == Some(&true) {
                    let p = positions[vertex];
                    let rest = words.get(4..).map(|w| w.join(" ")).unwrap_or_default();
                    let rest = if rest.is_empty() { rest } else { format!(" {rest}") };
                    out.push_str(&format!("{indent}v {} {} {}{rest}{ending}", p.x, p.y, p.z));
                } else {
                    out.push_str(line);
                }
                vertex += 1;
            }
            Some(&"vn") => {
                match recomputed.get(&normal).filter(|_| touched.contains(&normal)).map(|n| n.normalize_or_zero()) {
                    Some(n) if n != Vec3::ZERO => out.push_str(&format!("{indent}vn {} {} {}{ending}", n.x, n.y, n.z)),
                    _ => out.push_str(line),
                }
                normal += 1;
            }
            _ => out.push_str(line),
        }
    }
    out.into_bytes()
}

/// A PLY file with its vertices' `x y z` set to `positions` (file order) where they moved and
/// their `nx ny nz`, if it has them, recomputed there from the welded mesh's faces; written in
/// the file's own encoding, every other property and element kept.
fn ply_written_back(
    bytes: &[u8],
    positions: &[Vec3],
    file_vertices: &[u32],
    welded: &[Vec3],
    triangles: &[[u32; 3]],
) -> Result<Vec<u8>, MeshError> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    use ply_rs_bw::writer::Writer;
    let error = |message: String| MeshError::Parse { format: "PLY", message };
    let mut ply =
        Parser::<DefaultElement>::new().read_ply(&mut Cursor::new(bytes)).map_err(|e| error(e.to_string()))?;
    let mut normals = vec![Vec3::ZERO; welded.len()];
    for &[a, b, c] in triangles {
        let n = (welded[b as usize] - welded[a as usize]).cross(welded[c as usize] - welded[a as usize]);
        for v in [a, b, c] {
            normals[v as usize] += n;
        }
    }
    let set = |property: Option<&mut Property>, value: f32| match property {
        Some(Property::Float(v)) => *v = value,
        Some(Property::Double(v)) => *v = f64::from(value),
        _ => {}
    };
    let vertices = ply.payload.get_mut("vertex").ok_or_else(|| error("no `vertex` element".into()))?;
    let mut moved = 0;
    for (index, vertex) in vertices.iter_mut().enumerate() {
        let Some(&p) = positions.get(index) else { continue };
        let number = |name: &str| match vertex.get(name) {
            Some(Property::Float(v)) => Some(*v),
            Some(Property::Double(v)) => Some(*v as f32),
            _ => None,
        };
        let was = [number("x"), number("y"), number("z")];
        if let [Some(x), Some(y), Some(z)] = was
            && same(Vec3::new(x, y, z), p)
        {
            continue;
        }
        moved += 1;
        for (name, value) in [("x", p.x), ("y", p.y), ("z", p.z)] {
            set(vertex.get_mut(name), value);
        }
        if vertex.contains_key("nx") {
            let n = normals[file_vertices[index] as usize].normalize_or_zero();
            for (name, value) in [("nx", n.x), ("ny", n.y), ("nz", n.z)] {
                set(vertex.get_mut(name), value);
            }
        }
    }
    if moved == 0 {
        // Nothing moved: the file as it was, byte for byte.
        return Ok(bytes.to_vec());
    }
    let mut out = Vec::with_capacity(bytes.len());
    Writer::<DefaultElement>::new().write_ply(&mut out, &mut ply).map_err(|e| error(e.to_string()))?;
    Ok(out)
}

/// Writes `mesh` to `path` as OBJ or ASCII PLY, by its extension.
pub fn write(mesh: &TriangleMesh, path: &Path) -> Result<(), MeshError> {
    let bytes = match Format::of(path)? {
        Format::Obj => to_obj(mesh),
        Format::Ply => to_ply(mesh),
        Format::Stl | Format::Gltf | Format::Glb => {
            return Err(MeshError::Format(format!("{} (STL and glTF are read, not written)", path.display())));
        }
    };
    let mut file = std::fs::File::create(path)?;
    file.write_all(&bytes)?;
    Ok(())
}

/// `mesh` as Wavefront OBJ text.
fn to_obj(mesh: &TriangleMesh) -> Vec<u8> {
    let mut text = String::with_capacity(mesh.positions.len() * 32 + mesh.triangles.len() * 24);
    text.push_str("# written by Canopy\n");
    for p in &mesh.positions {
        text.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for [a, b, c] in &mesh.triangles {
        text.push_str(&format!("f {} {} {}\n", a + 1, b + 1, c + 1));
    }
    text.into_bytes()
}

/// `mesh` as ASCII PLY text.
fn to_ply(mesh: &TriangleMesh) -> Vec<u8> {
    let mut text = format!(
        "ply\nformat ascii 1.0\ncomment written by Canopy\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for p in &mesh.positions {
        text.push_str(&format!("{} {} {}\n", p.x, p.y, p.z));
    }
    for [a, b, c] in &mesh.triangles {
        text.push_str(&format!("3 {a} {b} {c}\n"));
    }
    text.into_bytes()
}

#[cfg(test)]
mod tests;
