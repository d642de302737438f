//! Solids: what a body's particles stay out of. Planes, balls and boxes; the scene's shapes
//! as they are placed; grounds given as height fields (a terrain's section, a streamed
//! world); the trees' supports as tapered segments in their hierarchy of bounds.
//!
//! Every kind whose entities are solid writes a [`Solid`] on them, after transforms are
//! propagated ([`SpatialSystems::Solids`](super::SpatialSystems::Solids)); what moves
//! through them reads only that component and never the kinds that made it.

use super::bvh::SegmentBvh;
use crate::raster::primitives::Primitive;
use bevy::ecs::component::Component;
use bevy::math::{Affine3A, Vec3};
use std::fmt::Debug;
use std::sync::Arc;

/// A ground under which nothing may go: heights over the horizontal plane.
pub trait HeightField: Debug + Send + Sync {
    /// Whether a point of the box from `min` to `max` could lie under the ground: false only
    /// where none can.
    fn may_touch(&self, _min: Vec3, _max: Vec3) -> bool {
        true
    }

    /// How deep `p` lies under the ground, metres, and the unit direction out, if it is under.
    fn penetration(&self, p: Vec3) -> Option<(f32, Vec3)>;

    /// The ground's height under the horizontal point `(x, z)`, metres, where there is ground.
    fn height(&self, x: f32, z: f32) -> Option<f32>;
}

/// The solid an entity is, for everything that moves through the scene.
#[derive(Component, Debug, Clone)]
pub struct Solid(pub Collider);

/// A static solid particles cannot enter.
#[derive(Debug, Clone)]
pub enum Collider {
    /// The half space below a plane through `point` facing `normal` (unit).
    Plane {
        /// A point of the plane, metres.
        point: Vec3,
        /// Its unit normal, out of the solid.
        normal: Vec3,
    },
    /// A ball.
    Sphere {
        /// Its centre, metres.
        centre: Vec3,
        /// Its radius, metres.
        radius_m: f32,
    },
    /// A box along the axes.
    Box {
        /// Its centre, metres.
        centre: Vec3,
        /// Half its size along x, y and z, metres.
        half_m: Vec3,
    },
    /// One of the scene's shapes: its primitive, one metre along each axis about its centre,
    /// placed (turned, scaled, moved) by `to_world`. A plane shape is a solid below its square
    /// that only what comes from above meets: it has no depth of its own.
    Shape {
        /// The primitive.
        primitive: Primitive,
        /// The shape's frame to the world's.
        to_world: Affine3A,
        /// The world's frame to the shape's.
        to_local: Affine3A,
    },
    /// A ground: a terrain's visible section, a streamed world's heights.
    Ground(Arc<dyn HeightField>),
    /// The trees' supports, every segment of them.
    Supports(Arc<SegmentBvh>),
}

impl Collider {
    /// Where solids of this kind come among the solids a body meets: shapes, grounds, supports.
    pub fn rank(&self) -> u8 {
        match self {
            Collider::Plane { .. } | Collider::Sphere { .. } | Collider::Box { .. } | Collider::Shape { .. } => 0,
            Collider::Ground(_) => 1,
            Collider::Supports(_) => 2,
        }
    }

    /// A shape placed by `to_world`.
    pub fn shape(primitive: Primitive, to_world: Affine3A) -> Self {
        Collider::Shape { primitive, to_world, to_local: to_world.inverse() }
    }

    /// Whether a point of the box from `min` to `max` could lie inside: false only where none
    /// can, so that a body whose particles all lie in the box skips this solid (checked once
    /// a substep, where [`penetration`](Self::penetration) is asked of every particle).
    pub fn may_touch(&self, min: Vec3, max: Vec3) -> bool {
        match self {
            Collider::Supports(bvh) => {
                let mut found = Vec::new();
                bvh.within((min + max) * 0.5, (max - min).length() * 0.5, &mut found);
                !found.is_empty()
            }
            Collider::Ground(ground) => ground.may_touch(min, max),
            _ => true,
        }
    }

    /// How deep `p` lies inside, metres, and the unit direction out, if it is inside;
    /// `previous` is where the particle was before this move (only a plane shape, which has
    /// no inside of its own, looks at it).
    pub fn penetration(&self, p: Vec3, previous: Vec3) -> Option<(f32, Vec3)> {
        match self {
            &Collider::Plane { point, normal } => {
                let depth = -(p - point).dot(normal);
                (depth > 0.0).then_some((depth, normal))
            }
            &Collider::Sphere { centre, radius_m } => ball(p - centre, radius_m),
            &Collider::Box { centre, half_m } => cuboid(p - centre, previous - centre, half_m),
            Collider::Shape { primitive, to_world, to_local } => {
                let local = to_local.transform_point3(p);
                let (depth, out) = match primitive {
                    Primitive::Box => cuboid(local, to_local.transform_point3(previous), Vec3::splat(0.5)),
                    Primitive::Sphere => ball(local, 0.5),
                    Primitive::Cylinder => cylinder(local),
                    Primitive::Plane => {
                        let before = to_local.transform_point3(previous);
                        let inside = local.y < 0.0 && before.y >= -1e-6 && local.x.abs() <= 0.5 && local.z.abs() <= 0.5;
                        inside.then_some((-local.y, Vec3::Y))
                    }
                }?;
                // Out in the shape's frame, then back: the placement keeps surfaces surfaces.
                let out = to_world.transform_point3(local + out * depth) - p;
                let depth = out.length();
                (depth > 0.0).then(|| (depth, out / depth))
            }
            Collider::Ground(ground) => ground.penetration(p),
            Collider::Supports(bvh) => {
                let nearest = bvh.nearest(p, 0.0)?;
                let depth = -nearest.surface.distance;
                (depth > 0.0).then_some((depth, nearest.surface.normal))
            }
        }
    }
}

