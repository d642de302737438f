//! Textures and how they are sampled.
//!
//! Texture coordinates run from `(0, 0)` at the image's top-left corner to `(1, 1)` at its
//! bottom-right; texel `(i, j)` covers `[i, i + 1] x [j, j + 1]` in texel units, so its centre is
//! at `((i + 1/2) / width, (j + 1/2) / height)`.

use bevy_math::{Vec2, Vec3};

/// How texels are combined at a sample point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Filter {
    /// The texel containing the point.
    Nearest,
    /// The four texels around the point, weighted by distance.
    #[default]
    Bilinear,
}

/// What coordinates outside `[0, 1]` read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Address {
    /// The texture tiles the plane.
    #[default]
    Repeat,
    /// The edge texels extend outwards.
    Clamp,
}

/// How a texture is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sampler {
    /// Texel filtering.
    pub filter: Filter,
    /// Addressing outside the unit square.
    pub address: Address,
}

/// Why an image could not become a texture.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The bytes are not a PNG or BMP image the decoder understands.
    #[error("not a readable PNG or BMP image: {0}")]
    Decode(#[from] image::ImageError),
    /// The image has no pixels.
    #[error("the image is empty")]
    Empty,
}

/// An RGB image with channels in `[0, 1]`, stored row by row from the top-left texel.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
}

impl Texture {
    /// A texture of `width` x `height` texels from a function of the texel position.
    ///
    /// # Panics
    /// If either size is zero.
    pub fn from_fn(width: u32, height: u32, texel: impl Fn(u32, u32) -> Vec3) -> Self {
        assert!(width > 0 && height > 0, "a texture needs at least one texel");
        let texels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| texel(x, y)).collect();
        Self { width, height, texels }
    }

    /// Decodes a PNG or BMP file's bytes (the format is recognised from the bytes). Alpha is
    /// dropped.
    pub fn decode(bytes: &[u8]) -> Result<Self, TextureError> {
        let image = image::load_from_memory(bytes)?.into_rgb8();
        if image.width() == 0 || image.height() == 0 {
            return Err(TextureError::Empty);
        }
        let (width, height) = image.dimensions();
        let texels = image.pixels().map(|p| Vec3::from_array(p.0.map(f32::from)) / 255.0).collect();
        Ok(Self { width, height, texels })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texel in column `x`, row `y`.
    fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.texels[(y * self.width + x) as usize]
    }

    /// The colour at texture coordinates `uv`.
    pub fn sample(&self, uv: Vec2, sampler: Sampler) -> Vec3 {
        let size = Vec2::new(self.width as f32, self.height as f32);
        // Texel units; non-finite coordinates (a degenerate interpolation) read texel 0.
        let p = if uv.is_finite() { uv * size } else { Vec2::ZERO };
        match sampler.filter {
            Filter::Nearest => {
                let x = wrap(p.x.floor(), self.width, sampler.address);
                let y = wrap(p.y.floor(), self.height, sampler.address);
                self.texel(x, y)
            }
            Filter::Bilinear => {
                let p = p - 0.5;
                let base = p.floor();
                let t = p - base;
                let [x0, x1] = [base.x, base.x + 1.0].map(|x| wrap(x, self.width, sampler.address));
                let [y0, y1] = [base.y, base.y + 1.0].map(|y| wrap(y, self.height, sampler.address));
                let top = self.texel(x0, y0).lerp(self.texel(x1, y0), t.x);
                let bottom = self.texel(x0, y1).lerp(self.texel(x1, y1), t.x);
                top.lerp(bottom, t.y)
            }
        }
    }
}

/// Maps a whole texel coordinate into `0..size` by the addressing rule.
fn wrap(coordinate: f32, size: u32, address: Address) -> u32 {
    // Large coordinates saturate in the cast; both rules keep the result in range anyway.
    let i = coordinate as i64;
    match address {
        Address::Repeat => i.rem_euclid(size as i64) as u32,
        Address::Clamp => i.clamp(0, size as i64 - 1) as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 2 texture: black, red / green, blue.
    fn quad() -> Texture {
        Texture::from_fn(2, 2, |x, y| match (x, y) {
            (0, 0) => Vec3::ZERO,
            (1, 0) => Vec3::X,
            (0, 1) => Vec3::Y,
            _ => Vec3::Z,
        })
    }

    const NEAREST_REPEAT: Sampler = Sampler { filter: Filter::Nearest, address: Address::Repeat };
    const NEAREST_CLAMP: Sampler = Sampler { filter: Filter::Nearest, address: Address::Clamp };
    const BILINEAR_CLAMP: Sampler = Sampler { filter: Filter::Bilinear, address: Address::Clamp };

    #[test]
    fn nearest_reads_the_texel_under_the_point() {
        let t = quad();
        assert_eq!(t.sample(Vec2::new(0.75, 0.25), NEAREST_REPEAT), Vec3::X);
        assert_eq!(t.sample(Vec2::new(0.25, 0.75), NEAREST_REPEAT), Vec3::Y);
    }

    #[test]
    fn repeat_tiles_and_clamp_extends_the_edge() {
        let t = quad();
        assert_eq!(t.sample(Vec2::new(1.75, -0.75), NEAREST_REPEAT), Vec3::X);
        assert_eq!(t.sample(Vec2::new(5.0, -3.0), NEAREST_CLAMP), Vec3::X);
        assert_eq!(t.sample(Vec2::new(-5.0, 9.0), NEAREST_CLAMP), Vec3::Y);
    }

    #[test]
    fn bilinear_blends_neighbours_and_hits_texel_centres_exactly() {
        let t = quad();
        assert_eq!(t.sample(Vec2::new(0.75, 0.75), BILINEAR_CLAMP), Vec3::Z);
        let middle = t.sample(Vec2::new(0.5, 0.5), BILINEAR_CLAMP);
        assert!(middle.distance(Vec3::splat(0.25)) < 1e-6, "{middle}");
        // Halfway between the black and red texel centres.
        let edge = t.sample(Vec2::new(0.5, 0.25), BILINEAR_CLAMP);
        assert!(edge.distance(Vec3::new(0.5, 0.0, 0.0)) < 1e-6, "{edge}");
    }

    #[test]
    fn decoding_png_and_bmp_gives_the_same_texels() {
        let image = image::RgbImage::from_fn(3, 2, |x, y| image::Rgb([x as u8 * 100, y as u8 * 200, 7]));
        for format in [image::ImageFormat::Png, image::ImageFormat::Bmp] {
            let mut bytes = std::io::Cursor::new(Vec::new());
            image.write_to(&mut bytes, format).unwrap();
            let texture = Texture::decode(bytes.get_ref()).unwrap();
            assert_eq!((texture.width(), texture.height()), (3, 2));
            assert_eq!(texture.texel(2, 1), Vec3::new(200.0, 200.0, 7.0) / 255.0);
        }
        assert!(matches!(Texture::decode(b"not an image"), Err(TextureError::Decode(_))));
    }
}
