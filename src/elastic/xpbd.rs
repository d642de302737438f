//! Dynamic soft bodies by extended position-based dynamics (XPBD, Macklin, Mueller and
//! Chentanez 2016) in small steps (Macklin et al. 2019: many substeps of one iteration each):
//! particles joined by edge-length and tetrahedron-volume constraints with compliance, under
//! gravity, kept out of static solids with friction, held by stems or a dragging hand.
//!
//! A constraint's compliance is its inverse stiffness in physical units, from the material's
//! Young's modulus and Poisson's ratio (metres per newton for an edge): it enters each substep
//! as `compliance / h^2`, so that a body is as stiff with five substeps as with twenty. A skin
//! that resists bending is optional: hinges between neighbouring surface triangles whose
//! stiffness comes from a bending rigidity as in discrete shells (Grinspun et al. 2003), with
//! the dihedral angle's gradient of Bridson, Marino and Fedkiw (2003).
//!
//! Each pass takes the constraints in the order of a greedy colouring, so that consecutive
//! projections move different particles and need not wait for one another.

use super::collide::Collider;
use crate::soft_body::pick::SurfaceBvh;
use crate::soft_body::surface::Surface;
use bevy::math::{IVec3, Vec3};
use std::collections::{BTreeMap, HashMap};
use std::f32::consts::{PI, TAU};

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
fn six_volume([a, b, c, d]: [Vec3; 4]) -> f32 {
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

/// The physical settings of a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Density, kilograms per cubic metre.
    pub density_kg_m3: f32,
    /// Young's modulus, pascals: each edge is a spring over its share of the body's volume,
    /// with the strain energy `E V (strain)^2 / 2` (infinite: rigid edges).
    pub young_modulus_pa: f32,
    /// Poisson's ratio, 0 to 0.5: the bulk modulus `K = E / (3 (1 - 2 nu))` of each
    /// tetrahedron's volume, with the energy `K (V - V0)^2 / (2 V0)` (0.5: its volume is kept
    /// as hard as the substeps can).
    pub poisson_ratio: f32,
    /// The share of velocity lost per second, from 0.
    pub damping_per_s: f32,
    /// The bending rigidity of its skin, newton metres: the hinge between two neighbouring
    /// surface triangles stores `3 B |e|^2 / (A1 + A2) (angle - rest)^2 / 2` (0: no skin).
    pub bending_rigidity_nm: f32,
}

impl Material {
    /// The compliance of an edge of rest length `length_m` over `volume_m3` of the body, metres
    /// per newton.
    fn edge_compliance(&self, length_m: f32, volume_m3: f32) -> f32 {
        length_m * length_m / (self.young_modulus_pa * volume_m3)
    }

    /// The compliance of the constraint `6 (V - V0)` of a tetrahedron of rest volume
    /// `volume_m3`, per joule and metres to the sixth.
    fn volume_compliance(&self, volume_m3: f32) -> f32 {
        let bulk = self.young_modulus_pa / (3.0 * (1.0 - 2.0 * self.poisson_ratio).max(0.0));
        36.0 * volume_m3 / bulk
    }

    /// The compliance of a hinge's angle of `weight` (`3 |e|^2 / (A1 + A2)` at rest), per
    /// joule; infinite without a skin.
    fn hinge_compliance(&self, weight: f32) -> f32 {
        1.0 / (self.bending_rigidity_nm * weight)
    }
}

/// What the broad phase adds around a body's particles, metres.
const BROAD_MARGIN_M: f32 = 0.01;

/// How many times a particle is pushed out of the solids in a substep at most.
const CONTACT_ROUNDS: usize = 4;

/// The longest step a body takes at once, seconds: a longer one (a stall of the app) is
/// taken as this long, so that nothing flies through a solid.
pub const MAX_STEP_S: f32 = 0.1;

/// A particle held at a distance from a fixed point: a fruit's stem on its branch, or the
/// user's hand dragging the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attachment {
    /// The particle held.
    pub particle: u32,
    /// The point it is held from, metres.
    pub anchor: Vec3,
    /// The distance it is held at, metres.
    pub length_m: f32,
    /// The hold's compliance, metres per newton (0: a rigid stem).
    pub compliance: f32,
}

/// The world a body moves in.
#[derive(Debug, Clone, Copy)]
pub struct World<'a> {
    /// Gravity, metres per second squared.
    pub gravity: Vec3,
    /// The solids particles stay out of.
    pub colliders: &'a [Collider],
    /// The friction of a contact: a particle slides when its sideways move in a substep is
    /// more than this many times the depth it was pushed out by, and is held otherwise.
    pub friction: f32,
    /// Substeps a step (each one iteration of every constraint).
    pub substeps: u32,
}

/// An edge constraint: its particles, rest length (metres) and compliance (metres per newton).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Edge {
    ends: [u32; 2],
    rest_m: f32,
    /// Its share of the body's volume, cubic metres.
    share_m3: f32,
    compliance: f32,
}

/// A tetrahedron's volume constraint: its corners, rest volume (cubic metres) and compliance.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cell {
    corners: [u32; 4],
    rest_m3: f32,
    compliance: f32,
}

/// A hinge of the surface: two triangles sharing the edge `[p, q]`, `[p, q, r]` and `[q, p, s]`
/// turned outwards, held at their rest dihedral angle.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Hinge {
    /// `[r, s, p, q]`: the wings' tips, then the shared edge's ends.
    corners: [u32; 4],
    /// The angle between the triangles' normals at rest, radians (0: flat).
    rest_rad: f32,
    /// `3 |e|^2 / (A1 + A2)` at rest, which makes the stiffness a rigidity's.
    weight: f32,
    compliance: f32,
}

impl Hinge {
    /// How far `angle` is from the rest angle, radians, the short way round.
    fn bend(&self, angle: f32) -> f32 {
        (angle - self.rest_rad + PI).rem_euclid(TAU) - PI
    }
}

