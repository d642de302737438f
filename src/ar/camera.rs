//! Live cameras through Video4Linux2 (the `linuxvideo` crate): a device opened at the size and
//! rate the scene asks for, in the first pixel format it offers that Canopy reads (YUYV, RGB
//! or MJPEG, in that order: the uncompressed ones cost no decoding), its frames converted to
//! RGBA as they arrive.

use super::stream::FrameReader;
use image::{ImageFormat, RgbaImage};
use linuxvideo::format::{FrameSizes, PixFormat, PixelFormat};
use linuxvideo::stream::ReadStream;
use linuxvideo::{BufType, Device, Fract};
use std::io::ErrorKind;
use std::path::Path;

/// The pixel formats read, in the order they are chosen.
pub const READ_FORMATS: [[u8; 4]; 3] = [*b"YUYV", *b"RGB3", *b"MJPG"];

/// The sizes a device offers in one pixel format.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Sizes {
    /// These sizes, width and height in pixels.
    Listed(Vec<[u32; 2]>),
    /// Any size from `min` to `max` in steps of `step`.
    Range {
        /// The smallest.
        min: [u32; 2],
        /// The largest.
        max: [u32; 2],
        /// The step between sizes.
        step: [u32; 2],
    },
}

impl Sizes {
    fn includes(&self, [width, height]: [u32; 2]) -> bool {
        match self {
            Sizes::Listed(sizes) => sizes.contains(&[width, height]),
            Sizes::Range { min, max, step } => [width, height].iter().enumerate().all(|(axis, &side)| {
                (min[axis]..=max[axis]).contains(&side) && (side - min[axis]) % step[axis].max(1) == 0
            }),
        }
    }

    fn describe(&self) -> String {
        match self {
            Sizes::Listed(sizes) => sizes.iter().map(|[w, h]| format!("{w} x {h}")).collect::<Vec<_>>().join(", "),
            Sizes::Range { min, max, .. } => format!("{} x {} to {} x {}", min[0], min[1], max[0], max[1]),
        }
    }
}

/// A pixel format a device offers and its sizes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Offer {
    /// The format's four-character code (`YUYV`, `MJPG`, ...).
    pub fourcc: [u8; 4],
    /// The sizes it comes in.
    pub sizes: Sizes,
}

/// The pixel format to ask for frames of `size` in, of those offered; the error says what the
/// device offers instead.
pub fn choose_format(offers: &[Offer], size: [u32; 2]) -> Result<[u8; 4], String> {
    let readable: Vec<&Offer> =
        READ_FORMATS.iter().filter_map(|fourcc| offers.iter().find(|offer| offer.fourcc == *fourcc)).collect();
    let names = |offers: &mut dyn Iterator<Item = &Offer>| {
        offers.map(|offer| String::from_utf8_lossy(&offer.fourcc).trim().to_string()).collect::<Vec<_>>().join(", ")
    };
    if readable.is_empty() {
        return Err(format!(
            "it offers only {}, and Canopy reads {}",
            names(&mut offers.iter()),
            READ_FORMATS.map(|f| String::from_utf8_lossy(&f).into_owned()).join(", ")
        ));
    }
    match readable.iter().find(|offer| offer.sizes.includes(size)) {
        Some(offer) => Ok(offer.fourcc),
        None => Err(format!(
            "it does not offer {} x {} pixels; it offers {}",
            size[0],
            size[1],
            readable
                .iter()
                .map(|offer| format!("{} at {}", String::from_utf8_lossy(&offer.fourcc), offer.sizes.describe()))
                .collect::<Vec<_>>()
                .join("; ")
        )),
    }
}

