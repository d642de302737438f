//! Picking: what a ray under the pointer meets first, across every kind. Kinds mark what can
//! be hit with a [`Pickable`]; one system casts each click and each grab into all of them and
//! hands the nearest hit to the entity's kind as a [`Picked`] message.

use super::bvh::SegmentBvh;
use super::segment::SegmentHit;
use super::surface_bvh::SurfaceBvh;
use crate::foundation::messages::{DragPhase, ViewClicked, ViewDragged};
use crate::view::CameraParams;
use bevy::math::Affine3A;
use bevy::prelude::*;
use std::sync::Arc;

/// What a ray can hit on an entity.
#[derive(Component, Debug, Clone)]
pub enum Pickable {
    /// Tapered segments in world coordinates (a tree's supports); a hit names the segment.
    Segments(Arc<SegmentBvh>),
    /// A triangle surface indexed in the entity's own frame, placed by `to_world`; a hit names
    /// the triangle and its corner nearest the point.
    Surface {
        /// The surface's triangles, in the entity's frame.
        bvh: Arc<SurfaceBvh>,
        /// The entity's frame to the world's.
        to_world: Affine3A,
    },
    /// A triangle mesh in world coordinates that changes with every step (a falling body):
    /// indexed only when a ray is cast at it.
    Mesh {
        /// Vertex positions, metres.
        positions: Arc<Vec<Vec3>>,
        /// Triangles as vertex indices.
        triangles: Arc<Vec<[u32; 3]>>,
    },
}

/// Where a ray met a pickable entity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// The entity hit.
    pub entity: Entity,
    /// The point hit, metres, in world coordinates.
    pub point: Vec3,
    /// Distance from the ray's origin, metres.
    pub distance: f32,
    /// The part hit: the segment of [`Pickable::Segments`], the triangle of a surface or mesh.
    pub part: usize,
    /// For a segment, how far along it the hit lies (0 at its start, 1 at its end).
    pub along: f32,
    /// For a segment, the surface's outward unit normal at the hit.
    pub normal: Option<Vec3>,
    /// For a surface or mesh, the corner of the triangle nearest the hit.
    pub vertex: Option<u32>,
}

impl Pickable {
    /// Where the ray from `origin` along the unit `direction` first meets this, if it does.
    pub fn cast(&self, entity: Entity, origin: Vec3, direction: Vec3) -> Option<Hit> {
        match self {
            Pickable::Segments(bvh) => {
                let hit = bvh.ray_cast(origin, direction, f32::MAX)?;
                let SegmentHit { distance, surface } = hit.hit;
                Some(Hit {
                    entity,
                    point: surface.point,
                    distance,
                    part: hit.index,
                    along: surface.along,
                    normal: Some(surface.normal),
                    vertex: None,
                })
            }
            Pickable::Surface { bvh, to_world } => {
                let to_local = to_world.inverse();
                let local_direction = to_local.transform_vector3(direction).try_normalize()?;
                let hit = bvh.pick(to_local.transform_point3(origin), local_direction)?;
                let point = to_world.transform_point3(hit.point);
                Some(Hit {
                    entity,
                    point,
                    distance: point.distance(origin),
                    part: hit.triangle,
                    along: 0.0,
                    normal: None,
                    vertex: Some(hit.vertex),
                })
            }
            Pickable::Mesh { positions, triangles } => {
                let hit = SurfaceBvh::new(positions, triangles).pick(origin, direction)?;
                Some(Hit {
                    entity,
                    point: hit.point,
                    distance: hit.distance,
                    part: hit.triangle,
                    along: 0.0,
                    normal: None,
                    vertex: Some(hit.vertex),
                })
            }
        }
    }
}

/// The nearest hit of the ray from `origin` along the unit `direction` among `pickables`.
pub fn nearest_hit<'a>(
    pickables: impl IntoIterator<Item = (Entity, &'a Pickable)>,
    origin: Vec3,
    direction: Vec3,
) -> Option<Hit> {
    pickables
        .into_iter()
        .filter_map(|(entity, pickable)| pickable.cast(entity, origin, direction))
        .min_by(|a, b| a.distance.total_cmp(&b.distance))
}

/// How the pointer picked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pointer {
    /// A click: pressed and let go without moving.
    Click,
    /// The start of a drag: the button held down and the pointer moving.
    Grab,
}

/// The nearest thing under the pointer, for the kind of the entity hit.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct Picked {
    /// Where the ray met it.
    pub hit: Hit,
    /// How the pointer picked it.
    pub pointer: Pointer,
}

/// Casts every click and every drag's start in the view into every [`Pickable`] and writes
/// the nearest hit, if any, as [`Picked`].
pub(super) fn pick_under_pointer(
    mut clicks: MessageReader<ViewClicked>,
    mut drags: MessageReader<ViewDragged>,
    cameras: Query<&CameraParams>,
    pickables: Query<(Entity, &Pickable)>,
    mut picked: MessageWriter<Picked>,
) {
    let Some(camera) = cameras.iter().next().map(CameraParams::camera) else { return };
    let clicked = clicks.read().map(|click| (click.ndc, click.aspect, Pointer::Click));
    let grabbed = drags.read().filter(|drag| drag.phase == DragPhase::Start);
    for (ndc, aspect, pointer) in clicked.chain(grabbed.map(|drag| (drag.ndc, drag.aspect, Pointer::Grab))) {
        let (origin, direction) = camera.ray(ndc, aspect);
        if let Some(hit) = nearest_hit(pickables.iter(), origin, direction) {
            picked.write(Picked { hit, pointer });
        }
    }
}
