//! The overlay's plugin: camera frames shown at their rate, the marker found in each and its
//! pose estimated, the rasterizer's camera put where the photographing camera was, and the
//! drawn frame laid over the photograph.
//!
//! | schedule, set | system | what it does |
//! |---|---|---|
//! | `FixedUpdate`, [`SimSystems::Streaming`] | `show_frames` | takes the frame due at the simulated time, finds the marker, updates the pose held |
//! | `PostUpdate`, [`RenderSystems::Camera`] | `place_camera` | the render camera at the pose, fitted to the view |
//! | `PostUpdate`, [`RenderSystems::Composite`] | `lay_over_frame` | the photograph behind what was drawn, or alone when the marker is lost |

use super::calibration::Calibration;
use super::def::{ArBuilt, ArDef};
use super::overlay::{Tracker, render_camera, world_from_marker};
use super::report::marker_json;
use super::source::{CameraSettings, Source};
use super::stream::{Backdrop, FrameStream, ReadFrame, StreamStatus, Taking};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::schedule::{LongWorkArrival, RenderSystems, SimSystems};
use crate::raster::plugin::RasterTarget;
use crate::raster::{MAX_TARGET_SIZE, RenderView};
use bevy::math::{DVec2, DVec3};
use bevy::prelude::*;
use canopy_vision::board::{Board, BoardPose};
use canopy_vision::camera::Intrinsics;
use canopy_vision::dictionary::Dictionary;
use canopy_vision::fit::{Fit, Remap};
use canopy_vision::pose::{Pose, PoseEstimate, estimate, marker_corners};
use canopy_vision::steady::PoseFollower;
use image::RgbaImage;
use serde_json::{Map, Value, json};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

/// Runs `ar` entities.
#[derive(Default)]
pub struct ArPlugin;

impl Plugin for ArPlugin {
    fn build(&self, app: &mut App) {
        app.register_dump::<ArView>()
            .register_dump::<ArState>()
            .add_systems(FixedUpdate, show_frames.in_set(SimSystems::Streaming))
            .add_systems(PostUpdate, place_camera.in_set(RenderSystems::Camera))
            .add_systems(PostUpdate, lay_over_frame.in_set(RenderSystems::Composite));
    }
}

/// The most frame records kept: an hour at 30 frames a second; older ones are dropped, so that
/// a scene left playing does not grow without bound.
pub const MAX_RECORDS: usize = 108_000;

/// What an `ar` entity shows and how: fixed when the scene is loaded.
#[derive(Component, Debug, Clone)]
pub struct ArView {
    /// Where the camera frames come from.
    pub source: Source,
    /// The calibrated camera, for the frames' size.
    pub camera: Intrinsics,
    /// The calibration, for a camera opened at another size.
    pub calibration: Arc<Calibration>,
    /// The markers' dictionary.
    pub dictionary: Dictionary,
    /// What the scene stands on.
    pub target: Target,
    /// Marker metres to the world metre.
    pub scale: f64,
    /// Frames a second.
    pub fps: f64,
    /// Whether a folder's or a video's frames start over after the last.
    pub repeat: bool,
    /// Seconds a lost marker's pose is kept.
    pub hold_s: f64,
}

impl ArView {
    /// The view an `ar` definition describes.
    pub fn new(def: &ArDef, built: &ArBuilt) -> Self {
        Self {
            source: built.source.clone(),
            camera: built.camera,
            calibration: built.calibration.clone(),
            dictionary: built.dictionary.clone(),
            target: Target::of(def, built),
            scale: def.scale.0,
            fps: built.source.fps(def.fps.map(|fps| fps.0)),
            repeat: def.repeat,
            hold_s: def.hold_s.0,
        }
    }

    /// The position (frames since the first) due at `time_s` seconds (a millionth of a frame
    /// early counts as on time: fixed steps of 1/60 s are not exact in binary).
    fn position_at(&self, time_s: f64) -> u64 {
        (time_s * self.fps + 1e-6).floor() as u64
    }

    /// Turns to a live camera with `settings`, the calibration scaled to its size; the view is
    /// unchanged if the calibration is for another shape.
    pub fn use_camera(&mut self, settings: CameraSettings) -> Result<(), String> {
        self.camera = self.calibration.for_frames(settings.size)?;
        self.source = Source::Camera(settings);
        Ok(())
    }