/// One camera frame's bytes in `fourcc`'s layout as RGBA pixels.
pub fn to_rgba(fourcc: [u8; 4], bytes: &[u8], [width, height]: [u32; 2]) -> Result<RgbaImage, String> {
    let pixels = width as usize * height as usize;
    let short = |needed: usize| format!("a frame of {} bytes where {width} x {height} needs {needed}", bytes.len());
    match &fourcc {
        b"YUYV" => {
            // Two pixels in four bytes, sharing their colour: ITU-R BT.601 in video range.
            let needed = pixels * 2;
            let bytes = bytes.get(..needed).ok_or_else(|| short(needed))?;
            let mut rgba = Vec::with_capacity(pixels * 4);
            for pair in bytes.chunks_exact(4) {
                let (u, v) = (f32::from(pair[1]) - 128.0, f32::from(pair[3]) - 128.0);
                for luma in [pair[0], pair[2]] {
                    let y = (f32::from(luma) - 16.0) * 1.164;
                    let channel = |value: f32| value.round().clamp(0.0, 255.0) as u8;
                    rgba.extend([
                        channel(y + 1.596 * v),
                        channel(y - 0.392 * u - 0.813 * v),
                        channel(y + 2.017 * u),
                        255,
                    ]);
                }
            }
            RgbaImage::from_raw(width, height, rgba).ok_or_else(|| short(needed))
        }
        b"RGB3" => {
            let needed = pixels * 3;
            let bytes = bytes.get(..needed).ok_or_else(|| short(needed))?;
            let rgba = bytes.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
            RgbaImage::from_raw(width, height, rgba).ok_or_else(|| short(needed))
        }
        b"MJPG" => {
            let image = image::load_from_memory_with_format(bytes, ImageFormat::Jpeg)
                .map_err(|error| format!("a frame that is not a readable JPEG: {error}"))?;
            match image.width() == width && image.height() == height {
                true => Ok(image.to_rgba8()),
                false => {
                    Err(format!("a frame of {} x {} pixels, not {width} x {height}", image.width(), image.height()))
                }
            }
        }
        other => Err(format!("frames in {}, which Canopy does not read", String::from_utf8_lossy(other))),
    }
}

/// The pixel formats `device` offers for capture, with their sizes.
fn offers(device: &Device) -> std::io::Result<Vec<Offer>> {
    let mut offers = Vec::new();
    for format in device.formats(BufType::VIDEO_CAPTURE) {
        let pixel_format = format?.pixel_format();
        let sizes = match device.frame_sizes(pixel_format)? {
            FrameSizes::Discrete(sizes) => Sizes::Listed(sizes.iter().map(|s| [s.width(), s.height()]).collect()),
            FrameSizes::Stepwise(range) | FrameSizes::Continuous(range) => Sizes::Range {
                min: [range.min_width(), range.min_height()],
                max: [range.max_width(), range.max_height()],
                step: [range.step_width(), range.step_height()],
            },
        };
        offers.push(Offer { fourcc: pixel_format.as_fourcc(), sizes });
    }
    Ok(offers)
}

/// The cameras connected: each video capture device's path and name.
pub fn connected() -> Vec<(String, String)> {
    let Ok(devices) = linuxvideo::list() else { return Vec::new() };
    let mut found: Vec<(String, String)> = devices
        .filter_map(Result::ok)
        .filter(|device| device.supported_buf_types().contains(linuxvideo::BufTypes::VIDEO_CAPTURE))
        .filter_map(|device| {
            let name = device.capabilities().map(|caps| caps.card().to_string()).unwrap_or_default();
            device.path().ok().map(|path| (path.display().to_string(), name))
        })
        .collect();
    found.sort();
    found
}

/// A camera opened and streaming.
pub struct CameraReader {
    device: String,
    stream: ReadStream,
    fourcc: [u8; 4],
    size: [u32; 2],
    /// Why the device stopped giving frames, once it has (unplugged, say): the stream ends.
    gone: Option<String>,
}

impl CameraReader {
    /// Opens `device` for frames of `size` pixels at `fps` a second (or as near as it goes);
    /// errors name the device and say what it offers.
    pub fn open(device: &str, size: [u32; 2], fps: f64) -> Result<Self, String> {
        let opened = Device::open(Path::new(device)).map_err(|error| match error.kind() {
            ErrorKind::NotFound => format!("{device}: no camera there"),
            ErrorKind::PermissionDenied => {
                format!("{device}: not allowed to open it (a member of the `video` group is)")
            }
            _ => format!("{device}: not a camera that can be opened: {error}"),
        })?;
        if !opened.supported_buf_types().contains(linuxvideo::BufTypes::VIDEO_CAPTURE) {
            return Err(format!("{device}: not a capture device"));
        }
        let offered = offers(&opened).map_err(|error| format!("{device}: its formats could not be read: {error}"))?;
        let fourcc = choose_format(&offered, size).map_err(|why| format!("{device}: {why}"))?;
        let format = PixFormat::new(size[0], size[1], PixelFormat::from_fourcc(fourcc));
        let capture = opened.video_capture(format).map_err(|error| format!("{device}: {error}"))?;
        let given = capture.format();
        if [given.width(), given.height()] != size || given.pixel_format().as_fourcc() != fourcc {
            return Err(format!(
                "{device}: asked for {} x {}, it gave {} x {}",
                size[0],
                size[1],
                given.width(),
                given.height()
            ));
        }
        // A driver that cannot set the rate keeps its own; the frames then come at that rate.
        let _ = capture.set_frame_interval(Fract::new(1000, (fps * 1000.0).round() as u32));
        let stream = capture.into_stream().map_err(|error| format!("{device}: cannot start streaming: {error}"))?;
        Ok(Self { device: device.to_string(), stream, fourcc, size, gone: None })
    }
}

