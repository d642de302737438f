//! Each forelimb's biceps: the muscle kind's volume-preserving node model on the sloth's own
//! arm, its length set every step by the elbow the IK produced.
//!
//! The muscle kind's carcass is scaled onto the limb: its rod 1 (`a1 + b1` config units) is
//! the upper arm, so one config unit is `upper arm / (a1 + b1)` metres; its rod 2 is the
//! forearm, of which the muscle uses only the attachment `a2` after the elbow. The elbow's
//! flexion is read from the limb's points (the angle between the upper arm and the forearm),
//! the carcass turns it into the muscle's length (the law of cosines, the muscle kind's
//! relation in reverse), and the node model takes that length keeping its volume. Nothing
//! here is specific to the sloth but the limb it reads; the muscle code is the muscle kind's.

use super::locomotion::Sloth;
use super::rig::Limb;
use crate::muscle::carcass::Carcass;
use crate::muscle::def::ConfigFile;
use crate::muscle::model::{Muscle, Refusal};
use crate::muscle::surface::build_surface;
use crate::raster::MeshData;
use bevy::math::{DVec3, Quat, Vec3};

/// Elbow flexions tried when a configuration is checked, from straight to fully bent.
const CHECKED_FLEXIONS: usize = 181;

/// The forelimbs that carry a biceps, left then right.
pub const BICEPS_LIMBS: [Limb; 2] = [Limb::LeftFore, Limb::RightFore];

/// The joints of `limb`'s arm in the sloth's current pose.
pub fn arm_points(sloth: &Sloth, limb: Limb) -> ArmPoints {
    let points = sloth.rigs[limb.index()].points(&sloth.frame, &sloth.feet[limb.index()].angles);
    ArmPoints { shoulder: points[1], elbow: points[2], wrist: points[3] }
}

/// Where a forelimb's bones meet, metres: the arm's three joints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmPoints {
    /// The shoulder joint (the upper arm's start).
    pub shoulder: Vec3,
    /// The elbow.
    pub elbow: Vec3,
    /// The wrist (the forearm's end).
    pub wrist: Vec3,
}

impl ArmPoints {
    /// The elbow's flexion in radians, 0 for a straight arm to pi fully folded.
    pub fn flexion(&self) -> f64 {
        let upper = (self.elbow - self.shoulder).as_dvec3().normalize_or_zero();
        let fore = (self.wrist - self.elbow).as_dvec3().normalize_or_zero();
        upper.dot(fore).clamp(-1.0, 1.0).acos()
    }

    /// The biceps' two attachments for `carcass` at `metres_per_unit`: `a1` after the
    /// shoulder on the upper arm, `a2` after the elbow on the forearm.
    pub fn attachments(&self, carcass: &Carcass, metres_per_unit: f64) -> (DVec3, DVec3) {
        let (shoulder, elbow, wrist) = (self.shoulder.as_dvec3(), self.elbow.as_dvec3(), self.wrist.as_dvec3());
        let upper = (elbow - shoulder).normalize_or_zero();
        let fore = (wrist - elbow).normalize_or_zero();
        (shoulder + upper * (carcass.a1 * metres_per_unit), elbow + fore * (carcass.a2 * metres_per_unit))
    }
}

/// One forelimb's biceps.
#[derive(Debug, Clone, PartialEq)]
pub struct Biceps {
    /// The node model, in config units.
    pub model: Muscle,
    /// The arm in config units: rod 1 the upper arm, rod 2 the forearm.
    pub carcass: Carcass,
    /// Metres per config unit.
    pub metres_per_unit: f64,
    /// The elbow flexion last followed, radians.
    pub flexion: f64,
    /// Why the model refused the last length, if it did (it then keeps its last state).
    pub refusal: Option<Refusal>,
}

impl Biceps {
    /// The biceps of `config` on an arm of `upper_arm_m` and `forearm_m`, at rest (straight
    /// elbow), or why it cannot follow every elbow flexion from 0 to 180 degrees.
    pub fn new(config: &ConfigFile, upper_arm_m: f32, forearm_m: f32) -> Result<Self, String> {
        let model = config.muscle_config.model(0.5, 1.5).map_err(|error| format!("muscle_config: {error}"))?;
        let arm = config.carcass_config.carcass();
        let metres_per_unit = f64::from(upper_arm_m) / (arm.a1 + arm.b1);
        let forearm = f64::from(forearm_m) / metres_per_unit;
        if arm.a2 >= forearm {
            return Err(format!(
                "carcass_config: a2 = {} lies beyond the forearm, which is {forearm:.1} units long at this scale",
                arm.a2
            ));
        }
        let carcass = Carcass { b2: forearm - arm.a2, ..arm };
        for step in 0..CHECKED_FLEXIONS {
            let flexion = std::f64::consts::PI * step as f64 / (CHECKED_FLEXIONS - 1) as f64;
            let length = carcass.length_from_flexion(flexion).value;
            model.radii_at(length).map_err(|refusal| {
                format!("the muscle cannot follow the elbow at {:.0} degrees: {refusal}", flexion.to_degrees())
            })?;
        }
        let mut biceps = Self { model, carcass, metres_per_unit, flexion: f64::NAN, refusal: None };
        biceps.follow_flexion(0.0);
        Ok(biceps)
    }

    /// Takes the length the elbow of `arm` gives, keeping the volume.
    pub fn follow(&mut self, arm: &ArmPoints) {
        self.follow_flexion(arm.flexion());
    }

    fn follow_flexion(&mut self, flexion: f64) {
        let length = self.carcass.length_from_flexion(flexion).value;
        self.refusal = self.model.set_length(length).err();
        if self.refusal.is_none() {
            self.flexion = flexion;
        }
    }

