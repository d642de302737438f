//! glTF 2.0 files, text (`.gltf`, its buffers and images in data URIs or in files beside it)
//! and binary (`.glb`): their triangles placed by the nodes of the file's scene, read for
//! drawing (with texture coordinates, vertex colours and base colours) and for deforming, and
//! written back with only the moved positions changed.
//!
//! Every buffer and accessor is checked against what the file holds before it is read: a view
//! past its buffer's end, a buffer claiming more bytes than it has, a reference leaving the
//! file's folder are errors, and the bytes read are bounded by [`MAX_FILE_BYTES`].

use super::{Drawing, MAX_ELEMENTS, MAX_FILE_BYTES, MeshError, Part};
use bevy::math::{Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::path::Path;

/// How deep nodes may nest in a file's scene (deeper is taken for a cycle).
const MAX_NODE_DEPTH: usize = 64;

/// A glTF file with its buffers at hand.
pub(super) struct GltfFile {
    document: gltf::Document,
    /// Each buffer's bytes, by buffer index.
    buffers: Vec<Vec<u8>>,
    /// The file's folder, where its relative references lie.
    folder: std::path::PathBuf,
}

impl GltfFile {
    /// The file in `bytes` (text or binary), its references resolved in `folder`.
    pub(super) fn open(bytes: &[u8], folder: &Path) -> Result<Self, MeshError> {
        let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| error(e.to_string()))?;
        let mut blob = gltf.blob;
        let mut budget = MAX_FILE_BYTES;
        let mut buffers = Vec::new();
        for buffer in gltf.document.buffers() {
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => {
                    blob.take().ok_or_else(|| error(format!("buffer {}: no binary chunk", buffer.index())))?
                }
                gltf::buffer::Source::Uri(uri) => {
                    uri_bytes(uri, folder, &mut budget).map_err(|m| error(format!("buffer {}: {m}", buffer.index())))?
                }
            };
            if data.len() < buffer.length() {
                return Err(error(format!(
                    "buffer {} claims {} bytes but holds {}",
                    buffer.index(),
                    buffer.length(),
                    data.len()
                )));
            }
            buffers.push(data);
        }
        Ok(Self { document: gltf.document, buffers, folder: folder.to_path_buf() })
    }

    /// The world placement of every node that draws a mesh in the file's scene (its default
    /// one, or its first), in the order the scene lists them, depth first.
    fn drawn(&self) -> Result<Vec<(gltf::Mesh<'_>, Mat4)>, MeshError> {
        fn visit<'a>(
            node: gltf::Node<'a>,
            parent: Mat4,
            depth: usize,
            out: &mut Vec<(gltf::Mesh<'a>, Mat4)>,
        ) -> Result<(), MeshError> {
            if depth > MAX_NODE_DEPTH {
                return Err(error(format!("nodes nested more than {MAX_NODE_DEPTH} deep (or in a cycle)")));
            }
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if let Some(mesh) = node.mesh() {
                if out.len() >= MAX_ELEMENTS {
                    return Err(MeshError::TooLarge { what: "a count of drawn meshes", count: out.len() });
                }
                out.push((mesh, world));
            }
            node.children().try_for_each(|child| visit(child, world, depth + 1, out))
        }
        let mut out = Vec::new();
        let scene = self.document.default_scene().or_else(|| self.document.scenes().next());
        for node in scene.iter().flat_map(|scene| scene.nodes()) {
            visit(node, Mat4::IDENTITY, 0, &mut out)?;
        }
        Ok(out)
    }

    /// Each mesh's placement for deforming: where the first node drawing it puts it, or where
    /// it stands if no node does.
    fn placements(&self) -> Result<Vec<Mat4>, MeshError> {
        let mut placed = vec![None; self.document.meshes().len()];
        for (mesh, world) in self.drawn()? {
            placed[mesh.index()].get_or_insert(world);
        }
        Ok(placed.into_iter().map(|p| p.unwrap_or(Mat4::IDENTITY)).collect())
    }

    /// Positions and faces for deforming: every triangle primitive of every mesh (vertices in
    /// file order, mesh after mesh), placed as [`Self::placements`] has it.
    pub(super) fn triangles(&self) -> Result<(Vec<Vec3>, Vec<[i64; 3]>), MeshError> {
        let placements = self.placements()?;
        let (mut positions, mut faces) = (Vec::new(), Vec::new());
        for mesh in self.document.meshes() {
            let place = placements[mesh.index()];
            for primitive in triangle_primitives(&mesh) {
                let base = positions.len() as i64;
                positions.extend(self.positions(&primitive)?.into_iter().map(|p| place.transform_point3(p)));
                let count = positions.len() as i64 - base;
                faces.extend(self.corners(&primitive, count as usize)?.into_iter().map(|t| t.map(|v| base + v as i64)));
                bounded(positions.len().max(faces.len()))?;
            }
        }
        Ok((positions, faces))
    }

    /// What drawing the file needs: every node's mesh placed in the scene, with its material.
    pub fn drawing(&self) -> Result<Drawing, MeshError> {
        let mut drawing = Drawing { parts: Vec::new(), images: vec![None; self.document.images().len()] };
        let mut total = 0;
        for (mesh, world) in self.drawn()? {
            let turn = Mat3::from_mat4(world);
            let normal_turn = turn.inverse().transpose();
            let mirrored = turn.determinant() < 0.0;
            for primitive in triangle_primitives(&mesh) {
                let positions: Vec<Vec3> =
                    self.positions(&primitive)?.into_iter().map(|p| world.transform_point3(p)).collect();
                let count = positions.len();
                let mut triangles = self.corners(&primitive, count)?;
                if mirrored {
                    triangles.iter_mut().for_each(|t| t.swap(1, 2));
                }
                total += count + triangles.len();
                bounded(total)?;
                let reader = primitive.reader(|buffer| self.buffers.get(buffer.index()).map(Vec::as_slice));
                let normals = match primitive.get(&gltf::Semantic::Normals) {
                    Some(accessor) => {
                        self.check(&accessor, Some(count))?;
                        reader.read_normals().map_or_else(Vec::new, |read| {
                            read.map(|n| (normal_turn * Vec3::from_array(n)).normalize_or_zero()).collect()
                        })
                    }
                    None => Vec::new(),
                };
                let colors = match primitive.get(&gltf::Semantic::Colors(0)) {
                    Some(accessor) => {
                        self.check(&accessor, Some(count))?;
                        reader
                            .read_colors(0)
                            .map_or_else(Vec::new, |read| read.into_rgb_f32().map(Vec3::from_array).collect())
                    }
                    None => Vec::new(),
                };
                let pbr = primitive.material().pbr_metallic_roughness();
                let [r, g, b, _] = pbr.base_color_factor();
                let (mut uvs, mut texture) = (Vec::new(), None);
                if let Some(info) = pbr.base_color_texture() {
                    let set = gltf::Semantic::TexCoords(info.tex_coord());
                    let accessor = primitive.get(&set).ok_or_else(|| {
                        error(format!("mesh {}: a base colour texture without its texture coordinates", mesh.index()))
                    })?;
                    self.check(&accessor, Some(count))?;
                    uvs = reader
                        .read_tex_coords(info.tex_coord())
                        .map_or_else(Vec::new, |read| read.into_f32().map(Vec2::from_array).collect());
                    let gltf_texture = info.texture();
                    let image = gltf_texture.source();
                    if drawing.images[image.index()].is_none() {
                        drawing.images[image.index()] = Some(self.image_bytes(&image)?);
                    }
                    let clamped = gltf_texture.sampler().wrap_s() == gltf::texture::WrappingMode::ClampToEdge;
                    texture = Some((image.index(), clamped));
                }
                drawing.parts.push(Part {
                    positions,
                    normals,
                    uvs,
                    colors,
                    triangles,
                    base_color: Vec3::new(r, g, b),
                    texture,
                });
            }
        }
        Ok(drawing)
    }

    /// The encoded bytes of `image`, from a buffer view or its URI.
    fn image_bytes(&self, image: &gltf::Image) -> Result<Vec<u8>, MeshError> {
        match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                buffer
                    .get(view.offset()..view.offset() + view.length())
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| error(format!("image {}: its view reaches past its buffer", image.index())))
            }
            gltf::image::Source::Uri { uri, .. } => {
                let mut budget = MAX_FILE_BYTES;
                uri_bytes(uri, &self.folder, &mut budget).map_err(|m| error(format!("image {}: {m}", image.index())))
            }
        }
    }

    /// The positions of a primitive as the file holds them.
    fn positions(&self, primitive: &gltf::Primitive) -> Result<Vec<Vec3>, MeshError> {
        let accessor =
            primitive.get(&gltf::Semantic::Positions).ok_or_else(|| error("a primitive without positions".into()))?;
        self.check(&accessor, None)?;
        let reader = primitive.reader(|buffer| self.buffers.get(buffer.index()).map(Vec::as_slice));
        let positions: Vec<Vec3> =
            reader.read_positions().map(|read| read.map(Vec3::from_array).collect()).unwrap_or_default();
        if positions.len() != accessor.count() {
            return Err(error(format!("accessor {}: positions outside the file's buffers", accessor.index())));
        }
        Ok(positions)
    }

    /// A primitive's triangles (its indices, or its vertices in threes), each corner checked to
    /// name one of its `count` vertices.
    fn corners(&self, primitive: &gltf::Primitive, count: usize) -> Result<Vec<[u32; 3]>, MeshError> {
        let indices: Vec<u32> = match primitive.indices() {
            Some(accessor) => {
                self.check(&accessor, None)?;
                let reader = primitive.reader(|buffer| self.buffers.get(buffer.index()).map(Vec::as_slice));
                let indices: Vec<u32> = reader.read_indices().map(|read| read.into_u32().collect()).unwrap_or_default();
                if let Some((at, &bad)) = indices.iter().enumerate().find(|&(_, &i)| i as usize >= count) {
                    return Err(MeshError::IndexOutOfRange { face: at / 3, vertex: i64::from(bad), count });
                }
                indices
            }
            None => (0..count as u32).collect(),
        };
        Ok(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect())
    }

    /// Checks that `accessor`'s elements lie within its view and its view within its buffer
    /// (and, where given, that it has `count` elements), so that reading it cannot reach past
    /// the bytes the file holds.
    fn check(&self, accessor: &gltf::Accessor, count: Option<usize>) -> Result<(), MeshError> {
        let located = |message: &str| error(format!("accessor {}: {message}", accessor.index()));
        if accessor.count() > MAX_ELEMENTS {
            return Err(MeshError::TooLarge { what: "an accessor's element count", count: accessor.count() });
        }
        if count.is_some_and(|count| count != accessor.count()) {
            return Err(located("a different count from the primitive's positions"));
        }
        if accessor.sparse().is_some() {
            return Err(located("sparse accessors are not read"));
        }
        let Some(view) = accessor.view() else { return Ok(()) };
        let buffer = self.buffers.get(view.buffer().index()).ok_or_else(|| located("its buffer is missing"))?;
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|end| end > buffer.len()) {
            return Err(located("its view reaches past its buffer"));
        }
        let size = accessor.size();
        let stride = view.stride().unwrap_or(size).max(size);
        let needed = match accessor.count() {
            0 => Some(0),
            n => (n - 1)
                .checked_mul(stride)
                .and_then(|s| s.checked_add(size))
                .and_then(|s| s.checked_add(accessor.offset())),
        };
        if needed.is_none_or(|needed| needed > view.length()) {
            return Err(located("its elements reach past its view"));
        }
        Ok(())
    }

    /// The file `bytes` (this file's contents) with the position accessors' values set to
    /// `positions` (in the order [`Self::triangles`] reads them, placed as it places them)
    /// where they moved, and those accessors' bounds kept true. A file whose positions did not
    /// move comes back as it was; a binary file whose bounds held, with only the floats of
    /// the moved positions changed. Otherwise its JSON is written anew (its members in
    /// alphabetical order, every value kept) and a changed buffer goes back where it came
    /// from: the binary chunk or a data URI; a buffer in a file beside the text file is written
    /// into it as a data URI, leaving that file as it was for whatever else uses it. With
    /// `elsewhere` (the result goes to another folder, where the files beside this one are
    /// not), every buffer and image still in a file beside it goes into it as a data URI too.
    pub(super) fn written_back(&self, bytes: &[u8], positions: &[Vec3], elsewhere: bool) -> Result<Vec<u8>, MeshError> {
        let placements = self.placements()?;
        let mut buffers = self.buffers.clone();
        let mut changed_buffers = vec![false; buffers.len()];
        let mut bounds = Vec::new();
        let mut next = 0;
        for mesh in self.document.meshes() {
            let place = placements[mesh.index()];
            let unplace = place.inverse();
            if !unplace.is_finite() {
                return Err(error(format!("mesh {}: its node's transform cannot be undone", mesh.index())));
            }
            for primitive in triangle_primitives(&mesh) {
                let accessor = primitive
                    .get(&gltf::Semantic::Positions)
                    .ok_or_else(|| error("a primitive without positions".into()))?;
                self.check(&accessor, None)?;
                let view = accessor
                    .view()
                    .ok_or_else(|| error("positions without a buffer view are not written back".into()))?;
                if accessor.data_type() != DataType::F32 || accessor.dimensions() != Dimensions::Vec3 {
                    return Err(error("positions that are not three 32-bit floats".into()));
                }
                let stride = view.stride().unwrap_or(12);
                let first = view.offset() + accessor.offset();
                let buffer = &mut buffers[view.buffer().index()];
                let (mut low, mut high) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                for k in 0..accessor.count() {
                    let p = *positions.get(next).ok_or_else(|| error("fewer positions than the file holds".into()))?;
                    next += 1;
                    let slot = &mut buffer[first + k * stride..first + k * stride + 12];
                    let was = Vec3::from_array(std::array::from_fn(|c| {
                        f32::from_le_bytes([slot[4 * c], slot[4 * c + 1], slot[4 * c + 2], slot[4 * c + 3]])
                    }));
                    let mut kept = was;
                    if !super::same(place.transform_point3(was), p) {
                        kept = unplace.transform_point3(p);
                        for (c, value) in kept.to_array().into_iter().enumerate() {
                            slot[4 * c..4 * c + 4].copy_from_slice(&value.to_le_bytes());
                        }
                        changed_buffers[view.buffer().index()] = true;
                    }
                    (low, high) = (low.min(kept), high.max(kept));
                }
                bounds.push((accessor.index(), low, high));
            }
        }
        let beside = |uri: &str| !uri.starts_with("data:");
        let buffer_uris: Vec<Option<&str>> = self
            .document
            .buffers()
            .map(|buffer| match buffer.source() {
                gltf::buffer::Source::Uri(uri) if beside(uri) => Some(uri),
                _ => None,
            })
            .collect();
        let image_uris: Vec<Option<&str>> = self
            .document
            .images()
            .map(|image| match image.source() {
                gltf::image::Source::Uri { uri, .. } if beside(uri) => Some(uri),
                _ => None,
            })
            .collect();
        let inline_files = elsewhere && buffer_uris.iter().chain(&image_uris).any(Option::is_some);
        if !changed_buffers.contains(&true) && !inline_files {
            return Ok(bytes.to_vec());
        }
        let binary = bytes.starts_with(b"glTF");
        let json_chunk = if binary { glb_chunk(bytes, 12).map(|(_, body)| body) } else { Some(bytes) };
        let json_chunk = json_chunk.ok_or_else(|| error("no JSON chunk".into()))?;
        let mut root: serde_json::Value = serde_json::from_slice(json_chunk).map_err(|e| error(e.to_string()))?;
        let mut json_changed = false;
        for (index, low, high) in bounds {
            let accessor = &mut root["accessors"][index];
            for (key, bound) in [("min", low), ("max", high)] {
                let bound = bound.to_array().map(f64::from);
                let numbers: Option<Vec<f64>> =
                    accessor[key].as_array().and_then(|values| values.iter().map(serde_json::Value::as_f64).collect());
                if numbers.as_deref() != Some(&bound[..]) {
                    accessor[key] = serde_json::json!(bound);
                    json_changed = true;
                }
            }
        }
        let mut blob = None;
        for (index, buffer) in self.document.buffers().enumerate() {
            let inlined = inline_files && buffer_uris[index].is_some();
            if !changed_buffers[index] && !inlined {
                continue;
            }
            match buffer.source() {
                gltf::buffer::Source::Bin => blob = Some(buffers[index].as_slice()),
                gltf::buffer::Source::Uri(_) => {
                    let encoded = data_encoding::BASE64.encode(&buffers[index][..buffer.length()]);
                    root["buffers"][index]["uri"] = format!("data:application/octet-stream;base64,{encoded}").into();
                    json_changed = true;
                }
            }
        }
        if inline_files {
            for (index, image) in self.document.images().enumerate() {
                let Some(uri) = image_uris[index] else { continue };
                let mut budget = MAX_FILE_BYTES;
                let data =
                    uri_bytes(uri, &self.folder, &mut budget).map_err(|m| error(format!("image {index}: {m}")))?;
                let mime = match image.source() {
                    gltf::image::Source::Uri { mime_type: Some(mime), .. } => mime.to_string(),
                    _ if data.starts_with(b"\x89PNG") => "image/png".into(),
                    _ => "image/jpeg".into(),
                };
                root["images"][index]["uri"] =
                    format!("data:{mime};base64,{}", data_encoding::BASE64.encode(&data)).into();
            }
            json_changed = true;
        }
        let json = match json_changed {
            true => serde_json::to_vec(&root).map_err(|e| error(e.to_string()))?,
            false => json_chunk.to_vec(),
        };
        Ok(if binary { glb_rebuilt(bytes, json, blob) } else { json })
    }
}

