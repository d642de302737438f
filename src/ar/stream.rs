//! Frames read and searched for markers on a thread of their own, ahead of when they are shown:
//! a video's decoding or a camera's waiting never holds up the frame being drawn.
//!
//! The reading thread takes a [`FrameReader`]'s frames in order, finds the markers in each
//! and sends it on a short queue, numbered by its *position* (frames since the first,
//! counting every pass through a looping source). The overlay takes the frame due at the
//! simulated time: a headless run waits for that very frame, so the same scene gives the same
//! dump however fast the machine; the window takes the newest frame ready and never waits.
//!
//! The thread also fits each frame to the view (the overlay's backdrop) with the map the
//! overlay last gave it, so that a large video's resampling is not the frame's work either.

use bevy::math::{DVec2, DVec3};
use canopy_vision::board::Board;
use canopy_vision::camera::Intrinsics;
use canopy_vision::detect::{Marker, Scratch, Settings, detect};
use canopy_vision::dictionary::Dictionary;
use canopy_vision::fit::Remap;
use canopy_vision::gray::Gray;
use image::RgbaImage;
use std::sync::mpsc::{Receiver, RecvError, SyncSender, TryRecvError, sync_channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Frames the reading thread may have ready before the overlay takes them.
pub const FRAMES_AHEAD: usize = 4;

/// A source of camera frames, read in order on the reading thread.
pub trait FrameReader: Send + 'static {
    /// The next frame; `None` after the last. An error names what could not be read; reading
    /// goes on with the frame after it.
    fn next_frame(&mut self) -> Option<Result<RgbaImage, String>>;

    /// Starts again from the first frame, for a source that loops.
    fn rewind(&mut self) -> Result<(), String>;

    /// Why the frames stopped before the source's end, once [`next_frame`](Self::next_frame)
    /// has returned `None`: a camera unplugged while it played, say.
    fn stopped(&mut self) -> Option<String> {
        None
    }
}

/// A frame read and searched.
#[derive(Debug, Clone)]
pub struct ReadFrame {
    /// Frames read before it since the first, over every pass of a looping source.
    pub position: u64,
    /// Its index in the source (its file in a folder, its frame in a video).
    pub index: usize,
    /// Its pixels and the markers in them, or why it could not be read.
    pub content: Result<Searched, String>,
}

/// A frame's pixels and the markers found in them.
#[derive(Debug, Clone)]
pub struct Searched {
    /// The pixels.
    pub image: Arc<RgbaImage>,
    /// Every marker of the dictionary found.
    pub markers: Vec<Marker>,
    /// The board's points found, each with where it lies on the board (metres), when the
    /// overlay stands on a board: see [`Board::points`].
    pub points: Vec<(DVec3, DVec2)>,
    /// The pixels fitted to the view, with the map they were fitted with (the overlay's map
    /// when the frame was read: one made since is not this one).
    pub fitted: Option<(Arc<Backdrop>, Vec<u8>)>,
    /// Wall-clock time its reading (decoding included) and searching took, for display.
    pub work: Duration,
}

/// How frames are fitted to the view: the map and the colour around the frame.
#[derive(Debug)]
pub struct Backdrop {
    /// The map from the view's pixels to the frame's.
    pub map: Remap,
    /// RGBA around the frame, where the view's shape differs.
    pub background: [u8; 4],
}

impl Backdrop {
    /// `frame` fitted to the view, RGBA row by row.
    pub fn fit(&self, frame: &RgbaImage) -> Vec<u8> {
        let mut pixels = Vec::new();
        self.map.apply(frame.as_raw(), self.background, &mut pixels);
        pixels
    }
}

/// The backdrop the reading thread fits frames with, set by the overlay.
type SharedBackdrop = Arc<Mutex<Option<Arc<Backdrop>>>>;

/// What the reading thread sends.
enum Message {
    Frame(ReadFrame),
    /// The source ended after this many frames (a source that does not loop).
    Ended(usize),
    /// The source failed and reading stopped.
    Failed(String),
}

/// How the overlay takes frames from a [`FrameStream`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Taking {
    /// The frame at this position, waiting for it if it is not read yet.
    Wait(u64),
    /// The newest frame read at or before this position, without waiting.
    Newest(u64),
}

/// What the reading thread reports besides frames.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum StreamStatus {
    /// Frames are coming.
    #[default]
    Reading,
    /// The source ended after this many frames.
    Ended(usize),
    /// Reading stopped; the message says why.
    Failed(String),
}

