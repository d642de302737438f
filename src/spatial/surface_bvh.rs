//! Picking points on a surface: a ray cast against its triangles through a bounding volume
//! hierarchy, so that a click on a surface of a hundred thousand triangles tests a few dozen.

use super::bvh::{Bvh, Primitive};
use bevy::math::Vec3;

/// One triangle of a surface, by its corners in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle(pub [Vec3; 3]);

/// Where a ray meets a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleHit {
    /// Distance along the unit ray direction, metres.
    pub distance: f32,
}

impl Primitive for Triangle {
    type Hit = TriangleHit;

    fn bounds(&self) -> (Vec3, Vec3) {
        let [a, b, c] = self.0;
        (a.min(b).min(c), a.max(b).max(c))
    }

    /// Möller and Trumbore's test; a triangle is hit from either side.
    fn ray_hit(&self, origin: Vec3, direction: Vec3, max_distance: f32) -> Option<TriangleHit> {
        let [a, b, c] = self.0;
        let (ab, ac) = (b - a, c - a);
        let p = direction.cross(ac);
        let determinant = ab.dot(p);
        if determinant.abs() <= f32::EPSILON * ab.length_squared().max(ac.length_squared()) {
            return None;
        }
        let inverse = determinant.recip();
        let to_origin = origin - a;
        let u = to_origin.dot(p) * inverse;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = to_origin.cross(ab);
        let v = direction.dot(q) * inverse;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let distance = ac.dot(q) * inverse;
        (distance >= 0.0 && distance <= max_distance).then_some(TriangleHit { distance })
    }

    fn hit_distance(hit: &TriangleHit) -> f32 {
        hit.distance
    }
}

/// A surface's triangles and the hierarchy over them.
#[derive(Debug, Clone, Default)]
pub struct SurfaceBvh {
    bvh: Bvh<Triangle>,
    triangles: Vec<[u32; 3]>,
}

/// A surface point a ray met.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePick {
    /// The triangle hit, an index into the surface's triangles.
    pub triangle: usize,
    /// The point hit, metres.
    pub point: Vec3,
    /// Distance along the ray, metres.
    pub distance: f32,
    /// The triangle's corner nearest the point: the vertex a mark snaps to.
    pub vertex: u32,
}

impl SurfaceBvh {
    /// The hierarchy over the triangles of a surface at `positions`.
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let corners = triangles.iter().map(|t| Triangle(t.map(|v| positions[v as usize]))).collect();
        Self { bvh: Bvh::new(corners), triangles: triangles.to_vec() }
    }

    /// The first surface point the ray from `origin` along the unit `direction` meets.
    pub fn pick(&self, origin: Vec3, direction: Vec3) -> Option<SurfacePick> {
        let hit = self.bvh.ray_cast(origin, direction, f32::MAX)?;
        let point = origin + direction * hit.hit.distance;
        let Triangle(corners) = self.bvh.primitives()[hit.index];
        let nearest = (0..3).min_by(|&i, &j| corners[i].distance(point).total_cmp(&corners[j].distance(point)));
        Some(SurfacePick {
            triangle: hit.index,
            point,
            distance: hit.hit.distance,
            vertex: self.triangles[hit.index][nearest.unwrap_or(0)],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::soft_body::sample;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn a_ray_at_the_sphere_hits_its_first_triangle(azimuth in 0.0f32..std::f32::consts::TAU, elevation in -1.4f32..1.4, aim in -0.5f32..0.5) {
            let sphere = sample::sphere(1.0, 24, 48);
            let bvh = SurfaceBvh::new(&sphere.positions, &sphere.triangles);
            let origin = Vec3::new(elevation.cos() * azimuth.cos(), elevation.sin(), elevation.cos() * azimuth.sin()) * 4.0;
            let direction = (Vec3::new(aim, -aim, aim * 0.5) - origin).normalize();
            let pick = bvh.pick(origin, direction).expect("a ray at the centre's neighbourhood meets the sphere");
            // The first of all the triangles the ray meets, and on the near side.
            let scan = sphere
                .triangles
                .iter()
                .filter_map(|t| Triangle(t.map(|v| sphere.positions[v as usize])).ray_hit(origin, direction, 100.0))
                .map(|hit| hit.distance)
                .fold(f32::INFINITY, f32::min);
            prop_assert_eq!(pick.distance, scan);
            prop_assert!((pick.point.length() - 1.0).abs() < 0.01, "on the sphere: {}", pick.point);
            prop_assert!(pick.point.dot(origin) > 0.0, "the near side");
            prop_assert!(sphere.triangles[pick.triangle].contains(&pick.vertex));
            let corner = sphere.positions[pick.vertex as usize];
            for v in sphere.triangles[pick.triangle] {
                prop_assert!(corner.distance(pick.point) <= sphere.positions[v as usize].distance(pick.point) + 1e-6);
            }
        }
    }

    #[test]
    fn a_ray_beside_the_surface_hits_nothing() {
        let belly = sample::belly(21);
        let bvh = SurfaceBvh::new(&belly.positions, &belly.triangles);
        assert!(bvh.pick(Vec3::new(0.3, 1.0, 0.0), Vec3::NEG_Y).is_none(), "beyond the patch's 0.2 m half side");
        let pick = bvh.pick(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y).unwrap();
        assert!((pick.point.y - 0.12).abs() < 1e-6, "the top of the belly: {}", pick.point);
        assert_eq!(pick.vertex, 10 * 21 + 10, "the vertex at the top");
        assert!(bvh.pick(Vec3::new(0.0, 1.0, 0.0), Vec3::Y).is_none(), "the surface lies behind the ray");
    }
}