    /// Starts reading the source's frames.
    fn start(&self) -> Result<FrameStream, String> {
        let reader = self.source.open()?;
        let board = match self.target {
            Target::Board(board) => Some(board),
            Target::Marker { .. } => None,
        };
        Ok(FrameStream::start(reader, self.dictionary.clone(), self.camera, board, self.repeat && !self.source.live()))
    }
}

/// What an `ar` scene stands on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// One marker.
    Marker {
        /// Its id in the dictionary.
        id: u32,
        /// Its side, metres.
        side_m: f64,
    },
    /// A board, the scene on its centre.
    Board(Board),
}

impl Target {
    /// The target a checked definition names: its board as built, or its marker.
    fn of(def: &ArDef, built: &ArBuilt) -> Self {
        match (built.board, def.marker_id, def.marker_side_m) {
            (Some(board), ..) => Target::Board(board),
            (None, id, side) => {
                Target::Marker { id: id.unwrap_or_default(), side_m: side.map_or(0.0, |side| f64::from(side.0)) }
            }
        }
    }
}

/// What became of the marker in one frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Finding {
    /// Found, with its corners (pixels, OpenCV's order) and its pose.
    Found {
        /// The corners.
        corners: [DVec2; 4],
        /// The pose, its error and the other planar solution's (boxed: the records of frames
        /// without the marker stay small).
        estimate: Box<PoseEstimate>,
        /// Whether the other solution was shown, for continuing the pose shown before.
        kept_alternative: bool,
        /// Whether the pose shown turned over from the one before.
        flipped: bool,
    },
    /// The board found: its pose from the markers of it found.
    Board {
        /// Its pose, moved to the board's centre with the axes of a marker's frame (x right, y
        /// up the printed board, z out of it), and its error over every corner used.
        pose: BoardPose,
        /// Every corner used: where it lies in that frame, metres, and where it was found.
        points: Vec<(DVec3, DVec2)>,
    },
    /// Not found; the last pose is shown while it is held.
    Lost {
        /// Whether an earlier pose is still shown.
        held: bool,
    },
    /// The frame could not be read (the message names the file).
    Unreadable(String),
}

/// One shown frame's record.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRecord {
    /// Its index in the source.
    pub frame: usize,
    /// When it was shown, simulated seconds.
    pub time_s: f64,
    /// The marker in it.
    pub finding: Finding,
}

/// The overlay's changing state.
#[derive(Component, Debug, Default)]
pub struct ArState {
    /// Fixed steps since the first frame.
    steps: u64,
    /// Simulated seconds since the first frame.
    time_s: f64,
    /// The frame shown: its index in the source.
    shown: Option<usize>,
    /// The frames being read; `None` until the first step, and after the source failed to
    /// open.
    stream: Option<FrameStream>,
    /// The position of the last frame taken from the stream.
    taken: Option<u64>,
    /// Why the source could not be opened or stopped, for the panel and the dump.
    pub source_error: Option<String>,
    /// Whether the source has been opened (or tried).
    opened: bool,
    /// The last frame read's pixels (an unreadable frame leaves the one before).
    image: Option<Arc<RgbaImage>>,
    /// Frames read so far: tells a new photograph from the one already fitted.
    images_read: u64,
    tracker: Tracker,
    /// Chooses between each frame's two solutions so that the pose does not flip.
    follower: PoseFollower,
    /// The pose the scene is drawn at; `None` hides it.
    pub pose: Option<Pose>,
    /// The shown frames' records, in order: the last [`MAX_RECORDS`].
    pub records: VecDeque<FrameRecord>,
    /// Records dropped from the front to keep [`MAX_RECORDS`].
    pub records_dropped: u64,
    /// The largest distance between the detected corners and the marker's corners as the
    /// render camera projects them in the last frame drawn, in camera-frame pixels (the view
    /// may show the frame larger or smaller): the overlay's alignment.
    pub overlay_error_px: Option<f64>,
    /// The largest [`ArState::overlay_error_px`] of every frame drawn so far.
    pub overlay_error_max_px: f64,
    /// Wall-clock time the last frame's decoding and detection took, on the reading thread
    /// (for display only).
    pub read_time: Duration,
    /// Whether the found marker's outline is drawn over the frame (the panel's switch).
    pub outline: bool,
    /// How the photograph is fitted to the view now.
    backdrop: Option<Arc<Backdrop>>,
    /// The shown frame fitted on the reading thread, and how.
    fitted: Option<(Arc<Backdrop>, Vec<u8>)>,
    /// The photograph fitted to the view, and the frame (by [`ArState::images_read`]) it
    /// was made from with the backdrop of now.
    backdrop_pixels: Vec<u8>,
    backdrop_of: Option<u64>,
}

