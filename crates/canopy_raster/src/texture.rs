//! Textures and how they are sampled.
//!
//! Texture coordinates run from `(0, 0)` at the image's top-left corner to `(1, 1)` at its
//! bottom-right; texel `(i, j)` covers `[i, i + 1] x [j, j + 1]` in texel units, so its centre is
//! at `((i + 1/2) / width, (j + 1/2) / height)`.
//!
//! A texture holds its image and the image's mip maps, made when the texture is: each level
//! half the size of the one before (rounded down, at least one texel), each texel the mean of
//! the two by two texels it covers, down to a single texel. Trilinear filtering reads the two
//! levels whose texels are nearest in size to the pixel's footprint, which the colour pass
//! works out per pixel from the derivatives of the texture coordinates across the screen; a
//! surface receding towards the horizon then fades into the mean of its texture instead of
//! showing moire.

use crate::lanes::{BYTE_TO_UNIT, bytes_of, floats_of, floor_lanes, lanes_of};

use bevy_math::{Vec2, Vec3, Vec4};
use wide::{i32x4, u32x4};

/// How texels are combined at a sample point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Filter {
    /// The texel containing the point.
    Nearest,
    /// The four texels around the point, weighted by distance.
    Bilinear,
    /// Bilinear reads of the two mip levels nearest in texel size to the pixel's footprint,
    /// blended by where the footprint lies between them.
    #[default]
    Trilinear,
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
    /// The image has more texels than a texture can hold.
    #[error("the image has {0} texels, more than the {MAX_TEXELS} a texture can hold")]
    TooLarge(u64),
}

/// The most texels a texture holds: their indices fit `i32` lanes.
pub const MAX_TEXELS: u64 = i32::MAX as u64;

/// An RGB image and its mip maps.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// The image first, then each mip level, down to one texel.
    levels: Vec<Level>,
}

/// One image of a texture: stored row by row from the top-left texel, eight bits a channel (as
/// the image files hold them), one word per texel with red in the low byte.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    width: u32,
    height: u32,
    texels: Vec<u32>,
}

impl Level {
    /// The next mip level: half the size, rounded down and at least one texel, each texel the
    /// rounded mean of the (up to) two by two texels of this level it covers.
    fn halved(&self) -> Self {
        let (width, height) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let texel = |x: u32, y: u32| {
            let (xs, ys) = ([2 * x, (2 * x + 1).min(self.width - 1)], [2 * y, (2 * y + 1).min(self.height - 1)]);
            let mut sums = [0u32; 3];
            for (x, y) in ys.iter().flat_map(|&y| xs.map(|x| (x, y))) {
                let bytes = self.texels[(y * self.width + x) as usize].to_le_bytes();
                for (sum, byte) in sums.iter_mut().zip(bytes) {
                    *sum += u32::from(byte);
                }
            }
            word(sums.map(|sum| ((sum + 2) / 4) as u8))
        };
        let texels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| texel(x, y)).collect();
        Self { width, height, texels }
    }
}

/// The screen derivatives of texture coordinates at four pixels: `[du/dx, dv/dx, du/dy,
/// dv/dy]`, per pixel along x and along y.
pub(crate) type UvDerivatives = [Vec4; 4];

/// Texel coordinates beyond this many texels from the origin are clamped to it: up to here an
/// `f32` holds every whole number, so wrapping stays exact.
const COORDINATE_LIMIT: f32 = 8_388_608.0;

