//! Camera frames from a folder: its PNG and JPEG files in name order (numbers in names
//! compared as numbers, so `frame-9` comes before `frame-10`), all of one size, decoded one at
//! a time when shown.

use super::stream::FrameReader;
use image::{ImageReader, Limits, RgbaImage};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The most frames a folder may hold.
pub const MAX_FRAMES: usize = 100_000;
/// The longest side of a frame, pixels.
pub const MAX_FRAME_SIDE: u32 = 8192;

/// The frames of a folder.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameFolder {
    /// The image files, in showing order.
    pub files: Vec<PathBuf>,
    /// Every frame's width and height in pixels (the first frame's).
    pub size: [u32; 2],
}

impl FrameFolder {
    /// Lists `folder`'s frames and reads the first one's size.
    pub fn open(folder: &Path) -> Result<Self, String> {
        let entries = std::fs::read_dir(folder)
            .map_err(|error| format!("{}: cannot read the folder: {error}", folder.display()))?;
        let mut files = Vec::new();
        for entry in entries {
            let path = entry.map_err(|error| format!("{}: {error}", folder.display()))?.path();
            let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
            if matches!(extension.as_deref(), Some("png" | "jpg" | "jpeg")) && path.is_file() {
                files.push(path);
                if files.len() > MAX_FRAMES {
                    return Err(format!("{}: more than {MAX_FRAMES} frames", folder.display()));
                }
            }
        }
        files.sort_by(|a, b| natural_order(&a.to_string_lossy(), &b.to_string_lossy()));
        let first = files
            .first()
            .ok_or_else(|| format!("{}: no frames (PNG or JPEG files) in the folder", folder.display()))?;
        let (width, height) = ImageReader::open(first)
            .and_then(|reader| reader.with_guessed_format())
            .map_err(|error| format!("{}: {error}", first.display()))?
            .into_dimensions()
            .map_err(|error| format!("{}: not a readable image: {error}", first.display()))?;
        if width == 0 || height == 0 || width.max(height) > MAX_FRAME_SIDE {
            return Err(format!(
                "{}: {width} x {height} pixels; a frame is 1 to {MAX_FRAME_SIDE} pixels a side",
                first.display()
            ));
        }
        Ok(Self { files, size: [width, height] })
    }

    /// Frames in the folder.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// Whether the folder has no frames (never true of an opened one).
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// Decodes frame `index`; an error names the file.
    pub fn load(&self, index: usize) -> Result<RgbaImage, String> {
        let path = self.files.get(index).ok_or_else(|| format!("no frame {index}"))?;
        load_image(path, Some(self.size))
    }
}

/// A folder's frames read in order.
pub struct FolderReader {
    /// The folder.
    pub frames: Arc<FrameFolder>,
    /// The next frame's index.
    pub next: usize,
}

impl FrameReader for FolderReader {
    fn next_frame(&mut self) -> Option<Result<RgbaImage, String>> {
        let index = self.next;
        (index < self.frames.len()).then(|| {
            self.next += 1;
            self.frames.load(index)
        })
    }

    fn rewind(&mut self) -> Result<(), String> {
        self.next = 0;
        Ok(())
    }
}

/// Decodes a PNG or JPEG image within the frame size bounds; with `size`, it must be that
/// size. Errors name the file.
pub fn load_image(path: &Path, size: Option<[u32; 2]>) -> Result<RgbaImage, String> {
    let mut reader = ImageReader::open(path)
        .and_then(|reader| reader.with_guessed_format())
        .map_err(|error| format!("{}: {error}", path.display()))?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_FRAME_SIDE);
    limits.max_image_height = Some(MAX_FRAME_SIDE);
    reader.limits(limits);
    let image =
        reader.decode().map_err(|error| format!("{}: not a readable image: {error}", path.display()))?.to_rgba8();
    match size {
        Some([w, h]) if image.dimensions() != (w, h) => Err(format!(
            "{}: {} x {} pixels, but the sequence's frames are {w} x {h}",
            path.display(),
            image.width(),
            image.height()
        )),
        _ => Ok(image),
    }
}

/// Compares names with runs of digits taken as numbers.
fn natural_order(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let digits = |s: &[u8]| s.iter().take_while(|c| c.is_ascii_digit()).count();
                let (da, db) = (digits(a), digits(b));
                let (na, nb) = (trim_zeros(&a[..da]), trim_zeros(&b[..db]));
                let order = na.len().cmp(&nb.len()).then_with(|| na.cmp(nb));
                if order != Ordering::Equal {
                    return order;
                }
                (a, b) = (&a[da..], &b[db..]);
            }
            (Some(x), Some(y)) if x != y => return x.cmp(y),
            _ => (a, b) = (&a[1..], &b[1..]),
        }
    }
}

fn trim_zeros(digits: &[u8]) -> &[u8] {
    let zeros = digits.iter().take_while(|&&c| c == b'0').count();
    &digits[zeros..]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_names_sort_as_numbers() {
        let mut names = vec!["f10.png", "f9.png", "f010b.png", "f1.png", "e99.png"];
        names.sort_by(|a, b| natural_order(a, b));
        assert_eq!(names, vec!["e99.png", "f1.png", "f9.png", "f10.png", "f010b.png"]);
    }

    #[test]
    fn folders_without_frames_and_unreadable_frames_are_named() {
        let folder = tempfile::tempdir().unwrap();
        let error = FrameFolder::open(folder.path()).unwrap_err();
        assert!(error.contains("no frames"), "{error}");
        std::fs::write(folder.path().join("0001.png"), b"not a png").unwrap();
        let error = FrameFolder::open(folder.path()).unwrap_err();
        assert!(error.contains("0001.png"), "{error}");
        let missing = FrameFolder::open(&folder.path().join("nowhere")).unwrap_err();
        assert!(missing.contains("cannot read the folder"), "{missing}");
    }

    #[test]
    fn frames_of_another_size_are_refused() {
        let folder = tempfile::tempdir().unwrap();
        RgbaImage::new(8, 6).save(folder.path().join("a1.png")).unwrap();
        RgbaImage::new(6, 6).save(folder.path().join("a2.png")).unwrap();
        let frames = FrameFolder::open(folder.path()).unwrap();
        assert_eq!((frames.len(), frames.size), (2, [8, 6]));
        assert!(frames.load(0).is_ok());
        assert!(frames.load(1).unwrap_err().contains("6 x 6 pixels, but the sequence's frames are 8 x 6"));
    }
}
