//! Tetrahedral meshes: particles and tetrahedra, built from a lattice or filled into a closed
//! surface (a lattice of cells kept where they lie inside, each cut into tetrahedra), with the
//! surface's vertices embedded in the tetrahedra that carry them.

use crate::spatial::surface::Surface;
use crate::spatial::surface_bvh::SurfaceBvh;
use bevy::math::{IVec3, Vec3};
use std::collections::HashMap;

/// Most lattice cells a surface may be filled with.
pub const MAX_CELLS: usize = 1 << 20;

/// Why a tetrahedral mesh cannot be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TetError {
    /// A tetrahedron names a particle that does not exist.
    #[error("tetrahedron {tet} names particle {particle}, but there are {count}")]
    IndexOutOfRange {
        /// The tetrahedron.
        tet: usize,
        /// The index it names.
        particle: u32,
        /// Particles there are.
        count: usize,
    },
    /// A tetrahedron without volume (or turned inside out) cannot hold one.
    #[error("tetrahedron {0} has no volume: its corners lie in a plane or it is inside out")]
    Flat(usize),
    /// A position is not a finite number.
    #[error("particle {0} has a position that is not a finite number")]
    NotFinite(usize),
    /// The cells asked for do not fit.
    #[error("{cells} cells of {cell_m} m would fill the surface's box, more than the {MAX_CELLS} allowed")]
    TooManyCells {
        /// Cells the box would take.
        cells: usize,
        /// The cell size asked for, metres.
        cell_m: f32,
    },
    /// No cell's centre lies inside the surface: it is smaller than a cell.
    #[error("no cell of {0} m lies inside the surface: it is smaller than a cell")]
    Empty(f32),
    /// The cells inside make more tetrahedra than allowed.
    #[error("cells of {cell_m} m make more than {most} tetrahedra: take larger cells")]
    TooManyTets {
        /// The most allowed.
        most: usize,
        /// The cell size asked for, metres.
        cell_m: f32,
    },
    /// The surface has holes: it has no inside to fill.
    #[error("the surface is not closed: {0} edges border a hole")]
    Open(usize),
}

/// A surface carried by a tetrahedral mesh: each vertex at fixed barycentric weights of one
/// tetrahedron, so that a fine surface rides on a coarse simulation mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Embedding {
    /// For each surface vertex, its tetrahedron and the weights of the tetrahedron's corners.
    pub weights: Vec<(u32, [f32; 4])>,
}

impl Embedding {
    /// The surface's vertices where the mesh's particles at `positions` carry them.
    pub fn place(&self, mesh: &TetMesh, positions: &[Vec3], out: &mut Vec<Vec3>) {
        out.clear();
        out.extend(self.weights.iter().map(|&(tet, w)| {
            let corners = mesh.tets[tet as usize];
            (0..4).map(|i| positions[corners[i] as usize] * w[i]).sum::<Vec3>()
        }));
    }
}

/// The barycentric weights of `p` in the tetrahedron `corners` (they sum to 1; all of them
/// from 0 to 1 inside it).
fn barycentric(p: Vec3, [a, b, c, d]: [Vec3; 4]) -> [f32; 4] {
    let volume = six_volume([a, b, c, d]);
    let wb = six_volume([a, p, c, d]) / volume;
    let wc = six_volume([a, b, p, d]) / volume;
    let wd = six_volume([a, b, c, p]) / volume;
    [1.0 - wb - wc - wd, wb, wc, wd]
}

/// How many edges of `surface` belong to one triangle alone: the borders of its holes.
fn open_edges(surface: &Surface) -> usize {
    let mut uses: HashMap<[u32; 2], u32> = HashMap::new();
    for &[a, b, c] in &surface.triangles {
        for [p, q] in [[a, b], [b, c], [c, a]] {
            *uses.entry([p.min(q), p.max(q)]).or_default() += 1;
        }
    }
    uses.values().filter(|&&n| n == 1).count()
}

