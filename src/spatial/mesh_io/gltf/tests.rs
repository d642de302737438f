//! glTF files' tests: text files with their buffers inline or beside them, nodes' placements,
//! drawing with materials, writing back, and bad files.

use super::super::{Format, MeshError, drawing, parse, parse_source};
use bevy::math::{Vec2, Vec3};
use std::path::Path;

/// The unit square's vertices (in xz, facing +y) and its two triangles.
const SQUARE: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]];
const TRIANGLES: [u16; 6] = [0, 2, 1, 0, 3, 2];

/// The square's buffer: positions (48 bytes), texture coordinates (32), indices (12).
fn square_buffer() -> Vec<u8> {
    let mut bytes: Vec<u8> = SQUARE.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend([[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].iter().flatten().flat_map(|c| c.to_le_bytes()));
    bytes.extend(TRIANGLES.iter().flat_map(|i| i.to_le_bytes()));
    bytes
}

/// A text glTF file of the square drawn by one node with `node` (its transform members) whose
/// buffer is at `uri`, `length` bytes claimed, and `extra` members added to its root.
fn square_gltf(uri: &str, length: usize, node: &str, extra: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0","generator":"hand"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0{node}}}],
        "buffers":[{{"uri":"{uri}","byteLength":{length}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},
            {{"buffer":0,"byteOffset":80,"byteLength":12}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
            {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},
            {{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.25,1,1]}}}}]{extra}}}"#
    )
}

/// The square's buffer as a data URI.
fn inline() -> String {
    format!("data:application/octet-stream;base64,{}", data_encoding::BASE64.encode(&square_buffer()))
}

fn here() -> &'static Path {
    Path::new(".")
}

#[test]
fn a_text_gltf_with_its_buffer_inline_is_read_where_its_node_places_it() {
    let file = square_gltf(&inline(), 92, r#","translation":[0,2,0],"scale":[2,2,2]"#, "");
    let (mesh, _) = parse(file.as_bytes(), Format::Gltf, here()).unwrap();
    let expected: Vec<Vec3> = SQUARE.iter().map(|&p| Vec3::from_array(p) * 2.0 + Vec3::Y * 2.0).collect();
    assert_eq!(mesh.positions, expected);
    assert_eq!(mesh.triangles, vec![[0, 2, 1], [0, 3, 2]]);
    assert!(matches!(Format::of(Path::new("prop.GLTF")), Ok(Format::Gltf)));
}

#[test]
fn a_buffer_in_a_file_beside_it_is_read_and_references_stay_in_its_folder() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::write(folder.path().join("square data.bin"), square_buffer()).unwrap();
    let file = square_gltf("square%20data.bin", 92, "", "");
    let (mesh, _) = parse(file.as_bytes(), Format::Gltf, folder.path()).unwrap();
    assert_eq!(mesh.positions.len(), 4);
    for (uri, expected) in [
        ("../square.bin", "is not a data URI or a file in the file's folder"),
        ("/etc/passwd", "is not a data URI or a file in the file's folder"),
        ("http://example.com/a.bin", "is not a data URI or a file in the file's folder"),
        ("missing.bin", "missing.bin"),
    ] {
        let file = square_gltf(uri, 92, "", "");
        let message = parse(file.as_bytes(), Format::Gltf, folder.path()).unwrap_err().to_string();
        assert!(message.contains("buffer 0: ") && message.contains(expected), "{uri}: {message}");
    }
}

