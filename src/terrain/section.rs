//! The visible section of a heightmap and its mesh: `w x h` vertices at an integer origin in
//! the map, two triangles per cell, vertex normals from the adjacent faces, texture
//! coordinates fixed to the map, and the triangles sorted into one mesh per height band.
//!
//! Normals at the section's border come from the map beyond it wherever the map has data, so
//! a section moved across the map shows the same normals where it overlaps its old place, and
//! two sections side by side meet without a seam.

use super::bands::{Band, BandRule};
use super::heightmap::Heightmap;
use bevy::math::{Vec2, Vec3};
use canopy_raster::{MeshData, Morph};

/// Which part of the map is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Section {
    /// The map sample at the section's first vertex, `(x, z)`.
    pub origin: [u32; 2],
    /// Vertices along x and z, each at least 2.
    pub size: [u32; 2],
}

/// Why a section does not fit its map.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SectionError {
    /// Fewer than two vertices along a side.
    #[error("a section of {0} x {1} vertices: it needs at least 2 along each side")]
    TooSmall(u32, u32),
    /// Larger than the map.
    #[error("a section of {0} x {1} vertices does not fit a map of {2} x {3} samples")]
    TooLarge(u32, u32, u32, u32),
}

impl Section {
    /// Whether the section's size fits `map` (the origin is clamped by [`Section::clamped`]).
    pub fn check(&self, map: &Heightmap) -> Result<(), SectionError> {
        let [w, h] = self.size;
        if w < 2 || h < 2 {
            return Err(SectionError::TooSmall(w, h));
        }
        if w > map.width() || h > map.height() {
            return Err(SectionError::TooLarge(w, h, map.width(), map.height()));
        }
        Ok(())
    }

    /// The section with its size limited to the map and its origin moved so that it lies
    /// inside the map.
    pub fn clamped(self, map: &Heightmap) -> Self {
        let size = [
            self.size[0].clamp(2.min(map.width()), map.width()),
            self.size[1].clamp(2.min(map.height()), map.height()),
        ];
        let origin = [self.origin[0].min(map.width() - size[0]), self.origin[1].min(map.height() - size[1])];
        Self { origin, size }
    }

    /// The section moved by `(dx, dz)` samples (the source's Move), stopping at the map's
    /// edges.
    pub fn moved(self, dx: i64, dz: i64, map: &Heightmap) -> Self {
        let shift = |origin: u32, d: i64| (i64::from(origin) + d).max(0) as u32;
        Self { origin: [shift(self.origin[0], dx), shift(self.origin[1], dz)], ..self }.clamped(map)
    }
}

/// How map units become metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Metres between neighbouring samples.
    pub cell_m: f32,
    /// Metres of height for a map height of 1.
    pub height_m: f32,
    /// Cells one repetition of a band texture covers.
    pub texture_cells: f32,
}

/// The pairs of bands that can meet in a blended triangle, lower band first.
pub const BORDERS: [(Band, Band); 10] = [
    (Band::Water, Band::Sand),
    (Band::Water, Band::Grass),
    (Band::Water, Band::Rock),
    (Band::Water, Band::Snow),
    (Band::Sand, Band::Grass),
    (Band::Sand, Band::Rock),
    (Band::Sand, Band::Snow),
    (Band::Grass, Band::Rock),
    (Band::Grass, Band::Snow),
    (Band::Rock, Band::Snow),
];

/// The section's meshes and figures.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionMesh {
    /// One mesh per band, in [`Band::ALL`] order, positions relative to `barycentre`: the
    /// triangles showing that band alone.
    pub bands: [MeshData; 5],
    /// With blending, one mesh per pair of [`BORDERS`]: the triangles where the two bands
    /// meet, textured with the lower band fading into the upper by the vertices' blend
    /// weights (the upper band's share of the two).
    pub borders: [MeshData; 10],
    /// Triangles per band by the per-triangle rule (the source's count, blended or not).
    pub counts: [usize; 5],
    /// What the positions are measured from, metres: the mean of the section's vertices (its
    /// first vertex at the origin), the centre it turns and scales about; zero for
    /// [`Placement::Samples`].
    pub barycentre: Vec3,
}

impl SectionMesh {
    /// The meshes of every surface: the five bands in [`Band::ALL`] order, then the borders
    /// in [`BORDERS`] order.
    pub fn into_surfaces(self) -> Vec<MeshData> {
        self.bands.into_iter().chain(self.borders).collect()
    }
}