/// The dihedral angle of a hinge's corners `[r, s, p, q]` (radians, 0 when its triangles lie
/// flat, positive where the surface is convex) and its gradient at each corner, or `None` for a
/// hinge with a collapsed triangle or edge.
fn dihedral([r, s, p, q]: [Vec3; 4]) -> Option<(f32, [Vec3; 4])> {
    let edge = q - p;
    let length = edge.length();
    let (n1, n2) = ((r - p).cross(r - q), (s - q).cross(s - p));
    let (a1, a2) = (n1.length_squared(), n2.length_squared());
    if length < 1e-12 || a1 < 1e-24 || a2 < 1e-24 {
        return None;
    }
    let angle = n1.cross(n2).dot(edge / length).atan2(n1.dot(n2));
    let (n1, n2) = (n1 / a1, n2 / a2);
    let along = |v: Vec3| v.dot(edge) / length;
    let gradients =
        [-length * n1, -length * n2, -(along(r - q) * n1 + along(s - q) * n2), along(r - p) * n1 + along(s - p) * n2];
    Some((angle, gradients))
}

/// The hinges of the surface of the tetrahedral `mesh`: its triangles that belong to one
/// tetrahedron each, turned outwards, taken two by two at every edge that exactly two share,
/// with the compliance `material` gives them.
fn hinges(mesh: &TetMesh, material: &Material) -> Vec<Hinge> {
    let mut faces: BTreeMap<[u32; 3], ([u32; 3], u32)> = BTreeMap::new();
    for &[a, b, c, d] in &mesh.tets {
        for (face, opposite) in [([b, c, d], a), ([a, c, d], b), ([a, b, d], c), ([a, b, c], d)] {
            let mut key = face;
            key.sort_unstable();
            let [x, y, z] = face.map(|p| mesh.positions[p as usize]);
            let outwards = (y - x).cross(z - x).dot(x - mesh.positions[opposite as usize]) > 0.0;
            let oriented = if outwards { face } else { [face[0], face[2], face[1]] };
            faces.entry(key).or_insert((oriented, 0)).1 += 1;
        }
    }
    // Each surface edge with the tips of the triangles that run along it either way.
    let mut wings: BTreeMap<[u32; 2], Vec<(bool, u32)>> = BTreeMap::new();
    for ([a, b, c], _) in faces.into_values().filter(|&(_, uses)| uses == 1) {
        for [p, q, r] in [[a, b, c], [b, c, a], [c, a, b]] {
            wings.entry([p.min(q), p.max(q)]).or_default().push((p < q, r));
        }
    }
    let area = |[p, q, r]: [u32; 3]| {
        let [x, y, z] = [p, q, r].map(|i| mesh.positions[i as usize]);
        (y - x).cross(z - x).length() / 2.0
    };
    wings
        .into_iter()
        .filter_map(|([low, high], tips)| {
            let (&[(true, r), (false, s)] | &[(false, s), (true, r)]) = tips.as_slice() else { return None };
            let (p, q) = (low, high);
            let corners = [r, s, p, q];
            let (rest_rad, _) = dihedral(corners.map(|i| mesh.positions[i as usize]))?;
            let length = mesh.positions[p as usize].distance(mesh.positions[q as usize]);
            let weight = 3.0 * length * length / (area([p, q, r]) + area([q, p, s]));
            Some(Hinge { corners, rest_rad, weight, compliance: material.hinge_compliance(weight) })
        })
        .collect()
}

/// Orders `constraints` by a greedy colouring of the particles they move (each takes the first
/// colour none of its particles has yet): within a colour no two share a particle, so that
/// one projection need not wait for the one before.
fn colour_order<T, const N: usize>(constraints: &mut Vec<T>, particles: impl Fn(&T) -> [u32; N], count: usize) {
    // The colours each particle's constraints have taken, as bits.
    let mut taken = vec![0u64; count];
    let mut coloured: Vec<(u32, T)> = constraints
        .drain(..)
        .map(|constraint| {
            let ends = particles(&constraint);
            let used = ends.iter().fold(0u64, |bits, &p| bits | taken[p as usize]);
            let colour = (!used).trailing_zeros().min(63);
            for &p in &ends {
                taken[p as usize] |= 1 << colour;
            }
            (colour, constraint)
        })
        .collect();
    coloured.sort_by_key(|&(colour, _)| colour);
    constraints.extend(coloured.into_iter().map(|(_, constraint)| constraint));
}

/// A body being simulated: its particles' positions and velocities, their inverse masses
/// (0 for a pinned particle), its constraints at rest, and what holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// The tetrahedral mesh at rest.
    pub rest: TetMesh,
    /// Positions now, metres.
    pub positions: Vec<Vec3>,
    /// Velocities, metres per second.
    pub velocities: Vec<Vec3>,
    /// Inverse masses, per kilogram; 0 pins a particle.
    pub inverse_mass: Vec<f32>,
    /// The stems that hold the body up, until they are released.
    pub stems: Vec<Attachment>,
    /// The hand dragging the body, while it does.
    pub grab: Vec<Attachment>,
    /// Masses, kilograms, pinned particles' included.
    mass: Vec<f32>,
    material: Material,
    edges: Vec<Edge>,
    cells: Vec<Cell>,
    hinges: Vec<Hinge>,
    previous: Vec<Vec3>,
    /// Particles in contact with each collider at the last substep.
    contacts: Vec<u32>,
    /// Steps undone because a number stopped being finite.
    recoveries: u32,
}