/// Frames read ahead on their own thread. Dropping it stops the thread at its next frame.
#[derive(Debug)]
pub struct FrameStream {
    /// The queue's receiving end (in a mutex only to be shared with the world's other
    /// threads; the overlay alone takes from it, through `&mut`).
    frames: Mutex<Receiver<Message>>,
    /// A frame taken from the queue but not due yet.
    early: Option<ReadFrame>,
    /// What the thread reported.
    pub status: StreamStatus,
    /// The map frames are fitted to the view with.
    backdrop: SharedBackdrop,
}

impl FrameStream {
    /// Starts reading `reader`'s frames, searching each for `dictionary`'s markers through
    /// `camera`'s lens, and for `board`'s points if it has one; `repeat` starts the source over
    /// after its last frame.
    pub fn start(
        reader: Box<dyn FrameReader>,
        dictionary: Dictionary,
        camera: Intrinsics,
        board: Option<Board>,
        repeat: bool,
    ) -> Self {
        let (sender, frames) = sync_channel(FRAMES_AHEAD);
        let backdrop = SharedBackdrop::default();
        let work = Work { dictionary, camera, board, repeat, backdrop: backdrop.clone() };
        // A thread that could not start dropped its end of the queue: nothing will come.
        let status = match std::thread::Builder::new()
            .name("canopy-frames".into())
            .spawn(move || read_frames(reader, work, sender))
        {
            Ok(_) => StreamStatus::Reading,
            Err(error) => StreamStatus::Failed(format!("cannot start the thread that reads frames: {error}")),
        };
        Self { frames: Mutex::new(frames), early: None, status, backdrop }
    }

    /// Fits the frames read from now on with `backdrop`.
    pub fn fit_with(&self, backdrop: Arc<Backdrop>) {
        *self.backdrop.lock().unwrap_or_else(|poisoned| poisoned.into_inner()) = Some(backdrop);
    }

    /// The frame to show now, if there is a new one; see [`Taking`]. Frames before it are let
    /// go.
    pub fn take(&mut self, taking: Taking) -> Option<ReadFrame> {
        let (due, wait) = match taking {
            Taking::Wait(due) => (due, true),
            Taking::Newest(due) => (due, false),
        };
        let frames = self.frames.get_mut().unwrap_or_else(|poisoned| poisoned.into_inner());
        let mut newest: Option<ReadFrame> = None;
        loop {
            if let Some(early) = self.early.take() {
                if early.position > due {
                    self.early = Some(early);
                    break;
                }
                newest = Some(early);
            }
            let wanted = wait && newest.as_ref().is_none_or(|frame| frame.position < due);
            let message =
                if wanted { frames.recv().map_err(|RecvError| TryRecvError::Disconnected) } else { frames.try_recv() };
            match message {
                Ok(Message::Frame(frame)) => self.early = Some(frame),
                Ok(Message::Ended(frames)) => self.status = StreamStatus::Ended(frames),
                Ok(Message::Failed(why)) => self.status = StreamStatus::Failed(why),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    if self.status == StreamStatus::Reading {
                        self.status = StreamStatus::Failed("the thread reading frames stopped".into());
                    }
                    break;
                }
            }
        }
        newest
    }
}

/// What the reading thread does with each frame.
struct Work {
    dictionary: Dictionary,
    camera: Intrinsics,
    board: Option<Board>,
    repeat: bool,
    backdrop: SharedBackdrop,
}