#[test]
fn bad_gltf_files_are_located_errors() {
    // A buffer claiming 2 GB that holds 92 bytes is refused before anything is read from it.
    let claimed = square_gltf(&inline(), 2_000_000_000, "", "");
    let message = parse(claimed.as_bytes(), Format::Gltf, here()).unwrap_err().to_string();
    assert!(message.contains("buffer 0 claims 2000000000 bytes but holds 92"), "{message}");
    // An index naming a fifth vertex of four.
    let mut buffer = square_buffer();
    buffer[80 + 4] = 4;
    let uri = format!("data:application/octet-stream;base64,{}", data_encoding::BASE64.encode(&buffer));
    let file = square_gltf(&uri, 92, "", "");
    let error = parse(file.as_bytes(), Format::Gltf, here()).unwrap_err();
    assert!(matches!(error, MeshError::IndexOutOfRange { face: 0, vertex: 4, count: 4 }), "{error}");
    // A view past its buffer, an accessor past its view, a node that is not there, no JSON.
    let past_buffer = square_gltf(&inline(), 92, "", "")
        .replace(r#""byteOffset":80,"byteLength":12"#, r#""byteOffset":88,"byteLength":12"#);
    let past_view = square_gltf(&inline(), 92, "", "").replace(r#""count":6"#, r#""count":60"#);
    let no_node = square_gltf(&inline(), 92, "", "").replace(r#""nodes":[0]"#, r#""nodes":[7]"#);
    for (file, expected) in [
        (past_buffer, "accessor 2: its view reaches past its buffer"),
        (past_view, "accessor 2: its elements reach past its view"),
        (no_node, "nodes"),
        ("{ not json".to_string(), "glTF"),
    ] {
        let message = parse(file.as_bytes(), Format::Gltf, here()).unwrap_err().to_string();
        assert!(message.contains(expected), "expected \"{expected}\" in: {message}");
    }
}

#[test]
fn drawing_keeps_materials_texture_coordinates_and_mirroring() {
    let file = square_gltf(&inline(), 92, r#","scale":[1,1,-1]"#, "");
    let drawn = drawing(file.as_bytes(), Format::Gltf, here()).unwrap();
    let part = &drawn.parts[0];
    assert_eq!(part.base_color, Vec3::new(0.5, 0.25, 1.0));
    assert!(part.uvs.is_empty(), "texture coordinates are read for a texture");
    assert_eq!(part.positions[2], Vec3::new(1.0, 0.0, -1.0));
    // Mirrored by its node, the square keeps facing up: its corners' order is reversed.
    assert_eq!(part.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(part.texture, None);
    // A base colour texture in a data URI, clamped by its sampler.
    let png = {
        let mut bytes = std::io::Cursor::new(Vec::new());
        image::RgbImage::from_pixel(2, 2, image::Rgb([200, 10, 10]))
            .write_to(&mut bytes, image::ImageFormat::Png)
            .unwrap();
        bytes.into_inner()
    };
    let images = format!(
        r#","textures":[{{"source":0,"sampler":0}}],"samplers":[{{"wrapS":33071,"wrapT":33071}}],
        "images":[{{"uri":"data:image/png;base64,{}"}}]"#,
        data_encoding::BASE64.encode(&png)
    );
    let textured = square_gltf(&inline(), 92, "", &images)
        .replace(r#""baseColorFactor":[0.5,0.25,1,1]"#, r#""baseColorTexture":{"index":0}"#);
    let drawn = drawing(textured.as_bytes(), Format::Gltf, here()).unwrap();
    assert_eq!(drawn.parts[0].texture, Some((0, true)));
    assert_eq!(drawn.parts[0].uvs, vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
    assert_eq!(drawn.parts[0].base_color, Vec3::ONE);
    assert_eq!(drawn.images, vec![Some(png)]);
}

#[test]
fn a_text_gltf_written_back_keeps_everything_but_the_moved_positions() {
    let file = square_gltf(&inline(), 92, r#","translation":[0,2,0]"#, r#","extras":{"author":"a user"}"#);
    let (mesh, _, source) = parse_source(file.clone().into_bytes(), Format::Gltf, here()).unwrap();
    let to = Path::new("moved.gltf");
    assert_eq!(
        source.written_back(&mesh.positions, &mesh.triangles, to).unwrap(),
        file.as_bytes(),
        "unmoved: the file"
    );
    let mut moved = mesh.positions.clone();
    moved[2] = Vec3::new(1.0, 2.5, 1.0);
    let bytes = source.written_back(&moved, &mesh.triangles, to).unwrap();
    let (read, _) = parse(&bytes, Format::Gltf, here()).unwrap();
    assert_eq!(read.positions, moved);
    let was: serde_json::Value = serde_json::from_str(&file).unwrap();
    let mut now: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    // In the file's own coordinates (its node lifts it by 2): the corner is 0.5 up.
    assert_eq!(now["accessors"][0]["max"], serde_json::json!([1.0, 0.5, 1.0]));
    // Apart from the buffer and that bound, the file is as it was, its extras too.
    now["accessors"][0]["max"] = was["accessors"][0]["max"].clone();
    now["buffers"][0]["uri"] = was["buffers"][0]["uri"].clone();
    assert_eq!(now, was);
}

#[test]
fn a_buffer_beside_the_file_is_left_as_it_was_and_the_moved_one_goes_inline() {
    let folder = tempfile::tempdir().unwrap();
    let beside = folder.path().join("square.bin");
    std::fs::write(&beside, square_buffer()).unwrap();
    let file = square_gltf("square.bin", 92, "", "");
    let (mesh, _, source) = parse_source(file.into_bytes(), Format::Gltf, folder.path()).unwrap();
    let inline = |bytes: &[u8]| {
        let root: serde_json::Value = serde_json::from_slice(bytes).unwrap();
        root["buffers"][0]["uri"].as_str().unwrap().starts_with("data:application/octet-stream;base64,")
    };
    // Beside the file and unmoved: the file as it was, its buffer still beside it.
    let same_folder = folder.path().join("copy.gltf");
    let bytes = source.written_back(&mesh.positions, &mesh.triangles, &same_folder).unwrap();
    assert!(!inline(&bytes));
    let mut moved = mesh.positions.clone();
    moved[0].y = -0.5;
    let bytes = source.written_back(&moved, &mesh.triangles, &same_folder).unwrap();
    assert_eq!(std::fs::read(&beside).unwrap(), square_buffer());
    assert!(inline(&bytes));
    assert_eq!(parse(&bytes, Format::Gltf, here()).unwrap().0.positions, moved);
    // Unmoved but written to another folder: the buffer goes inline, so the copy stands alone.
    let elsewhere = tempfile::tempdir().unwrap();
    let bytes = source.written_back(&mesh.positions, &mesh.triangles, &elsewhere.path().join("copy.gltf")).unwrap();
    assert!(inline(&bytes));
    assert_eq!(parse(&bytes, Format::Gltf, elsewhere.path()).unwrap().0.positions, mesh.positions);
}