/// Whether `p` lies inside the closed surface of `bvh`: the crossings of a ray from it, counted
/// one hit after another, are odd. The ray leans off the axes so that it meets no edge of a
/// surface made on a grid head on.
fn inside(bvh: &SurfaceBvh, p: Vec3) -> bool {
    let direction = Vec3::new(1.0, 0.001_37, 0.000_71).normalize();
    let (mut origin, mut crossings) = (p, 0u32);
    while let Some(hit) = bvh.pick(origin, direction) {
        crossings += 1;
        // Just past the hit, so that the next cast finds the next crossing.
        origin += direction * (hit.distance + 1e-5);
        if crossings > 10_000 {
            break;
        }
    }
    crossings % 2 == 1
}

/// A tetrahedral mesh: particles and the tetrahedra between them, each with a positive volume
/// (corners `[a, b, c, d]` with `(b - a) x (c - a) . (d - a) > 0`).
#[derive(Debug, Clone, PartialEq)]
pub struct TetMesh {
    /// Particle positions, metres.
    pub positions: Vec<Vec3>,
    /// Tetrahedra as particle indices.
    pub tets: Vec<[u32; 4]>,
}

/// Six times the signed volume of a tetrahedron.
pub(super) fn six_volume([a, b, c, d]: [Vec3; 4]) -> f32 {
    (b - a).cross(c - a).dot(d - a)
}