impl ArState {
    /// Reads the source again from its start at the next step (after the view's source changed).
    pub fn restart(&mut self) {
        self.stream = None;
        self.opened = false;
        self.taken = None;
        self.source_error = None;
    }

    /// Frames whose pose turned over from the one before.
    pub fn follower_flips(&self) -> u64 {
        self.follower.flips()
    }

    /// Frames that showed the other solution for continuing the pose.
    pub fn follower_kept(&self) -> u64 {
        self.follower.kept()
    }

    /// The corners found in the frame shown, each with where it lies in the target's frame
    /// (metres), if the target was found there.
    fn found_points(&self, target: &Target) -> Option<Vec<(DVec3, DVec2)>> {
        match (&self.records.back()?.finding, target) {
            (Finding::Found { corners, .. }, Target::Marker { side_m, .. }) => {
                Some(marker_corners(*side_m).into_iter().zip(*corners).collect())
            }
            (Finding::Board { points, .. }, _) => Some(points.clone()),
            _ => None,
        }
    }
}

fn show_frames(time: Res<Time>, arrival: Res<LongWorkArrival>, mut overlays: Query<(&ArView, &mut ArState)>) {
    for (view, mut state) in &mut overlays {
        let state = &mut *state;
        if !state.opened {
            state.opened = true;
            match view.start() {
                Ok(stream) => {
                    if let Some(backdrop) = &state.backdrop {
                        stream.fit_with(backdrop.clone());
                    }
                    state.stream = Some(stream);
                }
                Err(message) => {
                    warn!("{message}");
                    state.source_error = Some(message);
                }
            }
        }
        let due = view.position_at(state.time_s);
        let taking = match (view.source.live(), *arrival) {
            (true, _) => Some(Taking::Newest(u64::MAX)),
            (false, _) if state.taken.is_some_and(|taken| taken >= due) => None,
            (false, LongWorkArrival::FixedFrames) => Some(Taking::Wait(due)),
            (false, LongWorkArrival::WhenReady) => Some(Taking::Newest(due)),
        };
        if let (Some(taking), Some(stream)) = (taking, state.stream.as_mut()) {
            let frame = stream.take(taking);
            if let StreamStatus::Failed(message) = &stream.status
                && state.source_error.as_ref() != Some(message)
            {
                warn!("{message}");
                state.source_error = Some(message.clone());
            }
            if let Some(frame) = frame {
                show(view, state, frame);
            }
        }
        state.steps += 1;
        state.time_s = state.steps as f64 * time.delta_secs_f64();
    }
}

/// Shows a frame read: the target found in it, the pose updated.
fn show(view: &ArView, state: &mut ArState, frame: ReadFrame) {
    state.taken = Some(frame.position);
    state.shown = Some(frame.index);
    let finding = match frame.content {
        Err(message) => {
            warn!("{message}");
            Finding::Unreadable(message)
        }
        Ok(searched) => {
            state.image = Some(searched.image);
            state.fitted = searched.fitted;
            state.images_read += 1;
            state.read_time = searched.work;
            let markers = searched.markers;
            match view.target {
                Target::Marker { id, side_m } => {
                    let found = markers.iter().find(|m| m.id == id).and_then(|marker| {
                        let corners = marker.corners_f64();
                        estimate(&corners, side_m, &view.camera).map(|estimate| (corners, estimate))
                    });
                    match found {
                        Some((corners, estimate)) => {
                            let shown = state.follower.follow(&estimate);
                            let (kept_alternative, flipped) = (shown.kept_alternative, shown.flipped);
                            Finding::Found { corners, estimate: Box::new(estimate), kept_alternative, flipped }
                        }
                        None => Finding::Lost { held: false },
                    }
                }
                Target::Board(board) => match board.pose(&searched.points, &markers, &view.camera) {
                    Some(found) => board_finding(&board, &searched.points, found),
                    None => Finding::Lost { held: false },
                },
            }
        }
    };
    let found_pose = match &finding {
        Finding::Found { estimate, kept_alternative: true, .. } => Some(estimate.alternative),
        Finding::Found { estimate, .. } => Some(estimate.pose),
        Finding::Board { pose, .. } => Some(pose.pose),
        _ => None,
    };
    let shown = state.tracker.update(found_pose, state.time_s, view.hold_s);
    if shown.is_none() {
        state.follower.forget();
    }
    state.pose = shown.map(|(pose, _)| pose);
    let finding = match finding {
        Finding::Lost { .. } => Finding::Lost { held: shown.is_some() },
        other => other,
    };
    if state.records.len() == MAX_RECORDS {
        state.records.pop_front();
        state.records_dropped += 1;
    }
    state.records.push_back(FrameRecord { frame: frame.index, time_s: state.time_s, finding });
}