impl Body {
    /// A body of `mesh` made of `material`, at rest where the mesh is; its mass is its
    /// tetrahedra's volumes times the density, a quarter of each at each corner.
    pub fn new(mesh: TetMesh, material: Material) -> Self {
        let mut mass = vec![0.0f32; mesh.positions.len()];
        let mut cells: Vec<Cell> = mesh
            .tets
            .iter()
            .map(|&corners| {
                let rest_m3 = six_volume(corners.map(|p| mesh.positions[p as usize])) / 6.0;
                Cell { corners, rest_m3, compliance: material.volume_compliance(rest_m3) }
            })
            .collect();
        // Each edge's share of the volume: a sixth of every tetrahedron it belongs to.
        let mut shares: Vec<([u32; 2], f32)> = Vec::with_capacity(6 * cells.len());
        for cell in &cells {
            for &p in &cell.corners {
                mass[p as usize] += cell.rest_m3 * material.density_kg_m3 / 4.0;
            }
            let [a, b, c, d] = cell.corners;
            shares.extend(
                [[a, b], [a, c], [a, d], [b, c], [b, d], [c, d]]
                    .map(|[p, q]| ([p.min(q), p.max(q)], cell.rest_m3 / 6.0)),
            );
        }
        shares.sort_unstable_by_key(|&(ends, _)| ends);
        let mut edges: Vec<Edge> = Vec::new();
        for (ends, volume) in shares {
            match edges.last_mut() {
                Some(last) if last.ends == ends => last.share_m3 += volume,
                _ => {
                    let [a, b] = ends.map(|p| mesh.positions[p as usize]);
                    edges.push(Edge { ends, rest_m: a.distance(b), share_m3: volume, compliance: 0.0 });
                }
            }
        }
        for edge in &mut edges {
            edge.compliance = material.edge_compliance(edge.rest_m, edge.share_m3);
        }
        colour_order(&mut edges, |edge| edge.ends, mesh.positions.len());
        colour_order(&mut cells, |cell| cell.corners, mesh.positions.len());
        let inverse_mass = mass.iter().map(|&m| if m > 0.0 { 1.0 / m } else { 0.0 }).collect();
        let hinges = hinges(&mesh, &material);
        Self {
            positions: mesh.positions.clone(),
            velocities: vec![Vec3::ZERO; mesh.positions.len()],
            previous: mesh.positions.clone(),
            inverse_mass,
            stems: Vec::new(),
            grab: Vec::new(),
            mass,
            material,
            edges,
            cells,
            hinges,
            contacts: Vec::new(),
            recoveries: 0,
            rest: mesh,
        }
    }

    /// The material it is made of.
    pub fn material(&self) -> Material {
        self.material
    }

    /// Makes the body of `material` from now on, its mass kept: the stiffness and damping
    /// change, the density does not.
    pub fn set_material(&mut self, material: Material) {
        self.material = Material { density_kg_m3: self.material.density_kg_m3, ..material };
        for edge in &mut self.edges {
            edge.compliance = self.material.edge_compliance(edge.rest_m, edge.share_m3);
        }
        for cell in &mut self.cells {
            cell.compliance = self.material.volume_compliance(cell.rest_m3);
        }
        for hinge in &mut self.hinges {
            hinge.compliance = self.material.hinge_compliance(hinge.weight);
        }
    }

    /// Each particle's mass, kilograms, pinned particles' included.
    pub fn masses(&self) -> &[f32] {
        &self.mass
    }

    /// The body's mass, kilograms.
    pub fn mass_kg(&self) -> f32 {
        self.mass.iter().sum()
    }

    /// Pins particle `p` where it is.
    pub fn pin(&mut self, p: usize) {
        self.inverse_mass[p] = 0.0;
        self.velocities[p] = Vec3::ZERO;
    }

    /// Releases particle `p`: it moves with its mass again.
    pub fn release(&mut self, p: usize) {
        let mass = self.mass[p];
        self.inverse_mass[p] = if mass > 0.0 { 1.0 / mass } else { 0.0 };
    }

    /// Moves the body, unchanged in shape and at rest, by `offset`.
    pub fn translate(&mut self, offset: Vec3) {
        for p in &mut self.positions {
            *p += offset;
        }
        self.velocities.fill(Vec3::ZERO);
    }

    /// Advances the body by `dt` seconds (at most [`MAX_STEP_S`]) in `world`'s substeps. A step
    /// that leaves a number that is not finite is undone and the body stopped where it was.
    pub fn step(&mut self, dt: f32, world: World<'_>) {
        let dt = dt.clamp(0.0, MAX_STEP_S);
        if dt == 0.0 {
            return;
        }
        let substeps = world.substeps.max(1);
        let h = dt / substeps as f32;
        let start = self.positions.clone();
        self.contacts.clear();
        self.contacts.resize(world.colliders.len(), 0);
        for _ in 0..substeps {
            self.substep(h, world);
        }
        if !self.positions.iter().chain(&self.velocities).all(|v| v.is_finite()) {
            self.positions = start;
            self.velocities.fill(Vec3::ZERO);
            self.recoveries += 1;
        }
    }

    /// One substep of `h` seconds: predict, project every constraint once, keep out of the
    /// solids, take the velocities from the move.
    fn substep(&mut self, h: f32, world: World<'_>) {
        let damping = (1.0 - self.material.damping_per_s * h).max(0.0);
        for p in 0..self.positions.len() {
            self.previous[p] = self.positions[p];
            if self.inverse_mass[p] == 0.0 {
                continue;
            }
            self.velocities[p] = (self.velocities[p] + world.gravity * h) * damping;
            self.positions[p] += self.velocities[p] * h;
        }
        let h2 = h * h;
        self.project_edges(h2);
        self.project_volumes(h2);
        if self.material.bending_rigidity_nm > 0.0 {
            self.project_hinges(h2);
        }
        for attachment in self.stems.iter().chain(&self.grab) {
            hold(&mut self.positions, &self.inverse_mass, attachment, h2);
        }
        self.collide(world.colliders, world.friction);
        for p in 0..self.positions.len() {
            if self.inverse_mass[p] > 0.0 {
                self.velocities[p] = (self.positions[p] - self.previous[p]) / h;
            }
        }
    }

