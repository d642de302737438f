//! A mesh file drawn as a shape: its parts as the rasterizer takes them, each a mesh and its
//! material, decoded once however many shapes draw the file.

use crate::foundation::kind::{EntityContext, ReferencedFile};
use crate::foundation::yaml::FileError;
use crate::raster::mesh::vertex_normals;
use crate::raster::{Address, Filter, Material, MeshData, Sampler, Texture};
use crate::spatial::mesh_io::{self, Drawing, Part};
use bevy::color::{LinearRgba, Srgba};
use bevy::math::Vec3;
use std::sync::Arc;

/// A mesh file's parts, each drawn with its own material, in the file's metres.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshParts {
    /// Each part's triangles and material (its colour in sRGB channels, as the rasterizer
    /// shades).
    pub parts: Vec<(Arc<MeshData>, Material)>,
    /// Triangles in all parts.
    pub triangles: usize,
}

impl MeshParts {
    /// The parts of the mesh file `file`, decoded for the first shape that names it; a file
    /// that is no mesh, or an image in it that is none, is an error at the entity's `mesh`.
    pub fn resolve(file: &mut ReferencedFile, cx: &EntityContext) -> Result<Arc<Self>, FileError> {
        let located =
            |message: String| cx.field_error("mesh", 0, "mesh", format!("{}: {message}", file.path.display()));
        let format = mesh_io::Format::of(file.path).map_err(|error| located(error.to_string()))?;
        file.decoded(|path, bytes| {
            let drawing = mesh_io::drawing(bytes, format, mesh_io::folder_of(path)).map_err(|e| e.to_string())?;
            Self::from_drawing(drawing)
        })
        .map_err(located)
    }

    /// The parts of `drawing`, its images decoded.
    fn from_drawing(drawing: Drawing) -> Result<Self, String> {
        let images = drawing
            .images
            .iter()
            .enumerate()
            .map(|(index, bytes)| {
                bytes
                    .as_deref()
                    .map(|bytes| Texture::decode(bytes).map(Arc::new).map_err(|e| format!("image {index}: {e}")))
                    .transpose()
            })
            .collect::<Result<Vec<_>, String>>()?;
        let triangles = drawing.parts.iter().map(|part| part.triangles.len()).sum();
        let parts = drawing.parts.into_iter().map(|part| drawn(part, &images)).collect();
        Ok(Self { parts, triangles })
    }
}

/// One part as the rasterizer draws it: normals computed where the file has none, colours in
/// sRGB channels.
fn drawn(part: Part, images: &[Option<Arc<Texture>>]) -> (Arc<MeshData>, Material) {
    let normals = match part.normals.len() == part.positions.len() {
        true => part.normals,
        false => vertex_normals(&part.positions, &part.triangles),
    };
    let mut material = Material::colored(srgb(part.base_color));
    if let Some((image, clamped)) = part.texture {
        material.texture = images.get(image).cloned().flatten();
        let address = if clamped { Address::Clamp } else { Address::Repeat };
        material.sampler = Sampler { filter: Filter::Trilinear, address };
    }
    let mesh = MeshData {
        positions: part.positions,
        normals,
        uvs: part.uvs,
        colors: part.colors.into_iter().map(srgb).collect(),
        blend: Vec::new(),
        triangles: part.triangles,
        morph: None,
    };
    (Arc::new(mesh), material)
}

/// The sRGB channels of a linear colour, each clamped to `[0, 1]`.
fn srgb(linear: Vec3) -> Vec3 {
    let color = Srgba::from(LinearRgba::rgb(linear.x, linear.y, linear.z));
    Vec3::new(color.red, color.green, color.blue).clamp(Vec3::ZERO, Vec3::ONE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::math::Vec2;

    fn square(texture: Option<(usize, bool)>) -> Part {
        Part {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0)],
            normals: Vec::new(),
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE],
            colors: vec![Vec3::splat(0.5); 3],
            triangles: vec![[0, 2, 1]],
            base_color: Vec3::new(1.0, 0.5, 0.0),
            texture,
        }
    }

    #[test]
    fn parts_get_normals_srgb_colours_and_their_textures() {
        let png = {
            let mut bytes = std::io::Cursor::new(Vec::new());
            image::RgbImage::new(4, 4).write_to(&mut bytes, image::ImageFormat::Png).unwrap();
            bytes.into_inner()
        };
        let drawing = Drawing { parts: vec![square(None), square(Some((1, true)))], images: vec![None, Some(png)] };
        let parts = MeshParts::from_drawing(drawing).unwrap();
        assert_eq!(parts.triangles, 2);
        let (mesh, material) = &parts.parts[0];
        assert!(mesh.normals.iter().all(|n| (*n - Vec3::Y).length() < 1e-6), "{:?}", mesh.normals);
        // Linear 0.5 is sRGB 0.735; linear 1 and 0 stay.
        assert!((mesh.colors[0].x - 0.735).abs() < 1e-3, "{:?}", mesh.colors[0]);
        assert!((material.color - Vec3::new(1.0, 0.735, 0.0)).abs().max_element() < 1e-3, "{}", material.color);
        assert!(material.texture.is_none());
        let (_, textured) = &parts.parts[1];
        assert_eq!(textured.texture.as_ref().map(|t| t.width()), Some(4));
        assert_eq!(textured.sampler.address, Address::Clamp);
        let bad = Drawing { parts: vec![square(Some((0, false)))], images: vec![Some(b"no image".to_vec())] };
        assert!(MeshParts::from_drawing(bad).unwrap_err().starts_with("image 0: "));
    }
}
