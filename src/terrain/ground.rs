//! The visible section as a solid ground: the height and normal under any point, on the very
//! triangles its mesh draws, for whatever rests on the terrain.

use super::Heightmap;
use super::section::{Geometry, Section};
use crate::spatial::solid::HeightField;
use bevy::math::{Affine3A, Quat, Vec3};
use bevy::transform::components::Transform;

/// Where a section's mesh stands: its barycentre (`barycentre`, measured with vertex `(i, j)` at
/// `(i, height, j)` times the geometry's metres) at `position` raised by the barycentre's height,
/// turned `rotation_deg` about the vertical and scaled about it.
pub fn placement(position: Vec3, rotation_deg: f32, scale: Vec3, barycentre: Vec3) -> Transform {
    Transform {
        translation: position + Vec3::Y * barycentre.y,
        rotation: Quat::from_rotation_y(rotation_deg.to_radians()),
        scale: scale.max(Vec3::splat(1e-3)),
    }
}

/// The mean of a section's vertices, measured as [`placement`] measures them: the point the
/// mesh is drawn about.
pub fn section_barycentre(map: &Heightmap, section: Section, geometry: Geometry) -> Vec3 {
    let [x0, z0] = section.origin.map(|n| n as usize);
    let [w, h] = section.size.map(|n| n as usize);
    let mut sum = Vec3::ZERO;
    for j in 0..h {
        for (i, height) in map.row((z0 + j) as u32)[x0..x0 + w].iter().enumerate() {
            sum += Vec3::new(i as f32 * geometry.cell_m, height * geometry.height_m, j as f32 * geometry.cell_m);
        }
    }
    sum / (w * h) as f32
}

/// The height and upward unit normal of the surface a mesh draws over one cell, at `(fu, fv)`
/// (0 to 1) across it: `corners` are the heights at its first corner `a`, the next along x
/// `b`, along z `c` and across `d`, metres; the cell is the triangles `a c d` and `a d b`,
/// `cell_m` metres a side.
pub fn cell_surface([a, b, c, d]: [f32; 4], fu: f32, fv: f32, cell_m: f32) -> (f32, Vec3) {
    // Slopes of the height along u and v, per cell.
    let (along_u, along_v) = if fv >= fu { (d - c, c - a) } else { (b - a, d - b) };
    let height = a + along_u * fu + along_v * fv;
    (height, Vec3::new(-along_u / cell_m, 1.0, -along_v / cell_m).normalize())
}

/// The ground of a section, placed in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct Ground {
    /// Heights of the section's vertices row by row, metres.
    heights: Vec<f32>,
    /// Vertices along x and z.
    size: [usize; 2],
    /// Metres between vertices.
    cell_m: f32,
    /// Where the first vertex stands in the mesh's own frame (its height apart), metres.
    origin: Vec3,
    /// The mesh's frame to the world's.
    to_world: Affine3A,
    /// The world's frame to the mesh's.
    to_local: Affine3A,
}

impl Ground {
    /// The ground of `section` of `map` as the section's mesh is drawn: vertex `(i, j)` at
    /// `(i, height, j)` times the geometry's metres, less `barycentre`, then placed by
    /// `to_world`.
    pub fn of_section(
        map: &Heightmap,
        section: Section,
        geometry: Geometry,
        barycentre: Vec3,
        to_world: Affine3A,
    ) -> Self {
        let [x0, z0] = section.origin.map(|n| n as usize);
        let size = section.size.map(|n| n as usize);
        let heights = (z0..z0 + size[1])
            .flat_map(|z| map.row(z as u32)[x0..x0 + size[0]].iter().map(|h| h * geometry.height_m))
            .collect();
        Self { heights, size, cell_m: geometry.cell_m, origin: -barycentre, to_world, to_local: to_world.inverse() }
    }

    /// The height of the ground and its upward unit normal at `(x, z)` of the mesh's frame, if
    /// the section covers that point. Each cell is the two triangles the mesh draws: `a c d`
    /// and `a d b` with `a` its first corner, `b` the next along x, `c` along z, `d` across.
    pub fn surface(&self, x: f32, z: f32) -> Option<(f32, Vec3)> {
        let u = (x - self.origin.x) / self.cell_m;
        let v = (z - self.origin.z) / self.cell_m;
        let [w, h] = self.size;
        if !(u >= 0.0 && v >= 0.0 && u <= (w - 1) as f32 && v <= (h - 1) as f32) {
            return None;
        }
        let (i, j) = ((u as usize).min(w - 2), (v as usize).min(h - 2));
        let at = |di: usize, dj: usize| self.heights[(j + dj) * w + i + di];
        let corners = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
        let (height, normal) = cell_surface(corners, u - i as f32, v - j as f32, self.cell_m);
        Some((self.origin.y + height, normal))
    }

