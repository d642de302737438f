//! Sample surfaces made by the project itself, so that nothing is missing to deform.

use crate::spatial::surface::{Surface, triangle_cross};
use bevy::math::Vec3;
use serde::{Deserialize, Serialize};
use std::f32::consts::TAU;

/// The sample surfaces, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// [`belly`]: a patch 0.4 m a side with a belly, `size` vertices a side.
    Belly,
    /// [`sphere_cap`]: a cap of a unit sphere 60 degrees about its pole, `size` vertices around.
    Cap,
    /// [`sphere`]: a closed unit sphere, `size` vertices around.
    Sphere,
    /// [`cushion`]: a closed cube 2 m a side with rounded edges, `size` vertices around.
    Cushion,
    /// [`torus`]: a closed ring 1 m across its centre line, `size` vertices around it.
    Torus,
    /// [`torso`]: an open torso 0.6 m high with a belly, `size` rings from hips to chest.
    Torso,
}

/// Fewest and most vertices along a sample's `size`.
pub const SIZES: std::ops::RangeInclusive<u32> = 3..=1000;

impl Shape {
    /// Every sample surface.
    pub const ALL: [Shape; 6] = [Shape::Belly, Shape::Cap, Shape::Sphere, Shape::Cushion, Shape::Torus, Shape::Torso];

    /// Its name, as scene files and the command line write it.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Belly => "belly",
            Shape::Cap => "cap",
            Shape::Sphere => "sphere",
            Shape::Cushion => "cushion",
            Shape::Torus => "torus",
            Shape::Torso => "torso",
        }
    }

    /// What it is, in a line.
    pub fn about(self) -> &'static str {
        match self {
            Shape::Belly => "A patch of body surface 0.4 m a side with a belly 0.12 m high.",
            Shape::Cap => "A cap of a unit sphere, 60 degrees around its pole.",
            Shape::Sphere => "A closed unit sphere.",
            Shape::Cushion => "A closed cube 2 m a side with rounded edges.",
            Shape::Torus => "A closed torus 1 m across its centre line.",
            Shape::Torso => "An open torso 0.6 m high with a belly.",
        }
    }

    /// The surface with `size` vertices along its main direction (clamped to [`SIZES`]).
    pub fn make(self, size: u32) -> Surface {
        let size = size.clamp(*SIZES.start(), *SIZES.end());
        match self {
            Shape::Belly => belly(size),
            Shape::Cap => sphere_cap(1.0, 60.0, size.div_ceil(2), size),
            Shape::Sphere => sphere(1.0, size.div_ceil(2), size),
            Shape::Cushion => cushion(size.div_ceil(2), size),
            Shape::Torus => torus(0.5, 0.18, size, size.div_ceil(3).max(3)),
            Shape::Torso => torso(size, 2 * size),
        }
    }
}

/// The cap of a sphere of `radius` metres around its north pole (+y), out to `angle_deg`
/// degrees from it, in `rings` rings of `segments` vertices around a pole vertex; its last
/// ring, the border, is fixed and the rest may move. Triangles face out of the sphere.
pub fn sphere_cap(radius: f32, angle_deg: f32, rings: u32, segments: u32) -> Surface {
    let (rings, segments) = (rings.max(1), segments.max(3));
    let mut positions = vec![Vec3::Y * radius];
    for ring in 1..=rings {
        let polar = (angle_deg.to_radians() * ring as f32 / rings as f32).min(std::f32::consts::PI);
        for s in 0..segments {
            let around = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push(Vec3::new(polar.sin() * around.cos(), polar.cos(), polar.sin() * around.sin()) * radius);
        }
    }
    let at = |ring: u32, s: u32| 1 + (ring - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, at(1, s), at(1, s + 1)]);
    }
    for ring in 1..rings {
        for s in 0..segments {
            let (a, b, c, d) = (at(ring, s), at(ring, s + 1), at(ring + 1, s), at(ring + 1, s + 1));
            triangles.extend([[a, c, d], [a, d, b]]);
        }
    }
    // Outward: the area vector along the position (the sphere's centre is the origin).
    for t in &mut triangles {
        let centre = t.iter().map(|&v| positions[v as usize]).sum::<Vec3>();
        if triangle_cross(&positions, *t).dot(centre) < 0.0 {
            t.swap(1, 2);
        }
    }
    let border = 1 + (rings - 1) * segments;
    let movable = (0..positions.len() as u32).map(|v| v < border).collect();
    Surface::new(positions, triangles, movable).expect("a cap of finite positions and valid indices")
}

