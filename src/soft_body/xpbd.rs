//! Dynamic soft bodies by extended position-based dynamics (XPBD, Macklin, Mueller and
//! Chentanez 2016) in small steps (Macklin et al. 2019: many substeps of one iteration each):
//! particles joined by edge-length and tetrahedron-volume constraints with compliance, under
//! gravity, resting on a ground plane, some pinned.
//!
//! A constraint's compliance is its inverse stiffness in physical units (metres per newton for
//! an edge, square metres over newtons for a volume): it enters each substep as `compliance /
//! h^2`, so that a body is as stiff with five substeps as with twenty.

use bevy::math::Vec3;

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
    /// tetrahedra around its diagonal from its lowest to its highest corner (Kuhn's split, so
    /// that neighbouring cubes' faces match).
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
                    let corner = |[di, dj, dk]: [u32; 3]| at(i + di, j + dj, k + dk);
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
    /// Edge compliance, metres per newton (0: rigid edges).
    pub edge_compliance: f32,
    /// Volume compliance of each tetrahedron's constraint `V - V0`, metres to the sixth per
    /// joule (0: its volume is kept).
    pub volume_compliance: f32,
    /// The share of velocity lost per second, from 0.
    pub damping_per_s: f32,
}

/// The world a body moves in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct World {
    /// Gravity, metres per second squared.
    pub gravity: Vec3,
    /// Height of the ground plane, metres (particles stay above it).
    pub ground_y: f32,
    /// Substeps a step (each one iteration of every constraint).
    pub substeps: u32,
}

/// A body being simulated: its particles' positions and velocities, their inverse masses
/// (0 for a pinned particle), and its constraints at rest.
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
    /// Masses, kilograms, pinned particles' included.
    mass: Vec<f32>,
    material: Material,
    edges: Vec<([u32; 2], f32)>,
    rest_volumes: Vec<f32>,
    previous: Vec<Vec3>,
}

