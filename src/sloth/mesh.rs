//! The sloth's render mesh, rebuilt from its pose each frame: its [`Skin`] posed by the rig
//! (one surface over the torso, neck, head and limbs, with a pale face, dark eye patches and a
//! streaky coat), curved claws (two on each hand, three on each foot, as in *Choloepus*), and
//! each forelimb's biceps on the flexor side of its upper arm. Colours are per vertex, in the
//! rasterizer's colour space (the scene's sRGB values, as for every other mesh).

use super::biceps::{BICEPS_LIMBS, Biceps, arm_points};
use super::locomotion::Sloth;
use super::rig::{BodyFrame, JOINTS, Limb};
use super::skin::{LIMB_RADII, Skin, palm, thickness_scale};
use crate::raster::{MeshData, vertex_normals};
use crate::spatial::tube::add_tube;
use bevy::math::Vec3;

/// Vertices around each claw.
const SIDES: usize = 10;

/// Colours of the parts that are not skin.
const CLAW: Vec3 = Vec3::new(0.12, 0.1, 0.08);
const MUSCLE: Vec3 = Vec3::new(0.7, 0.22, 0.2);

/// Vertices around each ring of a biceps.
const BICEPS_SEGMENTS: usize = 12;

/// Appends a capsule chain along `points` with `radii` in `color`.
fn part(mesh: &mut MeshData, points: &[Vec3], radii: &[f32], color: Vec3) {
    add_tube(mesh, points, radii, SIDES);
    mesh.colors.resize(mesh.positions.len(), color);
}

/// The mesh of `sloth` in its current pose, its `skin` (made for its proportions) in the coat
/// colour `fur`, with its forelimbs' `biceps`.
pub fn sloth_mesh(sloth: &Sloth, skin: &Skin, biceps: &[Biceps; 2], fur: Vec3) -> MeshData {
    let frame = &sloth.frame;
    let positions = skin.posed(frame, &sloth.rigs, &sloth.feet.each_ref().map(|foot| foot.angles));
    let mut mesh = MeshData {
        normals: vertex_normals(&positions, skin.triangles()),
        positions,
        colors: skin.colors(fur),
        triangles: skin.triangles().to_vec(),
        ..Default::default()
    };
    let p = &sloth.proportions;
    let scale = thickness_scale(p);
    for limb in Limb::ALL {
        let points = sloth.rigs[limb.index()].points(frame, &sloth.feet[limb.index()].angles);
        claws(&mut mesh, frame, limb, palm(&points, p.claw), points[JOINTS - 1], scale);
    }
    // Each biceps lies along its attachments, lifted towards the forearm's side by the upper
    // arm's radius less its belly, so that the belly shows through the fur (more as it
    // thickens) and its ends stay in the limb.
    let upper_arm_radius = (LIMB_RADII[1] + LIMB_RADII[2]) * 0.5 * scale;
    for (muscle, limb) in biceps.iter().zip(BICEPS_LIMBS) {
        let arm = arm_points(sloth, limb);
        let upper = (arm.elbow - arm.shoulder).normalize_or_zero();
        let fore = (arm.wrist - arm.elbow).normalize_or_zero();
        let (_, flex) = sloth.rigs[limb.index()].axes(frame, sloth.feet[limb.index()].angles[0]);
        let side = (fore - upper * upper.dot(fore)).try_normalize().unwrap_or_else(|| upper.cross(flex).normalize());
        let lift = side * (upper_arm_radius - muscle.rest_thickness_m() as f32);
        muscle.append_surface(&arm, lift, BICEPS_SEGMENTS, MUSCLE, &mut mesh);
    }
    mesh
}

