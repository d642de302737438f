//! Dynamic soft bodies against rapier3d's, one core: the same tetrahedral sphere (about 1k, 5k
//! and 20k tetrahedra), its top layer pinned, under gravity, in 1/60 s steps of the same
//! substeps with one pass over the constraints each. Rapier's stiffness is found by bisection
//! so that both settle to the same sag; then steps are timed in alternating runs, and the
//! sag, time per step and per tetrahedron-substep are printed side by side. Last, two bodies
//! stepped on two threads against one after the other.
//!
//! Run with `cargo bench -p canopy_bench --bench soft_bodies`.

use bevy::math::Vec3;
use canopy::elastic::material::Material;
use canopy::elastic::tet_mesh::TetMesh;
use canopy::elastic::xpbd::{Body, World};
use canopy::soft_body::sample;
use rapier3d::prelude as rp;
use std::time::Instant;

/// Substeps a step, for both.
const SUBSTEPS: u32 = 10;
/// Simulated seconds a body is given to settle before its sag is taken.
const SETTLE_S: f32 = 4.0;
/// Steps timed in each run.
const TIMED_STEPS: usize = 60;
/// Runs of each, alternating.
const RUNS: usize = 5;
/// The sphere's radius, metres.
const RADIUS_M: f32 = 0.1;

const MATERIAL: Material = Material {
    density_kg_m3: 1000.0,
    young_modulus_pa: 5e4,
    poisson_ratio: 0.3,
    damping_per_s: 3.0,
    bending_rigidity_nm: 0.0,
};

/// A step of `dt` for one of the engines.
trait Stepper {
    fn step(&mut self);
    /// The centre of mass's height, metres (equal masses in both: the same particles').
    fn centre_y(&self) -> f32;
}

/// Canopy's body in a world of gravity alone.
struct Canopy(Body);

impl Stepper for Canopy {
    fn step(&mut self) {
        let world = World { gravity: Vec3::new(0.0, -9.81, 0.0), colliders: &[], friction: 0.0, substeps: SUBSTEPS };
        self.0.step(1.0 / 60.0, world);
    }

    fn centre_y(&self) -> f32 {
        self.0.centre_of_mass().y
    }
}

/// Rapier's soft body, the same particles, masses, tetrahedra and pins, no collider.
struct Rapier {
    pipeline: rp::PhysicsPipeline,
    params: rp::IntegrationParameters,
    islands: rp::IslandManager,
    broad_phase: rp::BroadPhaseBvh,
    narrow_phase: rp::NarrowPhase,
    bodies: rp::RigidBodySet,
    colliders: rp::ColliderSet,
    impulse_joints: rp::ImpulseJointSet,
    multibody_joints: rp::MultibodyJointSet,
    soft_bodies: rp::SoftBodySet,
    ccd: rp::CCDSolver,
    handle: rp::SoftBodyHandle,
    masses: Vec<f32>,
}

impl Rapier {
    /// The body of `mesh` with `masses`, `pinned` fixed, its edges and volumes as springs of
    /// `hz` (rapier normalises a constraint's frequency by its effective mass), undamped
    /// constraints and the same damping of velocity as Canopy's.
    fn new(mesh: &TetMesh, masses: &[f32], pinned: &[u32], hz: f32) -> Self {
        let positions: Vec<rp::Vector> = mesh.positions.iter().map(|p| rp::Vector::new(p.x, p.y, p.z)).collect();
        let springs = rp::SpringCoefficients::new(hz, 0.0);
        let builder = rp::SoftBodyBuilder::new(positions)
            .cells(mesh.tets.clone())
            .cell_model(rp::SoftBodyCellModel::Volume)
            .masses(masses.to_vec())
            .material(rp::SoftBodyMaterial { edge_softness: springs, volume_softness: springs, ..Default::default() })
            .pinned_particles(pinned.iter().copied())
            .additional_pgs_iterations(0)
            .linear_damping(MATERIAL.damping_per_s)
            .no_surface_collider()
            .can_sleep(false);
        let mut params = rp::IntegrationParameters {
            dt: 1.0 / 60.0,
            num_solver_iterations: SUBSTEPS as usize,
            ..Default::default()
        };
        params.soft_bodies.max_extra_substeps = 0;
        params.soft_bodies.resweep_strain = f32::MAX;
        let (mut bodies, mut colliders) = (rp::RigidBodySet::new(), rp::ColliderSet::new());
        let mut soft_bodies = rp::SoftBodySet::new();
        let handle = soft_bodies.insert(builder, &mut bodies, &mut colliders);
        Self {
            pipeline: rp::PhysicsPipeline::new(),
            params,
            islands: rp::IslandManager::new(),
            broad_phase: rp::BroadPhaseBvh::new(),
            narrow_phase: rp::NarrowPhase::new(),
            bodies,
            colliders,
            impulse_joints: rp::ImpulseJointSet::new(),
            multibody_joints: rp::MultibodyJointSet::new(),
            soft_bodies,
            ccd: rp::CCDSolver::new(),
            handle,
            masses: masses.to_vec(),
        }
    }
}