impl FrameReader for CameraReader {
    fn next_frame(&mut self) -> Option<Result<RgbaImage, String>> {
        if self.gone.is_some() {
            return None;
        }
        let (fourcc, size) = (self.fourcc, self.size);
        let frame = self.stream.dequeue(|buffer| Ok(to_rgba(fourcc, &buffer, size)));
        match frame {
            Ok(converted) => Some(converted.map_err(|why| format!("{}: {why}", self.device))),
            Err(error) => {
                self.gone = Some(format!("{}: the camera stopped: {error}", self.device));
                None
            }
        }
    }

    fn rewind(&mut self) -> Result<(), String> {
        Ok(())
    }

    fn stopped(&mut self) -> Option<String> {
        self.gone.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn offer(fourcc: &[u8; 4], sizes: Sizes) -> Offer {
        Offer { fourcc: *fourcc, sizes }
    }

    #[test]
    fn the_first_readable_format_offering_the_size_is_chosen() {
        let offers = [
            offer(b"MJPG", Sizes::Listed(vec![[640, 480], [1280, 720]])),
            offer(b"YUYV", Sizes::Listed(vec![[640, 480]])),
        ];
        assert_eq!(choose_format(&offers, [640, 480]), Ok(*b"YUYV"));
        assert_eq!(choose_format(&offers, [1280, 720]), Ok(*b"MJPG"));
        let range = [offer(b"RGB3", Sizes::Range { min: [16, 16], max: [1920, 1080], step: [16, 8] })];
        assert_eq!(choose_format(&range, [640, 480]), Ok(*b"RGB3"));
        assert!(choose_format(&range, [641, 480]).is_err());
    }

    #[test]
    fn a_size_or_format_not_offered_says_what_is() {
        let offers = [offer(b"YUYV", Sizes::Listed(vec![[320, 240], [640, 480]]))];
        let error = choose_format(&offers, [1920, 1080]).unwrap_err();
        assert!(error.contains("does not offer 1920 x 1080 pixels; it offers YUYV at 320 x 240, 640 x 480"), "{error}");
        let error = choose_format(&[offer(b"NV12", Sizes::Listed(vec![[640, 480]]))], [640, 480]).unwrap_err();
        assert!(error.contains("offers only NV12, and Canopy reads YUYV, RGB3, MJPG"), "{error}");
    }

    #[test]
    fn a_camera_that_is_not_there_is_named() {
        let error = CameraReader::open("/dev/video-that-is-not-there", [640, 480], 30.0).err().unwrap();
        assert_eq!(error, "/dev/video-that-is-not-there: no camera there");
        let error = CameraReader::open("/dev/null", [640, 480], 30.0).err().unwrap();
        assert!(error.starts_with("/dev/null: not a camera"), "{error}");
    }

    #[test]
    fn yuyv_and_rgb_frames_become_rgba() {
        // Black, white, then a saturated red pair in video range.
        let yuyv = [16, 128, 235, 128, 81, 90, 81, 240];
        let image = to_rgba(*b"YUYV", &yuyv, [4, 1]).unwrap();
        let pixels: Vec<[u8; 4]> = image.pixels().map(|p| p.0).collect();
        assert_eq!(pixels[0], [0, 0, 0, 255]);
        assert_eq!(pixels[1], [255, 255, 255, 255]);
        assert!(pixels[2][0] > 240 && pixels[2][1] < 10 && pixels[2][2] < 10, "{:?}", pixels[2]);
        let error = to_rgba(*b"YUYV", &yuyv[..6], [4, 1]).unwrap_err();
        assert!(error.contains("6 bytes where 4 x 1 needs 8"), "{error}");
        let rgb = to_rgba(*b"RGB3", &[1, 2, 3, 4, 5, 6], [2, 1]).unwrap();
        assert_eq!(rgb.as_raw(), &[1, 2, 3, 255, 4, 5, 6, 255]);
        assert!(to_rgba(*b"MJPG", b"not a jpeg", [2, 1]).unwrap_err().contains("not a readable JPEG"));
    }
}