impl Texture {
    /// A texture of `width` x `height` texels from a function of the texel position; channels
    /// are clamped to `[0, 1]` and rounded to eight bits.
    ///
    /// # Panics
    /// If either size is zero or the texture would hold more than [`MAX_TEXELS`].
    pub fn from_fn(width: u32, height: u32, texel: impl Fn(u32, u32) -> Vec3) -> Self {
        assert!(width > 0 && height > 0, "a texture needs at least one texel");
        assert!(u64::from(width) * u64::from(height) <= MAX_TEXELS, "at most {MAX_TEXELS} texels");
        let byte = |channel: f32| (channel.clamp(0.0, 1.0) * 255.0).round() as u8;
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| word(texel(x, y).to_array().map(byte)))
            .collect();
        Self::with_mip_maps(Level { width, height, texels })
    }

    /// Decodes a PNG or BMP file's bytes (the format is recognised from the bytes). Alpha is
    /// dropped.
    pub fn decode(bytes: &[u8]) -> Result<Self, TextureError> {
        let image = image::load_from_memory(bytes)?.into_rgb8();
        if image.width() == 0 || image.height() == 0 {
            return Err(TextureError::Empty);
        }
        let (width, height) = image.dimensions();
        let count = u64::from(width) * u64::from(height);
        if count > MAX_TEXELS {
            return Err(TextureError::TooLarge(count));
        }
        let texels = image.pixels().map(|p| word(p.0)).collect();
        Ok(Self::with_mip_maps(Level { width, height, texels }))
    }

    /// The texture of `image` and the mip levels made from it.
    fn with_mip_maps(image: Level) -> Self {
        let mut levels = vec![image];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(last.halved());
        }
        Self { levels }
    }

    /// The image, the first level.
    fn image(&self) -> &Level {
        &self.levels[0]
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.image().width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.image().height
    }

    /// The number of levels: the image and its mip maps.
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// Writes the texture as an 8-bit RGB PNG file.
    pub fn save_png(&self, path: &std::path::Path) -> image::ImageResult<()> {
        let bytes: Vec<u8> = self
            .image()
            .texels
            .iter()
            .flat_map(|w| <[u8; 3]>::try_from(&w.to_le_bytes()[..3]).unwrap_or([0; 3]))
            .collect();
        image::save_buffer_with_format(
            path,
            &bytes,
            self.width(),
            self.height(),
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
    }

    /// The colour at texture coordinates `uv`, read from the image itself (level of detail 0).
    pub fn sample(&self, uv: Vec2, sampler: Sampler) -> Vec3 {
        self.sample_at_level(uv, 0.0, sampler)
    }

    /// The colour at texture coordinates `uv` for a pixel whose footprint spans `2^lod` texels
    /// of the image: trilinear filtering reads the mip levels around `lod`, the other filters
    /// the image.
    pub fn sample_at_level(&self, uv: Vec2, lod: f32, sampler: Sampler) -> Vec3 {
        let [r, g, b] = self.sample_lanes(Vec4::splat(uv.x), Vec4::splat(uv.y), Vec4::splat(lod), sampler);
        Vec3::new(r.x, g.x, b.x)
    }

    /// The level of detail of four pixels from the derivatives of their texture coordinates
    /// across the screen: the base-2 logarithm of the longer side of the pixel's footprint in
    /// texels of the image, as graphics hardware takes it.
    ///
    /// The logarithm is the piecewise-linear one read from the float's bits (exact at powers
    /// of two, at most 0.09 low between them): it moves the blend between two levels by less
    /// than a tenth, and takes no time beside the texel reads.
    #[inline(always)]
    pub(crate) fn lod_lanes(&self, [du_dx, dv_dx, du_dy, dv_dy]: UvDerivatives) -> Vec4 {
        let (width, height) = (self.width() as f32, self.height() as f32);
        let squared = |du: Vec4, dv: Vec4| (du * width) * (du * width) + (dv * height) * (dv * height);
        let footprint = squared(du_dx, dv_dx).max(squared(du_dy, dv_dy));
        let bits: i32x4 = bytemuck::cast(lanes_of(footprint));
        // The bits of a positive float over 2^23, less the exponent's bias, approximate its
        // base-2 logarithm; half of it is the logarithm of the square root.
        (floats_of(bits) * (1.0 / 8_388_608.0) - 127.0) * 0.5
    }

    /// [`Texture::sample`] at four points at once, given as lanes of `u` and of `v`, with each
    /// point's level of detail (see [`Texture::lod_lanes`], read by trilinear filtering only):
    /// the red, green and blue lanes of their colours. Each point reads the texels its lane's
    /// coordinates lead to, four lanes' arithmetic at a time; non-finite coordinates (a
    /// degenerate interpolation) read texel `(0, 0)`.
    #[inline(always)]
    pub(crate) fn sample_lanes(&self, u: Vec4, v: Vec4, lod: Vec4, sampler: Sampler) -> [Vec4; 3] {
        let finite = u.is_finite_mask() & v.is_finite_mask();
        let (u, v) = (Vec4::select(finite, u, Vec4::ZERO), Vec4::select(finite, v, Vec4::ZERO));
        match sampler.filter {
            Filter::Nearest => {
                let level = self.image();
                let (x, y) = level.in_texels(u, v);
                level.texels_at(
                    level.row_start(level.wrap_y(floor_lanes(y), sampler.address))
                        + level.wrap_x(floor_lanes(x), sampler.address),
                )
            }
            Filter::Bilinear => self.image().bilinear(u, v, sampler.address),
            Filter::Trilinear => self.trilinear(u, v, lod, sampler.address),
        }
    }

    /// Bilinear reads of the levels around each lane's `lod`, blended: most runs of pixels
    /// share their pair of levels, and a run spanning more reads each level it touches.
    #[inline(always)]
    fn trilinear(&self, u: Vec4, v: Vec4, lod: Vec4, address: Address) -> [Vec4; 3] {
        let deepest = (self.levels.len() - 1) as f32;
        // A level that is not a number (a degenerate derivative) reads the image.
        let lod = Vec4::select(lod.is_nan_mask(), Vec4::ZERO, lod).clamp(Vec4::ZERO, Vec4::splat(deepest));
        let lower = floats_of(floor_lanes(lod));
        let upper_weight = lod - lower;
        let (first, last) =
            (lower.min_element() as usize, (lower.max_element() as usize + 1).min(self.levels.len() - 1));
        let mut rgb = [Vec4::ZERO; 3];
        for (index, level) in self.levels.iter().enumerate().take(last + 1).skip(first) {
            let at = Vec4::splat(index as f32);
            let weight = Vec4::select(lower.cmpeq(at), Vec4::ONE - upper_weight, Vec4::ZERO)
                + Vec4::select((lower + 1.0).cmpeq(at), upper_weight, Vec4::ZERO);
            if weight.cmpeq(Vec4::ZERO).all() {
                continue;
            }
            let texels = level.bilinear(u, v, address);
            for (c, texel) in rgb.iter_mut().zip(texels) {
                *c += texel * weight;
            }
        }
        rgb
    }
}

