//! The `ar` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::calibration;
use super::def::{ArBuilt, ArDef, DictionaryName, FrameRate};
use super::dictionary_file;
use super::frames::{FrameFolder, MAX_FRAME_SIDE};
use super::panel;
use super::plugin::{ArPlugin, ArState, ArView};
use super::source::Source;
use super::video::VideoFile;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use canopy_vision::board::Board;
use canopy_vision::dictionary::Dictionary;
use std::sync::Arc;

/// The board the scene stands on, if it stands on one, checked against `dictionary`, or the
/// marker's id checked against it.
fn target_board(def: &ArDef, dictionary: &Dictionary, cx: &EntityContext) -> Result<Option<Board>, FileError> {
    if let Some(id) = def.marker_id
        && id >= dictionary.len()
    {
        let message = format!("{} has markers 0 to {}, not {id}", dictionary.name, dictionary.len() - 1);
        return Err(cx.field_error("marker_id", 0, "marker_id", message));
    }
    def.board
        .map(|board| board.board(dictionary))
        .transpose()
        .map_err(|error| cx.field_error("board", 0, "board", error))
}

/// The `ar` kind.
pub struct ArKind;

impl EntityKind for ArKind {
    const KEY: &'static str = "ar";
    type Def = ArDef;
    type Built = ArBuilt;
    type Plugin = ArPlugin;

    fn validate(def: &ArDef, cx: &EntityContext) -> Result<(), FileError> {
        if !matches!((def.marker_id, def.marker_side_m, def.board), (Some(_), Some(_), None) | (None, None, Some(_))) {
            let message = "expected `marker_id` and `marker_side_m`, or a `board`, to stand the scene on";
            return Err(cx.locate(ArKind::KEY, cx.kind_index, format!("{}: {message}", cx.field("marker_id"))));
        }
        // Against a predefined dictionary now; against a dictionary file when it has been read,
        // as the entity is built.
        if let Some(dictionary) = def.dictionary.dictionary() {
            target_board(def, dictionary, cx)?;
        }
        let sources = [def.frames.is_some(), def.video.is_some(), def.camera.is_some()];
        if sources.iter().filter(|&&given| given).count() != 1 {
            let message = "expected one source of frames: `frames` (a folder), `video` (a file) or `camera`";
            return Err(cx.locate(ArKind::KEY, cx.kind_index, format!("{}: {message}", cx.field("frames"))));
        }
        if let Some(camera) = &def.camera {
            if def.fps.is_some() {
                let message = "a camera's rate is its `fps`, in `camera`";
                return Err(cx.field_error("fps", 0, "fps", message));
            }
            if camera.size.iter().any(|&side| side == 0 || side > MAX_FRAME_SIDE) {
                let message = format!("expected 1 to {MAX_FRAME_SIDE} pixels a side, found {:?}", camera.size);
                return Err(cx.field_error("size", 0, "camera.size", message));
            }
        }
        if cx.kind_index > 0 {
            return Err(cx.field_error("frames", 0, "frames", "a scene has one camera to draw over: one `ar` entity"));
        }
        Ok(())
    }

    fn references(def: &ArDef) -> Vec<String> {
        let mut files = vec![def.calibration.path.clone()];
        if let DictionaryName::File { file, .. } = &def.dictionary {
            files.push(file.path.clone());
        }
        files
    }

    fn resolve(def: &mut ArDef, file: &mut ReferencedFile, _cx: &EntityContext) -> Result<(), FileError> {
        if def.calibration.path == file.file {
            def.calibration_read = Some(file.decoded(calibration::parse)?);
        }
        if let DictionaryName::File { file: name, read } = &mut def.dictionary
            && name.path == file.file
        {
            *read = Some(file.decoded(dictionary_file::parse)?);
        }
        Ok(())
    }

    fn build(def: &ArDef, cx: &BuildContext) -> Result<ArBuilt, FileError> {
        let entity = cx.entity;
        let beside = |relative: &str| entity.path.parent().unwrap_or(std::path::Path::new(".")).join(relative);
        let source = match (&def.frames, &def.video, &def.camera) {
            (Some(folder), _, _) => {
                let path = beside(&folder.0);
                let frames =
                    FrameFolder::open(&path).map_err(|error| entity.field_error("frames", 0, "frames", error))?;
                Source::Folder { path, frames: Arc::new(frames) }
            }
            (_, Some(video), _) => {
                let video = VideoFile::probe(&beside(&video.path))
                    .map_err(|error| entity.field_error("video", 0, "video", error))?;
                Source::Video(Arc::new(video))
            }
            // A camera is opened when the scene plays: one that is not there is a message in
            // the panel, not a scene that cannot load.
            (_, _, Some(camera)) => Source::Camera(camera.settings()),
            (None, None, None) => {
                return Err(entity.field_error("frames", 0, "frames", "no source of frames"));
            }
        };
        let calibration = def
            .calibration_read
            .as_ref()
            .ok_or_else(|| entity.field_error("calibration", 0, "calibration", "the calibration file was not read"))?;
        let camera = calibration
            .for_frames(source.size())
            .map_err(|error| entity.field_error("calibration", 0, "calibration", error))?;
        let dictionary = def
            .dictionary
            .dictionary()
            .ok_or_else(|| entity.field_error("dictionary", 0, "dictionary", "the dictionary file was not read"))?
            .clone();
        let board = target_board(def, &dictionary, &entity)?;
        Ok(ArBuilt { source, camera, calibration: calibration.clone(), board, dictionary })
    }

    fn spawn(def: &ArDef, built: &ArBuilt, entity: &mut EntityWorldMut) {
        entity.insert((ArView::new(def, built), ArState::default()));
    }

    fn save_live(def: &mut ArDef, entity: EntityRef) {
        // A camera chosen in the panel is the one saved.
        if let (Some(camera), Some(Source::Camera(settings))) =
            (&mut def.camera, entity.get::<ArView>().map(|v| &v.source))
        {
            camera.device = settings.device.clone();
            camera.size = settings.size;
            camera.fps = FrameRate(settings.fps);
        }
    }

    fn register(app: &mut App) {
        app.register_panel_section::<Self>(panel::overlay_section);
    }
}
