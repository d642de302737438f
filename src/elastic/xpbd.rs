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

use super::colouring::colour_order;
use super::hinge::{Hinge, dihedral, hinges};
use super::material::Material;
use super::tet_mesh::{TetMesh, six_volume};
use crate::spatial::solid::Collider;
use bevy::math::Vec3;

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
mod tests;