    /// The height of the ground under the world point `(x, z)`, metres; `None` outside the
    /// section.
    pub fn height_under(&self, x: f32, z: f32) -> Option<f32> {
        let local = self.to_local.transform_point3(Vec3::new(x, 0.0, z));
        let (height, _) = self.surface(local.x, local.z)?;
        Some(self.to_world.transform_point3(Vec3::new(local.x, height, local.z)).y)
    }

    /// How deep the world point `p` lies under the ground, metres, and the unit direction out
    /// (towards the nearest point of the triangle's plane), if it does.
    pub fn penetration(&self, p: Vec3) -> Option<(f32, Vec3)> {
        let local = self.to_local.transform_point3(p);
        let (height, normal) = self.surface(local.x, local.z)?;
        let below = height - local.y;
        if below <= 0.0 {
            return None;
        }
        // Out along the triangle's normal, to its plane; the placement keeps planes planes.
        let out = self.to_world.transform_point3(local + normal * (below * normal.y)) - p;
        let depth = out.length();
        (depth > 0.0).then(|| (depth, out / depth))
    }
}

/// The section's ground is what solids meet of the terrain.
impl HeightField for Ground {
    fn penetration(&self, p: Vec3) -> Option<(f32, Vec3)> {
        Ground::penetration(self, p)
    }

    fn height(&self, x: f32, z: f32) -> Option<f32> {
        self.height_under(x, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::bands::BandRule;
    use crate::terrain::section::{Placement, SampleFrame, mesh_section_in};
    use bevy::math::Quat;

    fn map() -> Heightmap {
        Heightmap::from_fn(9, 7, |x, z| ((x * 7 + z * 13) % 5) as f32 * 0.1 + (x as f32 * 0.3).sin() * 0.2).unwrap()
    }

    #[test]
    fn the_ground_lies_on_the_triangles_the_mesh_draws() {
        let geometry = Geometry { cell_m: 0.5, height_m: 2.0, texture_cells: 4.0 };
        let section = Section { origin: [1, 2], size: [6, 4] };
        let map = map();
        let mesh = mesh_section_in(
            &map,
            section,
            geometry,
            &BandRule::default(),
            SampleFrame { origin: [1, 2], step: 1 },
            Placement::Barycentre,
            None,
        );
        let place = Affine3A::from_scale_rotation_translation(
            Vec3::new(1.5, 0.7, 1.2),
            Quat::from_rotation_y(0.6),
            Vec3::new(3.0, -1.0, 2.0),
        );
        let ground = Ground::of_section(&map, section, geometry, mesh.barycentre, place);
        assert!(section_barycentre(&map, section, geometry).distance(mesh.barycentre) < 1e-5);
        let mut checked = 0;
        for surface in mesh.into_surfaces() {
            for triangle in &surface.triangles {
                let [a, b, c] = triangle.map(|k| surface.positions[k as usize]);
                // Points inside the triangle, and its face normal.
                let normal = (b - a).cross(c - a).normalize();
                for (wa, wb) in [(0.2, 0.3), (0.6, 0.2), (0.1, 0.1)] {
                    let p = a + (b - a) * wa + (c - a) * wb;
                    let (height, up) = ground.surface(p.x, p.z).expect("inside the section");
                    assert!((height - p.y).abs() < 1e-5, "{height} against {}", p.y);
                    assert!(up.distance(normal) < 1e-5, "{up} against {normal}");
                    // Placed: a point just under the surface is pushed out onto it.
                    let under = place.transform_point3(p - Vec3::Y * 0.01);
                    let (depth, out) = ground.penetration(under).expect("under the ground");
                    let back = place.inverse().transform_point3(under + out * depth);
                    assert!((back - p).dot(normal).abs() < 1e-4, "onto the plane");
                    assert!(ground.penetration(place.transform_point3(p + Vec3::Y * 0.01)).is_none());
                    // The height under the placed point is the placed point's.
                    let placed = place.transform_point3(p);
                    let height = ground.height_under(placed.x, placed.z).expect("over the section");
                    assert!((height - placed.y).abs() < 1e-4, "{height} against {}", placed.y);
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 3 * 2 * 5 * 3);
        // Outside the section there is no ground.
        assert_eq!(ground.surface(-10.0, 0.0), None);
    }
}
