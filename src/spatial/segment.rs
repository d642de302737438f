//! The shape of a support, one segment at a time: a tapered segment is the union of the spheres
//! centred on its axis whose radius changes linearly from one end to the other (a "round
//! cone"), which gives smooth joints between the segments of a polyline and closed tips.
//!
//! A round cone is convex, and the nearest point of its axis to any point has a closed form, so
//! the signed distance, the closest surface point and its normal are exact; ray casts find the
//! first zero of the (convex) signed distance along the ray with Newton steps from the left,
//! which never overshoot.

use bevy::math::Vec3;

/// Newton steps a ray cast may take against one segment.
const MAX_RAY_STEPS: usize = 64;

/// How close to the surface, in metres, a ray cast's hit is.
pub const RAY_TOLERANCE: f32 = 1e-5;

/// A segment of a support: the round cone between spheres at `a` and `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaperedSegment {
    /// Axis start, metres.
    pub a: Vec3,
    /// Axis end, metres.
    pub b: Vec3,
    /// Radius at `a`, metres (> 0).
    pub radius_a: f32,
    /// Radius at `b`, metres (> 0).
    pub radius_b: f32,
}

/// The nearest point of a segment's surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The point on the surface, metres.
    pub point: Vec3,
    /// Outward unit normal there.
    pub normal: Vec3,
    /// Signed distance from the query point: negative inside.
    pub distance: f32,
    /// Where along the axis the nearest sphere is centred, 0 at `a` to 1 at `b`.
    pub along: f32,
}

/// A ray's first hit on a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentHit {
    /// Distance along the (unit) ray direction, metres.
    pub distance: f32,
    /// The surface point and normal hit.
    pub surface: SurfacePoint,
}

impl TaperedSegment {
    /// The axis parameter (0 at `a`, 1 at `b`) of the sphere nearest to `p`, found in closed
    /// form: the signed distance to the sphere at `t`, `|p - c(t)| - r(t)`, is convex in `t`.
    fn nearest_sphere(&self, p: Vec3) -> f32 {
        let axis = self.b - self.a;
        let length = axis.length();
        let taper = self.radius_b - self.radius_a;
        // One sphere inside the other (or a zero-length axis): the larger one is the shape.
        if length <= taper.abs() {
            return if taper > 0.0 { 1.0 } else { 0.0 };
        }
        let along = axis / length;
        let u = p - self.a;
        let q = u.dot(along);
        let h = (u - along * q).length();
        let w = taper * h / (length * length - taper * taper).sqrt();
        ((q + w) / length).clamp(0.0, 1.0)
    }

    /// The nearest surface point to `p`, with the signed distance.
    pub fn closest(&self, p: Vec3) -> SurfacePoint {
        let t = self.nearest_sphere(p);
        let centre = self.a.lerp(self.b, t);
        let radius = self.radius_a + (self.radius_b - self.radius_a) * t;
        let offset = p - centre;
        let length = offset.length();
        let normal = if length > 1e-12 { offset / length } else { (self.b - self.a).any_orthonormal_vector() };
        SurfacePoint { point: centre + normal * radius, normal, distance: length - radius, along: t }
    }

    /// The first point where the ray from `origin` along the unit vector `direction` meets the
    /// segment, within `max_distance`. A ray starting inside hits at distance 0.
    pub fn ray_hit(&self, origin: Vec3, direction: Vec3, max_distance: f32) -> Option<SegmentHit> {
        // Enter the bounding sphere first: Newton steps start close and stay bounded.
        let (centre, bound) = self.bounding_sphere();
        let to_centre = centre - origin;
        let middle = to_centre.dot(direction);
        let miss_squared = to_centre.length_squared() - middle * middle;
        if miss_squared > bound * bound {
            return None;
        }
        let half_chord = (bound * bound - miss_squared).sqrt();
        let (enter, exit) = (middle - half_chord, (middle + half_chord).min(max_distance));
        let mut s = enter.max(0.0);
        for _ in 0..MAX_RAY_STEPS {
            if s > exit {
                return None;
            }
            let surface = self.closest(origin + direction * s);
            if surface.distance <= RAY_TOLERANCE {
                return Some(SegmentHit { distance: s, surface });
            }
            // The signed distance is convex along the ray: while it falls, the tangent's zero
            // lies at or before the surface; once it rises, the ray has passed by.
            let slope = surface.normal.dot(direction);
            if slope >= -1e-6 {
                return None;
            }
            s -= surface.distance / slope;
        }
        None
    }

