//! Sample surfaces made by the project itself, so that nothing is missing to deform.

use super::surface::{Surface, triangle_cross};
use bevy::math::Vec3;

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