/// Two claws on a hand, three on a foot, spread across the grip and tapering to points.
fn claws(mesh: &mut MeshData, frame: &BodyFrame, limb: Limb, palm: Vec3, grip: Vec3, scale: f32) {
    let count = if limb.is_fore() { 2 } else { 3 };
    let across = (grip - palm).cross(frame.forward).normalize_or(frame.right());
    let bend = -frame.up * ((grip - palm).length() * 0.25);
    for k in 0..count {
        let offset = across * ((k as f32 - (count - 1) as f32 * 0.5) * 0.012 * scale);
        let middle = palm.lerp(grip, 0.55) + offset + bend;
        part(
            mesh,
            &[palm + offset, middle, grip + offset * 0.5],
            &[0.006 * scale, 0.004 * scale, 0.0015 * scale],
            CLAW,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sloth::locomotion::Tuning;
    use crate::sloth::rig::Proportions;
    use crate::sloth::supports::Supports;
    use crate::tree::{Shape, SupportSpec, Tree};

    /// A sloth of default proportions in the middle of a straight bough, and its biceps.
    fn sloth_on_a_bough() -> (Sloth, Skin, [Biceps; 2]) {
        let shape = Shape::Polyline {
            points: vec![Vec3::new(-2.0, 2.0, 0.0), Vec3::new(2.0, 2.0, 0.0)],
            radii: vec![0.04, 0.04],
        };
        let tree = Tree::build(&[SupportSpec { name: "b".into(), shape, kind: None }]).unwrap();
        let supports = Supports::new([("t", &tree)]);
        let placement = crate::sloth::Placement { support: 0, fraction: 0.5, facing: 1.0, around: 0.0 };
        let sloth =
            Sloth::place(&supports, placement, Proportions::default(), Tuning::animal(0.11, &Proportions::default()))
                .unwrap();
        let def: crate::sloth::SlothDef = serde_yaml::from_str("support: b").unwrap();
        let skin = Skin::new(&sloth.proportions, &sloth.rigs);
        (sloth, skin, def.biceps().unwrap())
    }

    #[test]
    fn the_mesh_covers_the_body_and_reaches_every_grip() {
        let (sloth, skin, biceps) = sloth_on_a_bough();
        let mesh = sloth_mesh(&sloth, &skin, &biceps, Vec3::new(0.4, 0.3, 0.2));
        assert_eq!(mesh.colors.len(), mesh.positions.len());
        assert_eq!(mesh.normals.len(), mesh.positions.len());
        assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < mesh.positions.len()));
        for foot in &sloth.feet {
            let nearest = mesh.positions.iter().map(|p| p.distance(foot.position)).fold(f32::INFINITY, f32::min);
            assert!(nearest < 0.01, "a claw tip reaches each grip: {nearest}");
        }
        let centre = mesh.positions.iter().copied().sum::<Vec3>() / mesh.positions.len() as f32;
        assert!(centre.distance(sloth.frame.centre) < 0.3);
    }

    #[test]
    fn each_biceps_lies_on_its_upper_arm() {
        let (sloth, skin, biceps) = sloth_on_a_bough();
        let mesh = sloth_mesh(&sloth, &skin, &biceps, Vec3::ONE);
        let muscle: Vec<Vec3> =
            mesh.positions.iter().zip(&mesh.colors).filter(|(_, c)| **c == MUSCLE).map(|(p, _)| *p).collect();
        assert!(!muscle.is_empty() && muscle.len().is_multiple_of(2), "both muscles are drawn alike");
        let (arm_radius, belly) = (LIMB_RADII[1], biceps[0].rest_thickness_m() as f32);
        for (half, limb) in muscle.chunks(muscle.len() / 2).zip(BICEPS_LIMBS) {
            let arm = arm_points(&sloth, limb);
            let axis = arm.elbow - arm.shoulder;
            let from_bone = |p: Vec3| {
                let t = ((p - arm.shoulder).dot(axis) / axis.length_squared()).clamp(0.0, 1.0);
                p.distance(arm.shoulder + axis * t)
            };
            // Along the upper arm, nowhere farther from its fur than two thicknesses of the belly...
            let far = half.iter().map(|&p| from_bone(p)).fold(0.0, f32::max);
            assert!(far < arm_radius + 2.0 * belly, "{limb:?} strays from its arm: {far} m from the bone");
            // ...and showing through it.
            assert!(half.iter().any(|&p| from_bone(p) > arm_radius), "{limb:?} is hidden in the fur");
        }
    }
}
