//! Triangle meshes as the rasterizer consumes them, and the primitive shapes.

use bevy_math::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// An indexed triangle mesh in model space.
///
/// Front faces wind counter-clockwise seen from outside (the right-handed convention of
/// `glam`); `normals` has one unit normal per position. `uvs`, `colors` and `blend` are either
/// empty or hold one entry per position, and so do `morph`'s targets when it is set.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions in model units.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty (then every vertex reads `(0, 0)`).
    pub uvs: Vec<Vec2>,
    /// Linear RGB vertex colours multiplying the material colour, or empty (white).
    pub colors: Vec<Vec3>,
    /// How far each vertex's texture fades into the material's blend texture, in `[0, 1]`,
    /// one per position, or empty (the texture alone).
    pub blend: Vec<f32>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Where the vertices move as the mesh is seen from farther away, or `None` for a mesh
    /// that stays as it is.
    pub morph: Option<Morph>,
}

/// A geomorph: each vertex slides towards its target, and its normal towards the target's,
/// by its horizontal distance from the camera, so that a mesh turns into a coarser one
/// continuously instead of at once (level-of-detail terrain).
///
/// The distance is measured in the world's `x`-`z` plane from the camera's eye to the
/// vertex's unmorphed world position: the vertex is where `positions` has it up to
/// `start_m`, at its target from `end_m` on, and moves linearly in between.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Morph {
    /// Each vertex's target position, in model units.
    pub positions: Vec<Vec3>,
    /// Each vertex's target normal (unit length).
    pub normals: Vec<Vec3>,
    /// Metres at which the vertices start to move.
    pub start_m: f32,
    /// Metres at which they reach their targets; more than `start_m`.
    pub end_m: f32,
}

impl Morph {
    /// How far a vertex `distance_m` metres from the eye has moved towards its target, from
    /// 0 to 1.
    pub fn weight(&self, distance_m: f32) -> f32 {
        ((distance_m - self.start_m) / (self.end_m - self.start_m).max(f32::MIN_POSITIVE)).clamp(0.0, 1.0)
    }
}

impl MeshData {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The smallest axis-aligned box holding every position (and every morph target), as
    /// `(min, max)`; `None` for a mesh without positions.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        let targets = self.morph.iter().flat_map(|morph| &morph.positions);
        Some(self.positions.iter().chain(targets).fold((first, first), |(min, max), &p| (min.min(p), max.max(p))))
    }

    /// Appends a vertex and returns its index.
    fn push_vertex(&mut self, position: Vec3, normal: Vec3, uv: Vec2) -> u32 {
        self.positions.push(position);
        self.normals.push(normal);
        self.uvs.push(uv);
        (self.positions.len() - 1) as u32
    }

    /// Appends the quad `a b c d` (counter-clockwise seen from the side `normal` points to),
    /// textured with the whole image: `a` at the bottom-left, `c` at the top-right.
    fn push_quad(&mut self, corners: [Vec3; 4], normal: Vec3) {
        let uvs = [Vec2::new(0.0, 1.0), Vec2::ONE, Vec2::new(1.0, 0.0), Vec2::ZERO];
        let [a, b, c, d] = [0, 1, 2, 3].map(|i| self.push_vertex(corners[i], normal, uvs[i]));
        self.triangles.push([a, b, c]);
        self.triangles.push([a, c, d]);
    }

    /// An axis-aligned cube of edge 1 centred on the origin, with flat faces.
    pub fn cube() -> Self {
        let mut mesh = Self::default();
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            for normal in [axis, -axis] {
                // Two tangents such that (u, v, normal) is right-handed.
                let u = normal.any_orthonormal_vector();
                let v = normal.cross(u);
                let centre = normal * 0.5;
                let (u, v) = (u * 0.5, v * 0.5);
                mesh.push_quad([centre - u - v, centre + u - v, centre + u + v, centre - u + v], normal);
            }
        }
        mesh
    }

    /// A sphere of diameter 1 centred on the origin, as `stacks` rings of `slices` quads with
    /// smooth normals; `u` runs once around the equator, `v` from the north pole to the south.
    pub fn sphere(stacks: u32, slices: u32) -> Self {
        let (stacks, slices) = (stacks.max(2), slices.max(3));
        let mut mesh = Self::default();
        for i in 0..=stacks {
            let polar = PI * i as f32 / stacks as f32;
            for j in 0..=slices {
                // The seam column and the poles repeat positions exactly, so the surface
                // is closed to the bit.
                let azimuth = TAU * (j % slices) as f32 / slices as f32;
                let normal = match i {
                    0 => Vec3::Y,
                    i if i == stacks => -Vec3::Y,
                    _ => Vec3::new(polar.sin() * azimuth.cos(), polar.cos(), -polar.sin() * azimuth.sin()),
                };
                let uv = Vec2::new(j as f32 / slices as f32, i as f32 / stacks as f32);
                mesh.push_vertex(normal * 0.5, normal, uv);
            }
        }
        let row = slices + 1;
        for i in 0..stacks {
            for j in 0..slices {
                let (a, b) = (i * row + j, (i + 1) * row + j);
                if i != 0 {
                    mesh.triangles.push([a, b, a + 1]);
                }
                if i != stacks - 1 {
                    mesh.triangles.push([a + 1, b, b + 1]);
                }
            }
        }
        mesh
    }

    /// A cylinder of diameter 1 and height 1 along the y axis, centred on the origin: a smooth
    /// side of `slices` quads (`u` around, `v` down) and two flat caps (mapped from above).
    pub fn cylinder(slices: u32) -> Self {
        let slices = slices.max(3);
        let mut mesh = Self::default();
        let ring = |j: u32| {
            let azimuth = TAU * (j % slices) as f32 / slices as f32;
            Vec3::new(azimuth.cos(), 0.0, -azimuth.sin())
        };
        for j in 0..=slices {
            let radial = ring(j);
            let u = j as f32 / slices as f32;
            mesh.push_vertex(radial * 0.5 - Vec3::Y * 0.5, radial, Vec2::new(u, 1.0));
            mesh.push_vertex(radial * 0.5 + Vec3::Y * 0.5, radial, Vec2::new(u, 0.0));
        }
        for j in 0..slices {
            let (bottom, top) = (2 * j, 2 * j + 1);
            mesh.triangles.push([bottom, bottom + 2, top]);
            mesh.triangles.push([top, bottom + 2, top + 2]);
        }
        for (normal, y) in [(Vec3::Y, 0.5), (-Vec3::Y, -0.5)] {
            let cap_uv = |p: Vec3| Vec2::new(p.x + 0.5, p.z + 0.5);
            let centre = mesh.push_vertex(Vec3::Y * y, normal, cap_uv(Vec3::ZERO));
            let first = mesh.positions.len() as u32;
            for j in 0..slices {
                let p = ring(j) * 0.5;
                mesh.push_vertex(p + Vec3::Y * y, normal, cap_uv(p));
            }
            for j in 0..slices {
                let (a, b) = (first + j, first + (j + 1) % slices);
                // The ring runs counter-clockwise seen from +y.
                mesh.triangles.push(if y > 0.0 { [centre, a, b] } else { [centre, b, a] });
            }
        }
        mesh
    }

    /// A square of edge 1 in the xz plane, facing +y, split into `cells` x `cells` quads so
    /// that per-vertex lighting and near-plane clipping stay smooth on large planes; the
    /// texture covers it once, `u` along +x and `v` along +z.
    pub fn plane(cells: u32) -> Self {
        let cells = cells.max(1);
        let mut mesh = Self::default();
        let row = cells + 1;
        for i in 0..=cells {
            for j in 0..=cells {
                let x = j as f32 / cells as f32 - 0.5;
                let z = i as f32 / cells as f32 - 0.5;
                mesh.push_vertex(Vec3::new(x, 0.0, z), Vec3::Y, Vec2::new(x + 0.5, z + 0.5));
            }
        }
        for i in 0..cells {
            for j in 0..cells {
                let (a, b) = (i * row + j, (i + 1) * row + j);
                mesh.triangles.push([a, b, b + 1]);
                mesh.triangles.push([a, b + 1, a + 1]);
            }
        }
        mesh
    }
}

