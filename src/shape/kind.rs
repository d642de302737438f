//! The `shape` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::ShapeDef;
use super::mesh::MeshParts;
use super::plugin::{self, Shape, ShapeParams, ShapePart, ShapePlugin};
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::yaml::FileError;
use crate::raster::RasterMesh;
use crate::raster::primitives::PrimitiveMeshes;
use crate::raster::texture::TextureDef;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::prelude::*;

/// The `shape` kind.
pub struct ShapeKind;

impl EntityKind for ShapeKind {
    const KEY: &'static str = "shape";
    type Def = ShapeDef;
    type Built = ();
    type Plugin = ShapePlugin;

    fn references(def: &ShapeDef) -> Vec<String> {
        let mut files = TextureDef::reference(def.texture.as_ref());
        files.extend(def.mesh.as_ref().map(|mesh| mesh.path.clone()));
        files
    }

    fn resolve(def: &mut ShapeDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        if let Some(texture) = def.texture.as_mut() {
            texture.resolve(file, cx, "texture.file")?;
        }
        if def.mesh.as_ref().is_some_and(|mesh| mesh.path == file.file) {
            def.drawn = Some(MeshParts::resolve(file, cx)?);
        }
        Ok(())
    }

    fn build(def: &ShapeDef, cx: &BuildContext) -> Result<(), FileError> {
        let cx = &cx.entity;
        match (def.primitive, &def.mesh) {
            (Some(_), Some(_)) => Err(cx.field_error("mesh", 0, "mesh", "a primitive or a mesh, not both")),
            (None, None) => Err(cx.locate(
                ShapeKind::KEY,
                cx.kind_index,
                format!(
                    "{}: expected `primitive: box` (or sphere, cylinder, plane) or `mesh: FILE`",
                    cx.field("primitive")
                ),
            )),
            (None, Some(_)) if def.texture.is_some() => {
                Err(cx.field_error("texture", 0, "texture", "a mesh shape takes its textures from its file"))
            }
            _ => Ok(()),
        }
    }

    fn spawn(def: &ShapeDef, _built: &(), entity: &mut EntityWorldMut) {
        let params = ShapeParams::from(def);
        let tint = params.color_channels();
        entity.insert((params.transform(), params));
        if let Some(primitive) = def.primitive {
            let mesh = entity.world().resource::<PrimitiveMeshes>().get(primitive).clone();
            entity.insert((Shape::Primitive(primitive), RasterMesh { mesh, material: def.material(tint) }));
        } else if let Some(drawn) = &def.drawn {
            entity.insert(Shape::Mesh { triangles: drawn.triangles }).with_children(|children| {
                for (mesh, material) in &drawn.parts {
                    let part = ShapePart { color: material.color };
                    let material = crate::raster::Material { color: part.tinted(tint), ..material.clone() };
                    children.spawn((part, RasterMesh { mesh: mesh.clone(), material }, Transform::IDENTITY));
                }
            });
        }
    }

    fn save_live(def: &mut ShapeDef, entity: EntityRef) {
        plugin::save_live(def, entity);
    }
}