    /// Pushes every particle out of every collider along the way out, and holds back its
    /// sideways move in the substep by the friction (positional friction: a move shorter than
    /// `friction` times the depth is undone, a longer one shortened by that much). A particle
    /// pushed out of one surface into another (a crease of the ground, a corner between two
    /// solids) is pushed again, up to [`CONTACT_ROUNDS`] times. Counts the particles each
    /// collider touches.
    fn collide(&mut self, colliders: &[Collider], friction: f32) {
        self.contacts.fill(0);
        let mut touched = vec![false; colliders.len()];
        // A broad phase: the solids a particle could meet, from the box of the particles
        // grown by the farthest move of the substep (a push out of one solid moves a particle
        // at most that far back, plus a margin).
        let reach = self.positions.iter().zip(&self.previous).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max);
        let grow = Vec3::splat(reach + BROAD_MARGIN_M);
        let (min, max) =
            self.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let near: Vec<bool> = colliders.iter().map(|c| c.may_touch(min - grow, max + grow)).collect();
        for p in 0..self.positions.len() {
            if self.inverse_mass[p] == 0.0 {
                continue;
            }
            touched.fill(false);
            for _ in 0..CONTACT_ROUNDS {
                let mut pushed = false;
                for (index, collider) in colliders.iter().enumerate().filter(|(index, _)| near[*index]) {
                    let Some((depth, out)) = collider.penetration(self.positions[p], self.previous[p]) else {
                        continue;
                    };
                    touched[index] = true;
                    pushed = true;
                    self.positions[p] += out * depth;
                    let moved = self.positions[p] - self.previous[p];
                    let sideways = moved - out * moved.dot(out);
                    let length = sideways.length();
                    let hold = friction * depth;
                    self.positions[p] -= if length <= hold { sideways } else { sideways * (hold / length) };
                }
                if !pushed {
                    break;
                }
            }
            for (touching, &hit) in self.contacts.iter_mut().zip(&touched) {
                *touching += u32::from(hit);
            }
        }
    }

    /// Each edge towards its rest length, its compliance over `h2`, the substep squared.
    fn project_edges(&mut self, h2: f32) {
        for edge in &self.edges {
            let [a, b] = edge.ends.map(|p| p as usize);
            let w = self.inverse_mass[a] + self.inverse_mass[b];
            if w == 0.0 {
                continue;
            }
            let delta = self.positions[a] - self.positions[b];
            let length = delta.length();
            if length == 0.0 {
                continue;
            }
            let lambda = -(length - edge.rest_m) / (w + edge.compliance / h2);
            let correction = delta * (lambda / length);
            self.positions[a] += correction * self.inverse_mass[a];
            self.positions[b] -= correction * self.inverse_mass[b];
        }
    }

    /// Each tetrahedron towards its rest volume along the volume's gradient (an inverted one
    /// too: its signed volume is driven back to the positive rest volume).
    fn project_volumes(&mut self, h2: f32) {
        for cell in &self.cells {
            let corners = cell.corners.map(|p| p as usize);
            let [pa, pb, pc, pd] = corners.map(|p| self.positions[p]);
            // The gradient of six times the volume at each corner.
            let gradients = [
                (pd - pb).cross(pc - pb),
                (pc - pa).cross(pd - pa),
                (pd - pa).cross(pb - pa),
                (pb - pa).cross(pc - pa),
            ];
            let w: f32 = corners.iter().zip(&gradients).map(|(&p, g)| self.inverse_mass[p] * g.length_squared()).sum();
            if w == 0.0 {
                continue;
            }
            let volume = six_volume([pa, pb, pc, pd]) / 6.0;
            let lambda = -6.0 * (volume - cell.rest_m3) / (w + cell.compliance / h2);
            for (&p, g) in corners.iter().zip(&gradients) {
                self.positions[p] += *g * (lambda * self.inverse_mass[p]);
            }
        }
    }

    /// Each hinge of the skin towards its rest angle.
    fn project_hinges(&mut self, h2: f32) {
        for hinge in &self.hinges {
            let corners = hinge.corners.map(|p| p as usize);
            let Some((angle, gradients)) = dihedral(corners.map(|p| self.positions[p])) else { continue };
            let w: f32 = corners.iter().zip(&gradients).map(|(&p, g)| self.inverse_mass[p] * g.length_squared()).sum();
            if w == 0.0 {
                continue;
            }
            let lambda = -hinge.bend(angle) / (w + hinge.compliance / h2);
            for (&p, g) in corners.iter().zip(&gradients) {
                self.positions[p] += *g * (lambda * self.inverse_mass[p]);
            }
        }
    }

    /// The centre of mass, metres.
    pub fn centre_of_mass(&self) -> Vec3 {
        let total: f32 = self.mass.iter().sum();
        self.positions.iter().zip(&self.mass).map(|(p, m)| *p * *m).sum::<Vec3>() / total.max(f32::MIN_POSITIVE)
    }

    /// Kinetic energy, joules (pinned particles have none).
    pub fn kinetic_energy(&self) -> f64 {
        self.velocities
            .iter()
            .zip(&self.inverse_mass)
            .filter(|(_, w)| **w > 0.0)
            .map(|(v, w)| 0.5 * f64::from(v.length_squared()) / f64::from(*w))
            .sum()
    }

    /// The energy stored in the stretched edges and squeezed tetrahedra, joules (hard
    /// constraints store none).
    pub fn elastic_energy(&self) -> f64 {
        let stored = |c: f32, compliance: f32| {
            if compliance > 0.0 { f64::from(c * c) / (2.0 * f64::from(compliance)) } else { 0.0 }
        };
        let edges: f64 = self
            .edges
            .iter()
            .map(|edge| {
                let [a, b] = edge.ends.map(|p| self.positions[p as usize]);
                stored(a.distance(b) - edge.rest_m, edge.compliance)
            })
            .sum();
        let cells: f64 = self
            .cells
            .iter()
            .map(|cell| {
                stored(
                    six_volume(cell.corners.map(|p| self.positions[p as usize])) - 6.0 * cell.rest_m3,
                    cell.compliance,
                )
            })
            .sum();
        let hinges: f64 = self
            .hinges
            .iter()
            .map(|hinge| {
                let angle = dihedral(hinge.corners.map(|p| self.positions[p as usize])).map_or(0.0, |(a, _)| a);
                stored(hinge.bend(angle), hinge.compliance)
            })
            .sum();
        edges + cells + hinges
    }

    /// The body's volume now over its volume at rest.
    pub fn volume_ratio(&self) -> f64 {
        self.rest.volume(&self.positions) / self.rest.volume(&self.rest.positions)
    }

    /// The largest strain of an edge: how far its length is from its rest length, as a share
    /// of the rest length.
    pub fn max_strain(&self) -> f32 {
        self.edges
            .iter()
            .map(|edge| {
                let [a, b] = edge.ends.map(|p| self.positions[p as usize]);
                (a.distance(b) / edge.rest_m - 1.0).abs()
            })
            .fold(0.0, f32::max)
    }

    /// The tetrahedra turned inside out now.
    pub fn inverted(&self) -> usize {
        self.cells.iter().filter(|cell| six_volume(cell.corners.map(|p| self.positions[p as usize])) <= 0.0).count()
    }

    /// The lowest particle, metres.
    pub fn lowest(&self) -> Vec3 {
        self.positions.iter().copied().min_by(|a, b| a.y.total_cmp(&b.y)).unwrap_or(Vec3::ZERO)
    }

    /// Particles in contact with each collider of the last step's world at its last substep.
    pub fn contacts(&self) -> &[u32] {
        &self.contacts
    }

    /// Steps undone because a number stopped being finite.
    pub fn recoveries(&self) -> u32 {
        self.recoveries
    }

    /// The tetrahedra.
    pub fn tet_count(&self) -> usize {
        self.cells.len()
    }
}