    /// The muscle's length, metres.
    pub fn length_m(&self) -> f64 {
        self.model.length() * self.metres_per_unit
    }

    /// `|volume - rest volume| / rest volume`.
    pub fn relative_volume_error(&self) -> f64 {
        ((self.model.volume() - self.model.rest_volume()) / self.model.rest_volume()).abs()
    }

    /// The largest radius at rest, metres.
    pub fn rest_thickness_m(&self) -> f64 {
        self.model.rest_radii().iter().copied().fold(0.0, f64::max) * self.metres_per_unit
    }

    /// Appends the muscle's surface, in metres, between the attachments of `arm`, its axis
    /// moved by `lift` (the same for both ends, so the drawn length stays the model's),
    /// with `segments` vertices around each ring, coloured `color`.
    pub fn append_surface(&self, arm: &ArmPoints, lift: Vec3, segments: usize, color: Vec3, mesh: &mut MeshData) {
        let mut surface = MeshData::default();
        build_surface(self.model.radii(), self.model.node_spacing(), segments, &mut surface);
        let (start, end) = arm.attachments(&self.carcass, self.metres_per_unit);
        let axis = (end - start).as_vec3().normalize_or(Vec3::X);
        let rotation = Quat::from_rotation_arc(Vec3::X, axis);
        let (origin, scale) = (start.as_vec3() + lift, self.metres_per_unit as f32);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(surface.positions.iter().map(|&p| origin + rotation * (p * scale)));
        mesh.normals.extend(surface.normals.iter().map(|&n| rotation * n));
        mesh.colors.resize(mesh.positions.len(), color);
        mesh.triangles.extend(surface.triangles.iter().map(|t| t.map(|i| i + base)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn biceps() -> Biceps {
        Biceps::new(&ConfigFile::source_first(), 0.17, 0.16).unwrap()
    }

    /// An arm in the xy plane, its elbow at the origin, flexed `degrees`.
    fn arm(degrees: f64) -> ArmPoints {
        let f = degrees.to_radians() as f32;
        ArmPoints {
            shoulder: Vec3::new(-0.17, 0.0, 0.0),
            elbow: Vec3::ZERO,
            wrist: Vec3::new(f.cos(), f.sin(), 0.0) * 0.16,
        }
    }

    #[test]
    fn the_length_is_the_distance_between_the_attachments_and_the_volume_is_kept() {
        let mut biceps = biceps();
        let rest = biceps.model.rest_volume();
        for degrees in [0.0, 20.0, 45.0, 90.0, 135.0, 170.0] {
            let arm = arm(degrees);
            biceps.follow(&arm);
            assert!((biceps.flexion.to_degrees() - degrees).abs() < 1e-4, "{degrees}: {}", biceps.flexion);
            let (a, b) = arm.attachments(&biceps.carcass, biceps.metres_per_unit);
            assert!(
                (a.distance(b) - biceps.length_m()).abs() < 1e-7,
                "{degrees}: {} vs {}",
                a.distance(b),
                biceps.length_m()
            );
            assert!(biceps.relative_volume_error() < 1e-12);
            assert!(((biceps.model.volume() - rest) / rest).abs() < 1e-12);
        }
    }

    #[test]
    fn flexing_the_elbow_shortens_and_thickens_the_muscle() {
        let mut biceps = biceps();
        biceps.follow(&arm(10.0));
        let (long, thin) = (biceps.length_m(), biceps.model.radii()[4]);
        biceps.follow(&arm(120.0));
        assert!(biceps.length_m() < long && biceps.model.radii()[4] > thin);
    }

    #[test]
    fn the_carcass_is_scaled_onto_the_upper_arm() {
        let biceps = biceps();
        let (c, upper_arm) = (&biceps.carcass, f64::from(0.17f32));
        assert!(((c.a1 + c.b1) * biceps.metres_per_unit - upper_arm).abs() < 1e-12);
        assert!(((c.a2 + c.b2) * biceps.metres_per_unit - f64::from(0.16f32)).abs() < 1e-12);
        // The source's 18-unit belly on a 260-unit rod: about 1.2 cm on a 17 cm arm.
        assert!((biceps.rest_thickness_m() - 18.0 * upper_arm / 260.0).abs() < 1e-12);
    }

    #[test]
    fn a_muscle_that_cannot_follow_the_elbow_is_refused() {
        let mut config = ConfigFile::source_first();
        // Rest length 150 with spacing bounds 0.5-1.5: at most 225, but a straight arm needs 260.
        config.muscle_config.len = crate::muscle::def::ConfigLength(150.0);
        let error = Biceps::new(&config, 0.17, 0.16).unwrap_err();
        assert!(error.contains("cannot follow the elbow at 0 degrees"), "{error}");
        let mut far = ConfigFile::source_first();
        far.carcass_config.data[1][0] = crate::muscle::def::ConfigLength(400.0);
        assert!(Biceps::new(&far, 0.17, 0.16).unwrap_err().contains("beyond the forearm"));
    }

    #[test]
    fn the_surface_lies_along_the_attachments() {
        let biceps = biceps();
        let arm = arm(0.0);
        let mut mesh = MeshData::default();
        biceps.append_surface(&arm, Vec3::ZERO, 12, Vec3::ONE, &mut mesh);
        let (a, b) = arm.attachments(&biceps.carcass, biceps.metres_per_unit);
        let xs = mesh.positions.iter().map(|p| p.x);
        let (min, max) = xs.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
        let end_radius = (5.0 * biceps.metres_per_unit) as f32;
        assert!((min - (a.x as f32 - end_radius)).abs() < 1e-5 && (max - (b.x as f32 + end_radius)).abs() < 1e-5);
        assert_eq!(mesh.colors.len(), mesh.positions.len());
    }
}