/// A closed sphere of `radius` metres: a vertex at each pole (+y first, -y last) and `rings`
/// rings of `segments` vertices between them; every vertex may move. Triangles face out.
pub fn sphere(radius: f32, rings: u32, segments: u32) -> Surface {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut surface = sphere_cap(radius, 180.0 * rings as f32 / (rings + 1) as f32, rings, segments);
    let south = surface.positions.len() as u32;
    let mut positions = std::mem::take(&mut surface.positions);
    let mut triangles = std::mem::take(&mut surface.triangles);
    positions.push(Vec3::NEG_Y * radius);
    let last = 1 + (rings - 1) * segments;
    for s in 0..segments {
        // Outward (down) seen from below: the order the cap's winding rule gives.
        let (a, b) = (last + s, last + (s + 1) % segments);
        let t = [south, a, b];
        let centre = t.iter().map(|&v| positions[v as usize]).sum::<Vec3>();
        triangles.push(if triangle_cross(&positions, t).dot(centre) < 0.0 { [south, b, a] } else { t });
    }
    let movable = vec![true; positions.len()];
    Surface::new(positions, triangles, movable).expect("a sphere of finite positions and valid indices")
}

/// A closed cube 2 m a side with rounded edges and corners (the surface `x^4 + y^4 + z^4 =
/// 1`): the unit sphere of `rings` rings of `segments` vertices, each vertex pushed out along
/// its direction onto that surface.
pub fn cushion(rings: u32, segments: u32) -> Surface {
    let mut surface = sphere(1.0, rings, segments);
    for p in &mut surface.positions {
        let q = *p * *p;
        *p /= (q.x * q.x + q.y * q.y + q.z * q.z).sqrt().sqrt();
    }
    surface
}

/// A patch of body surface with a belly: [`patch`] with a bump 0.12 m high.
pub fn belly(n: u32) -> Surface {
    patch(n, 0.12)
}

/// A patch of `n x n` vertices (at least 3) over a square 0.4 m a side in x and z, raised by
/// a smooth bump `height_m` high in its middle (7 cm wide), split along one diagonal of each
/// cell and facing +y; the outer ring of vertices is fixed.
pub fn patch(n: u32, height_m: f32) -> Surface {
    let n = n.max(3);
    let (side, height, width) = (0.4f32, height_m, 0.07f32);
    let mut positions = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let [x, z] = [i, j].map(|k| (k as f32 / (n - 1) as f32 - 0.5) * side);
            let bump = height * (-(x * x + z * z) / (2.0 * width * width)).exp();
            positions.push(Vec3::new(x, bump, z));
        }
    }
    let at = |i: u32, j: u32| j * n + i;
    let mut triangles = Vec::with_capacity((2 * (n - 1) * (n - 1)) as usize);
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            // Counter-clockwise seen from above (+y).
            triangles.extend([[a, c, d], [a, d, b]]);
        }
    }
    let movable = (0..n * n).map(|v| (1..n - 1).contains(&(v % n)) && (1..n - 1).contains(&(v / n))).collect();
    Surface::new(positions, triangles, movable).expect("a patch of finite positions and valid indices")
}

