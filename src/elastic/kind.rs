//! The `elastic` entity kind: how its entries are checked, built, spawned and saved, and what
//! the app offers for its entities beside its plugin.

use super::def::{ElasticBodyDef, ElasticBuilt, MAX_TETS, stem_anchor, stems};
use super::panel;
use super::plugin::{self, ElasticAction, ElasticPlugin, spawn_elastic_body};
use super::tet_mesh::{TetError, TetMesh};
use super::xpbd::Body;
use crate::foundation::actions::RegisterActions;
use crate::foundation::keys::RegisterKeys;
use crate::foundation::kind::{BuildContext, EntityContext, EntityKind, ReferencedFile};
use crate::foundation::panel::RegisterPanel;
use crate::foundation::yaml::FileError;
use crate::soft_body::def::{check_source, read_mesh, source_surface};
use bevy::app::App;
use bevy::ecs::world::{EntityRef, EntityWorldMut};
use bevy::math::Vec3;
use std::sync::Arc;

/// The `elastic_body` kind, built after the trees its stems may hang from.
pub struct ElasticBodyKind;

impl EntityKind for ElasticBodyKind {
    const KEY: &'static str = "elastic_body";
    type Def = ElasticBodyDef;
    type Built = Arc<ElasticBuilt>;
    type Plugin = ElasticPlugin;

    fn validate(def: &ElasticBodyDef, cx: &EntityContext) -> Result<(), FileError> {
        check_source(Self::KEY, &def.mesh, &def.sample, cx)?;
        let Some(stem) = &def.stem else { return Ok(()) };
        if def.position.is_some() {
            return Err(cx.field_error("position", 0, "position", "a body on a stem hangs below it: give no position"));
        }
        match (&stem.support, &stem.point) {
            (Some(_), Some(_)) => {
                Err(cx.field_error("point", 0, "stem.point", "a stem hangs from a support or a point, not both"))
            }
            (None, None) => {
                Err(cx.field_error("stem", 0, "stem", "expected `support: TREE/SUPPORT` or `point: [x, y, z]`"))
            }
            (None, Some(_)) if stem.at.is_some() => {
                Err(cx.field_error("at", 0, "stem.at", "`at` is a place along a support: give it with `support`"))
            }
            _ => Ok(()),
        }
    }

    fn references(def: &ElasticBodyDef) -> Vec<String> {
        def.mesh.iter().map(|file| file.path.clone()).collect()
    }

    fn resolve(def: &mut ElasticBodyDef, file: &mut ReferencedFile, cx: &EntityContext) -> Result<(), FileError> {
        def.decoded = Some(read_mesh(file, cx)?);
        Ok(())
    }

    /// Scales the surface to its size, places it (below its stem's anchor, or at its
    /// position), fills it with tetrahedra and attaches its top to the stem.
    fn build(def: &ElasticBodyDef, cx: &BuildContext) -> Result<Arc<ElasticBuilt>, FileError> {
        let entity = &cx.entity;
        let (mut surface, read) = source_surface(&def.decoded, def.sample, cx)?;
        let (low, high) = surface.bounds();
        let scale = def.size.0 / (high - low).max(Vec3::splat(f32::MIN_POSITIVE));
        let centre = (low + high) / 2.0;
        let anchor = def.stem.as_ref().map(|stem| stem_anchor(stem, cx)).transpose()?;
        let placed_centre = match (anchor, &def.stem) {
            (Some(anchor), Some(stem)) => anchor - Vec3::Y * (stem.length_m.0 + def.size.0.y / 2.0),
            _ => def.position.map_or(Vec3::ZERO, |p| p.0),
        };
        for p in &mut surface.positions {
            *p = (*p - centre) * scale + placed_centre;
        }
        let cell = def.cell();
        let fill_error = |error: TetError| {
            let key = match (&error, def.sample) {
                (TetError::Open(_), Some(_)) => "sample",
                (TetError::Open(_), None) => "mesh",
                _ => "cell_m",
            };
            entity.field_error(key, 0, key, format!("the body cannot be filled with tetrahedra: {error}"))
        };
        let (mesh, embedding) = TetMesh::fill(&surface, cell, MAX_TETS).map_err(fill_error)?;
        let mut body = Body::new(mesh, def.material());
        if let Some(velocity) = def.velocity {
            body.velocities.fill(velocity.0);
        }
        if let Some(anchor) = anchor {
            body.stems = stems(&body, anchor, cell);
        }
        let shaken_loose = anchor.zip(def.stem.as_ref().and_then(|stem| stem.shaken_loose_m)).map(|(a, m)| (a, m.0));
        Ok(Arc::new(ElasticBuilt {
            body,
            embedding,
            triangles: Arc::new(surface.triangles),
            read,
            cell_m: cell,
            shaken_loose,
        }))
    }

    fn spawn(def: &ElasticBodyDef, built: &Arc<ElasticBuilt>, entity: &mut EntityWorldMut) {
        spawn_elastic_body(entity, def, built.clone());
    }

    fn save_live(def: &mut ElasticBodyDef, entity: EntityRef) {
        super::plugin::save_live(def, entity);
    }

    fn register(app: &mut App) {
        app.register_actions::<Self, ElasticAction>(plugin::perform_action)
            .register_kind_keys::<Self>(&plugin::ELASTIC_KEYS)
            .register_panel_section::<Self>(panel::elastic_section);
    }
}