/// The two triangles of cell `(x, z)` as corner offsets, counter-clockwise seen from above:
/// `a c d` and `a d b` with `a = (x, z)`, `b = (x + 1, z)`, `c = (x, z + 1)`, `d = (x + 1, z + 1)`.
const CELL_TRIANGLES: [[(u32, u32); 3]; 2] = [[(0, 0), (0, 1), (1, 1)], [(0, 0), (1, 1), (1, 0)]];

/// Which samples a mesh's vertices stand for, for their texture coordinates: the sample (of
/// the map, or of the world for a chunk) at the first vertex, and the samples from one vertex
/// to the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleFrame {
    /// The sample at the first vertex, `(x, z)`.
    pub origin: [i64; 2],
    /// Samples between neighbouring vertices.
    pub step: u32,
}

impl SampleFrame {
    /// Where vertex `(i, j)` lies from the samples' origin along x and z, for vertices
    /// `spacing_m` metres apart: its sample times the metres between samples.
    pub fn metres(&self, vertex: [u32; 2], spacing_m: f32) -> [f32; 2] {
        let sample_m = spacing_m / self.step as f32;
        [0, 1].map(|axis| (self.origin[axis] + i64::from(vertex[axis]) * i64::from(self.step)) as f32 * sample_m)
    }
}

/// What a section's mesh positions are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// The mean of its vertices (the first vertex at the origin): the centre a section turns
    /// and scales about.
    Barycentre,
    /// The origin of the frame's samples, each vertex at its sample times the metres between
    /// samples (`geometry.cell_m / frame.step`): pieces of one grid so place the vertices they
    /// share bit for bit alike, whichever piece and level they belong to.
    Samples,
}

/// Where a section's vertices move as it morphs into a coarser mesh (see
/// [`canopy_raster::Morph`]): per vertex, row by row, its target position (metres, measured
/// as the placement of [`mesh_section_in`] places the vertices before their barycentre is
/// taken away) and unit normal, and the distances of the morph.
#[derive(Debug, Clone, PartialEq)]
pub struct MorphTargets {
    /// Target positions, `w x h`.
    pub positions: Vec<Vec3>,
    /// Target normals, `w x h`.
    pub normals: Vec<Vec3>,
    /// Metres from the camera at which the vertices start to move.
    pub start_m: f32,
    /// Metres at which they reach their targets.
    pub end_m: f32,
}

/// The mesh of `section` (which must fit `map`), banded by `rule`, its texture coordinates
/// fixed to the map's samples.
pub fn mesh_section(map: &Heightmap, section: Section, geometry: Geometry, rule: &BandRule) -> SectionMesh {
    let frame = SampleFrame { origin: section.origin.map(i64::from), step: 1 };
    mesh_section_in(map, section, geometry, rule, frame, Placement::Barycentre, None)
}

