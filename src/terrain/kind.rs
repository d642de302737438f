//! The `terrain` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::{TerrainBuilt, TerrainDef, default_section_size};
use super::ground::{Ground, placement, section_barycentre};
use super::plugin::{TerrainPlugin, spawn_terrain};
use super::section::{Geometry, Section};
use super::{panel, plugin};
use crate::foundation::keys::RegisterKeys;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::math::Vec3;
use std::sync::Arc;

/// The `terrain` kind.
pub struct TerrainKind;

impl EntityKind for TerrainKind {
    const KEY: &'static str = "terrain";
    type Def = TerrainDef;
    type Built = TerrainBuilt;
    type Plugin = TerrainPlugin;

    fn validate(def: &TerrainDef, cx: &EntityContext) -> Result<(), FileError> {
        def.height.validate("height", cx)
    }

    fn references(def: &TerrainDef) -> Vec<String> {
        def.height.references().into_iter().chain(def.bands.references()).collect()
    }

    fn resolve(def: &mut TerrainDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        def.height.resolve("height", file, cx)?;
        def.bands.resolve(file, cx)
    }

    fn build(def: &TerrainDef, cx: &BuildContext) -> Result<TerrainBuilt, FileError> {
        let (map, seed) = def.height.build("height", cx)?;
        let section = Section { origin: def.section.origin, size: def.section.size };
        // The default size fits small maps; a size the file asks for must fit.
        let section = if def.section.size == default_section_size() { section.clamped(&map) } else { section };
        section.check(&map).map_err(|error| cx.entity.field_error("section", 0, "section.size", error))?;
        let [x, z] = section.origin;
        if x + section.size[0] > map.width() || z + section.size[1] > map.height() {
            let message = format!(
                "a section of {} x {} vertices at [{x}, {z}] reaches beyond the map's {} x {} samples",
                section.size[0],
                section.size[1],
                map.width(),
                map.height()
            );
            return Err(cx.entity.field_error("section", 0, "section.origin", message));
        }
        def.bands.rule().check().map_err(|message| cx.entity.field_error("bands", 0, "bands", message))?;
        let geometry =
            Geometry { cell_m: def.cell_m.0, height_m: def.height_m.0, texture_cells: def.bands.texture_cells.0 };
        let barycentre = section_barycentre(&map, section, geometry);
        let scale = Vec3::from_array(def.scale.map(|f| f.0));
        let place = placement(def.position.0, def.rotation_deg.0, scale, barycentre).compute_affine();
        let ground = Arc::new(Ground::of_section(&map, section, geometry, barycentre, place));
        Ok(TerrainBuilt { map: Arc::new(map), seed, ground })
    }

    fn spawn(def: &TerrainDef, built: &TerrainBuilt, entity: &mut EntityWorldMut) {
        spawn_terrain(entity, def, built);
    }

    fn saved(def: &TerrainDef) -> TerrainDef {
        let mut saved = def.clone();
        saved.height.decoded = None;
        saved
    }

    fn save_live(def: &mut TerrainDef, entity: EntityRef) {
        super::plugin::save_live(def, entity);
    }

    fn register(app: &mut App) {
        let moves = plugin::MOVE_KEYS.iter().map(|&(key, action, ..)| (key, action));
        let model = plugin::MODEL_KEYS.iter().map(|&(key, action, ..)| (key, action));
        let map = [
            (plugin::NEW_SEED, "make the map again with the next seed"),
            (plugin::SAVE_MAP, "save the heightmap as a 16-bit PNG in heightmaps/"),
        ];
        app.register_kind_keys::<Self>(&moves.chain(model).chain(map).collect::<Vec<_>>())
            .register_panel_section::<Self>(panel::terrain_section);
    }
}