/// Area-weighted unit vertex normals of a surface (a vertex of no triangle points up).
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let [pa, pb, pc] = [a, b, c].map(|v| positions[v as usize]);
        let cross = (pb - pa).cross(pc - pa);
        for v in [a, b, c] {
            normals[v as usize] += cross;
        }
    }
    normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Y)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn all_primitives() -> Vec<(&'static str, MeshData)> {
        vec![
            ("cube", MeshData::cube()),
            ("sphere", MeshData::sphere(12, 24)),
            ("cylinder", MeshData::cylinder(24)),
            ("plane", MeshData::plane(4)),
        ]
    }

    #[test]
    fn triangles_wind_counter_clockwise_seen_from_their_normals() {
        for (name, mesh) in all_primitives() {
            for &[a, b, c] in &mesh.triangles {
                let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
                let face = (pb - pa).cross(pc - pa);
                assert!(face.length() > 1e-7, "{name}: degenerate triangle");
                let mean = mesh.normals[a as usize] + mesh.normals[b as usize] + mesh.normals[c as usize];
                assert!(face.dot(mean) > 0.0, "{name}: triangle {a} {b} {c} faces inwards");
            }
        }
    }

    #[test]
    fn normals_are_unit_and_indices_valid() {
        for (name, mesh) in all_primitives() {
            assert_eq!(mesh.positions.len(), mesh.normals.len());
            assert_eq!(mesh.positions.len(), mesh.uvs.len());
            assert!(mesh.uvs.iter().all(|uv| (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)), "{name}");
            for n in &mesh.normals {
                assert!((n.length() - 1.0).abs() < 1e-5, "{name}: normal {n}");
            }
            let count = mesh.positions.len() as u32;
            assert!(mesh.triangles.iter().flatten().all(|&i| i < count), "{name}");
        }
    }

    /// Every edge of a closed mesh is shared by exactly two triangles, once in each direction
    /// (positions compared exactly, since flat faces duplicate vertices).
    #[test]
    fn closed_primitives_are_watertight() {
        for (name, mesh) in all_primitives().into_iter().filter(|(n, _)| *n != "plane") {
            let key = |i: u32| mesh.positions[i as usize].to_array().map(|c| (c + 0.0).to_bits());
            let mut edges: HashMap<_, i32> = HashMap::new();
            for &[a, b, c] in &mesh.triangles {
                for (from, to) in [(a, b), (b, c), (c, a)] {
                    *edges.entry((key(from), key(to))).or_default() += 1;
                }
            }
            for (&(from, to), &count) in &edges {
                let back = edges.get(&(to, from)).copied().unwrap_or(0);
                assert_eq!((count, back), (1, 1), "{name}: open or doubled edge");
            }
        }
    }

    #[test]
    fn primitives_fit_the_unit_box() {
        for (name, mesh) in all_primitives() {
            let (min, max) = mesh.bounds().unwrap();
            assert!((max.max(-min).max_element() - 0.5).abs() < 1e-6, "{name}: extent {min} {max}");
        }
    }
}
