//! The `sloth` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::biceps::Biceps;
use super::debug::{SlothDebug, SlothDebugPlugin};
use super::def::SlothDef;
use super::locomotion::Sloth;
use super::panel;
use super::plugin::{self, SlothPlugin};
use super::supports::Supports;
use crate::foundation::keys::RegisterKeys;
use crate::foundation::kind::{BuildContext, EntityKind};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use crate::tree::TreeKind;
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use std::sync::Arc;

/// The `sloth` kind, built after the trees it hangs from.
pub struct SlothKind;

impl EntityKind for SlothKind {
    const KEY: &'static str = "sloth";
    type Def = SlothDef;
    type Built = (Sloth, Arc<Supports>, [Biceps; 2]);
    type Plugin = SlothPlugin;

    /// Places the sloth on the scene's trees (built by the tree kind before, gathered once for
    /// all the sloths) and builds its biceps; an error is located at the sloth's `support` or
    /// `biceps` key.
    fn build(def: &SlothDef, cx: &BuildContext) -> Result<Self::Built, FileError> {
        let supports = cx.shared(|| Supports::new(cx.built::<TreeKind>()));
        let entity = &cx.entity;
        let sloth = def.place(&supports, def.speed.0).map_err(|error| {
            entity.locate("support", entity.kind_index, format!("{}: {error}", entity.field("support")))
        })?;
        let biceps = def.biceps().map_err(|error| entity.field_error("biceps", 0, "biceps", error))?;
        Ok((sloth, supports, biceps))
    }

    fn spawn(def: &SlothDef, (sloth, supports, biceps): &Self::Built, entity: &mut EntityWorldMut) {
        plugin::spawn_sloth(entity, def, sloth.clone(), supports.clone(), biceps.clone());
        entity.insert(SlothDebug::default());
    }

    fn save_live(def: &mut SlothDef, entity: EntityRef) {
        plugin::save_live(def, entity);
    }

    fn register(app: &mut App) {
        app.register_kind_keys::<Self>(&plugin::SLOTH_KEYS)
            .register_panel_section::<Self>(panel::sloth_section)
            .add_plugins(SlothDebugPlugin);
    }
}