/// A board's finding: its pose moved to its centre with a marker frame's axes, and its points
/// found, in that frame.
fn board_finding(board: &Board, points: &[(DVec3, DVec2)], found: BoardPose) -> Finding {
    let points = points.iter().map(|&(object, pixel)| (board.from_board(object), pixel)).collect();
    Finding::Board { pose: BoardPose { pose: board.centred(&found.pose), ..found }, points }
}

fn place_camera(
    target: Res<RasterTarget>,
    mut render: ResMut<RenderView>,
    mut overlays: Query<(&ArView, &mut ArState)>,
) {
    let Some((view, mut state)) = overlays.iter_mut().next() else { return };
    let Some(pose) = state.pose else {
        state.overlay_error_px = None;
        return;
    };
    // The size the frame will be drawn at (the rasterizer's bound applied).
    let size = target.size.clamp(UVec2::ONE, UVec2::splat(MAX_TARGET_SIZE));
    let fit = Fit::new(view.camera.size, size.to_array());
    let (near, far) = (render.camera.near, render.camera.far);
    render.camera = render_camera(&pose, &view.camera, &fit, size, view.scale, near, far);
    // Where the drawn scene puts the marker's corners, against where they were found (both
    // without the lens's distortion, as the backdrop shows them).
    let clip = render.camera.view_projection(size.x as f32 / size.y as f32);
    state.overlay_error_px = state.found_points(&view.target).map(|points| {
        points
            .into_iter()
            .map(|(corner, found)| {
                let ndc = clip.project_point3(world_from_marker(corner, view.scale));
                let drawn = DVec2::new(
                    f64::from((ndc.x + 1.0) * 0.5 * size.x as f32) - 0.5,
                    f64::from((1.0 - ndc.y) * 0.5 * size.y as f32) - 0.5,
                );
                drawn.distance(fit.to_view(view.camera.straightened(found))) / fit.scale
            })
            .fold(0.0, f64::max)
    });
    state.overlay_error_max_px = state.overlay_error_max_px.max(state.overlay_error_px.unwrap_or(0.0));
}

fn lay_over_frame(
    render: Res<RenderView>,
    mut target: ResMut<RasterTarget>,
    mut overlays: Query<(&ArView, &mut ArState)>,
) {
    let Some((view, mut state)) = overlays.iter_mut().next() else { return };
    let state = &mut *state;
    let Some(image) = &state.image else { return };
    let framebuffer = &mut target.framebuffer;
    let size = [framebuffer.width(), framebuffer.height()];
    let background = render.background;
    if state.backdrop.as_ref().is_none_or(|backdrop| {
        backdrop.map.target != size || backdrop.map.camera != view.camera || backdrop.background != background
    }) {
        let backdrop = Arc::new(Backdrop { map: Remap::new(&view.camera, size), background });
        if let Some(stream) = &state.stream {
            stream.fit_with(backdrop.clone());
        }
        state.backdrop = Some(backdrop);
        state.backdrop_of = None;
    }
    // The photograph fitted to the view once per camera frame: on the reading thread when it
    // had the backdrop of now.
    if state.backdrop_of != Some(state.images_read)
        && let Some(backdrop) = &state.backdrop
    {
        match state.fitted.take() {
            Some((by, pixels)) if Arc::ptr_eq(&by, backdrop) => state.backdrop_pixels = pixels,
            _ => backdrop.map.apply(image.as_raw(), backdrop.background, &mut state.backdrop_pixels),
        }
        state.backdrop_of = Some(state.images_read);
    }
    if state.pose.is_none() {
        // The marker is lost: the photograph alone.
        framebuffer.clear(render.background);
    }
    framebuffer.fill_empty(&state.backdrop_pixels);
    if state.outline
        && let Some(points) = state.found_points(&view.target)
    {
        let fit = Fit::new(view.camera.size, size);
        let shown: Vec<Vec2> =
            points.iter().map(|&(_, found)| fit.to_view(view.camera.straightened(found)).as_vec2()).collect();
        if let Target::Board(Board::Charuco(_)) = view.target {
            // Each chessboard corner found: a cross.
            for &corner in &shown {
                for arm in [Vec2::new(4.0, 4.0), Vec2::new(4.0, -4.0)] {
                    framebuffer.draw_line(corner - arm, corner + arm, [40, 220, 60, 255]);
                }
            }
            return;
        }
        // Each marker found: its four corners in OpenCV's order.
        for corners in shown.chunks_exact(4) {
            for (i, &from) in corners.iter().enumerate() {
                // The first side (top-left to top-right as printed) in red, the others in green.
                let color = if i == 0 { [230, 40, 40, 255] } else { [40, 220, 60, 255] };
                framebuffer.draw_line(from, corners[(i + 1) % 4], color);
            }
        }
    }
}