impl TetMesh {
    /// The mesh, checked.
    pub fn new(positions: Vec<Vec3>, tets: Vec<[u32; 4]>) -> Result<Self, TetError> {
        if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
            return Err(TetError::NotFinite(bad));
        }
        let count = positions.len();
        for (tet, corners) in tets.iter().enumerate() {
            if let Some(&particle) = corners.iter().find(|&&p| p as usize >= count) {
                return Err(TetError::IndexOutOfRange { tet, particle, count });
            }
            if six_volume(corners.map(|p| positions[p as usize])) <= 0.0 {
                return Err(TetError::Flat(tet));
            }
        }
        Ok(Self { positions, tets })
    }

    /// A box of `cells` cubes of `cell_m` metres along x, y and z from `min`, each cut into six
    /// tetrahedra around one of its diagonals (Kuhn's split), mirrored from one cube to the
    /// next along each axis: neighbouring cubes' faces match, and the diagonals alternate, so
    /// that the lattice leans no way (one diagonal everywhere makes a squeezed body creep
    /// sideways).
    pub fn lattice_box(min: Vec3, cells: [u32; 3], cell_m: f32) -> Self {
        let [nx, ny, nz] = cells.map(|n| n.max(1));
        let at = |i: u32, j: u32, k: u32| (k * (ny + 1) + j) * (nx + 1) + i;
        let mut positions = Vec::with_capacity(((nx + 1) * (ny + 1) * (nz + 1)) as usize);
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    positions.push(min + Vec3::new(i as f32, j as f32, k as f32) * cell_m);
                }
            }
        }
        let mut tets = Vec::with_capacity((6 * nx * ny * nz) as usize);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    // Mirrored along the axes where the cube's index is odd.
                    let flip = |d: u32, n: u32| if n % 2 == 1 { 1 - d } else { d };
                    let corner = |[di, dj, dk]: [u32; 3]| at(i + flip(di, i), j + flip(dj, j), k + flip(dk, k));
                    // The six paths from corner 000 to 111 along one axis at a time.
                    for axes in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
                        let mut step = [0u32; 3];
                        let mut path = [corner(step); 4];
                        for (n, &axis) in axes.iter().enumerate() {
                            step[axis] = 1;
                            path[n + 1] = corner(step);
                        }
                        let volume = six_volume(path.map(|p| positions[p as usize]));
                        tets.push(if volume > 0.0 { path } else { [path[0], path[2], path[1], path[3]] });
                    }
                }
            }
        }
        Self { positions, tets }
    }

    /// The cubes of `cell_m` metres of a lattice over `surface`'s box whose centres lie inside
    /// it, each cut into six tetrahedra as [`Self::lattice_box`] cuts them, and the surface
    /// embedded in them (a vertex outside every kept cube in the nearest kept cube's
    /// tetrahedron that holds it best, its weights reaching out of it); at most `most_tets`
    /// tetrahedra.
    pub fn fill(surface: &Surface, cell_m: f32, most_tets: usize) -> Result<(Self, Embedding), TetError> {
        let (low, high) = surface.bounds();
        let extent = ((high - low) / cell_m).ceil();
        let cells = extent.x.max(1.0) as f64 * extent.y.max(1.0) as f64 * extent.z.max(1.0) as f64;
        if !(cell_m > 0.0 && cells.is_finite() && cells <= MAX_CELLS as f64) {
            return Err(TetError::TooManyCells { cells: cells.min(usize::MAX as f64) as usize, cell_m });
        }
        let open = open_edges(surface);
        if open > 0 {
            return Err(TetError::Open(open));
        }
        let counts = extent.as_uvec3().max(bevy::math::UVec3::ONE).to_array();
        let bvh = SurfaceBvh::new(&surface.positions, &surface.triangles);
        let lattice = Self::lattice_box(low, counts, cell_m);
        let [nx, ny, _] = counts;
        let cell_of = |i: u32, j: u32, k: u32| ((k * ny + j) * nx + i) as usize;
        let mut kept = HashMap::new();
        let mut used = vec![u32::MAX; lattice.positions.len()];
        let (mut positions, mut tets) = (Vec::new(), Vec::new());
        for k in 0..counts[2] {
            for j in 0..ny {
                for i in 0..nx {
                    let centre = low + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * cell_m;
                    if !inside(&bvh, centre) {
                        continue;
                    }
                    if tets.len() + 6 > most_tets {
                        return Err(TetError::TooManyTets { most: most_tets, cell_m });
                    }
                    kept.insert(IVec3::new(i as i32, j as i32, k as i32), tets.len());
                    for corners in &lattice.tets[6 * cell_of(i, j, k)..6 * cell_of(i, j, k) + 6] {
                        tets.push(corners.map(|p| {
                            if used[p as usize] == u32::MAX {
                                used[p as usize] = positions.len() as u32;
                                positions.push(lattice.positions[p as usize]);
                            }
                            used[p as usize]
                        }));
                    }
                }
            }
        }
        if tets.is_empty() {
            return Err(TetError::Empty(cell_m));
        }
        let mesh = Self { positions, tets };
        let weights = surface.positions.iter().map(|&p| mesh.holder(p, low, cell_m, &kept)).collect();
        Ok((mesh, Embedding { weights }))
    }

    /// The tetrahedron that holds `p` best among the kept cubes nearest its own (`kept` maps a
    /// cube to its first tetrahedron), and `p`'s weights in it.
    fn holder(&self, p: Vec3, low: Vec3, cell_m: f32, kept: &HashMap<IVec3, usize>) -> (u32, [f32; 4]) {
        let cell = ((p - low) / cell_m).floor().as_ivec3();
        // Rings of cubes around `p`'s own, nearest first, until one holds kept cubes.
        for ring in 0..64i32 {
            let mut best: Option<(f32, u32, [f32; 4])> = None;
            for dz in -ring..=ring {
                for dy in -ring..=ring {
                    for dx in -ring..=ring {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != ring {
                            continue;
                        }
                        let Some(&first) = kept.get(&(cell + IVec3::new(dx, dy, dz))) else { continue };
                        for tet in first..first + 6 {
                            let w = barycentric(p, self.tets[tet].map(|c| self.positions[c as usize]));
                            // How far outside it is: the most negative weight.
                            let outside = -w.iter().copied().fold(f32::INFINITY, f32::min);
                            if best.is_none_or(|(o, ..)| outside < o) {
                                best = Some((outside, tet as u32, w));
                            }
                        }
                    }
                }
            }
            if let Some((_, tet, w)) = best {
                return (tet, w);
            }
        }
        (0, barycentric(p, self.tets[0].map(|c| self.positions[c as usize])))
    }

    /// The volume of every tetrahedron at `positions`, cubic metres.
    pub fn volume(&self, positions: &[Vec3]) -> f64 {
        self.tets.iter().map(|t| f64::from(six_volume(t.map(|p| positions[p as usize]))) / 6.0).sum()
    }
}