impl Level {
    /// Coordinates in this level's texel units, within the limit.
    #[inline(always)]
    fn in_texels(&self, u: Vec4, v: Vec4) -> (Vec4, Vec4) {
        let limit = Vec4::splat(COORDINATE_LIMIT);
        ((u * self.width as f32).clamp(-limit, limit), (v * self.height as f32).clamp(-limit, limit))
    }

    #[inline(always)]
    fn wrap_x(&self, whole: i32x4, address: Address) -> i32x4 {
        wrap(whole, self.width, address)
    }

    #[inline(always)]
    fn wrap_y(&self, whole: i32x4, address: Address) -> i32x4 {
        wrap(whole, self.height, address)
    }

    /// The four texels around each point, weighted by distance.
    #[inline(always)]
    fn bilinear(&self, u: Vec4, v: Vec4, address: Address) -> [Vec4; 3] {
        let (x, y) = self.in_texels(u, v);
        let (x, y) = (x - 0.5, y - 0.5);
        let (left, top) = (floor_lanes(x), floor_lanes(y));
        let (right_weight, down_weight) = (x - floats_of(left), y - floats_of(top));
        let (x0, x1) = (self.wrap_x(left, address), self.wrap_x(left + 1, address));
        // Each row's first texel, once for both of its columns.
        let (row0, row1) = (self.row_start(self.wrap_y(top, address)), self.row_start(self.wrap_y(top + 1, address)));
        let lerp = |a: [Vec4; 3], b: [Vec4; 3], t: Vec4| {
            let inverse = Vec4::ONE - t;
            [a[0] * inverse + b[0] * t, a[1] * inverse + b[1] * t, a[2] * inverse + b[2] * t]
        };
        let upper = lerp(self.texels_at(row0 + x0), self.texels_at(row0 + x1), right_weight);
        let lower = lerp(self.texels_at(row1 + x0), self.texels_at(row1 + x1), right_weight);
        lerp(upper, lower, down_weight)
    }

    /// The index of the first texel of each of the rows `y`, each inside the level.
    #[inline(always)]
    fn row_start(&self, y: i32x4) -> i32x4 {
        // Below `MAX_TEXELS` every index fits an `i32`.
        y * i32x4::splat(self.width as i32)
    }

    /// The red, green and blue lanes of the texels at `index` (row by row), one per lane, each
    /// inside the level.
    #[inline(always)]
    fn texels_at(&self, index: i32x4) -> [Vec4; 3] {
        let [a, b, c, d] = index.to_array().map(|i| i as usize);
        let words = u32x4::new([self.texels[a], self.texels[b], self.texels[c], self.texels[d]]);
        [bytes_of(words, 0) * BYTE_TO_UNIT, bytes_of(words, 8) * BYTE_TO_UNIT, bytes_of(words, 16) * BYTE_TO_UNIT]
    }
}

/// The texel word holding `rgb`.
fn word(rgb: [u8; 3]) -> u32 {
    u32::from_le_bytes([rgb[0], rgb[1], rgb[2], 0xff])
}

