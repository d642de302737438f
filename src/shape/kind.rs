//! The `shape` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::ShapeDef;
use super::plugin::{self, Shape, ShapeParams, ShapePlugin};
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::yaml::FileError;
use crate::raster::RasterMesh;
use crate::raster::primitives::PrimitiveMeshes;
use crate::raster::texture::TextureDef;
use bevy::ecs::world::{EntityRef, EntityWorldMut};

/// The `shape` kind.
pub struct ShapeKind;

impl EntityKind for ShapeKind {
    const KEY: &'static str = "shape";
    type Def = ShapeDef;
    type Built = ();
    type Plugin = ShapePlugin;

    fn references(def: &ShapeDef) -> Vec<String> {
        TextureDef::reference(def.texture.as_ref())
    }

    fn resolve(def: &mut ShapeDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        def.texture.as_mut().map_or(Ok(()), |texture| texture.resolve(file, cx, "texture.file"))
    }

    fn build(_def: &ShapeDef, _cx: &BuildContext) -> Result<(), FileError> {
        Ok(())
    }

    fn spawn(def: &ShapeDef, _built: &(), entity: &mut EntityWorldMut) {
        let params = ShapeParams::from(def);
        let mesh = entity.world().resource::<PrimitiveMeshes>().get(def.primitive).clone();
        entity.insert((
            Shape(def.primitive),
            params.transform(),
            RasterMesh { mesh, material: def.material(params.color_channels()) },
            params,
        ));
    }

    fn save_live(def: &mut ShapeDef, entity: EntityRef) {
        plugin::save_live(def, entity);
    }
}
