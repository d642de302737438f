//! The `world` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::chunk::CHUNK_CELLS;
use super::def::{WorldBuilt, WorldDef};
use super::panel;
use super::plugin::spawn_world;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use crate::terrain::def::HeightDef;
use crate::terrain::section::Geometry;
use bevy::app::App;
use bevy::ecs::world::EntityWorldMut;

/// The `world` kind.
#[derive(Debug, Default)]
pub struct WorldKind;

impl EntityKind for WorldKind {
    const KEY: &'static str = "world";
    type Def = WorldDef;
    type Built = WorldBuilt;
    type Plugin = super::plugin::WorldPlugin;

    fn validate(def: &WorldDef, cx: &EntityContext) -> Result<(), FileError> {
        match &def.map {
            Some(_) if !def.layers.is_empty() || !def.apply.is_empty() || def.seed != -1 => {
                let beside = if !def.layers.is_empty() {
                    "layers"
                } else if !def.apply.is_empty() {
                    "apply"
                } else {
                    "seed"
                };
                let message = format!(
                    "`{beside}` beside `map`: a finite world's heights are its map's, so its seed, layers and \
                     apply go inside `map`"
                );
                Err(cx.field_error("map", 0, "map", message))
            }
            Some(map) => map.validate("map", cx),
            None if def.layers.is_empty() => Err(cx.field_error(
                "world",
                0,
                "layers",
                "expected `layers` for a world without bounds, or a `map` for a finite one",
            )),
            None => Ok(()),
        }
    }

    fn references(def: &WorldDef) -> Vec<String> {
        def.map.iter().flat_map(HeightDef::references).chain(def.bands.references()).collect()
    }

    fn resolve(def: &mut WorldDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        if let Some(map) = &mut def.map {
            map.resolve("map", file, cx)?;
        }
        def.bands.resolve(file, cx)
    }

    fn build(def: &WorldDef, cx: &BuildContext) -> Result<WorldBuilt, FileError> {
        if !CHUNK_CELLS.contains(&def.chunk_cells) {
            let message = format!("expected one of {CHUNK_CELLS:?} cells, found {}", def.chunk_cells);
            return Err(cx.entity.field_error("chunk_cells", 0, "chunk_cells", message));
        }
        let (heights, seed) = def.heights(cx)?;
        let stream = def.stream(heights.chunks(def.chunk_cells));
        stream.check().map_err(|error| {
            // The chunk's side follows from `chunk_cells` and `cell_m`, both checked already.
            let key = if error.field == "chunk_m" { "chunk_cells" } else { error.field };
            cx.entity.field_error(key, 0, key, &error.message)
        })?;
        if !(1..=64).contains(&def.spawn_budget) {
            let message = format!("expected 1 to 64 chunks a frame, found {}", def.spawn_budget);
            return Err(cx.entity.field_error("spawn_budget", 0, "spawn_budget", message));
        }
        def.bands.rule().check().map_err(|message| cx.entity.field_error("bands", 0, "bands", message))?;
        let geometry =
            Geometry { cell_m: def.cell_m.0, height_m: def.height_m.0, texture_cells: def.bands.texture_cells.0 };
        Ok(WorldBuilt { heights, seed, stream, geometry })
    }

    fn spawn(def: &WorldDef, built: &WorldBuilt, entity: &mut EntityWorldMut) {
        spawn_world(entity, def, built);
    }

    fn saved(def: &WorldDef) -> WorldDef {
        let mut saved = def.clone();
        if let Some(map) = &mut saved.map {
            map.decoded = None;
        }
        saved
    }

    fn register(app: &mut App) {
        app.register_panel_section::<Self>(panel::world_section);
    }
}
