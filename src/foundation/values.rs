//! Checked value types for scene files: each refuses what makes no sense where it is used and
//! says what was expected, so that `serde_yaml` reports the error at the offending value. And
//! the few conversions every domain shares: degrees wrapped into one turn, colours as the
//! rasterizer takes them, the first free numbered file name.

use bevy::color::Srgba;
use bevy::math::Vec3;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::fmt;

/// Largest magnitude accepted for lengths and coordinates, in metres: far beyond any scene,
/// small enough that `f32` arithmetic on it stays meaningful.
pub const MAX_METRES: f64 = 1.0e6;

/// The largest angle a scene file holds, either way, degrees: one hundred turns.
pub const MAX_DEGREES: f64 = 36_000.0;

/// A number as a message shows it: plainly, or in exponent form when very large or small.
pub fn shown(value: f64) -> String {
    if value != 0.0 && value.is_finite() && !(1e-6..1e9).contains(&value.abs()) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

/// Defines a number newtype whose deserializer accepts only finite numbers passing a check.
/// The check runs inside the deserializer, so errors point at the offending value.
macro_rules! checked_number {
    ($(#[$doc:meta])* $name:ident($inner:ty), $expected:literal, |$v:ident| $valid:expr) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct $name(pub $inner);

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                self.0.serialize(serializer)
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                struct NumberVisitor;

                impl<'de> serde::de::Visitor<'de> for NumberVisitor {
                    type Value = $name;

                    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                        f.write_str($expected)
                    }

                    fn visit_f64<E: serde::de::Error>(self, $v: f64) -> Result<$name, E> {
                        if $v.is_finite() && $valid {
                            Ok($name($v as $inner))
                        } else {
                            Err(E::custom(format_args!(
                                "expected {}, found {}",
                                $expected,
                                $crate::foundation::values::shown($v)
                            )))
                        }
                    }

                    fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<$name, E> {
                        self.visit_f64(v as f64)
                    }

                    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<$name, E> {
                        self.visit_f64(v as f64)
                    }
                }

                deserializer.deserialize_f64(NumberVisitor)
            }
        }
    };
}
pub(crate) use checked_number;

checked_number!(
    /// A coordinate or signed length in metres, finite and within [`MAX_METRES`].
    Metres(f32),
    "a coordinate in metres between -1e6 and 1e6",
    |v| v.abs() <= MAX_METRES
);
checked_number!(
    /// A positive length in metres, at most [`MAX_METRES`].
    PositiveMetres(f32),
    "a length in metres greater than 0 and at most 1e6",
    |v| v > 0.0 && v <= MAX_METRES
);
checked_number!(
    /// An angle in degrees, finite and within one hundred turns either way.
    Degrees(f32),
    "an angle in degrees between -36000 and 36000",
    |v| v.abs() <= MAX_DEGREES
);
checked_number!(
    /// A vertical field of view in degrees, strictly between 0 and 180.
    FieldOfView(f32),
    "a field of view in degrees greater than 0 and less than 180",
    |v| v > 0.0 && v < 180.0
);
checked_number!(
    /// A radius in metres: positive and at most 100 m.
    Radius(f32),
    "a radius in metres greater than 0 and at most 100",
    |v| v > 0.0 && v <= 100.0
);

checked_number!(
    /// A length along a branch in metres: positive and at most 1000 m.
    Length(f32),
    "a length in metres greater than 0 and at most 1000",
    |v| v > 0.0 && v <= 1000.0
);

checked_number!(
    /// How many times a texture repeats across its surface.
    Repeats(f32),
    "a number of repetitions greater than 0 and at most 10000",
    |v| v > 0.0 && v <= 10_000.0
);

/// Whether `path` is relative and stays inside the folder it is relative to (no `..`, no root).
pub(crate) fn inside_folder(path: &str) -> bool {
    !path.is_empty()
        && std::path::Path::new(path)
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir))
}

/// What files a [`FolderFile`] may name: their extensions and how a message describes them.
pub trait FileType: 'static {
    /// The accepted extensions, lower case with the dot; a file's extension is compared
    /// ignoring case, so `bark.PNG` is a `.png` file.
    const EXTENSIONS: &'static [&'static str];
    /// What a valid value is, for messages: "a .png or .bmp file in the scene's folder".
    const EXPECTING: &'static str;
    /// The files named in the "expected ..." of an error: "a .png or .bmp file".
    const FILES: &'static str;
}

/// A file next to the scene: a relative path that stays inside the scene's folder (no `..`,
/// no root) with one of `T`'s extensions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FolderFile<T> {
    /// The path as written, relative to the scene's folder.
    pub path: String,
    _type: std::marker::PhantomData<T>,
}