/// The triangle primitives of `mesh` (points, lines and strips are not surfaces it reads).
fn triangle_primitives<'a>(mesh: &gltf::Mesh<'a>) -> impl Iterator<Item = gltf::Primitive<'a>> {
    mesh.primitives().filter(|p| p.mode() == Mode::Triangles)
}

/// An error in a glTF file.
fn error(message: String) -> MeshError {
    MeshError::Parse { format: "glTF", message }
}

/// `count` elements so far, refused beyond what a mesh may have.
fn bounded(count: usize) -> Result<(), MeshError> {
    if count > MAX_ELEMENTS {
        return Err(MeshError::TooLarge { what: "an element count", count });
    }
    Ok(())
}

/// The bytes a URI names: a base64 data URI, or a file in `folder` (or below it) named by a
/// relative, percent-encoded path; at most `budget` bytes, which are taken from it.
fn uri_bytes(uri: &str, folder: &Path, budget: &mut u64) -> Result<Vec<u8>, String> {
    if let Some(data) = uri.strip_prefix("data:") {
        let (_, encoded) = data.split_once(";base64,").ok_or("a data URI that is not base64")?;
        if encoded.len() as u64 / 4 * 3 > *budget {
            return Err(format!("a data URI of more than {MAX_FILE_BYTES} bytes"));
        }
        let bytes = data_encoding::BASE64.decode(encoded.as_bytes()).map_err(|e| format!("its data URI: {e}"))?;
        *budget -= bytes.len() as u64;
        return Ok(bytes);
    }
    let path =
        percent_encoding::percent_decode_str(uri).decode_utf8().map_err(|_| format!("\"{uri}\" is not UTF-8"))?;
    if uri.contains(':') || !crate::foundation::values::inside_folder(&path) {
        return Err(format!("\"{uri}\" is not a data URI or a file in the file's folder"));
    }
    let path = folder.join(&*path);
    let size = std::fs::metadata(&path).map_err(|e| format!("{}: {e}", path.display()))?.len();
    if size > *budget {
        return Err(format!("{}: more than {MAX_FILE_BYTES} bytes", path.display()));
    }
    *budget -= size;
    std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The chunk of a binary glTF file starting at byte `at`: its type and body.
fn glb_chunk(bytes: &[u8], at: usize) -> Option<([u8; 4], &[u8])> {
    let length = u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?) as usize;
    let kind = bytes.get(at + 4..at + 8)?.try_into().ok()?;
    Some((kind, bytes.get(at + 8..at + 8 + length)?))
}

