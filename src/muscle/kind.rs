//! The `muscle` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::{BuiltMuscle, ConfigFile, MuscleDef};
use super::model::ConfigError;
use super::panel;
use super::plugin::{self, MusclePlugin};
use crate::foundation::keys::RegisterKeys;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile, Standalone, ViewPoint};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::{FileError, parse_yaml};
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::math::Vec3;
use std::path::Path;

/// The `muscle` kind.
pub struct MuscleKind;

impl EntityKind for MuscleKind {
    const KEY: &'static str = "muscle";
    type Def = MuscleDef;
    type Built = BuiltMuscle;
    type Plugin = MusclePlugin;

    /// A file whose top level is the source program's configuration (`muscle_config` and
    /// `carcass_config`) is a scene too: that muscle, named `muscle`, seen from a camera that
    /// frames its arm.
    fn standalone(path: &Path, bytes: &[u8]) -> Option<Result<Standalone<MuscleDef>, FileError>> {
        let text = String::from_utf8_lossy(bytes);
        text.lines().any(|line| line.starts_with("muscle_config:")).then(|| {
            let view =
                ViewPoint { position: Vec3::new(-0.2, 0.7, 2.4), look_at: Vec3::new(-0.2, 0.1, 0.0), fov_deg: 45.0 };
            parse_yaml(path, bytes, "a muscle configuration").map(|def| Standalone { def, view })
        })
    }

    fn validate(def: &MuscleDef, cx: &EntityContext) -> Result<(), FileError> {
        if def.file.is_some() && (def.muscle_config.is_some() || def.carcass_config.is_some()) {
            let message =
                format!("{}: give the configuration either inline or from a file, not both", cx.field("file"));
            return Err(cx.locate("file", 0, message));
        }
        Ok(())
    }

    fn references(def: &MuscleDef) -> Vec<String> {
        def.file.iter().map(|file| file.path.clone()).collect()
    }

    fn resolve(def: &mut MuscleDef, file: &mut ReferencedFile, _cx: &EntityContext) -> Result<(), FileError> {
        let config = file.decoded(ConfigFile::read)?;
        def.fill_from((*config).clone());
        Ok(())
    }

    /// Builds the model; an error in an inline configuration is located at its
    /// `muscle_config` key (the nth inline muscle has the nth of the file).
    fn build(def: &MuscleDef, cx: &BuildContext) -> Result<BuiltMuscle, FileError> {
        let entity = &cx.entity;
        def.build().map_err(|error| {
            if let ConfigError::NotMeasuredLayout(_) | ConfigError::NoFitFrom = error {
                let nth = cx.earlier::<MuscleKind>().filter(|earlier| earlier.fit_growth).count();
                entity.locate("fit_growth", nth, format!("{}: {error}", entity.field("fit_growth")))
            } else if def.file.is_some() {
                entity.whole_file(format!("entities[{}].muscle: {error}", entity.index))
            } else {
                let nth = cx.earlier::<MuscleKind>().filter(|earlier| earlier.file.is_none()).count();
                entity.locate("muscle_config", nth, format!("{}: {error}", entity.field("muscle_config")))
            }
        })
    }

    fn spawn(def: &MuscleDef, built: &BuiltMuscle, entity: &mut EntityWorldMut) {
        plugin::spawn_muscle(entity, def, built.clone());
    }

    fn saved(def: &MuscleDef) -> MuscleDef {
        let mut saved = def.clone();
        if saved.file.is_some() {
            saved.muscle_config = None;
            saved.carcass_config = None;
        }
        saved
    }

    fn save_live(def: &mut MuscleDef, entity: EntityRef) {
        plugin::save_live(def, entity);
    }

    fn register(app: &mut App) {
        let flexion = plugin::MUSCLE_KEYS.iter().map(|&(key, action, ..)| (key, action));
        let placement = plugin::PLACEMENT_KEYS.iter().map(|&(key, action, ..)| (key, action));
        app.register_kind_keys::<Self>(&flexion.chain(placement).collect::<Vec<_>>())
            .register_panel_section::<Self>(panel::muscle_section);
    }
}
