//! Camera calibration files in OpenCV's layout, YAML (as `cv::FileStorage` writes it, with
//! its `%YAML:1.0` header and `!!opencv-matrix` tags) or JSON: `camera_matrix` (3 x 3) and
//! `distortion_coefficients` (4, 5 or 8 numbers: `k1 k2 p1 p2 [k3 [k4 k5 k6]]`), with
//! `image_width` and `image_height` when the file has them.

use super::opencv_file::{read_bounded, read_mapping, untag};
use crate::foundation::yaml::{FileError, locate_key};
use canopy_vision::camera::{Distortion, Intrinsics};
use serde_yaml::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The largest calibration file read, bytes.
pub const MAX_CALIBRATION_BYTES: usize = 1 << 20;

/// A calibration and whether the file said which image size it is for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// The camera; its `size` is the file's, or `[0, 0]` if it has none.
    pub intrinsics: Intrinsics,
    /// Whether the file gave `image_width` and `image_height`.
    pub sized: bool,
}

impl Calibration {
    /// The camera for frames of `size` pixels: as calibrated if the file gave no size or the
    /// same one; scaled if the frames are the calibrated images resized (same shape).
    pub fn for_frames(&self, size: [u32; 2]) -> Result<Intrinsics, String> {
        let calibrated = self.intrinsics.size;
        if !self.sized || calibrated == size {
            return Ok(Intrinsics { size, ..self.intrinsics });
        }
        let (a, b) = (u64::from(calibrated[0]) * u64::from(size[1]), u64::from(calibrated[1]) * u64::from(size[0]));
        if a != b {
            return Err(format!(
                "the frames are {} x {} pixels but the calibration is for {} x {}, another shape",
                size[0], size[1], calibrated[0], calibrated[1]
            ));
        }
        Ok(self.intrinsics.scaled_to(size))
    }
}

/// Reads a calibration file.
pub fn read(path: &Path) -> Result<Calibration, FileError> {
    parse(path, &read_bounded(path, MAX_CALIBRATION_BYTES, "a calibration file")?)
}

/// Parses a calibration file's bytes; `path` names it in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Calibration, FileError> {
    let (text, fields) =
        read_mapping(path, bytes, "OpenCV's calibration YAML or JSON with camera_matrix and distortion_coefficients")?;
    let text = text.as_str();
    let at = |key: &str, message: String| locate_key(path, text, key, 0, format!("{key}: {message}"));
    let matrix = |key: &str| -> Result<Vec<f64>, FileError> {
        let value = fields.get(key).ok_or_else(|| {
            FileError::whole_file(
                path,
                format!("missing {key} (OpenCV's layout: `{key}: !!opencv-matrix` with rows, cols, dt and data)"),
            )
        })?;
        numbers(value).map_err(|message| at(key, message))
    };
    let k = matrix("camera_matrix")?;
    if k.len() != 9 {
        return Err(at("camera_matrix", format!("expected 9 numbers (3 x 3), found {}", k.len())));
    }
    let (fx, fy, cx, cy) = (k[0], k[4], k[2], k[5]);
    if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite() && cx.is_finite() && cy.is_finite()) {
        return Err(at("camera_matrix", "fx and fy must be positive and cx, cy finite".into()));
    }
    if k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
        return Err(at("camera_matrix", "expected [fx, 0, cx, 0, fy, cy, 0, 0, 1] (no skew)".into()));
    }
    let d = matrix("distortion_coefficients")?;
    if ![4, 5, 8].contains(&d.len()) || d.iter().any(|v| !v.is_finite()) {
        return Err(at(
            "distortion_coefficients",
            format!("expected 4, 5 or 8 finite numbers (k1 k2 p1 p2 [k3 [k4 k5 k6]]), found {}", d.len()),
        ));
    }
    let mut coefficients = [0.0; 8];
    coefficients[..d.len()].copy_from_slice(&d);
    let dimension = |key: &str| -> Result<Option<u32>, FileError> {
        fields
            .get(key)
            .map(|v| match untag(v).as_u64() {
                Some(n @ 1..=16384) => Ok(n as u32),
                _ => Err(at(key, "expected a whole number of pixels from 1 to 16384".into())),
            })
            .transpose()
    };
    let size = match (dimension("image_width")?, dimension("image_height")?) {
        (Some(w), Some(h)) => Some([w, h]),
        (None, None) => None,
        (Some(_), None) => return Err(at("image_width", "given without image_height".into())),
        (None, Some(_)) => return Err(at("image_height", "given without image_width".into())),
    };
    Ok(Calibration {
        intrinsics: Intrinsics { fx, fy, cx, cy, distortion: Distortion(coefficients), size: size.unwrap_or([0, 0]) },
        sized: size.is_some(),
    })
}

/// The numbers of an OpenCV matrix (`rows`, `cols`, `data`) or of a plain list (flat or
/// nested rows).
fn numbers(value: &Value) -> Result<Vec<f64>, String> {
    match untag(value) {
        Value::Mapping(map) => {
            let data = map.get("data").ok_or("expected an OpenCV matrix with `data`")?;
            let out = numbers(data)?;
            let dim = |key: &str| map.get(key).and_then(Value::as_u64);
            if let (Some(rows), Some(cols)) = (dim("rows"), dim("cols"))
                && rows * cols != out.len() as u64
            {
                return Err(format!("rows x cols is {rows} x {cols} but data holds {} numbers", out.len()));
            }
            Ok(out)
        }
        Value::Sequence(items) => {
            let mut out = Vec::new();
            for item in items.iter().take(64) {
                match untag(item) {
                    Value::Sequence(_) => out.extend(numbers(item)?),
                    other => out.push(other.as_f64().ok_or_else(|| format!("expected numbers, found {other:?}"))?),
                }
            }
            if items.len() > 64 {
                return Err(format!("{} numbers: too many for a calibration", items.len()));
            }
            Ok(out)
        }
        other => Err(format!("expected a matrix or a list of numbers, found {other:?}")),
    }
}