/// [`mesh_section`] with the texture coordinates of the samples of `frame`: vertex `(i, j)`
/// reads the texture at sample `origin + step (i, j)`, one repetition every
/// `geometry.texture_cells` samples; positions measured from what `placement` says; and with
/// `morph`, the meshes morph into its targets.
///
/// Two passes: the first decides each triangle's surface (a band, or with blending a border)
/// and numbers the vertices each surface uses; the second fills every mesh at its final size,
/// so that nothing is moved as the meshes grow.
pub fn mesh_section_in(
    map: &Heightmap,
    section: Section,
    geometry: Geometry,
    rule: &BandRule,
    frame: SampleFrame,
    placement: Placement,
    morph: Option<&MorphTargets>,
) -> SectionMesh {
    let [x0, z0] = section.origin;
    let [w, h] = section.size.map(|n| n as usize);
    let count = w * h;
    // The section's heights and positions, row by row.
    let heights: Vec<f32> =
        (z0..z0 + h as u32).flat_map(|z| map.row(z)[x0 as usize..x0 as usize + w].iter().copied()).collect();
    let place = |i: usize, j: usize| match placement {
        Placement::Barycentre => [i, j].map(|k| k as f32 * geometry.cell_m),
        Placement::Samples => frame.metres([i as u32, j as u32], geometry.cell_m),
    };
    let positions: Vec<Vec3> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .zip(&heights)
        .map(|((i, j), &height)| {
            let [x, z] = place(i, j);
            Vec3::new(x, height * geometry.height_m, z)
        })
        .collect();
    let normals = vertex_normals(map, section, geometry);
    let barycentre = match placement {
        Placement::Barycentre => positions.iter().fold(Vec3::ZERO, |sum, &p| sum + p) / count as f32,
        Placement::Samples => Vec3::ZERO,
    };
    // Each vertex's share of every band, when blending.
    let weights: Vec<[f32; 5]> = match rule.blend {
        Some(_) => heights.iter().zip(&normals).map(|(&height, normal)| rule.weights(height, normal.y)).collect(),
        None => Vec::new(),
    };
    let surfaces = if weights.is_empty() { 5 } else { 15 };

    // The first pass: each triangle's surface and, per surface, the section vertices it uses
    // in the order of their indices in its mesh (with their blend weights on borders).
    let mut counts = [0; 5];
    let mut chosen: Vec<u8> = Vec::with_capacity(2 * (w - 1) * (h - 1));
    let mut remap = vec![u32::MAX; count * surfaces];
    // Each used vertex as its column and row in the section.
    let mut used: [Vec<[u32; 2]>; 15] = Default::default();
    let mut blend: [Vec<f32>; 15] = Default::default();
    let mut triangles = [0usize; 15];
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            for (corners, offsets) in cell_triangles(j * w + i, w).into_iter().zip(CELL_TRIANGLES) {
                let mean = corners.iter().map(|&k| heights[k]).sum::<f32>() / 3.0;
                // The face's slope matters only to a rock slope.
                let up = match rule.rock_slope_deg {
                    Some(_) => {
                        let [a, b, c] = corners.map(|k| positions[k]);
                        (b - a).cross(c - a).normalize_or_zero().y
                    }
                    None => 1.0,
                };
                let band = rule.band(mean, up);
                counts[band.index()] += 1;
                let (surface, border) = match weights.is_empty() {
                    true => (band.index(), None),
                    false => blended_surface(corners.map(|k| &weights[k])),
                };
                for (k, (di, dj)) in corners.into_iter().zip(offsets) {
                    let slot = &mut remap[k * surfaces + surface];
                    if *slot == u32::MAX {
                        *slot = used[surface].len() as u32;
                        used[surface].push([i as u32 + di, j as u32 + dj]);
                        if let Some(border) = border {
                            blend[surface].push(border.upper_share(&weights[k]));
                        }
                    }
                }
                triangles[surface] += 1;
                chosen.push(surface as u8);
            }
        }
    }

    // The second pass: every mesh at its final size.
    let mut blend = blend.into_iter();
    let mut meshes: [MeshData; 15] = std::array::from_fn(|surface| {
        let vertices = &used[surface];
        let index = |[i, j]: [u32; 2]| j as usize * w + i as usize;
        MeshData {
            positions: vertices.iter().map(|&v| positions[index(v)] - barycentre).collect(),
            normals: vertices.iter().map(|&v| normals[index(v)]).collect(),
            uvs: vertices
                .iter()
                .map(|&[i, j]| {
                    let [x, z] = [(0, i), (1, j)].map(|(axis, k)| frame.origin[axis] + i64::from(k * frame.step));
                    Vec2::new(x as f32, z as f32) / geometry.texture_cells
                })
                .collect(),
            colors: Vec::new(),
            blend: blend.next().unwrap_or_default(),
            triangles: Vec::with_capacity(triangles[surface]),
            morph: morph.map(|targets| Morph {
                positions: vertices.iter().map(|&v| targets.positions[index(v)] - barycentre).collect(),
                normals: vertices.iter().map(|&v| targets.normals[index(v)]).collect(),
                start_m: targets.start_m,
                end_m: targets.end_m,
            }),
        }
    });
    let mut next = chosen.iter();
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            for corners in cell_triangles(j * w + i, w) {
                let Some(&surface) = next.next() else { break };
                let surface = usize::from(surface);
                meshes[surface].triangles.push(corners.map(|k| remap[k * surfaces + surface]));
            }
        }
    }
    let [water, sand, grass, rock, snow, borders @ ..] = meshes;
    SectionMesh { bands: [water, sand, grass, rock, snow], borders, counts, barycentre }
}

/// The two triangles of the cell whose first corner is section vertex `a`, in rows of `w`
/// vertices, as vertex indices (see [`CELL_TRIANGLES`]).
fn cell_triangles(a: usize, w: usize) -> [[usize; 3]; 2] {
    let (b, c, d) = (a + 1, a + w, a + w + 1);
    [[a, c, d], [a, d, b]]
}

