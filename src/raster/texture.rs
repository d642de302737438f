//! The `texture:` section that shapes and trees share: an image file next to the scene, its
//! sampling and repetition, decoded once however many entities use it, and the material it
//! makes with a colour.

use super::{Address, Filter, Material, Sampler, Texture};
use crate::foundation::kind::{EntityContext, ReferencedFile};
use crate::foundation::values::{FileType, FolderFile, Repeats};
use crate::foundation::yaml::FileError;
use bevy::math::{Vec2, Vec3};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Texture files: PNG or BMP images (`.png`, `.bmp`, in any case).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageFile;

impl FileType for ImageFile {
    const EXTENSIONS: &'static [&'static str] = &[".png", ".bmp"];
    const EXPECTING: &'static str = "a .png or .bmp file in the scene's folder";
    const FILES: &'static str = "a .png or .bmp file";
}

/// A texture in a scene file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDef {
    /// The image file.
    pub file: FolderFile<ImageFile>,
    /// `nearest`, `bilinear` or `trilinear` (the default: mip-mapped, no moire at a distance).
    #[serde(default)]
    pub filter: Filter,
    /// `repeat` (the default) or `clamp`.
    #[serde(default)]
    pub address: Address,
    /// Repetitions across the surface along u and v; `[1, 1]` by default.
    #[serde(default = "once")]
    pub repeat: [Repeats; 2],
    /// The decoded image, filled in when the scene is resolved.
    #[serde(skip)]
    pub image: Option<Arc<Texture>>,
}

fn once() -> [Repeats; 2] {
    [Repeats(1.0); 2]
}

impl TextureDef {
    /// The file this texture reads, for a kind's references.
    pub fn reference(texture: Option<&TextureDef>) -> Vec<String> {
        texture.map(|t| t.file.path.clone()).into_iter().collect()
    }

    /// Decodes the image from `file` when it is this texture's (once per file, shared by
    /// every entity); a file that is no image is an error at the entity's `field` (the path of
    /// this texture's `file` within the kind, e.g. `texture.file`).
    pub fn resolve(&mut self, file: &mut ReferencedFile, cx: &EntityContext, field: &str) -> Result<(), FileError> {
        if self.file.path != file.file {
            return Ok(());
        }
        let image = file.decoded(|path, bytes| {
            Texture::decode(bytes).map_err(|error| FileError::whole_file(path, format!("{}: {error}", cx.field(field))))
        })?;
        self.image = Some(image);
        Ok(())
    }
}

/// A material of `color` (sRGB channels, see
/// [`srgb_channels`](crate::foundation::values::srgb_channels)) with an optional texture.
pub fn material(color: Vec3, texture: Option<&TextureDef>) -> Material {
    let mut material = Material::colored(color);
    if let Some(texture) = texture {
        material.texture = texture.image.clone();
        material.sampler = Sampler { filter: texture.filter, address: texture.address };
        material.uv_scale = Vec2::new(texture.repeat[0].0, texture.repeat[1].0);
    }
    material
}