/// A calibration file in OpenCV's YAML layout, as `cv::FileStorage` writes it.
pub fn to_yaml(intrinsics: &Intrinsics) -> String {
    let mut out = String::from("%YAML:1.0\n---\n");
    let [width, height] = intrinsics.size;
    let _ = writeln!(out, "image_width: {width}\nimage_height: {height}");
    let k = [intrinsics.fx, 0.0, intrinsics.cx, 0.0, intrinsics.fy, intrinsics.cy, 0.0, 0.0, 1.0];
    let list = |values: &[f64]| values.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(", ");
    let _ =
        writeln!(out, "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ {} ]", list(&k));
    let d = &intrinsics.distortion.0[..if intrinsics.distortion.0[5..].iter().all(|&v| v == 0.0) { 5 } else { 8 }];
    let _ = writeln!(
        out,
        "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: {}\n   dt: d\n   data: [ {} ]",
        d.len(),
        list(d)
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const OPENCV_YAML: &str = "%YAML:1.0
---
calibration_time: \"Sat 05 Dec 2026\"
image_width: 640
image_height: 480
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 6.1e+02, 0., 3.195e+02, 0., 6.12e+02, 2.395e+02, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.1, 0.02, 0., 0.001, 0. ]
";

    fn parse_text(text: &str) -> Result<Calibration, FileError> {
        parse(Path::new("cam.yaml"), text.as_bytes())
    }

    #[test]
    fn opencv_yaml_and_json_read_alike() {
        let yaml = parse_text(OPENCV_YAML).unwrap();
        assert_eq!((yaml.intrinsics.fx, yaml.intrinsics.cy, yaml.intrinsics.size), (610.0, 239.5, [640, 480]));
        assert_eq!(yaml.intrinsics.distortion.0, [-0.1, 0.02, 0.0, 0.001, 0.0, 0.0, 0.0, 0.0]);
        let json = r#"{
            "image_width": 640, "image_height": 480,
            "camera_matrix": {"type_id": "opencv-matrix", "rows": 3, "cols": 3, "dt": "d",
                "data": [610.0, 0.0, 319.5, 0.0, 612.0, 239.5, 0.0, 0.0, 1.0]},
            "distortion_coefficients": {"type_id": "opencv-matrix", "rows": 1, "cols": 5, "dt": "d",
                "data": [-0.1, 0.02, 0.0, 0.001, 0.0]}
        }"#;
        assert_eq!(parse_text(json).unwrap(), yaml);
    }

    #[test]
    fn what_is_written_reads_back() {
        let yaml = parse_text(OPENCV_YAML).unwrap();
        assert_eq!(parse_text(&to_yaml(&yaml.intrinsics)).unwrap(), yaml);
    }

    #[test]
    fn missing_and_malformed_fields_are_named_and_located() {
        let missing =
            parse_text("%YAML:1.0\n---\ncamera_matrix: [1, 0, 1, 0, 1, 1, 0, 0, 1]\n").unwrap_err().to_string();
        assert!(missing.contains("missing distortion_coefficients"), "{missing}");
        let short = OPENCV_YAML.replace("data: [ -0.1, 0.02, 0., 0.001, 0. ]", "data: [ -0.1, 0.02, 0. ]");
        let error = parse_text(&short).unwrap_err();
        assert_eq!(error.location.map(|l| l.0), Some(11), "{error}");
        assert!(
            error.to_string().contains("distortion_coefficients: rows x cols is 1 x 5 but data holds 3"),
            "{error}"
        );
        let skewed = OPENCV_YAML.replace("6.1e+02, 0., 3.195e+02", "6.1e+02, 2., 3.195e+02");
        assert!(parse_text(&skewed).unwrap_err().to_string().contains("no skew"));
        assert!(parse_text("[1, 2").unwrap_err().to_string().contains("not valid YAML"));
        // Not a number where a number must be: YAML's `.nan` and `.inf`.
        let focal = parse_text(&OPENCV_YAML.replace("6.1e+02, 0., 3.195e+02", ".nan, 0., 3.195e+02")).unwrap_err();
        assert!(focal.to_string().contains("camera_matrix: fx and fy must be positive"), "{focal}");
        assert!(focal.location.is_some(), "{focal}");
        let distortion = parse_text(&OPENCV_YAML.replace("data: [ -0.1, 0.02,", "data: [ .inf, 0.02,")).unwrap_err();
        assert!(distortion.to_string().contains("distortion_coefficients: expected 4, 5 or 8 finite"), "{distortion}");
    }

    #[test]
    fn frames_of_another_size_scale_the_camera_or_are_refused() {
        let calibration = parse_text(OPENCV_YAML).unwrap();
        let half = calibration.for_frames([320, 240]).unwrap();
        assert!((half.fx - 305.0).abs() < 1e-9 && (half.cx - 159.5).abs() < 1e-9);
        assert!(calibration.for_frames([1280, 720]).unwrap_err().contains("another shape"));
    }
}