impl Stepper for Rapier {
    fn step(&mut self) {
        self.pipeline.step(
            rp::Vector::new(0.0, -9.81, 0.0),
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
    }

    fn centre_y(&self) -> f32 {
        let body = &self.soft_bodies[self.handle];
        let total: f32 = self.masses.iter().sum();
        body.particle_positions().zip(&self.masses).map(|(p, m)| p.y * m).sum::<f32>() / total
    }
}

/// The sag a stepper settles to from `rest_y`, metres.
fn settle(stepper: &mut impl Stepper, rest_y: f32) -> f32 {
    for _ in 0..(SETTLE_S * 60.0) as usize {
        stepper.step();
    }
    rest_y - stepper.centre_y()
}

/// Seconds per step over [`TIMED_STEPS`] steps.
fn time_steps(stepper: &mut impl Stepper) -> f64 {
    let started = Instant::now();
    for _ in 0..TIMED_STEPS {
        stepper.step();
    }
    started.elapsed().as_secs_f64() / TIMED_STEPS as f64
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// The sphere filled with cells of `cell_m`, and its top layer's particles.
fn sphere(cell_m: f32) -> (TetMesh, Vec<u32>) {
    let mut surface = sample::sphere(RADIUS_M, 24, 48);
    surface.positions.iter_mut().for_each(|p| *p += Vec3::Y);
    let (mesh, _) = TetMesh::fill(&surface, cell_m, usize::MAX).expect("a closed sphere");
    let top = mesh.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    let pinned =
        (0..mesh.positions.len() as u32).filter(|&p| mesh.positions[p as usize].y > top - cell_m / 2.0).collect();
    (mesh, pinned)
}

fn canopy_body(mesh: &TetMesh, pinned: &[u32]) -> Body {
    let mut body = Body::new(mesh.clone(), MATERIAL);
    for &p in pinned {
        body.pin(p as usize);
    }
    body
}

fn main() {
    println!(
        "a sphere of {RADIUS_M} m radius filled with tetrahedra, its top layer pinned, E = {} Pa, nu = {}, {} kg/m^3, damping {} /s; \
         1/60 s steps of {SUBSTEPS} substeps, one pass each; {RUNS} alternating runs of {TIMED_STEPS} steps, medians; one core",
        MATERIAL.young_modulus_pa, MATERIAL.poisson_ratio, MATERIAL.density_kg_m3, MATERIAL.damping_per_s
    );
    println!(
        "| tets | particles | Canopy sag mm | rapier sag mm (at Hz) | Canopy ms / step | rapier ms / step | rapier / Canopy | Canopy ns / tet-substep | rapier ns / tet-substep |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for cell_m in [0.029, 0.017, 0.0108] {
        let (mesh, pinned) = sphere(cell_m);
        let tets = mesh.tets.len();
        let mut canopy = Canopy(canopy_body(&mesh, &pinned));
        let rest_y = canopy.centre_y();
        let masses = canopy.0.masses().to_vec();
        let sag = settle(&mut canopy, rest_y);
        // Rapier's frequency for the same sag: the sag falls as the frequency rises.
        let (mut low, mut high) = (1.0f32, 2000.0f32);
        let mut found = None;
        for _ in 0..24 {
            let hz = (low * high).sqrt();
            let mut rapier = Rapier::new(&mesh, &masses, &pinned, hz);
            let rapier_sag = settle(&mut rapier, rest_y);
            found = Some((hz, rapier_sag, rapier));
            if (rapier_sag - sag).abs() < 0.01 * sag {
                break;
            }
            if rapier_sag > sag { low = hz } else { high = hz }
        }
        let (hz, rapier_sag, mut rapier) = found.expect("one bisection step at least");
        let (mut ours, mut theirs) = (Vec::new(), Vec::new());
        for _ in 0..RUNS {
            ours.push(time_steps(&mut canopy));
            theirs.push(time_steps(&mut rapier));
        }
        let (ours, theirs) = (median(ours), median(theirs));
        let per = |seconds: f64| seconds * 1e9 / (tets as f64 * f64::from(SUBSTEPS));
        println!(
            "| {tets} | {} | {:.2} | {:.2} ({hz:.0}) | {:.3} | {:.3} | {:.2}x | {:.1} | {:.1} |",
            mesh.positions.len(),
            sag * 1e3,
            rapier_sag * 1e3,
            ours * 1e3,
            theirs * 1e3,
            theirs / ours,
            per(ours),
            per(theirs)
        );
    }
    two_threads();
}

/// Two bodies of about 5k tetrahedra stepped on two threads against one after the other.
fn two_threads() {
    let (mesh, pinned) = sphere(0.017);
    let mut bodies = [0, 1].map(|_| Canopy(canopy_body(&mesh, &pinned)));
    let (mut alone, mut together) = (Vec::new(), Vec::new());
    for _ in 0..RUNS {
        let started = Instant::now();
        for body in &mut bodies {
            for _ in 0..TIMED_STEPS {
                body.step();
            }
        }
        alone.push(started.elapsed().as_secs_f64());
        let started = Instant::now();
        std::thread::scope(|scope| {
            for body in &mut bodies {
                scope.spawn(|| {
                    for _ in 0..TIMED_STEPS {
                        body.step();
                    }
                });
            }
        });
        together.push(started.elapsed().as_secs_f64());
    }
    let (alone, together) = (median(alone), median(together));
    println!();
    println!(
        "two bodies of {} tetrahedra, {TIMED_STEPS} steps each: one thread {:.1} ms, two threads {:.1} ms: {:.2}x",
        mesh.tets.len(),
        alone * 1e3,
        together * 1e3,
        alone / together
    );
}