/// A binary glTF file like `bytes` with the JSON chunk `json` (padded with spaces to four
/// bytes) and, where given, the binary chunk's body `blob` (the same length as before), every
/// other chunk kept.
fn glb_rebuilt(bytes: &[u8], mut json: Vec<u8>, blob: Option<&[u8]>) -> Vec<u8> {
    json.resize(json.len().div_ceil(4) * 4, b' ');
    let mut chunks = vec![(*b"JSON", json.as_slice())];
    let mut at = 12;
    while let Some((kind, body)) = glb_chunk(bytes, at) {
        at += 8 + body.len();
        match &kind {
            b"JSON" => {}
            b"BIN\0" => chunks.push((kind, blob.filter(|blob| blob.len() == body.len()).unwrap_or(body))),
            _ => chunks.push((kind, body)),
        }
    }
    let length = 12 + chunks.iter().map(|(_, body)| 8 + body.len()).sum::<usize>();
    let mut out = Vec::with_capacity(length);
    out.extend_from_slice(&bytes[..8]);
    out.extend_from_slice(&(length as u32).to_le_bytes());
    for (kind, body) in chunks {
        out.extend_from_slice(&(body.len() as u32).to_le_bytes());
        out.extend_from_slice(&kind);
        out.extend_from_slice(body);
    }
    out
}

#[cfg(test)]
mod tests;
