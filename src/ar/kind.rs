//! The `ar` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::calibration;
use super::def::{ArBuilt, ArDef};
use super::frames::FrameFolder;
use super::panel;
use super::plugin::{ArPlugin, ArState, ArView};
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use bevy::app::App;
use bevy::ecs::world::EntityWorldMut;
use canopy_vision::board::GridBoard;
use std::sync::Arc;

/// The `ar` kind.
pub struct ArKind;

impl EntityKind for ArKind {
    const KEY: &'static str = "ar";
    type Def = ArDef;
    type Built = ArBuilt;
    type Plugin = ArPlugin;

    fn validate(def: &ArDef, cx: &EntityContext) -> Result<(), FileError> {
        let dictionary = def.dictionary.0;
        match (def.marker_id, def.marker_side_m, def.board) {
            (Some(id), Some(_), None) if id >= dictionary.len() => {
                let message = format!("{} has markers 0 to {}, not {id}", dictionary.name, dictionary.len() - 1);
                return Err(cx.field_error("marker_id", 0, "marker_id", message));
            }
            (Some(_), Some(_), None) => {}
            (None, None, Some(board)) => {
                GridBoard::new(board.markers, board.marker_m, board.separation_m, board.first_id, &dictionary)
                    .map_err(|error| cx.field_error("board", 0, "board", error))?;
            }
            _ => {
                let message = "expected `marker_id` and `marker_side_m`, or a `board`, to stand the scene on";
                return Err(cx.locate(ArKind::KEY, cx.kind_index, format!("{}: {message}", cx.field("marker_id"))));
            }
        }
        if cx.kind_index > 0 {
            return Err(cx.field_error("frames", 0, "frames", "a scene has one camera to draw over: one `ar` entity"));
        }
        Ok(())
    }

    fn references(def: &ArDef) -> Vec<String> {
        vec![def.calibration.path.clone()]
    }

    fn resolve(def: &mut ArDef, file: &mut ReferencedFile, _cx: &EntityContext) -> Result<(), FileError> {
        if def.calibration.path == file.file {
            def.calibration_read = Some(file.decoded(calibration::parse)?);
        }
        Ok(())
    }

    fn build(def: &ArDef, cx: &BuildContext) -> Result<ArBuilt, FileError> {
        let entity = cx.entity;
        let folder = entity.path.parent().unwrap_or(std::path::Path::new(".")).join(&def.frames.0);
        let frames = FrameFolder::open(&folder).map_err(|error| entity.field_error("frames", 0, "frames", error))?;
        let calibration = def
            .calibration_read
            .as_ref()
            .ok_or_else(|| entity.field_error("calibration", 0, "calibration", "the calibration file was not read"))?;
        let camera = calibration
            .for_frames(frames.size)
            .map_err(|error| entity.field_error("calibration", 0, "calibration", error))?;
        Ok(ArBuilt { frames: Arc::new(frames), camera, folder })
    }

    fn spawn(def: &ArDef, built: &ArBuilt, entity: &mut EntityWorldMut) {
        entity.insert((ArView::new(def, built), ArState::default()));
    }

    fn register(app: &mut App) {
        app.register_panel_section::<Self>(panel::overlay_section);
    }
}