impl<T: FileType> FolderFile<T> {
    /// A checked path, or what was expected.
    pub fn new(path: &str) -> Result<Self, String> {
        let lower = path.to_ascii_lowercase();
        if inside_folder(path) && T::EXTENSIONS.iter().any(|extension| lower.ends_with(extension)) {
            Ok(Self { path: path.to_string(), _type: std::marker::PhantomData })
        } else {
            Err(format!("expected {} inside the scene's folder (relative, without `..`), found \"{path}\"", T::FILES))
        }
    }
}

impl<T> serde::Serialize for FolderFile<T> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.path)
    }
}

impl<'de, T: FileType> Deserialize<'de> for FolderFile<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        crate::foundation::yaml::deserialize_str_with(deserializer, T::EXPECTING, Self::new)
    }
}

/// An angle in degrees brought into `[-180, 180)`.
pub fn wrap_degrees(angle: f32) -> f32 {
    (angle + 180.0).rem_euclid(360.0) - 180.0
}

/// The sRGB channels of `color`, each clamped to `[0, 1]`, as the rasterizer's material and
/// vertex colours take them (it shades in these values as they are, without converting them
/// to linear light).
pub fn srgb_channels(color: Srgba) -> Vec3 {
    Vec3::new(color.red, color.green, color.blue).clamp(Vec3::ZERO, Vec3::ONE)
}

/// The first of `candidate(1)`, `candidate(2)`, ... that names no existing file: numbered
/// outputs never overwrite an earlier one.
pub fn first_free_path(candidate: impl Fn(u32) -> std::path::PathBuf) -> std::path::PathBuf {
    (1..).map(candidate).find(|path| !path.exists()).expect("an unbounded range always yields a free name")
}

checked_number!(
    /// A fraction in `[0, 1]`: a coefficient or a colour channel.
    UnitInterval(f32),
    "a number from 0 to 1",
    |v| (0.0..=1.0).contains(&v)
);

/// Deserializes `[x, y, z]` into a [`Vec3`] through the checked type `T`.
fn vec3_from<'de, T, D>(deserializer: D) -> Result<Vec3, D::Error>
where
    T: Deserialize<'de> + Into<f32>,
    D: Deserializer<'de>,
{
    let [x, y, z] = <[T; 3]>::deserialize(deserializer)?;
    Ok(Vec3::new(x.into(), y.into(), z.into()))
}

impl From<Metres> for f32 {
    fn from(value: Metres) -> f32 {
        value.0
    }
}

impl From<Degrees> for f32 {
    fn from(value: Degrees) -> f32 {
        value.0
    }
}

impl From<PositiveMetres> for f32 {
    fn from(value: PositiveMetres) -> f32 {
        value.0
    }
}

/// Writes a vector as `[x, y, z]`.
fn serialize_vec3<S: serde::Serializer>(v: Vec3, serializer: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&v.to_array(), serializer)
}

/// A point or displacement `[x, y, z]` in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point(pub Vec3);

impl Point {
    /// The point a scene file holds nearest `v`: each coordinate within [`MAX_METRES`].
    pub fn nearest(v: Vec3) -> Self {
        let metres = MAX_METRES as f32;
        Point(v.clamp(Vec3::splat(-metres), Vec3::splat(metres)))
    }
}

impl serde::Serialize for Point {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serialize_vec3(self.0, serializer)
    }
}

impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        vec3_from::<Metres, D>(deserializer).map(Self)
    }
}

/// Three angles `[x, y, z]` in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles(pub Vec3);

impl Angles {
    /// The angles a scene file holds nearest `v`: each within [`MAX_DEGREES`].
    pub fn nearest(v: Vec3) -> Self {
        let degrees = MAX_DEGREES as f32;
        Angles(v.clamp(Vec3::splat(-degrees), Vec3::splat(degrees)))
    }
}

impl serde::Serialize for Angles {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serialize_vec3(self.0, serializer)
    }
}

impl<'de> Deserialize<'de> for Angles {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        vec3_from::<Degrees, D>(deserializer).map(Self)
    }
}

/// A size along x, y and z in metres, all positive: written `[x, y, z]`, or one number for
/// the same size along every axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Size(pub Vec3);

impl serde::Serialize for Size {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serialize_vec3(self.0, serializer)
    }
}

impl<'de> Deserialize<'de> for Size {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct SizeVisitor;

        impl<'de> Visitor<'de> for SizeVisitor {
            type Value = Size;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a size in metres: one positive number or [x, y, z]")
            }

            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Size, E> {
                let length = PositiveMetres::deserialize(de::value::F64Deserializer::<E>::new(v))?;
                Ok(Size(Vec3::splat(length.0)))
            }

            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Size, E> {
                self.visit_f64(v as f64)
            }

            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Size, E> {
                self.visit_f64(v as f64)
            }

            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Size, A::Error> {
                let de = de::value::SeqAccessDeserializer::new(seq);
                vec3_from::<PositiveMetres, _>(de).map(Size)
            }
        }

        deserializer.deserialize_any(SizeVisitor)
    }
}