/// Whole texel coordinates (within the limit, or one past it) mapped into `0..size` by the
/// addressing rule, four at a time.
#[inline(always)]
fn wrap(whole: i32x4, size: u32, address: Address) -> i32x4 {
    let last = i32x4::splat(size as i32 - 1);
    match address {
        // Two's complement keeps the low bits of a whole number the same modulo a power of
        // two, negative or not.
        Address::Repeat if size.is_power_of_two() => whole & last,
        Address::Repeat => {
            // Exact in floats: every value stays below 2^24. The rounded quotient may be one
            // off either way, which the two corrections undo; the clamp only keeps textures
            // wider than the limit inside themselves.
            let (whole, size) = (floats_of(whole), size as f32);
            let wrapped = whole - (whole / size).floor() * size;
            let wrapped = Vec4::select(wrapped.cmplt(Vec4::ZERO), wrapped + size, wrapped);
            let wrapped = Vec4::select(wrapped.cmpge(Vec4::splat(size)), wrapped - size, wrapped);
            floor_lanes(wrapped).min(last).max(i32x4::ZERO)
        }
        Address::Clamp => whole.min(last).max(i32x4::ZERO),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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
    fn mip_levels_halve_down_to_one_texel_and_keep_the_mean() {
        // Columns of black and white: every level above the last but one keeps their mean.
        let stripes = Texture::from_fn(8, 2, |x, _| Vec3::splat((x % 2) as f32));
        let sizes: Vec<(u32, u32)> = stripes.levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(8, 2), (4, 1), (2, 1), (1, 1)]);
        for level in &stripes.levels[1..] {
            assert!(level.texels.iter().all(|&t| t.to_le_bytes()[..3] == [128; 3]), "{level:?}");
        }
        // Odd sizes round down and the last column or row is shared by the texels beside it.
        let odd = Texture::from_fn(5, 3, |x, y| Vec3::new(x as f32 / 4.0, y as f32 / 2.0, 0.0));
        let sizes: Vec<(u32, u32)> = odd.levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(5, 3), (2, 1), (1, 1)]);
        assert_eq!(Texture::from_fn(1, 1, |_, _| Vec3::ONE).levels(), 1);
    }

    #[test]
    fn trilinear_reads_the_image_up_close_and_the_mean_far_off() {
        let checker = Texture::from_fn(16, 16, |x, y| Vec3::splat(((x + y) % 2) as f32));
        let trilinear = Sampler { filter: Filter::Trilinear, address: Address::Repeat };
        let centre = Vec2::new(0.5 / 16.0, 0.5 / 16.0);
        // At level 0 and below (magnification) a texel centre reads the texel itself.
        assert_eq!(checker.sample_at_level(centre, 0.0, trilinear), Vec3::ZERO);
        assert_eq!(checker.sample_at_level(centre, -3.0, trilinear), Vec3::ZERO);
        // From level 1 up every texel is the mean; halfway to level 1 blends the two.
        let grey = 128.0 / 255.0;
        for lod in [1.0, 2.5, 4.0, 40.0, f32::INFINITY] {
            // (An endless footprint reads the last level; one that is not a number the image.)
            let far = checker.sample_at_level(centre, lod, trilinear);
            assert!(far.distance(Vec3::splat(grey)) < 1e-6, "level {lod}: {far}");
        }
        let half = checker.sample_at_level(centre, 0.5, trilinear);
        assert!(half.distance(Vec3::splat(grey / 2.0)) < 1e-6, "{half}");
        // The other filters ignore the level.
        assert_eq!(checker.sample_at_level(centre, 4.0, NEAREST_REPEAT), Vec3::ZERO);
    }

    #[test]
    fn the_level_of_detail_is_the_logarithm_of_the_footprint() {
        let texture = Texture::from_fn(256, 64, |_, _| Vec3::ONE);
        let lod = |du_dx: f32, dv_dx: f32, du_dy: f32, dv_dy: f32| {
            texture.lod_lanes([du_dx, dv_dx, du_dy, dv_dy].map(Vec4::splat)).x
        };
        // One texel a pixel, four, and a footprint of 16 texels along v.
        assert!(lod(1.0 / 256.0, 0.0, 0.0, 1.0 / 64.0).abs() < 1e-4);
        assert!((lod(4.0 / 256.0, 0.0, 0.0, 1.0 / 64.0) - 2.0).abs() < 1e-4);
        assert!((lod(1.0 / 256.0, 0.0, 0.0, 16.0 / 64.0) - 4.0).abs() < 1e-4);
        // Between powers of two the logarithm is within 0.09 of the true one.
        for texels in [1.3f32, 3.0, 5.7, 11.0, 1000.0] {
            let approximate = lod(texels / 256.0, 0.0, 0.0, 0.0);
            assert!((approximate - texels.log2()).abs() < 0.09, "{texels}: {approximate}");
        }
    }

    #[test]
    fn decoding_png_and_bmp_gives_the_same_texels() {
        let image = image::RgbImage::from_fn(3, 2, |x, y| image::Rgb([x as u8 * 100, y as u8 * 200, 7]));
        for format in [image::ImageFormat::Png, image::ImageFormat::Bmp] {
            let mut bytes = std::io::Cursor::new(Vec::new());
            image.write_to(&mut bytes, format).unwrap();
            let texture = Texture::decode(bytes.get_ref()).unwrap();
            assert_eq!((texture.width(), texture.height()), (3, 2));
            let last = Vec2::new(2.5 / 3.0, 1.5 / 2.0);
            assert_eq!((texture.sample(last, NEAREST_CLAMP) * 255.0).round(), Vec3::new(200.0, 200.0, 7.0));
        }
        assert!(matches!(Texture::decode(b"not an image"), Err(TextureError::Decode(_))));
    }

    #[test]
    fn extreme_coordinates_read_inside_the_texture() {
        // Three by five texels, each a colour of its own, a quarter apart in some channel
        // (stored to within half of 1/255).
        let colour = |x: u32, y: u32| Vec3::new(x as f32 / 4.0, y as f32 / 4.0, 1.0);
        let texture = Texture::from_fn(3, 5, colour);
        let texels: Vec<Vec3> = (0..5).flat_map(|y| (0..3).map(move |x| colour(x, y))).collect();
        let huge = [f32::MAX, -f32::MAX, 1e30, -1e30, 8_388_607.5, -8_388_609.0];
        for filter in [Filter::Nearest, Filter::Bilinear, Filter::Trilinear] {
            for address in [Address::Repeat, Address::Clamp] {
                let sampler = Sampler { filter, address };
                for (u, v) in huge.iter().flat_map(|&u| huge.map(|v| (u, v))) {
                    let sampled = texture.sample(Vec2::new(u, v), sampler);
                    let blended = sampled.cmpge(Vec3::ZERO).all() && sampled.cmple(Vec3::ONE).all();
                    assert!(blended, "{filter:?} {address:?} at ({u}, {v}): {sampled}");
                    if filter == Filter::Nearest {
                        assert!(texels.iter().any(|t| t.distance(sampled) < 0.01), "({u}, {v}): {sampled}");
                    }
                }
                // Non-finite coordinates read the first texel.
                for (u, v) in [(f32::NAN, 0.5), (0.5, f32::INFINITY), (f32::NEG_INFINITY, f32::NAN)] {
                    let sampled = texture.sample(Vec2::new(u, v), Sampler { filter: Filter::Nearest, address });
                    assert!(sampled.distance(colour(0, 0)) < 0.01, "({u}, {v}): {sampled}");
                }
            }
        }
    }

    proptest! {
        /// Four points read at once each find the texel that whole-number arithmetic on their
        /// coordinates gives, for sizes that are powers of two and sizes that are not.
        #[test]
        fn lanes_repeat_and_clamp_like_whole_numbers(
            us in prop::array::uniform4(-1e4f32..1e4),
            vs in prop::array::uniform4(-1e4f32..1e4),
            width in 1u32..9,
            height in 1u32..9,
        ) {
            // Each texel's red and green channels tell its column and row.
            let texture = Texture::from_fn(width, height, |x, y| Vec3::new(x as f32, y as f32, 0.0) / 8.0);
            for address in [Address::Repeat, Address::Clamp] {
                let sampler = Sampler { filter: Filter::Nearest, address };
                let [red, green, _] = texture.sample_lanes(Vec4::from_array(us), Vec4::from_array(vs), Vec4::ZERO, sampler);
                let expected = |t: f32, size: u32| {
                    let whole = (t * size as f32).floor() as i64;
                    match address {
                        Address::Repeat => whole.rem_euclid(i64::from(size)),
                        Address::Clamp => whole.clamp(0, i64::from(size) - 1),
                    }
                };
                for lane in 0..4 {
                    prop_assert_eq!((red[lane] * 8.0).round() as i64, expected(us[lane], width));
                    prop_assert_eq!((green[lane] * 8.0).round() as i64, expected(vs[lane], height));
                }
            }
        }
    }
}