    /// A sphere holding the whole segment: centre and radius.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let centre = (self.a + self.b) * 0.5;
        (centre, (self.b - self.a).length() * 0.5 + self.radius_a.max(self.radius_b))
    }

    /// The axis-aligned box holding the segment: min and max corners.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (ra, rb) = (Vec3::splat(self.radius_a), Vec3::splat(self.radius_b));
        ((self.a - ra).min(self.b - rb), (self.a + ra).max(self.b + rb))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The signed distance by brute force: the minimum over finely sampled spheres of the axis.
    fn sampled_distance(segment: &TaperedSegment, p: Vec3) -> f32 {
        (0..=1000)
            .map(|i| {
                let t = i as f32 / 1000.0;
                let centre = segment.a.lerp(segment.b, t);
                (p - centre).length() - (segment.radius_a + (segment.radius_b - segment.radius_a) * t)
            })
            .fold(f32::INFINITY, f32::min)
    }

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    fn segment() -> impl Strategy<Value = TaperedSegment> {
        (vec3(), vec3(), 0.02f32..0.6, 0.02f32..0.6).prop_map(|(a, b, radius_a, radius_b)| TaperedSegment {
            a,
            b,
            radius_a,
            radius_b,
        })
    }

    #[test]
    fn a_cylinder_and_its_caps() {
        let rod = TaperedSegment { a: Vec3::ZERO, b: Vec3::X * 2.0, radius_a: 0.5, radius_b: 0.5 };
        let side = rod.closest(Vec3::new(1.0, 2.0, 0.0));
        assert!((side.distance - 1.5).abs() < 1e-6 && side.point.distance(Vec3::new(1.0, 0.5, 0.0)) < 1e-6);
        assert!((side.along - 0.5).abs() < 1e-6);
        let tip = rod.closest(Vec3::new(3.0, 0.0, 0.0));
        assert!((tip.distance - 0.5).abs() < 1e-6 && tip.normal.distance(Vec3::X) < 1e-6);
        assert!((rod.closest(Vec3::new(1.0, 0.1, 0.0)).distance + 0.4).abs() < 1e-6, "inside is negative");
    }

    #[test]
    fn a_ray_along_a_cone_hits_its_side_at_the_exact_place() {
        // Radius 1 at x = 0 to 0.5 at x = 4: the side's slant is known exactly.
        let cone = TaperedSegment { a: Vec3::ZERO, b: Vec3::X * 4.0, radius_a: 1.0, radius_b: 0.5 };
        let hit = cone.ray_hit(Vec3::new(2.0, 5.0, 0.0), Vec3::NEG_Y, 100.0).unwrap();
        // In the xy plane the side is the line y = m x + c tangent to both end circles:
        // c = sqrt(1 + m^2) and 4 m + c = 0.5 sqrt(1 + m^2), so m = -sqrt(0.25 / 15.75).
        let m = -(0.25f32 / 15.75).sqrt();
        let expected = 5.0 - (2.0 * m + (1.0 + m * m).sqrt());
        assert!((hit.distance - expected).abs() < 1e-4, "{} vs {expected}", hit.distance);
        assert!(hit.surface.normal.y > 0.9);
        assert!(cone.ray_hit(Vec3::new(2.0, 5.0, 0.0), Vec3::Y, 100.0).is_none(), "pointing away");
        assert!(cone.ray_hit(Vec3::new(2.0, 5.0, 0.0), Vec3::NEG_Y, 3.0).is_none(), "too short");
        let inside = cone.ray_hit(Vec3::new(1.0, 0.0, 0.0), Vec3::Z, 10.0).unwrap();
        assert_eq!(inside.distance, 0.0);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(100))]

        /// The closed-form distance equals the brute-force minimum over the axis's spheres.
        #[test]
        fn distance_matches_brute_force(segment in segment(), p in vec3()) {
            let exact = segment.closest(p);
            let sampled = sampled_distance(&segment, p);
            prop_assert!((exact.distance - sampled).abs() < 2e-3, "{} vs {sampled}", exact.distance);
            // The closest point is on the surface and the normal points from it to p.
            prop_assert!(sampled_distance(&segment, exact.point).abs() < 2e-3);
            prop_assert!((exact.normal.length() - 1.0).abs() < 1e-4);
        }

        /// A ray's hit lies on the surface, and nothing of the segment lies earlier on the ray.
        #[test]
        fn ray_hits_are_first_and_on_the_surface(segment in segment(), origin in vec3(), target in vec3()) {
            let origin = origin * 3.0;
            let Some(direction) = (target - origin).try_normalize() else { return Ok(()) };
            let hit = segment.ray_hit(origin, direction, 100.0);
            // March the ray finely with the brute-force distance.
            let first_inside = (0..=4000)
                .map(|i| i as f32 * 0.003)
                .find(|&s| sampled_distance(&segment, origin + direction * s) <= 0.0);
            match (hit, first_inside) {
                (Some(hit), Some(s)) => prop_assert!((hit.distance - s).abs() < 5e-3, "{} vs {s}", hit.distance),
                (Some(hit), None) => prop_assert!(hit.surface.distance.abs() < 1e-3 && sampled_distance(&segment, origin + direction * hit.distance) < 2e-3, "{hit:?}"),
                (None, Some(s)) => prop_assert!(sampled_distance(&segment, origin + direction * s) > -2e-3, "missed a hit at {s}"),
                (None, None) => {}
            }
        }
    }
}
