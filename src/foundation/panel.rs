//! Panel sections: a kind's own part of the window's side panel, drawn under the parameters
//! of a selected entity of that kind.

use super::kind::EntityKind;
use bevy::prelude::*;
use bevy_egui::egui;

/// Draws a kind's own section of the panel for a selected entity, with access to the world.
pub type PanelSection = fn(&mut egui::Ui, &mut World, Entity);

/// The panel sections of entity kinds, in registration order.
#[derive(Resource, Default)]
pub struct PanelSections(Vec<(&'static str, PanelSection)>);

impl PanelSections {
    /// The sections of `kind`.
    pub fn of<'a>(&'a self, kind: &'a str) -> impl Iterator<Item = PanelSection> + 'a {
        self.0.iter().filter(move |(k, _)| *k == kind).map(|(_, section)| *section)
    }
}

/// Registration of panel sections on the app.
pub trait RegisterPanel {
    /// Draws `section` in the panel when an entity of kind `K` is selected.
    fn register_panel_section<K: EntityKind>(&mut self, section: PanelSection) -> &mut Self;
}

impl RegisterPanel for App {
    fn register_panel_section<K: EntityKind>(&mut self, section: PanelSection) -> &mut Self {
        self.world_mut().get_resource_or_init::<PanelSections>().0.push((K::KEY, section));
        self
    }
}