/// The two bands a blended triangle shows.
#[derive(Debug, Clone, Copy)]
struct Border {
    lower: Band,
    upper: Band,
    /// Whether the upper band has the more weight over the triangle.
    upper_leads: bool,
}

impl Border {
    /// The upper band's share of the two at a vertex of band `weights`; a vertex showing
    /// neither (where three bands meet) takes the triangle's leading band.
    fn upper_share(self, weights: &[f32; 5]) -> f32 {
        let (low, high) = (weights[self.lower.index()], weights[self.upper.index()]);
        if low + high > 1e-6 { high / (low + high) } else { f32::from(u8::from(self.upper_leads)) }
    }
}

/// The surface a blended triangle is drawn in, from its vertices' band weights: the band
/// with the most weight over the three vertices alone, or with the runner-up the border of
/// the two (at [`BORDERS`]' index plus five).
fn blended_surface(weights: [&[f32; 5]; 3]) -> (usize, Option<Border>) {
    let total: [f32; 5] = std::array::from_fn(|b| weights.iter().map(|w| w[b]).sum());
    let order = |a: &usize, b: &usize| total[*a].total_cmp(&total[*b]).then(b.cmp(a));
    let first = (0..5).max_by(order).unwrap_or(0);
    let second = (0..5).filter(|&b| b != first).max_by(order).unwrap_or(0);
    // Less than a thousandth of one vertex: the runner-up does not show.
    if total[second] < 1e-3 {
        return (first, None);
    }
    let (lower, upper) = (Band::ALL[first.min(second)], Band::ALL[first.max(second)]);
    let index = BORDERS.iter().position(|&pair| pair == (lower, upper)).unwrap_or(0);
    (5 + index, Some(Border { lower, upper, upper_leads: first > second }))
}

/// Unit normals of the section's vertices, row by row: the sum of the (area-weighted) normals
/// of the up to six map triangles around each vertex.
pub(crate) fn vertex_normals(map: &Heightmap, section: Section, geometry: Geometry) -> Vec<Vec3> {
    let [x0, z0] = section.origin.map(i64::from);
    let [w, h] = section.size.map(|n| n as usize);
    // The face normals (area-weighted) of the cells around the section's vertices, from one
    // before the first vertex to the last along each axis, zero where the map has no cell.
    let (last_x, last_z) = (i64::from(map.width()) - 2, i64::from(map.height()) - 2);
    // Corners relative to their cell's first: a face depends on its heights alone, never on
    // where the cell lies, so every section (and every piece of a world) that has a cell
    // gives it the same normal bit for bit.
    let corner = |x: i64, z: i64, (dx, dz): (u32, u32)| {
        let height = map.at((x + i64::from(dx)) as u32, (z + i64::from(dz)) as u32);
        Vec3::new(dx as f32 * geometry.cell_m, height * geometry.height_m, dz as f32 * geometry.cell_m)
    };
    // Two rows of cells at a time: those above a row of vertices and those below it.
    let row_of_faces = |z: i64, faces: &mut Vec<[Vec3; 2]>| {
        faces.clear();
        faces.extend((x0 - 1..x0 + w as i64).map(|x| match (0..=last_x).contains(&x) && (0..=last_z).contains(&z) {
            true => CELL_TRIANGLES.map(|t| {
                let [a, b, c] = t.map(|offset| corner(x, z, offset));
                (b - a).cross(c - a)
            }),
            false => [Vec3::ZERO; 2],
        }));
    };
    let (mut above, mut below) = (Vec::with_capacity(w + 1), Vec::with_capacity(w + 1));
    row_of_faces(z0 - 1, &mut above);
    let mut normals = Vec::with_capacity(w * h);
    for z in z0..z0 + h as i64 {
        row_of_faces(z, &mut below);
        for i in 0..w {
            // As corner a of its own cell (both triangles), b of the cell to the left (the
            // second), c of the cell above (the first) and d of the cell diagonally before it
            // (both).
            let (own, left, up, diagonal) = (below[i + 1], below[i], above[i + 1], above[i]);
            let sum = own[0] + own[1] + left[1] + up[0] + diagonal[0] + diagonal[1];
            normals.push(sum.try_normalize().unwrap_or(Vec3::Y));
        }
        std::mem::swap(&mut above, &mut below);
    }
    normals
}

/// The band each triangle of a section fell into, counted: for dumps.
pub fn band_counts(mesh: &SectionMesh) -> impl Iterator<Item = (Band, usize)> + '_ {
    Band::ALL.into_iter().zip(mesh.counts)
}

#[cfg(test)]
mod tests;
