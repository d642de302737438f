//! The solver's tests: meshes filled into surfaces, bodies sagging, falling, resting and held.

use super::*;
use crate::elastic::material::Material;
use crate::elastic::tet_mesh::{TetError, TetMesh};
use std::collections::HashMap;

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
