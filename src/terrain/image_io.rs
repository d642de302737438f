//! Heightmaps as grayscale images: read from PNG (8 or 16 bit) or BMP, brightness as height in
//! `[0, 1]`; written as 8-bit BMP (the source's format), 8-bit or 16-bit PNG. A 16-bit file read
//! and written again gives the same samples.

use super::heightmap::{Heightmap, MAX_SIDE};
use image::{ColorType, DynamicImage, ImageFormat, ImageReader, Limits};
use std::io::Cursor;
use std::path::Path;

/// Why an image is no heightmap.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// Not a PNG or BMP the decoder can read.
    #[error("not a readable PNG or BMP image: {0}")]
    Decode(#[from] image::ImageError),
    /// A side is zero or beyond [`MAX_SIDE`].
    #[error("the image is {0} x {1} pixels; a heightmap's sides are 1 to {MAX_SIDE} samples")]
    Size(u32, u32),
    /// The image has colour.
    #[error("the image has colour (pixel ({0}, {1}) is not gray); a heightmap is a grayscale image")]
    NotGray(u32, u32),
    /// The file could not be written.
    #[error("{0}")]
    Write(String),
}

/// How a heightmap is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// 8-bit grayscale BMP.
    Bmp8,
    /// 8-bit grayscale PNG.
    Png8,
    /// 16-bit grayscale PNG.
    Png16,
}

impl Encoding {
    /// The encoding for a file name (`.bmp` is 8-bit; `.png` takes `bits`, 8 or 16), or why
    /// none fits.
    pub fn for_path(path: &Path, bits: u8) -> Result<Self, String> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match (extension.as_deref(), bits) {
            (Some("png"), 8) => Ok(Encoding::Png8),
            (Some("png"), 16) => Ok(Encoding::Png16),
            (Some("bmp"), 8) => Ok(Encoding::Bmp8),
            (Some("bmp"), _) => Err("a BMP heightmap has 8 bits a sample".into()),
            (Some("png"), _) => Err(format!("a PNG heightmap has 8 or 16 bits a sample, not {bits}")),
            _ => Err(format!("{}: expected a .png or .bmp file name", path.display())),
        }
    }
}

/// The heightmap in an image file's bytes: each pixel's gray level over its largest value.
pub fn decode(bytes: &[u8]) -> Result<Heightmap, ImageError> {
    let mut reader = ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(image::ImageError::IoError)?;
    let mut limits = Limits::default();
    (limits.max_image_width, limits.max_image_height) = (Some(MAX_SIDE), Some(MAX_SIDE));
    reader.limits(limits);
    let (width, height) = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(image::ImageError::IoError)?
        .into_dimensions()?;
    if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
        return Err(ImageError::Size(width, height));
    }
    let image = reader.decode()?;
    let values = match image.color() {
        ColorType::L16 | ColorType::La16 => {
            image.into_luma16().into_raw().into_iter().map(|v| f32::from(v) / 65535.0).collect()
        }
        ColorType::L8 | ColorType::La8 => {
            image.into_luma8().into_raw().into_iter().map(|v| f32::from(v) / 255.0).collect()
        }
        // A BMP's palette of grays decodes as colour: accepted when every pixel is gray.
        _ => {
            let rgb = image.into_rgb16();
            if let Some((x, y, _)) = rgb.enumerate_pixels().find(|(_, _, p)| p.0[0] != p.0[1] || p.0[1] != p.0[2]) {
                return Err(ImageError::NotGray(x, y));
            }
            rgb.pixels().map(|p| f32::from(p.0[0]) / 65535.0).collect()
        }
    };
    Heightmap::from_values(width, height, values).ok_or(ImageError::Size(width, height))
}