impl DumpState for ArView {
    fn dump(&self, out: &mut Map<String, Value>) {
        out.insert("source".into(), json!(self.source.kind()));
        out.insert("frames".into(), json!(self.source.frame_count()));
        out.insert("frame_size".into(), json!(self.source.size()));
        out.insert("fps".into(), json!(self.fps));
        out.insert("dictionary".into(), json!(self.dictionary.name.as_ref()));
        match self.target {
            Target::Marker { id, side_m } => {
                out.insert("marker_id".into(), json!(id));
                out.insert("marker_side_m".into(), json!(side_m));
            }
            Target::Board(Board::Grid(grid)) => {
                let board = json!({"markers": grid.markers, "marker_m": grid.marker_m,
                    "separation_m": grid.separation_m, "first_id": grid.first_id});
                out.insert("board".into(), board);
            }
            Target::Board(Board::Charuco(charuco)) => {
                let board = json!({"squares": charuco.squares, "square_m": charuco.square_m,
                    "marker_m": charuco.marker_m, "first_id": charuco.first_id, "legacy": charuco.legacy});
                out.insert("board".into(), board);
            }
        }
    }
}

impl DumpState for ArState {
    fn dump(&self, out: &mut Map<String, Value>) {
        let records: Vec<Value> = self
            .records
            .iter()
            .map(|record| {
                let mut entry = json!({"frame": record.frame, "time_s": record.time_s});
                let fields = match &record.finding {
                    Finding::Found { corners, estimate, kept_alternative, flipped } => {
                        let mut found = marker_json(corners, Some(estimate));
                        found["marker"] = json!("found");
                        found["shown"] = json!(if *kept_alternative { "alternative" } else { "best" });
                        found["flipped"] = json!(flipped);
                        found
                    }
                    Finding::Board { pose, points } => json!({
                        "marker": "found",
                        "board_markers": pose.markers,
                        "board_points": points.len(),
                        "rvec": pose.pose.rvec().to_array(),
                        "tvec": pose.pose.translation.to_array(),
                        "reprojection_error_px": pose.error_px,
                    }),
                    Finding::Lost { held: true } => json!({"marker": "held"}),
                    Finding::Lost { held: false } => json!({"marker": "not found"}),
                    Finding::Unreadable(message) => json!({"marker": "unreadable", "error": message}),
                };
                if let (Value::Object(entry), Value::Object(fields)) = (&mut entry, fields) {
                    entry.extend(fields);
                }
                entry
            })
            .collect();
        out.insert("shown".into(), json!(self.shown));
        out.insert("source_error".into(), json!(self.source_error));
        out.insert("overlay_visible".into(), json!(self.pose.is_some()));
        out.insert("outline".into(), json!(self.outline));
        out.insert("overlay_error_px".into(), json!(self.overlay_error_px));
        out.insert("overlay_error_max_px".into(), json!(self.overlay_error_max_px));
        out.insert("poses".into(), Value::Array(records));
        out.insert("flips".into(), json!(self.follower.flips()));
        out.insert("alternatives_kept".into(), json!(self.follower.kept()));
        out.insert("poses_dropped".into(), json!(self.records_dropped));
    }
}