/// A closed torus about the y axis: its centre line a circle of `major_m` metres radius, its
/// tube `minor_m` metres in radius, in `around` rings of `tube` vertices; every vertex may
/// move. Triangles face out of the tube.
pub fn torus(major_m: f32, minor_m: f32, around: u32, tube: u32) -> Surface {
    let (around, tube) = (around.max(3), tube.max(3));
    let centre = |i: u32| {
        let a = TAU * i as f32 / around as f32;
        Vec3::new(a.cos(), 0.0, a.sin()) * major_m
    };
    let mut positions = Vec::with_capacity((around * tube) as usize);
    for i in 0..around {
        let out = centre(i).normalize();
        for j in 0..tube {
            let b = TAU * j as f32 / tube as f32;
            positions.push(centre(i) + (out * b.cos() + Vec3::Y * b.sin()) * minor_m);
        }
    }
    let at = |i: u32, j: u32| (i % around) * tube + j % tube;
    let mut triangles = Vec::with_capacity((2 * around * tube) as usize);
    for i in 0..around {
        for j in 0..tube {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            for t in [[a, b, d], [a, d, c]] {
                let middle = t.iter().map(|&v| positions[v as usize]).sum::<Vec3>() / 3.0;
                let axis = centre(i) + (centre(i + 1) - centre(i)) * 0.5;
                let outward = triangle_cross(&positions, t).dot(middle - axis) > 0.0;
                triangles.push(if outward { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    let movable = vec![true; positions.len()];
    Surface::new(positions, triangles, movable).expect("a torus of finite positions and valid indices")
}

/// A torso 0.6 m high from the hips (y = 0) to the chest, `rings` rings of `segments` vertices
/// around it: an elliptic tube 0.34 m wide and 0.22 m deep with a waist, and a belly rising
/// 5 cm out of its front (+z) about 0.2 m up. Open at both ends, whose rings are fixed;
/// triangles face out.
pub fn torso(rings: u32, segments: u32) -> Surface {
    let (rings, segments) = (rings.max(3), segments.max(3));
    let height = 0.6f32;
    let mut positions = Vec::with_capacity((rings * segments) as usize);
    for r in 0..rings {
        let y = height * r as f32 / (rings - 1) as f32;
        let half_width = 0.17 - 0.025 * (-((y - 0.34) / 0.12).powi(2)).exp();
        let half_depth = 0.11;
        let belly = 0.05 * (-((y - 0.2) / 0.09).powi(2)).exp();
        for s in 0..segments {
            let a = TAU * s as f32 / segments as f32;
            let front = a.sin().max(0.0).powi(6);
            positions.push(Vec3::new(half_width * a.cos(), y, half_depth * a.sin() + belly * front));
        }
    }
    let at = |r: u32, s: u32| r * segments + s % segments;
    let mut triangles = Vec::with_capacity((2 * (rings - 1) * segments) as usize);
    for r in 0..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
            for t in [[a, c, d], [a, d, b]] {
                let middle = t.iter().map(|&v| positions[v as usize]).sum::<Vec3>();
                let outward = triangle_cross(&positions, t).dot(middle * Vec3::new(1.0, 0.0, 1.0)) > 0.0;
                triangles.push(if outward { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    let movable = (0..rings * segments).map(|v| (1..rings - 1).contains(&(v / segments))).collect();
    Surface::new(positions, triangles, movable).expect("a torso of finite positions and valid indices")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shape_is_listed_under_the_name_scene_files_give_it() {
        for shape in Shape::ALL {
            assert_eq!(serde_yaml::to_string(&shape).unwrap().trim(), shape.name());
            assert_eq!(serde_yaml::from_str::<Shape>(shape.name()).unwrap(), shape);
        }
        let names: std::collections::BTreeSet<_> = Shape::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(names.len(), Shape::ALL.len());
    }

    #[test]
    fn the_sphere_is_closed_and_faces_out() {
        let sphere = sphere(1.0, 15, 32);
        assert_eq!(sphere.positions.len(), 2 + 15 * 32);
        // Closed: every edge has two triangles; Euler's V - E + F = 2.
        let (v, e, f) = (sphere.positions.len(), sphere.edges().len(), sphere.triangles.len());
        assert_eq!(v + f, e + 2);
        assert!(sphere.triangles.iter().all(|&t| {
            let centre: Vec3 = t.iter().map(|&v| sphere.positions[v as usize]).sum();
            triangle_cross(&sphere.positions, t).dot(centre) > 0.0
        }));
        let area = sphere.area(&sphere.positions);
        // A polyhedron inside the sphere: a little less than its area.
        let sphere_area = 4.0 * std::f64::consts::PI;
        assert!(area < sphere_area && area > 0.98 * sphere_area, "{area}");
    }

    #[test]
    fn samples_face_out_and_fix_their_border_alone() {
        let cap = sphere_cap(2.0, 60.0, 8, 16);
        assert_eq!(cap.positions.len(), 1 + 8 * 16);
        assert!(cap.positions.iter().all(|p| (p.length() - 2.0).abs() < 1e-5), "on the sphere");
        assert!(cap.triangles.iter().all(|&t| {
            let centre: Vec3 = t.iter().map(|&v| cap.positions[v as usize]).sum();
            triangle_cross(&cap.positions, t).dot(centre) > 0.0
        }));
        assert_eq!(cap.movable.iter().filter(|&&m| !m).count(), 16, "the last ring is fixed");
        let belly = belly(5);
        assert!(belly.triangles.iter().all(|&t| triangle_cross(&belly.positions, t).y > 0.0), "facing +y");
        assert_eq!(belly.movable.iter().filter(|&&m| m).count(), 9, "the inner 3 x 3 may move");
        assert!(belly.positions[12].y > belly.positions[0].y + 0.1, "the belly rises in the middle");
    }

    #[test]
    fn the_torus_is_closed_and_the_torso_open_at_its_fixed_ends() {
        let torus = torus(0.5, 0.18, 48, 16);
        let (v, e, f) = (torus.positions.len(), torus.edges().len(), torus.triangles.len());
        assert_eq!(v + f, e, "a torus has Euler characteristic 0");
        let area = torus.area(&torus.positions);
        let exact = 4.0 * std::f64::consts::PI.powi(2) * 0.5 * 0.18;
        assert!((area / exact - 1.0).abs() < 0.02, "{area} vs {exact}");
        let torso = torso(40, 80);
        assert_eq!(torso.movable.iter().filter(|&&m| !m).count(), 2 * 80, "the hips' and the chest's rings");
        assert!(torso.triangles.iter().all(|&t| {
            let middle: Vec3 = t.iter().map(|&v| torso.positions[v as usize]).sum();
            triangle_cross(&torso.positions, t).dot(middle * Vec3::new(1.0, 0.0, 1.0)) > 0.0
        }));
        let front = torso.positions.iter().map(|p| p.z).fold(f32::MIN, f32::max);
        assert!(front > 0.11 + 0.045, "the belly stands out of the front: {front}");
        for shape in [Shape::Belly, Shape::Cap, Shape::Sphere, Shape::Torus, Shape::Torso] {
            assert_eq!(shape.make(1), shape.make(3), "sizes are clamped");
        }
    }
}
