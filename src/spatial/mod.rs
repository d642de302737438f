//! The spatial layer: what things are made of, for everyone else. Kinds write neutral
//! components on their entities, and what moves through the scene or points into it reads
//! those alone, never the kinds that made them (as avian's `Collider` and bevy_picking's
//! backends let domains meet).
//!
//! | module | what it holds |
//! |---|---|
//! | [`solid`] | [`Solid`](solid::Solid): planes, balls, boxes, placed shapes, grounds as height fields, tapered segments; how deep a point lies inside |
//! | [`pick`] | [`Pickable`](pick::Pickable), the ray cast under the pointer that finds the nearest hit across every kind, and [`Picked`](pick::Picked), the hit handed to the entity's kind |
//! | [`ground`] | [`GroundPatch`](ground::GroundPatch): a patch of a streamed ground, for what grows on it |
//! | [`bvh`] | a bounding-volume hierarchy generic over its primitives: ray casts, nearest points, what lies within a ball |
//! | [`segment`] | tapered segments (capsules with two radii): rays, nearest surface points |
//! | [`geodesic`] | distances along a triangle surface, by fast marching |
//! | [`surface`] | triangle surfaces: their edges, areas, volumes and facts |
//! | [`surface_bvh`] | a surface's triangles in a hierarchy, for rays |
//! | [`mesh_io`] | OBJ, PLY, STL and glTF files read into triangle meshes and written back |
//! | [`polyline`] | polylines with a radius at each point, simplified within a tolerance |
//! | [`tube`] | tubes around polylines, for supports, limbs and stems |
//!
//! | schedule | set | what runs there |
//! |---|---|---|
//! | `RunFixedMainLoop`, before [`ControlSystems::Input`] | [`SpatialSystems::Pick`] | clicks and grabs in the view cast into every [`Pickable`](pick::Pickable) |
//! | `PostUpdate`, after transforms are propagated | [`SpatialSystems::Publish`] | kinds write their [`Solid`](solid::Solid)s and [`Pickable`](pick::Pickable)s |
//! | `Update`, after input | [`SpatialSystems::Ground`] | streamed grounds bring their [`GroundPatch`](ground::GroundPatch)es in and out |

pub mod bvh;
pub mod geodesic;
pub mod ground;
pub mod mesh_io;
pub mod pick;
pub mod polyline;
pub mod segment;
pub mod solid;
pub mod surface;
pub mod surface_bvh;
pub mod tube;

use crate::foundation::schedule::{ControlSystems, RenderSystems};
use bevy::app::RunFixedMainLoopSystems;
use bevy::prelude::*;
use bevy::transform::TransformSystems;

/// The spatial layer's sets.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpatialSystems {
    /// `RunFixedMainLoop`, before the kinds read input: the pointer's rays cast, the hits
    /// written as [`Picked`](pick::Picked) messages.
    Pick,
    /// `PostUpdate`, after transforms are propagated and before the frame is drawn: kinds write
    /// what their entities are made of, placed where they are now.
    Publish,
    /// `Update`, after input: streamed grounds bring their patches in and take them out; what
    /// grows on the ground follows.
    Ground,
}

/// The picking system and the order of the spatial sets.
pub struct SpatialPlugin;

impl Plugin for SpatialPlugin {
    fn build(&self, app: &mut App) {
        app.add_message::<pick::Picked>()
            .configure_sets(
                RunFixedMainLoop,
                SpatialSystems::Pick.in_set(RunFixedMainLoopSystems::BeforeFixedMainLoop).before(ControlSystems::Input),
            )
            .configure_sets(
                PostUpdate,
                SpatialSystems::Publish.after(TransformSystems::Propagate).before(RenderSystems::Collect),
            )
            .configure_sets(Update, SpatialSystems::Ground.after(ControlSystems::Input))
            .add_systems(RunFixedMainLoop, pick::pick_under_pointer.in_set(SpatialSystems::Pick));
    }
}
