//! The mesh files' tests: reading each format, welding, writing back.

use super::*;

/// A unit square of two triangles.
fn square() -> TriangleMesh {
    TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
    }
}

/// The mesh's triangles as their corners' positions, each turned to start at its least
/// corner (keeping its winding), sorted: equal for equal meshes whatever their numbering.
fn shape(mesh: &TriangleMesh) -> Vec<[[u32; 3]; 3]> {
    let mut triangles: Vec<[[u32; 3]; 3]> = mesh
        .triangles
        .iter()
        .map(|t| {
            let corners = t.map(|v| mesh.positions[v as usize].to_array().map(f32::to_bits));
            let first = (0..3).min_by_key(|&k| corners[k]).unwrap_or(0);
            [0, 1, 2].map(|k| corners[(first + k) % 3])
        })
        .collect();
    triangles.sort();
    triangles
}

#[test]
fn obj_and_ply_written_read_back_the_same_mesh() {
    let folder = tempfile::tempdir().unwrap();
    for name in ["square.obj", "square.ply"] {
        let path = folder.path().join(name);
        write(&square(), &path).unwrap();
        let (mesh, report) = read(&path).unwrap();
        assert_eq!((mesh.positions.len(), shape(&mesh)), (4, shape(&square())), "{name}");
        assert_eq!(report, MeshReport::default(), "{name}");
    }
}

#[test]
fn stl_repeats_its_vertices_and_is_welded_into_one_piece() {
    let stl = b"solid square
facet normal 0 1 0
 outer loop
  vertex 0 0 0
  vertex 1 0 1
  vertex 1 0 0
 endloop
endfacet
facet normal 0 1 0
 outer loop
  vertex 0 0 0
  vertex 0 0 1
  vertex 1 0 1
 endloop
endfacet
endsolid square
";
    let (mesh, _) = parse(stl, Format::Stl, Path::new(".")).unwrap();
    assert_eq!((mesh.positions.len(), mesh.triangles.len()), (4, 2), "two triangles on four shared corners");
}

#[test]
fn welding_merges_coincident_vertices_and_counts_what_it_finds() {
    // The square with its diagonal's ends repeated, a face collapsed by the weld, and a
    // fin: a third face on the diagonal.
    let positions =
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), Vec3::Z, Vec3::Y];
    let triangles = vec![[0, 2, 1], [3, 5, 4], [0, 3, 1], [0, 2, 6]];
    let (mesh, report, remap) = weld(positions, triangles);
    assert_eq!(remap, [0, 1, 2, 0, 2, 3, 4]);
    assert_eq!(mesh.positions.len(), 5);
    assert_eq!(report, MeshReport { welded: 2, degenerate: 1, non_manifold_edges: 1 });
}

#[test]
fn a_ply_written_back_keeps_its_other_properties_and_unmoved_vertices() {
    let ply = b"ply\nformat ascii 1.0\ncomment scanned\nelement vertex 4\nproperty float x\nproperty float y\n\
                property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n\
                element face 2\nproperty list uchar int vertex_indices\nend_header\n\
                0 0 0 0 1 0 10\n1 0 0 0 1 0 20\n1 0 1 0 1 0 30\n0 0 1 0 1 0 40\n3 0 2 1\n3 0 3 2\n";
    let (mesh, _, source) = parse_source(ply.to_vec(), Format::Ply, Path::new(".")).unwrap();
    // Unmoved: the file itself.
    assert_eq!(source.written_back(&mesh.positions, &mesh.triangles, Path::new("out")).unwrap(), ply.to_vec());
    // One corner raised: its position and normal change, nothing else.
    let mut moved = mesh.positions.clone();
    moved[2].y = 0.5;
    let bytes = source.written_back(&moved, &mesh.triangles, Path::new("out")).unwrap();
    let (read_back, _, _) = parse_in_order(&bytes, Format::Ply, Path::new(".")).unwrap();
    assert_eq!(read_back.positions, moved);
    let text = String::from_utf8(bytes).unwrap();
    assert!(text.contains("comment scanned") && text.contains("property uchar red"), "{text}");
    let rows: Vec<&str> = text.lines().skip_while(|l| *l != "end_header").skip(1).collect();
    assert_eq!(rows[0], "0 0 0 0 1 0 10");
    assert!(rows[2].starts_with("1 0.5 1 ") && rows[2].ends_with(" 30") && !rows[2].contains(" 0 1 0 "), "{}", rows[2]);
}

