//! The surfaces a terrain is drawn in: one mesh a band, and with blending one a border where
//! two bands meet, each with its material (the scene's textures or the project's). A terrain's
//! section and a world's chunks are drawn alike.

use super::bands::{Band, band_texture};
use super::def::BandsDef;
use super::section::BORDERS;
use crate::raster::texture::material;
use crate::raster::{Material, Texture};
use bevy::ecs::component::Component;
use bevy::math::Vec3;
use std::sync::{Arc, OnceLock};

/// What one mesh of a terrain shows, a child of the terrain entity.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub enum TerrainSurface {
    /// The triangles showing one band alone.
    Band(Band),
    /// With blending, the triangles where the pair of bands at this index of [`BORDERS`] meet.
    Border(usize),
}

impl TerrainSurface {
    /// The surface's place in [`SectionMesh::into_surfaces`](super::section::SectionMesh::into_surfaces).
    pub fn index(self) -> usize {
        match self {
            TerrainSurface::Band(band) => band.index(),
            TerrainSurface::Border(index) => 5 + index,
        }
    }
}

/// The project's band textures, made once.
fn project_textures() -> &'static [Arc<Texture>; 5] {
    static TEXTURES: OnceLock<[Arc<Texture>; 5]> = OnceLock::new();
    TEXTURES.get_or_init(|| Band::ALL.map(|band| Arc::new(band_texture(band))))
}

/// The material of `band`: the scene's texture for it, or the project's.
fn band_material(bands: &BandsDef, band: Band) -> Material {
    match bands.textures.all()[band.index()] {
        Some(texture) => material(Vec3::ONE, Some(texture)),
        None => Material { texture: Some(project_textures()[band.index()].clone()), ..Material::colored(Vec3::ONE) },
    }
}

/// Each surface a terrain of `bands` is drawn in, with its material: the five bands, and with
/// blending the borders, each band's texture fading into the next one's.
pub fn surface_materials(bands: &BandsDef) -> Vec<(TerrainSurface, Material)> {
    let plain = Band::ALL.map(|band| (TerrainSurface::Band(band), band_material(bands, band)));
    let borders = BORDERS.into_iter().enumerate().filter(|_| bands.blend.is_some()).map(|(index, (lower, upper))| {
        let material = Material { blend: band_material(bands, upper).texture, ..band_material(bands, lower) };
        (TerrainSurface::Border(index), material)
    });
    plain.into_iter().chain(borders).collect()
}