/// The heightmap as an image file's bytes; heights are clamped to `[0, 1]` and rounded to the
/// encoding's levels.
pub fn encode(map: &Heightmap, encoding: Encoding) -> Result<Vec<u8>, ImageError> {
    let (width, height) = (map.width(), map.height());
    let level = |h: f32, top: f32| (h.clamp(0.0, 1.0) * top).round();
    let image = match encoding {
        Encoding::Png16 => DynamicImage::ImageLuma16(
            image::ImageBuffer::from_raw(
                width,
                height,
                map.values().iter().map(|&h| level(h, 65535.0) as u16).collect(),
            )
            .ok_or(ImageError::Size(width, height))?,
        ),
        Encoding::Png8 | Encoding::Bmp8 => DynamicImage::ImageLuma8(
            image::ImageBuffer::from_raw(width, height, map.values().iter().map(|&h| level(h, 255.0) as u8).collect())
                .ok_or(ImageError::Size(width, height))?,
        ),
    };
    let format = if encoding == Encoding::Bmp8 { ImageFormat::Bmp } else { ImageFormat::Png };
    let mut bytes = Cursor::new(Vec::new());
    image.write_to(&mut bytes, format)?;
    Ok(bytes.into_inner())
}

/// Writes the heightmap to `path` in `encoding`.
pub fn save(map: &Heightmap, path: &Path, encoding: Encoding) -> Result<(), ImageError> {
    let bytes = encode(map, encoding)?;
    std::fs::write(path, bytes).map_err(|e| ImageError::Write(format!("{}: {e}", path.display())))
}

/// How many heights lie outside `[0, 1]` (and are clamped when written).
pub fn outside_unit(map: &Heightmap) -> usize {
    map.values().iter().filter(|h| !(0.0..=1.0).contains(*h)).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(width: u32, height: u32) -> Heightmap {
        Heightmap::from_fn(width, height, |x, z| (x + z * width) as f32 / (width * height - 1) as f32).unwrap()
    }

    #[test]
    fn sixteen_bit_round_trips_are_lossless() {
        let map = decode(&encode(&ramp(37, 23), Encoding::Png16).unwrap()).unwrap();
        let bytes = encode(&map, Encoding::Png16).unwrap();
        let again = decode(&bytes).unwrap();
        assert_eq!(again, map);
        assert_eq!(encode(&again, Encoding::Png16).unwrap(), bytes);
        // 16 bits keep heights to within half a level.
        let original = ramp(37, 23);
        for (a, b) in original.values().iter().zip(map.values()) {
            assert!((a - b).abs() <= 0.5 / 65535.0 + 1e-7);
        }
    }

    #[test]
    fn eight_bit_png_and_bmp_keep_256_levels() {
        let original = ramp(16, 16);
        for encoding in [Encoding::Png8, Encoding::Bmp8] {
            let map = decode(&encode(&original, encoding).unwrap()).unwrap();
            assert_eq!((map.width(), map.height()), (16, 16));
            for (a, b) in original.values().iter().zip(map.values()) {
                assert!((a - b).abs() <= 0.5 / 255.0 + 1e-6, "{encoding:?}: {a} vs {b}");
            }
            assert_eq!(decode(&encode(&map, encoding).unwrap()).unwrap(), map, "{encoding:?}");
        }
    }

    #[test]
    fn colour_and_garbage_are_refused() {
        let mut colour = image::RgbImage::new(3, 3);
        colour.put_pixel(1, 2, image::Rgb([10, 20, 30]));
        let mut bytes = Cursor::new(Vec::new());
        colour.write_to(&mut bytes, ImageFormat::Png).unwrap();
        assert!(matches!(decode(bytes.get_ref()), Err(ImageError::NotGray(1, 2))));
        assert!(matches!(decode(b"no image"), Err(ImageError::Decode(_))));
        let large = image::GrayImage::new(MAX_SIDE + 1, 1);
        let mut bytes = Cursor::new(Vec::new());
        large.write_to(&mut bytes, ImageFormat::Png).unwrap();
        assert!(decode(bytes.get_ref()).is_err());
    }

    #[test]
    fn file_names_choose_the_encoding() {
        assert_eq!(Encoding::for_path(Path::new("a.PNG"), 16), Ok(Encoding::Png16));
        assert_eq!(Encoding::for_path(Path::new("a.bmp"), 8), Ok(Encoding::Bmp8));
        assert!(Encoding::for_path(Path::new("a.bmp"), 16).is_err());
        assert!(Encoding::for_path(Path::new("a.jpg"), 8).is_err());
    }
}