/// The reading thread: frames in order, each searched and fitted, until the source ends or
/// fails or the stream is dropped.
fn read_frames(mut reader: Box<dyn FrameReader>, work: Work, sender: SyncSender<Message>) {
    let settings = Settings::default();
    let mut scratch = Scratch::default();
    let (mut position, mut index) = (0u64, 0usize);
    loop {
        let started = Instant::now();
        let message = match reader.next_frame() {
            Some(read) => {
                let content = read.map(|image| {
                    let gray = Gray::from_rgba(image.width(), image.height(), image.as_raw());
                    let markers = detect(&gray, &work.dictionary, &settings, Some(&work.camera), &mut scratch);
                    let points = work.board.map(|board| board.points(&gray, &markers)).unwrap_or_default();
                    let backdrop = work.backdrop.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).clone();
                    let fitted = backdrop.map(|backdrop| {
                        let pixels = backdrop.fit(&image);
                        (backdrop, pixels)
                    });
                    Searched { image: Arc::new(image), markers, points, fitted, work: started.elapsed() }
                });
                let frame = ReadFrame { position, index, content };
                position += 1;
                index += 1;
                Message::Frame(frame)
            }
            None => match reader.stopped() {
                Some(why) => Message::Failed(why),
                None if work.repeat && index > 0 => match reader.rewind() {
                    Ok(()) => {
                        index = 0;
                        continue;
                    }
                    Err(why) => Message::Failed(why),
                },
                None => Message::Ended(index),
            },
        };
        let last = !matches!(message, Message::Frame(_));
        if sender.send(message).is_err() || last {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames of one grey level each, from 0; `failing` names a frame that cannot be read,
    /// `vanishing` the frame before which the source goes away, as an unplugged camera does.
    struct Counting {
        frames: usize,
        next: usize,
        failing: Option<usize>,
        vanishing: Option<usize>,
    }

    impl FrameReader for Counting {
        fn next_frame(&mut self) -> Option<Result<RgbaImage, String>> {
            let index = self.next;
            (index < self.frames && self.vanishing != Some(index)).then(|| {
                self.next += 1;
                match self.failing == Some(index) {
                    true => Err(format!("frame {index} is damaged")),
                    false => Ok(RgbaImage::from_pixel(8, 6, image::Rgba([index as u8, 0, 0, 255]))),
                }
            })
        }

        fn rewind(&mut self) -> Result<(), String> {
            self.next = 0;
            Ok(())
        }

        fn stopped(&mut self) -> Option<String> {
            self.vanishing.filter(|&index| index == self.next).map(|index| format!("gone before frame {index}"))
        }
    }

    fn reading(reader: Counting, repeat: bool) -> FrameStream {
        let camera = Intrinsics::pinhole([8, 6], 60.0);
        let dictionary = Dictionary::named("4x4_50").unwrap();
        FrameStream::start(Box::new(reader), dictionary, camera, None, repeat)
    }

    fn stream(frames: usize, failing: Option<usize>, repeat: bool) -> FrameStream {
        reading(Counting { frames, next: 0, failing, vanishing: None }, repeat)
    }

    fn level(frame: &ReadFrame) -> u8 {
        frame.content.as_ref().unwrap().image.get_pixel(0, 0)[0]
    }

    #[test]
    fn waiting_gives_the_frame_due_and_loops_through_the_source() {
        let mut frames = stream(3, None, true);
        for due in [0, 1, 2, 3, 5, 9] {
            let frame = frames.take(Taking::Wait(due)).unwrap();
            assert_eq!((frame.position, frame.index, level(&frame)), (due, due as usize % 3, due as u8 % 3));
        }
        assert_eq!(frames.status, StreamStatus::Reading);
    }

    #[test]
    fn a_source_that_ends_reports_its_length_and_an_unreadable_frame_its_reason() {
        let mut frames = stream(3, Some(1), false);
        assert!(frames.take(Taking::Wait(1)).unwrap().content.unwrap_err().contains("frame 1 is damaged"));
        assert_eq!(level(&frames.take(Taking::Wait(2)).unwrap()), 2);
        assert!(frames.take(Taking::Wait(3)).is_none(), "no frame after the last");
        assert_eq!(frames.status, StreamStatus::Ended(3));
    }

    #[test]
    fn a_source_that_goes_away_keeps_what_it_gave_and_says_why_it_stopped() {
        let mut frames = reading(Counting { frames: 10, next: 0, failing: None, vanishing: Some(2) }, true);
        assert_eq!(level(&frames.take(Taking::Wait(1)).unwrap()), 1);
        assert!(frames.take(Taking::Wait(2)).is_none(), "nothing comes after it went");
        assert_eq!(frames.status, StreamStatus::Failed("gone before frame 2".into()), "and it is not rewound");
    }

    #[test]
    fn the_newest_frame_is_taken_without_waiting_and_never_one_not_due() {
        let mut frames = stream(40, None, false);
        // Whatever is ready: never past the position due, never older than one taken before.
        let mut last = None;
        for due in [0, 0, 5, 5, 30] {
            if let Some(frame) = frames.take(Taking::Newest(due)) {
                assert!(frame.position <= due && last.is_none_or(|last| frame.position > last));
                last = Some(frame.position);
            }
        }
        let frame = frames.take(Taking::Wait(39)).unwrap();
        assert_eq!(frame.position, 39, "waiting still reaches the frame due");
    }
}