/// An sRGB colour: `[r, g, b]` with channels from 0 to 1, or `"#rrggbb"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Color(pub Srgba);

impl serde::Serialize for Color {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serde::Serialize::serialize(&[self.0.red, self.0.green, self.0.blue], serializer)
    }
}

impl<'de> Deserialize<'de> for Color {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct ColorVisitor;

        impl<'de> Visitor<'de> for ColorVisitor {
            type Value = Color;

            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a colour: [r, g, b] with channels from 0 to 1, or \"#rrggbb\"")
            }

            fn visit_str<E: de::Error>(self, v: &str) -> Result<Color, E> {
                let hex = v.strip_prefix('#').filter(|h| h.len() == 6);
                hex.and_then(|h| Srgba::hex(h).ok()).map(Color).ok_or_else(|| {
                    E::custom(format_args!("expected a colour \"#rrggbb\" (six hex digits), found \"{v}\""))
                })
            }

            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Color, A::Error> {
                let de = de::value::SeqAccessDeserializer::new(seq);
                let [r, g, b] = <[UnitInterval; 3]>::deserialize(de)?;
                Ok(Color(Srgba::rgb(r.0, g.0, b.0)))
            }
        }

        deserializer.deserialize_any(ColorVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse<T: for<'de> Deserialize<'de>>(text: &str) -> Result<T, String> {
        serde_yaml::from_str(text).map_err(|e| e.to_string())
    }

    #[test]
    fn sizes_are_uniform_or_per_axis_and_positive() {
        assert_eq!(parse::<Size>("2").unwrap().0, Vec3::splat(2.0));
        assert_eq!(parse::<Size>("[1, 2.5, 3]").unwrap().0, Vec3::new(1.0, 2.5, 3.0));
        assert!(parse::<Size>("-1").unwrap_err().contains("greater than 0"));
        assert!(parse::<Size>("[1, 0, 3]").unwrap_err().contains("greater than 0"));
        assert!(parse::<Size>("[1, 2]").unwrap_err().contains("length 2"));
        assert!(parse::<Size>("big").is_err());
    }

    #[test]
    fn non_finite_and_huge_numbers_are_refused() {
        for text in ["[.nan, 0, 0]", "[0, .inf, 0]", "[0, 0, 1e300]", "[0, 0, 2e6]"] {
            let error = parse::<Point>(text).unwrap_err();
            assert!(error.contains("expected a coordinate in metres"), "{text}: {error}");
        }
        // Beyond f64, YAML reads the number as a string.
        let error = parse::<Point>("[0, 0, 1e400]").unwrap_err();
        assert!(error.contains("invalid type: string \"1e400\", expected a coordinate in metres"), "{error}");
        assert_eq!(parse::<Point>("[1, -2, 3]").unwrap().0, Vec3::new(1.0, -2.0, 3.0));
    }

    #[test]
    fn colours_from_channels_or_hex() {
        assert_eq!(parse::<Color>("[1, 0.5, 0]").unwrap().0, Srgba::rgb(1.0, 0.5, 0.0));
        assert_eq!(parse::<Color>("\"#ff0000\"").unwrap().0, Srgba::rgb(1.0, 0.0, 0.0));
        assert!(parse::<Color>("\"#ff00\"").unwrap_err().contains("six hex digits"));
        assert!(parse::<Color>("[1, 2, 0]").unwrap_err().contains("from 0 to 1"));
    }

    #[derive(Debug, Clone, PartialEq, Eq)]
    struct Images;

    impl FileType for Images {
        const EXTENSIONS: &'static [&'static str] = &[".png", ".bmp"];
        const EXPECTING: &'static str = "an image";
        const FILES: &'static str = "a .png or .bmp file";
    }

    #[test]
    fn folder_files_stay_inside_and_match_their_extension_in_any_case() {
        assert_eq!(parse::<FolderFile<Images>>("textures/bark.PNG").unwrap().path, "textures/bark.PNG");
        assert!(parse::<FolderFile<Images>>("./a.bmp").is_ok());
        for bad in ["../up.png", "/abs.png", "image.jpg", "\"\""] {
            let error = parse::<FolderFile<Images>>(bad).unwrap_err();
            assert!(error.contains("expected a .png or .bmp file inside the scene's folder"), "{bad}: {error}");
        }
    }

    #[test]
    fn degrees_wrap_into_one_turn() {
        assert_eq!(wrap_degrees(190.0), -170.0);
        assert_eq!(wrap_degrees(-180.0), -180.0);
        assert_eq!(wrap_degrees(180.0), -180.0);
        assert_eq!(wrap_degrees(45.0), 45.0);
    }

    #[test]
    fn field_of_view_is_open_interval() {
        assert!(parse::<FieldOfView>("0").is_err());
        assert!(parse::<FieldOfView>("180").is_err());
        assert_eq!(parse::<FieldOfView>("60").unwrap().0, 60.0);
    }
}