/// A binary glTF file of `json` (padded) and `bin`.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().div_ceil(4) * 4, b' ');
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

/// The unit square's glTF: four positions and six 16-bit indices, `count` positions claimed.
fn square_glb(count: usize) -> Vec<u8> {
    let mut bin: Vec<u8> = square().positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    bin.extend(square().triangles.iter().flatten().flat_map(|&i| (i as u16).to_le_bytes()));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":60}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
        {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}]}}"#
    );
    glb(&json, &bin)
}

#[test]
fn a_binary_gltf_mesh_is_read() {
    let (mesh, report) = parse(&square_glb(4), Format::Glb, Path::new(".")).unwrap();
    assert_eq!((mesh.positions.len(), shape(&mesh)), (4, shape(&square())));
    assert_eq!(report, MeshReport::default());
    // More positions claimed than the buffer holds, or a file cut short: errors.
    assert!(parse(&square_glb(400), Format::Glb, Path::new(".")).is_err());
    let whole = square_glb(4);
    assert!(parse(&whole[..whole.len() - 20], Format::Glb, Path::new(".")).is_err());
    assert!(matches!(Format::of(Path::new("a.glb")), Ok(Format::Glb)));
}

#[test]
fn a_binary_gltf_written_back_changes_only_the_moved_positions_and_their_bounds() {
    let file = square_glb(4);
    let (mesh, _, source) = parse_source(file.clone(), Format::Glb, Path::new(".")).unwrap();
    assert_eq!(
        source.written_back(&mesh.positions, &mesh.triangles, Path::new("out")).unwrap(),
        file,
        "unmoved: the file itself"
    );
    // A corner pulled in: its floats change in place, the bounds stay, nothing else moves.
    let mut inward = mesh.positions.clone();
    inward[2] = Vec3::new(0.5, 0.0, 1.0);
    let bytes = source.written_back(&inward, &mesh.triangles, Path::new("out")).unwrap();
    assert_eq!(bytes.len(), file.len());
    let differ: Vec<usize> = (0..file.len()).filter(|&i| bytes[i] != file[i]).collect();
    assert!(!differ.is_empty() && differ[differ.len() - 1] - differ[0] < 4, "one float's bytes: {differ:?}");
    assert_eq!(parse(&bytes, Format::Glb, Path::new(".")).unwrap().0.positions, inward);
    // A corner raised above the old bounds: the accessor's max follows.
    let mut raised = mesh.positions.clone();
    raised[2].y = 0.25;
    let bytes = source.written_back(&raised, &mesh.triangles, Path::new("out")).unwrap();
    let gltf = ::gltf::Gltf::from_slice(&bytes).unwrap();
    let max = gltf.accessors().next().unwrap().max().unwrap();
    assert_eq!(max, ::gltf::json::Value::from(vec![1.0, 0.25, 1.0]));
    assert_eq!(parse(&bytes, Format::Glb, Path::new(".")).unwrap().0.positions, raised);
}

#[test]
fn bad_meshes_are_errors_not_panics() {
    let too_far = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
    assert!(parse(too_far, Format::Obj, Path::new(".")).is_err(), "a face beyond the vertices");
    let nan = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n";
    assert!(matches!(
        parse(nan, Format::Ply, Path::new(".")),
        Err(MeshError::NotFinite(1)) | Err(MeshError::Parse { .. })
    ));
    let out = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    assert!(matches!(
        parse(out, Format::Ply, Path::new(".")),
        Err(MeshError::IndexOutOfRange { face: 0, vertex: 7, count: 3 })
    ));
    assert!(matches!(parse(b"not a mesh at all", Format::Stl, Path::new(".")), Err(MeshError::Parse { .. })));
    assert!(matches!(Format::of(Path::new("a.fbx")), Err(MeshError::Format(_))));
}