impl Body {
    /// A body of `mesh` made of `material`, at rest where the mesh is; its mass is its
    /// tetrahedra's volumes times the density, a quarter of each at each corner.
    pub fn new(mesh: TetMesh, material: Material) -> Self {
        let mut mass = vec![0.0f32; mesh.positions.len()];
        let rest_volumes: Vec<f32> =
            mesh.tets.iter().map(|t| six_volume(t.map(|p| mesh.positions[p as usize])) / 6.0).collect();
        for (t, &volume) in mesh.tets.iter().zip(&rest_volumes) {
            for &p in t {
                mass[p as usize] += volume * material.density_kg_m3 / 4.0;
            }
        }
        let mut edges: Vec<[u32; 2]> = mesh
            .tets
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b], [a, c], [a, d], [b, c], [b, d], [c, d]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let edges = edges
            .into_iter()
            .map(|[a, b]| ([a, b], mesh.positions[a as usize].distance(mesh.positions[b as usize])))
            .collect();
        let inverse_mass = mass.iter().map(|&m| if m > 0.0 { 1.0 / m } else { 0.0 }).collect();
        Self {
            positions: mesh.positions.clone(),
            velocities: vec![Vec3::ZERO; mesh.positions.len()],
            previous: mesh.positions.clone(),
            inverse_mass,
            mass,
            material,
            edges,
            rest_volumes,
            rest: mesh,
        }
    }

    /// Pins particle `p` where it is.
    pub fn pin(&mut self, p: usize) {
        self.inverse_mass[p] = 0.0;
        self.velocities[p] = Vec3::ZERO;
    }

    /// Advances the body by `dt` seconds in `world`'s substeps.
    pub fn step(&mut self, dt: f32, world: World) {
        let substeps = world.substeps.max(1);
        let h = dt / substeps as f32;
        for _ in 0..substeps {
            self.substep(h, world);
        }
    }

    /// One substep of `h` seconds: predict, project every constraint once, keep above the
    /// ground, take the velocities from the move.
    fn substep(&mut self, h: f32, world: World) {
        let damping = (1.0 - self.material.damping_per_s * h).max(0.0);
        for p in 0..self.positions.len() {
            if self.inverse_mass[p] == 0.0 {
                continue;
            }
            self.velocities[p] = (self.velocities[p] + world.gravity * h) * damping;
            self.previous[p] = self.positions[p];
            self.positions[p] += self.velocities[p] * h;
        }
        self.project_edges(self.material.edge_compliance / (h * h));
        self.project_volumes(self.material.volume_compliance / (h * h));
        for p in &mut self.positions {
            p.y = p.y.max(world.ground_y);
        }
        for p in 0..self.positions.len() {
            if self.inverse_mass[p] > 0.0 {
                self.velocities[p] = (self.positions[p] - self.previous[p]) / h;
            }
        }
    }

    /// Each edge towards its rest length, with `alpha` its compliance over the substep squared.
    fn project_edges(&mut self, alpha: f32) {
        for &([a, b], rest) in &self.edges {
            let (a, b) = (a as usize, b as usize);
            let w = self.inverse_mass[a] + self.inverse_mass[b];
            if w == 0.0 {
                continue;
            }
            let delta = self.positions[a] - self.positions[b];
            let length = delta.length();
            if length == 0.0 {
                continue;
            }
            let lambda = -(length - rest) / (w + alpha);
            let correction = delta * (lambda / length);
            self.positions[a] += correction * self.inverse_mass[a];
            self.positions[b] -= correction * self.inverse_mass[b];
        }
    }

    /// Each tetrahedron towards its rest volume along the volume's gradient.
    fn project_volumes(&mut self, alpha: f32) {
        for (t, &rest) in self.rest.tets.iter().zip(&self.rest_volumes) {
            let [a, b, c, d] = t.map(|p| p as usize);
            let [pa, pb, pc, pd] = [a, b, c, d].map(|p| self.positions[p]);
            // The gradient of six times the volume at each corner.
            let gradients = [
                (pd - pb).cross(pc - pb),
                (pc - pa).cross(pd - pa),
                (pd - pa).cross(pb - pa),
                (pb - pa).cross(pc - pa),
            ];
            let corners = [a, b, c, d];
            let w: f32 = corners.iter().zip(&gradients).map(|(&p, g)| self.inverse_mass[p] * g.length_squared()).sum();
            if w == 0.0 {
                continue;
            }
            let volume = six_volume([pa, pb, pc, pd]) / 6.0;
            let lambda = -6.0 * (volume - rest) / (w + alpha);
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

    /// The body's volume now over its volume at rest.
    pub fn volume_ratio(&self) -> f64 {
        self.rest.volume(&self.positions) / self.rest.volume(&self.rest.positions)
    }

    /// The lowest particle's height, metres.
    pub fn lowest(&self) -> f32 {
        self.positions.iter().map(|p| p.y).fold(f32::INFINITY, f32::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const JELLY: Material =
        Material { density_kg_m3: 1000.0, edge_compliance: 1e-4, volume_compliance: 0.0, damping_per_s: 0.0 };

    fn world(substeps: u32) -> World {
        World { gravity: Vec3::new(0.0, -9.81, 0.0), ground_y: f32::NEG_INFINITY, substeps }
    }

    /// A cube of 4 x 4 x 4 cells 5 cm a side, its lowest corner at `min`.
    fn cube(min: Vec3) -> TetMesh {
        TetMesh::lattice_box(min, [4, 4, 4], 0.05)
    }

    #[test]
    fn the_lattice_fills_its_box_with_positive_tetrahedra() {
        let mesh = cube(Vec3::ZERO);
        assert_eq!((mesh.positions.len(), mesh.tets.len()), (125, 6 * 64));
        assert!((mesh.volume(&mesh.positions) - 0.2f64.powi(3)).abs() < 1e-9);
        let checked = TetMesh::new(mesh.positions.clone(), mesh.tets.clone()).expect("every tetrahedron positive");
        assert_eq!(checked, mesh);
        let flat = TetMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X + Vec3::Y], vec![[0, 1, 2, 3]]);
        assert_eq!(flat, Err(TetError::Flat(0)));
        assert!(matches!(TetMesh::new(vec![Vec3::ZERO], vec![[0, 0, 0, 9]]), Err(TetError::IndexOutOfRange { .. })));
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
        let material = Material { edge_compliance: 2e-3, volume_compliance: 1e-6, damping_per_s: 4.0, ..JELLY };
        let mut body = Body::new(cube(Vec3::ZERO), material);
        for p in 0..body.positions.len() {
            if body.positions[p].y > 0.2 - 1e-6 {
                body.pin(p);
            }
        }
        for _ in 0..(seconds * 60.0) as usize {
            body.step(1.0 / 60.0, world(substeps));
        }
        (body.lowest(), body)
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
    }

    #[test]
    fn a_dropped_body_rests_on_the_ground_keeping_its_volume() {
        let mut body = Body::new(cube(Vec3::new(0.0, 0.3, 0.0)), Material { damping_per_s: 2.0, ..JELLY });
        let world = World { ground_y: 0.0, ..world(10) };
        let mut energies = Vec::new();
        for _ in 0..180 {
            body.step(1.0 / 60.0, world);
            assert!(body.lowest() >= 0.0, "never below the ground");
            energies.push(body.kinetic_energy());
        }
        assert!(body.lowest() < 1e-4, "it lies on the ground: {}", body.lowest());
        assert!((body.volume_ratio() - 1.0).abs() < 0.02, "{}", body.volume_ratio());
        assert!(energies.last().unwrap() < &1e-4, "it has come to rest: {:?}", energies.last());
        assert!(body.positions.iter().all(|p| p.is_finite()));
    }
}
