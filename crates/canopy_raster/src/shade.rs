//! What a pixel's colour is made of: materials, shading modes and the values interpolated across
//! triangles.
//!
//! Every vertex carries the same [`Varyings`]; which of them a pixel actually interpolates
//! depends on the shading mode, the texture and shadows, chosen once per triangle so that the
//! pixel loops are compiled for each combination.

use crate::texture::{Sampler, Texture};
use bevy_math::{Vec2, Vec3};
use std::sync::Arc;

/// How light is computed across a triangle; the sources compare all three. Scene files name
/// the modes `flat`, `gouraud` and `phong`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
#[cfg_attr(feature = "reflect", derive(bevy_reflect::Reflect))]
pub enum Shading {
    /// One intensity per triangle, from its geometric normal.
    Flat,
    /// Intensity per vertex, interpolated across the triangle.
    #[default]
    Gouraud,
    /// Normal interpolated and lit per pixel.
    Phong,
}

impl Shading {
    /// Every mode, in the order the sources present them.
    pub const ALL: [Shading; 3] = [Shading::Flat, Shading::Gouraud, Shading::Phong];

    /// The mode's name in scene files and dumps.
    pub fn key(self) -> &'static str {
        match self {
            Shading::Flat => "flat",
            Shading::Gouraud => "gouraud",
            Shading::Phong => "phong",
        }
    }

    /// The mode after this one in [`Self::ALL`], the last followed by the first.
    pub fn next(self) -> Self {
        let index = Self::ALL.iter().position(|&mode| mode == self).unwrap_or(0);
        Self::ALL[(index + 1) % Self::ALL.len()]
    }
}

/// The surface an instance is drawn with.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Linear RGB colour in `[0, 1]`, multiplying vertex colours and the texture.
    pub color: Vec3,
    /// An image modulating the colour, read at the mesh's texture coordinates.
    pub texture: Option<Arc<Texture>>,
    /// A second image the texture fades into by the mesh's blend weights, read at the same
    /// coordinates with the same sampler: two textures meet at a border without a seam.
    pub blend: Option<Arc<Texture>>,
    /// How the textures are read.
    pub sampler: Sampler,
    /// Texture repetitions along `u` and `v` (texture coordinates are multiplied by it).
    pub uv_scale: Vec2,
}

impl Material {
    /// A plain untextured colour.
    pub fn colored(color: Vec3) -> Self {
        Self { color, texture: None, blend: None, sampler: Sampler::default(), uv_scale: Vec2::ONE }
    }
}

/// Number of values interpolated across triangles.
pub const VARYINGS: usize = 10;

/// The values a vertex hands to the pixels of its triangles, indexed by the [`slot`] constants.
pub type Varyings = [f32; VARYINGS];

/// Where each value lives in [`Varyings`].
pub mod slot {
    /// Base colour, RGB: material colour times vertex colour (times the light's intensity, as
    /// if nothing shadowed the vertex, for Gouraud shading).
    pub const COLOR: usize = 0;
    /// The light's diffuse term at the vertex (Gouraud with shadows: what shadows take away).
    pub const DIFFUSE: usize = 3;
    /// World-space unit normal, xyz (Phong).
    pub const NORMAL: usize = 4;
    /// Texture coordinates, uv.
    pub const UV: usize = 7;
    /// The weight of the material's blend texture against its texture.
    pub const BLEND: usize = 9;
}

/// How far each value may be off when a triangle is interpolated in screen space instead of
/// perspective-correctly, in the value's own units: a sixteenth of what a pixel can show of
/// it. Colours, diffuse terms and normals reach the image through 8-bit channels; texture
/// coordinates (on `texture`) are measured in texels. Values `pass` does not read may be off
/// by any amount.
pub(crate) fn affine_tolerances(pass: Pass, texture: Option<&Texture>) -> Varyings {
    let texels = texture.map_or(1, |t| t.width().max(t.height())) as f32;
    std::array::from_fn(|index| match index {
        _ if !pass.uses(index) => f32::INFINITY,
        slot::UV..slot::BLEND => 1.0 / (16.0 * texels),
        _ => 1.0 / (16.0 * 255.0),
    })
}

/// The combination a pixel loop is compiled for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Pass {
    pub shading: Shading,
    pub textured: bool,
    pub shadowed: bool,
}

impl Pass {
    /// Whether the pixel needs the varying at `slot`.
    pub const fn uses(self, index: usize) -> bool {
        match index {
            0..3 => true,
            // Gouraud interpolates the colour lit at the vertices, and with shadows the diffuse
            // term too.
            slot::DIFFUSE => matches!(self.shading, Shading::Gouraud) && self.shadowed,
            4..7 => matches!(self.shading, Shading::Phong),
            _ => self.textured,
        }
    }
}

/// A [`Pass`] fixed at compile time: the setup and pixel loops built for it fold its choices
/// away.
pub(crate) trait CompiledPass {
    const PASS: Pass;
}

/// The [`CompiledPass`] of a shading mode number (see [`mode`]), texture and shadows.
pub(crate) struct Compiled<const MODE: u8, const TEXTURED: bool, const SHADOWED: bool>;

impl<const MODE: u8, const TEXTURED: bool, const SHADOWED: bool> CompiledPass for Compiled<MODE, TEXTURED, SHADOWED> {
    const PASS: Pass = Pass {
        shading: match MODE {
            mode::FLAT => Shading::Flat,
            mode::GOURAUD => Shading::Gouraud,
            _ => Shading::Phong,
        },
        textured: TEXTURED,
        shadowed: SHADOWED,
    };
}

/// Shading mode numbers, for [`Compiled`].
pub(crate) mod mode {
    pub const FLAT: u8 = 0;
    pub const GOURAUD: u8 = 1;
    pub const PHONG: u8 = 2;
}

/// Calls `function::<C>(arguments)` with `C` the [`Compiled`] pass equal to `pass`.
macro_rules! with_compiled_pass {
    ($pass:expr, $function:ident $arguments:tt) => {
        $crate::shade::with_compiled_pass!(@modes $pass, $function $arguments, Flat => FLAT, Gouraud => GOURAUD, Phong => PHONG)
    };
    (@modes $pass:expr, $function:ident $arguments:tt, $($shading:ident => $mode:ident),*) => {{
        use $crate::shade::{Compiled, Shading, mode};
        let pass: $crate::shade::Pass = $pass;
        match (pass.shading, pass.textured, pass.shadowed) {
            $(
                (Shading::$shading, false, false) => $function::<Compiled<{ mode::$mode }, false, false>> $arguments,
                (Shading::$shading, true, false) => $function::<Compiled<{ mode::$mode }, true, false>> $arguments,
                (Shading::$shading, false, true) => $function::<Compiled<{ mode::$mode }, false, true>> $arguments,
                (Shading::$shading, true, true) => $function::<Compiled<{ mode::$mode }, true, true>> $arguments,
            )*
        }
    }};
}
pub(crate) use with_compiled_pass;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_interpolate_only_what_they_use() {
        let count = |pass: Pass| (0..VARYINGS).filter(|&i| pass.uses(i)).count();
        let pass = |shading, textured, shadowed| Pass { shading, textured, shadowed };
        assert_eq!(count(pass(Shading::Flat, false, false)), 3);
        assert_eq!(count(pass(Shading::Gouraud, false, false)), 3);
        assert_eq!(count(pass(Shading::Gouraud, false, true)), 4);
        assert_eq!(count(pass(Shading::Phong, true, true)), VARYINGS - 1);
    }
}