/// Inside a ball of `radius` about the origin.
fn ball(offset: Vec3, radius: f32) -> Option<(f32, Vec3)> {
    let depth = radius - offset.length();
    (depth > 0.0).then(|| (depth, offset.try_normalize().unwrap_or(Vec3::Y)))
}

/// Inside a box of half size `half` about the origin: out through the face `previous` came
/// in by, the one it lay farthest outside of (so that a body pressed deep into a box's top is
/// not sent out of its side), or through the nearest face for a point that was inside already.
fn cuboid(local: Vec3, previous: Vec3, half: Vec3) -> Option<(f32, Vec3)> {
    let room = half - local.abs();
    if room.min_element() <= 0.0 {
        return None;
    }
    let outside = previous.abs() - half;
    if outside.max_element() > 0.0 {
        let axis = if outside.x >= outside.y && outside.x >= outside.z {
            0
        } else if outside.y >= outside.z {
            1
        } else {
            2
        };
        let mut out = Vec3::ZERO;
        out[axis] = previous[axis].signum();
        return Some((room[axis], out));
    }
    let axis = if room.x <= room.y && room.x <= room.z {
        Vec3::X
    } else if room.y <= room.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let sign = if local.dot(axis) < 0.0 { -1.0 } else { 1.0 };
    Some((room.min_element(), axis * sign))
}

/// Inside the cylinder of radius 0.5 along y from -0.5 to 0.5: out through the nearer of its
/// side and its caps.
fn cylinder(local: Vec3) -> Option<(f32, Vec3)> {
    let across = Vec3::new(local.x, 0.0, local.z);
    let (side, cap) = (0.5 - across.length(), 0.5 - local.y.abs());
    if side <= 0.0 || cap <= 0.0 {
        return None;
    }
    Some(if side < cap { (side, across.try_normalize().unwrap_or(Vec3::X)) } else { (cap, Vec3::Y * local.y.signum()) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::segment::TaperedSegment;
    use bevy::math::Quat;

    #[test]
    fn a_point_inside_a_placed_shape_is_sent_out_onto_its_surface() {
        let place = Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 0.5),
            Quat::from_rotation_z(0.4),
            Vec3::new(1.0, 2.0, 3.0),
        );
        for primitive in [Primitive::Box, Primitive::Sphere, Primitive::Cylinder] {
            let collider = Collider::shape(primitive, place);
            let inside = place.transform_point3(Vec3::new(0.1, 0.2, 0.05));
            let (depth, out) = collider.penetration(inside, inside).expect("inside");
            let surface = place.inverse().transform_point3(inside + out * depth);
            let on = match primitive {
                Primitive::Box => (surface.abs().max_element() - 0.5).abs(),
                Primitive::Sphere => (surface.length() - 0.5).abs(),
                _ => (Vec3::new(surface.x, 0.0, surface.z).length() - 0.5).abs().min((surface.y.abs() - 0.5).abs()),
            };
            assert!(on < 1e-5, "{primitive:?} sends {inside} to {surface}");
            let outside = place.transform_point3(Vec3::new(0.7, 0.0, 0.0));
            assert!(collider.penetration(outside, outside).is_none(), "{primitive:?}");
        }
    }

    #[test]
    fn a_plane_shape_stops_what_comes_from_above_only() {
        let floor = Collider::shape(Primitive::Plane, Affine3A::from_scale(Vec3::new(4.0, 1.0, 4.0)));
        let (above, below) = (Vec3::new(0.5, 0.01, 0.0), Vec3::new(0.5, -0.02, 0.0));
        assert_eq!(floor.penetration(below, above).map(|(d, n)| ((d * 1e4).round(), n)), Some((200.0, Vec3::Y)));
        assert!(floor.penetration(below, below - Vec3::Y).is_none(), "from below it passes");
        assert!(floor.penetration(Vec3::new(3.0, -0.02, 0.0), Vec3::new(3.0, 0.01, 0.0)).is_none(), "beside it");
    }

    #[test]
    fn a_point_inside_a_support_is_sent_out_of_it() {
        let segment = TaperedSegment { a: Vec3::ZERO, b: Vec3::X, radius_a: 0.1, radius_b: 0.1 };
        let supports = Collider::Supports(Arc::new(SegmentBvh::new(vec![segment])));
        let p = Vec3::new(0.5, 0.05, 0.0);
        let (depth, out) = supports.penetration(p, p).expect("inside the branch");
        assert!((depth - 0.05).abs() < 1e-6 && out.distance(Vec3::Y) < 1e-6);
        assert!(supports.penetration(Vec3::new(0.5, 0.2, 0.0), p).is_none());
    }
}
