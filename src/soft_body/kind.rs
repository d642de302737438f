//! The `soft_body` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::{SoftBodyBuilt, SoftBodyDef, check_source, read_mesh, source_surface};
use super::panel;
use super::plugin::{self, SoftBodyAction, SoftBodyPlugin, spawn_soft_body};
use crate::foundation::actions::RegisterActions;
use crate::foundation::keys::RegisterKeys;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use std::sync::Arc;

/// The `soft_body` kind.
pub struct SoftBodyKind;

impl EntityKind for SoftBodyKind {
    const KEY: &'static str = "soft_body";
    type Def = SoftBodyDef;
    type Built = Arc<SoftBodyBuilt>;
    type Plugin = SoftBodyPlugin;

    fn validate(def: &SoftBodyDef, cx: &EntityContext) -> Result<(), FileError> {
        check_source(Self::KEY, &def.mesh, &def.sample, cx)?;
        let (method, settings) = def.deformer();
        settings.check(method).map_err(|error| cx.field_error("k", 0, "k", error))
    }

    fn references(def: &SoftBodyDef) -> Vec<String> {
        def.mesh.iter().map(|file| file.path.clone()).collect()
    }

    fn resolve(def: &mut SoftBodyDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        def.decoded = Some(read_mesh(file, cx)?);
        Ok(())
    }

    fn build(def: &SoftBodyDef, cx: &BuildContext) -> Result<Arc<SoftBodyBuilt>, FileError> {
        let (surface, read) = source_surface(&def.decoded, def.sample, cx)?;
        Ok(Arc::new(SoftBodyBuilt { surface, read, file: def.decoded.clone() }))
    }

    fn spawn(def: &SoftBodyDef, built: &Arc<SoftBodyBuilt>, entity: &mut EntityWorldMut) {
        spawn_soft_body(entity, def, built);
    }

    fn save_live(def: &mut SoftBodyDef, entity: EntityRef) {
        super::plugin::save_live(def, entity);
    }

    fn register(app: &mut App) {
        app.register_actions::<Self, SoftBodyAction>(plugin::perform_action)
            .register_kind_keys::<Self>(&plugin::SOFT_BODY_KEYS)
            .register_panel_section::<Self>(panel::soft_body_section);
    }
}