/// Holds a particle at its attachment's distance from the anchor, with its compliance over
/// `h2`, the substep squared.
fn hold(positions: &mut [Vec3], inverse_mass: &[f32], attachment: &Attachment, h2: f32) {
    let p = attachment.particle as usize;
    let w = inverse_mass[p];
    let offset = positions[p] - attachment.anchor;
    let distance = offset.length();
    if w == 0.0 || distance == 0.0 {
        return;
    }
    let lambda = -(distance - attachment.length_m) / (w + attachment.compliance / h2);
    positions[p] += offset * (lambda * w / distance);
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::soft_body::sample;

    const JELLY: Material = Material {
        density_kg_m3: 1000.0,
        young_modulus_pa: 2e4,
        poisson_ratio: 0.3,
        damping_per_s: 0.0,
        bending_rigidity_nm: 0.0,
    };

    fn world(substeps: u32) -> World<'static> {
        World { gravity: Vec3::new(0.0, -9.81, 0.0), colliders: &[], friction: 0.5, substeps }
    }

    /// The ground: the plane y = 0.
    const GROUND: Collider = Collider::Plane { point: Vec3::ZERO, normal: Vec3::Y };

    /// A cube of 4 x 4 x 4 cells 5 cm a side, its lowest corner at `min`.
    fn cube(min: Vec3) -> TetMesh {
        TetMesh::lattice_box(min, [4, 4, 4], 0.05)
    }

    #[test]
    fn a_body_dropped_on_a_box_rests_on_it_without_sinking_or_jitter() {
        let solids = [GROUND, Collider::Box { centre: Vec3::new(0.1, 0.1, 0.1), half_m: Vec3::splat(0.1) }];
        let world = World { colliders: &solids, ..world(10) };
        let material = Material { damping_per_s: 1.0, ..JELLY };
        let mut body = Body::new(TetMesh::lattice_box(Vec3::new(0.05, 0.4, 0.05), [2, 2, 2], 0.05), material);
        let mut heights = Vec::new();
        for frame in 0..900 {
            body.step(1.0 / 60.0, world);
            for p in &body.positions {
                assert!(
                    solids.iter().all(|s| s.penetration(*p, *p).is_none_or(|(depth, _)| depth < 1e-6)),
                    "inside at {p}"
                );
            }
            if frame >= 300 {
                heights.push(body.lowest().y);
            }
        }
        let (low, high) = heights.iter().fold((f32::MAX, f32::MIN), |(l, h), &y| (l.min(y), h.max(y)));
        assert!((low - 0.2).abs() < 1e-3, "it rests on the box's top: {low}");
        assert!(high - low < 1e-4, "no jitter over ten seconds at rest: {low} to {high}");
        assert!(body.centre_of_mass().x > 0.05 && body.centre_of_mass().x < 0.15, "it stays on the box");
    }

    #[test]
    fn a_block_dropped_on_a_terrain_rests_on_it_without_sinking_or_jitter() {
        use crate::terrain::Heightmap;
        use crate::terrain::ground::Ground;
        use crate::terrain::section::{Geometry, Section};
        use bevy::math::Affine3A;
        use std::sync::Arc;
        // A slope of about 6 degrees with bumps, 0.1 m cells, its lowest corner at the origin.
        let map = Heightmap::from_fn(16, 16, |x, z| 0.01 * x as f32 + 0.02 * ((x * 3 + z * 5) % 4) as f32).unwrap();
        let geometry = Geometry { cell_m: 0.1, height_m: 1.0, texture_cells: 4.0 };
        let section = Section { origin: [0, 0], size: [16, 16] };
        let ground = Ground::of_section(&map, section, geometry, Vec3::ZERO, Affine3A::IDENTITY);
        let solids = [Collider::Ground(Arc::new(ground))];
        let world = World { colliders: &solids, ..world(10) };
        let material = Material { damping_per_s: 1.0, ..JELLY };
        let mut body = Body::new(TetMesh::lattice_box(Vec3::new(0.6, 0.4, 0.6), [4, 2, 4], 0.05), material);
        let (mut lowest, mut centres) = (Vec::new(), Vec::new());
        for frame in 0..600 {
            body.step(1.0 / 60.0, world);
            for p in &body.positions {
                let depth = solids[0].penetration(*p, *p).map_or(0.0, |(depth, _)| depth);
                assert!(depth < 1e-4, "frame {frame}: {depth} m inside at {p}");
            }
            if frame >= 300 {
                lowest.push(body.lowest().y);
                centres.push(body.centre_of_mass());
            }
        }
        assert!(body.contacts()[0] > 0, "it lies on the ground");
        let (low, high) = lowest.iter().fold((f32::MAX, f32::MIN), |(l, h), &y| (l.min(y), h.max(y)));
        let moved = centres[0].distance(centres[centres.len() - 1]);
        // Held by friction on the slope, it keeps a tremor of a fraction of a millimetre that
        // flat ground does not show: well under anything the eye sees.
        let wandered = centres.iter().map(|c| c.distance(centres[0])).fold(0.0f32, f32::max);
        assert!(
            high - low < 1e-4 && wandered < 1e-3 && moved < 1e-3,
            "still for five seconds: lowest {low} to {high}, moved {moved} m, at most {wandered} m"
        );
        assert!(body.kinetic_energy() < 1e-4, "{}", body.kinetic_energy());
    }

    #[test]
    fn constraints_are_ordered_in_runs_that_share_no_particle() {
        let mesh = cube(Vec3::ZERO);
        let mut edges: Vec<[u32; 2]> =
            mesh.tets.iter().flat_map(|&[a, b, c, d]| [[a, b], [a, c], [a, d], [b, c], [b, d], [c, d]]).collect();
        edges.iter_mut().for_each(|e| e.sort_unstable());
        edges.sort_unstable();
        edges.dedup();
        let mut ordered = edges.clone();
        colour_order(&mut ordered, |e| *e, mesh.positions.len());
        let mut sorted = ordered.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, edges, "the same constraints");
        // Runs in which no particle is moved twice: at most as many as a greedy colouring
        // needs, below twice the most edges a particle has.
        let most = (0..mesh.positions.len() as u32).map(|p| edges.iter().filter(|e| e.contains(&p)).count()).max();
        let (mut runs, mut moved) = (1, std::collections::HashSet::new());
        for edge in &ordered {
            if edge.iter().any(|p| moved.contains(p)) {
                runs += 1;
                moved.clear();
            }
            moved.extend(edge.iter().copied());
        }
        assert!(runs < 2 * most.unwrap(), "{runs} runs for at most {most:?} edges a particle");
    }

    #[test]
    fn a_body_pinned_at_one_corner_swings_below_it_and_drops_when_released() {
        let material = Material { damping_per_s: 0.5, ..JELLY };
        let mut body = Body::new(TetMesh::lattice_box(Vec3::ZERO, [2, 2, 2], 0.05), material);
        // The stem: the top corner farthest along x, so that the body hangs off to one side.
        let stem = (0..body.positions.len()).max_by(|&a, &b| {
            let key = |p: Vec3| p.x + p.y;
            key(body.positions[a]).total_cmp(&key(body.positions[b]))
        });
        let stem = stem.unwrap();
        body.pin(stem);
        let held = body.positions[stem];
        let mut xs = Vec::new();
        for _ in 0..240 {
            body.step(1.0 / 60.0, world(10));
            xs.push(body.centre_of_mass().x);
        }
        assert_eq!(body.positions[stem], held, "the stem holds");
        let centre = body.centre_of_mass();
        assert!(centre.y < held.y - 0.05, "it hangs below its stem: {centre} under {held}");
        let (low, high) = xs.iter().fold((f32::MAX, f32::MIN), |(l, h), &x| (l.min(x), h.max(x)));
        assert!(high - low > 0.02, "it swings: x from {low} to {high}");
        body.release(stem);
        let before = body.centre_of_mass().y;
        for _ in 0..60 {
            body.step(1.0 / 60.0, world(10));
        }
        let fell = before - body.centre_of_mass().y;
        assert!(fell > 0.8 * 0.5 * 9.81, "released, it falls: {fell} m in a second");
    }

    #[test]
    fn the_lattice_fills_its_box_with_positive_tetrahedra() {
        let mesh = cube(Vec3::ZERO);
        // Conforming: every inner triangle is shared by two tetrahedra, and the boundary's
        // triangles are those of the box's six faces, two per cell face.
        let mut faces: HashMap<[u32; 3], u32> = HashMap::new();
        for &[a, b, c, d] in &mesh.tets {
            for mut face in [[a, b, c], [a, b, d], [a, c, d], [b, c, d]] {
                face.sort_unstable();
                *faces.entry(face).or_default() += 1;
            }
        }
        assert!(faces.values().all(|&n| n <= 2));
        assert_eq!(faces.values().filter(|&&n| n == 1).count(), 6 * 16 * 2);
        assert_eq!((mesh.positions.len(), mesh.tets.len()), (125, 6 * 64));
        assert!((mesh.volume(&mesh.positions) - 0.2f64.powi(3)).abs() < 1e-9);
        let checked = TetMesh::new(mesh.positions.clone(), mesh.tets.clone()).expect("every tetrahedron positive");
        assert_eq!(checked, mesh);
        let flat = TetMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X + Vec3::Y], vec![[0, 1, 2, 3]]);
        assert_eq!(flat, Err(TetError::Flat(0)));
        assert!(matches!(TetMesh::new(vec![Vec3::ZERO], vec![[0, 0, 0, 9]]), Err(TetError::IndexOutOfRange { .. })));
    }

    #[test]
    fn a_sphere_is_filled_with_cells_and_carries_its_surface() {
        let sphere = sample::sphere(0.5, 24, 48);
        let (mesh, embedding) = TetMesh::fill(&sphere, 0.05, usize::MAX).unwrap();
        let volume = mesh.volume(&mesh.positions);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.125;
        assert!((volume / exact - 1.0).abs() < 0.1, "{volume} against {exact}");
        assert!(TetMesh::new(mesh.positions.clone(), mesh.tets.clone()).is_ok());
        // At rest the embedding gives the surface back; moved, the surface moves along.
        let mut placed = Vec::new();
        embedding.place(&mesh, &mesh.positions, &mut placed);
        let worst = placed.iter().zip(&sphere.positions).map(|(a, b)| a.distance(*b)).fold(0.0f32, f32::max);
        assert!(worst < 1e-5, "{worst}");
        let shifted: Vec<Vec3> = mesh.positions.iter().map(|p| *p + Vec3::Y).collect();
        embedding.place(&mesh, &shifted, &mut placed);
        assert!(placed.iter().zip(&sphere.positions).all(|(a, b)| (*a - *b - Vec3::Y).length() < 1e-4));
        // An open surface has no inside, too fine a lattice is refused, and too coarse a one
        // holds nothing.
        let cap = sample::sphere_cap(0.5, 30.0, 6, 12);
        assert_eq!(TetMesh::fill(&cap, 0.05, usize::MAX), Err(TetError::Open(12)));
        assert!(matches!(TetMesh::fill(&sphere, 2.0, usize::MAX), Err(TetError::Empty(_))));
        assert!(matches!(TetMesh::fill(&sphere, 1e-4, usize::MAX), Err(TetError::TooManyCells { .. })));
        assert!(matches!(TetMesh::fill(&sphere, 0.05, 1000), Err(TetError::TooManyTets { most: 1000, .. })));
    }

    #[test]
    fn a_free_body_falls_at_g_and_keeps_its_shape() {
        let mut body = Body::new(cube(Vec3::ZERO), JELLY);
        let start = body.centre_of_mass();
        for _ in 0..60 {
            body.step(1.0 / 60.0, world(10));
        }
        let drop = start.y - body.centre_of_mass().y;
        assert!((drop - 0.5 * 9.81).abs() < 0.01 * 4.905, "fell {drop} m in a second");
        assert!((body.volume_ratio() - 1.0).abs() < 1e-4, "{}", body.volume_ratio());
    }

    /// The lowest point of a cube hung by its top face after `seconds`, with `substeps`.
    fn sag(substeps: u32, seconds: f32) -> (f32, Body) {
        // Hard constraints (compliance 0) are met only as far as the substeps' iterations go;
        // compliant ones settle where their compliance says, whatever the substeps.
        let material = Material { young_modulus_pa: 3e4, damping_per_s: 4.0, ..JELLY };
        let mut body = Body::new(cube(Vec3::ZERO), material);
        for p in 0..body.positions.len() {
            if body.positions[p].y > 0.2 - 1e-6 {
                body.pin(p);
            }
        }
        for _ in 0..(seconds * 60.0) as usize {
            body.step(1.0 / 60.0, world(substeps));
        }
        (body.lowest().y, body)
    }

    #[test]
    fn a_hanging_body_sags_alike_with_five_and_twenty_substeps() {
        let (five, _) = sag(5, 4.0);
        let (twenty, body) = sag(20, 4.0);
        let (sag5, sag20) = (-five, -twenty);
        assert!(sag20 > 1e-3, "it sags: {sag20} m below its rest");
        assert!((sag5 - sag20).abs() < 0.05 * sag20, "sags of {sag5} and {sag20} m");
        assert!(body.kinetic_energy() < 1e-4, "it has come to rest: {} J", body.kinetic_energy());
        assert!(body.positions.iter().all(|p| p.y <= 0.2 + 1e-6), "it hangs below its pinned top");
        let strain = body.max_strain();
        assert!(strain > 1e-3 && strain < 0.5, "stretched, not torn: {strain}");
        assert_eq!(Body::new(cube(Vec3::ZERO), JELLY).max_strain(), 0.0, "at rest nothing is strained");
    }

    #[test]
    fn a_dropped_body_rests_on_the_ground_keeping_its_volume() {
        let material = Material { poisson_ratio: 0.49, damping_per_s: 2.0, ..JELLY };
        let mut body = Body::new(cube(Vec3::new(0.0, 0.3, 0.0)), material);
        let ground = [GROUND];
        let world = World { colliders: &ground, ..world(10) };
        let mut energies = Vec::new();
        for _ in 0..600 {
            body.step(1.0 / 60.0, world);
            assert!(body.lowest().y >= 0.0, "never below the ground");
            energies.push(body.kinetic_energy());
        }
        assert!(body.lowest().y < 1e-4, "it lies on the ground: {}", body.lowest());
        assert!((body.volume_ratio() - 1.0).abs() < 0.02, "{}", body.volume_ratio());
        assert!(energies.last().unwrap() < &1e-4, "it has come to rest: {:?}", energies.last());
        assert!(body.positions.iter().all(|p| p.is_finite()));
    }

    #[test]
    fn with_damping_and_nothing_acting_the_energy_only_falls() {
        let mut body = Body::new(cube(Vec3::ZERO), Material { damping_per_s: 1.0, ..JELLY });
        // Set it wobbling: every particle's velocity away from the centre.
        let centre = body.centre_of_mass();
        for (v, p) in body.velocities.iter_mut().zip(&body.positions) {
            *v = (*p - centre) * 2.0;
        }
        let still = World { gravity: Vec3::ZERO, ..world(10) };
        let total = |body: &Body| body.kinetic_energy() + body.elastic_energy();
        let mut energy = total(&body);
        let first = energy;
        // Each sixth of a second holds less energy than the one before (within a step, XPBD
        // trades kinetic and stored energy without keeping their sum exactly).
        for _ in 0..12 {
            for _ in 0..10 {
                body.step(1.0 / 60.0, still);
            }
            let now = total(&body);
            assert!(now < energy, "energy rose from {energy} to {now}");
            energy = now;
        }
        assert!(energy < 0.01 * first, "it settles: {energy} of {first} J");
    }

    #[test]
    fn inverted_tetrahedra_recover_and_huge_steps_stay_finite() {
        let mut body =
            Body::new(TetMesh::lattice_box(Vec3::ZERO, [2, 2, 2], 0.05), Material { damping_per_s: 2.0, ..JELLY });
        // A corner pushed through the body to the far side turns its tetrahedra inside out.
        let corner = (0..body.positions.len()).find(|&p| body.positions[p] == Vec3::ZERO).unwrap();
        body.positions[corner] = Vec3::splat(0.07);
        assert!(body.inverted() > 0);
        let still = World { gravity: Vec3::ZERO, ..world(10) };
        for _ in 0..240 {
            body.step(1.0 / 60.0, still);
        }
        assert_eq!(body.inverted(), 0, "every tetrahedron turned the right way out again");
        assert!((body.volume_ratio() - 1.0).abs() < 0.02, "{}", body.volume_ratio());
        // A step of ten seconds is taken as the longest step there is.
        let before = body.centre_of_mass();
        body.step(10.0, world(2));
        assert!(body.positions.iter().all(|p| p.is_finite()));
        let fell = before.y - body.centre_of_mass().y;
        assert!(fell <= 9.81 * MAX_STEP_S * MAX_STEP_S + 1e-4, "fell {fell} m in one capped step");
        assert_eq!(body.recoveries(), 0);
        // A body made to blow up is put back where it was.
        body.velocities[0] = Vec3::splat(f32::INFINITY);
        let held = body.positions.clone();
        body.step(1.0 / 60.0, world(2));
        assert_eq!((body.recoveries(), &body.positions), (1, &held));
        assert!(body.velocities.iter().all(|v| *v == Vec3::ZERO));
    }

    #[test]
    fn a_body_on_stems_hangs_below_their_anchor_and_swings() {
        let mut body =
            Body::new(TetMesh::lattice_box(Vec3::ZERO, [2, 2, 2], 0.05), Material { damping_per_s: 0.3, ..JELLY });
        // Stems from a point above and to one side to the top face's particles.
        let anchor = Vec3::new(0.15, 0.15, 0.05);
        let top: Vec<usize> = (0..body.positions.len()).filter(|&p| body.positions[p].y > 0.099).collect();
        body.stems = top
            .iter()
            .map(|&p| Attachment {
                particle: p as u32,
                anchor,
                length_m: body.positions[p].distance(anchor),
                compliance: 0.0,
            })
            .collect();
        let mut xs = Vec::new();
        for _ in 0..300 {
            body.step(1.0 / 60.0, world(10));
            xs.push(body.centre_of_mass().x);
            for stem in &body.stems {
                let held = body.positions[stem.particle as usize].distance(anchor);
                assert!((held - stem.length_m).abs() < 0.02 * stem.length_m, "the stem keeps its length: {held}");
            }
        }
        let (low, high) = xs.iter().fold((f32::MAX, f32::MIN), |(l, h), &x| (l.min(x), h.max(x)));
        assert!(high - low > 0.05, "it swings: x from {low} to {high}");
        assert!(body.centre_of_mass().y < anchor.y, "below its anchor");
    }

    #[test]
    fn a_hinge_s_angle_has_the_gradient_its_differences_give() {
        let corners =
            [Vec3::new(0.1, 0.9, -0.3), Vec3::new(0.2, -0.4, 0.8), Vec3::new(-0.5, 0.1, 0.0), Vec3::new(0.7, 0.2, 0.1)];
        let (_, gradients) = dihedral(corners).unwrap();
        let step = 1e-3;
        for (corner, gradient) in gradients.iter().enumerate() {
            for axis in 0..3 {
                let moved = |by: f32| {
                    let mut c = corners;
                    c[corner][axis] += by;
                    dihedral(c).unwrap().0
                };
                let difference = (moved(step) - moved(-step)) / (2.0 * step);
                assert!(
                    (difference - gradient[axis]).abs() < 2e-3,
                    "corner {corner} axis {axis}: {difference} against {}",
                    gradient[axis]
                );
            }
        }
        assert!(dihedral([Vec3::ZERO, Vec3::Y, Vec3::ZERO, Vec3::ZERO]).is_none(), "a collapsed hinge has no angle");
    }

    #[test]
    fn a_cube_s_skin_folds_at_its_edges_alone() {
        let hinges = hinges(&cube(Vec3::ZERO), &JELLY);
        // 192 surface triangles of a closed surface: 288 edges, each a hinge.
        assert_eq!(hinges.len(), 288);
        let folded: Vec<f32> = hinges.iter().map(|h| h.rest_rad).filter(|a| a.abs() > 1e-4).collect();
        assert_eq!(folded.len(), 12 * 4, "the cube's twelve edges, four hinges each");
        assert!(folded.iter().all(|a| (a - std::f32::consts::FRAC_PI_2).abs() < 1e-4), "convex: {folded:?}");
    }

    /// The height of the free end of a slab 0.4 m long held at one end, after settling.
    fn droop(bending_rigidity_nm: f32) -> f32 {
        let material = Material { young_modulus_pa: 3e4, damping_per_s: 5.0, bending_rigidity_nm, ..JELLY };
        let mut body = Body::new(TetMesh::lattice_box(Vec3::ZERO, [8, 1, 2], 0.05), material);
        for p in 0..body.positions.len() {
            if body.positions[p].x < 0.051 {
                body.pin(p);
            }
        }
        for _ in 0..240 {
            body.step(1.0 / 60.0, world(10));
        }
        assert!(body.positions.iter().all(|p| p.is_finite()));
        let end: Vec<usize> = (0..body.positions.len()).filter(|&p| body.rest.positions[p].x > 0.399).collect();
        end.iter().map(|&p| body.positions[p].y).sum::<f32>() / end.len() as f32
    }

    #[test]
    fn a_skin_that_resists_bending_holds_a_slab_up() {
        let (bare, thin, thick) = (droop(0.0), droop(0.1), droop(1.0));
        assert!(bare < -0.3, "without a skin the soft slab hangs down: its end at {bare} m");
        assert!(thin > bare && thick > thin + 0.1, "a firmer skin holds it higher: {bare}, {thin}, {thick} m");
    }

    #[test]
    fn the_same_body_in_the_same_world_moves_alike_bit_for_bit() {
        let run = || {
            let ground = [GROUND];
            let mut body = Body::new(cube(Vec3::new(0.0, 0.3, 0.0)), Material { damping_per_s: 0.5, ..JELLY });
            for _ in 0..90 {
                body.step(1.0 / 60.0, World { colliders: &ground, ..world(8) });
            }
            body
        };
        assert_eq!(run(), run());
    }
}
