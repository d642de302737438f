//! A tree as the program holds it: named supports, each a polyline of points with a radius at
//! each point, built from the scene's descriptions (polylines, or branches forking from a
//! parent), and classified as trunks or branches.

use crate::spatial::segment::TaperedSegment;
use bevy::math::Vec3;
use std::fmt;

/// A support tilted more than this from horizontal is a trunk (degrees).
pub const TRUNK_TILT_DEG: f32 = 70.0;

/// Consecutive points closer than this (metres) are coincident.
const COINCIDENT: f32 = 1e-6;

/// Whether a support is climbed (a trunk) or hung from (a branch).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SupportKind {
    /// Steeper than [`TRUNK_TILT_DEG`].
    Trunk,
    /// Everything else.
    Branch,
}

impl SupportKind {
    /// The name used in files and dumps.
    pub fn key(self) -> &'static str {
        match self {
            SupportKind::Trunk => "trunk",
            SupportKind::Branch => "branch",
        }
    }

    /// The kind of a support running from `first` to `last`, by its tilt.
    pub fn of_direction(first: Vec3, last: Vec3) -> Self {
        let direction = (last - first).normalize_or_zero();
        let tilt_deg = direction.y.abs().clamp(0.0, 1.0).asin().to_degrees();
        if tilt_deg > TRUNK_TILT_DEG { SupportKind::Trunk } else { SupportKind::Branch }
    }
}

/// How a support's shape is given.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// Explicit points (metres) and a radius at each.
    Polyline {
        /// At least two points, no two consecutive ones coincident.
        points: Vec<Vec3>,
        /// One radius per point, metres.
        radii: Vec<f32>,
    },
    /// A branch growing from a point of its parent.
    Fork {
        /// The parent support's name.
        parent: String,
        /// Where along the parent it starts, as a fraction of the parent's length.
        at: f32,
        /// Initial heading about +y, degrees (0 towards +z, 90 towards +x).
        yaw_deg: f32,
        /// Initial angle above the horizontal, degrees.
        pitch_deg: f32,
        /// Length along the branch, metres.
        length: f32,
        /// Radius at the start and at the tip, metres.
        radius: [f32; 2],
        /// Total change of heading and pitch from start to tip, degrees, spread evenly.
        bend_deg: [f32; 2],
        /// Straight sections the branch is made of.
        sections: u32,
    },
    /// Explicit points and radii of a branch growing out of a parent support (as a scanned
    /// tree's branches do): its first point lies on or in the parent's wood.
    Attached {
        /// The parent support's name.
        parent: String,
        /// At least two points, no two consecutive ones coincident, metres.
        points: Vec<Vec3>,
        /// One radius per point, metres.
        radii: Vec<f32>,
    },
}

/// One support as described in a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportSpec {
    /// Unique within the tree.
    pub name: String,
    /// Its geometry.
    pub shape: Shape,
    /// Trunk or branch; by tilt when not given.
    pub kind: Option<SupportKind>,
}

/// A built support.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// Its name.
    pub name: String,
    /// Trunk or branch.
    pub kind: SupportKind,
    /// The support it forks from, as an index into the tree's supports.
    pub parent: Option<usize>,
    /// Axis points, metres.
    pub points: Vec<Vec3>,
    /// Radius at each point, metres.
    pub radii: Vec<f32>,
}

impl Support {
    /// The tapered segments between consecutive points.
    pub fn segments(&self) -> impl Iterator<Item = TaperedSegment> + '_ {
        self.points.windows(2).zip(self.radii.windows(2)).map(|(p, r)| TaperedSegment {
            a: p[0],
            b: p[1],
            radius_a: r[0],
            radius_b: r[1],
        })
    }

    /// Total axis length, metres.
    pub fn length(&self) -> f32 {
        self.points.windows(2).map(|p| p[0].distance(p[1])).sum()
    }

    /// The axis point, unit direction and radius at `fraction` of the length.
    pub fn at(&self, fraction: f32) -> (Vec3, Vec3, f32) {
        let mut remaining = fraction.clamp(0.0, 1.0) * self.length();
        let last = self.points.len() - 2;
        for (i, pair) in self.points.windows(2).enumerate() {
            let span = pair[0].distance(pair[1]);
            if remaining <= span || i == last {
                let t = if span > 0.0 { (remaining / span).clamp(0.0, 1.0) } else { 0.0 };
                let radius = self.radii[i] + (self.radii[i + 1] - self.radii[i]) * t;
                return (pair[0].lerp(pair[1], t), (pair[1] - pair[0]).normalize_or_zero(), radius);
            }
            remaining -= span;
        }
        unreachable!("a support has at least two points")
    }
}

/// Why supports do not make a tree. Each names the support (by its index in the description)
/// and the field at fault.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeError {
    /// Index of the support in the description; `None` for the tree's own fields.
    pub support: Option<usize>,
    /// The field at fault (`name`, `parent`, `points`, `radii`).
    pub field: &'static str,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for TreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.support {
            Some(support) => write!(f, "supports[{support}].{}: {}", self.field, self.message),
            None => write!(f, "{}: {}", self.field, self.message),
        }
    }
}

/// A built tree: supports in description order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tree {
    /// The supports.
    pub supports: Vec<Support>,
    /// How far each support that forks from no other was raised to stand on a terrain, by
    /// name (see the `ground` of a tree in a scene file); empty for a tree on nothing.
    pub lifts: Vec<(String, f32)>,
    /// Supports whose every radius is below this, metres, are drawn but never gripped.
    pub grip_min_radius_m: f32,
}

impl Tree {
    /// Whether support `index` is offered to grip: some radius of it is at least
    /// [`Self::grip_min_radius_m`].
    pub fn gripped(&self, index: usize) -> bool {
        self.supports[index].radii.iter().any(|&r| r >= self.grip_min_radius_m)
    }

    /// Builds the supports described by `specs`, resolving forks from their parents (which may
    /// be described before or after them).
    pub fn build(specs: &[SupportSpec]) -> Result<Self, TreeError> {
        for (index, spec) in specs.iter().enumerate() {
            if specs[..index].iter().any(|s| s.name == spec.name) {
                let message = format!("the name \"{}\" is used by an earlier support; names must be unique", spec.name);
                return Err(TreeError { support: Some(index), field: "name", message });
            }
        }
        let mut built: Vec<Option<Support>> = vec![None; specs.len()];
        for index in 0..specs.len() {
            build_support(specs, index, &mut built, &mut Vec::new())?;
        }
        let supports = built.into_iter().map(|s| s.expect("every support was built")).collect();
        Ok(Self { supports, lifts: Vec::new(), grip_min_radius_m: 0.0 })
    }

    /// Every segment of every support, with its support's index.
    pub fn segments(&self) -> impl Iterator<Item = (usize, TaperedSegment)> + '_ {
        self.supports.iter().enumerate().flat_map(|(i, s)| s.segments().map(move |segment| (i, segment)))
    }
}

/// Builds support `index` (and, first, the parents it forks from); `path` holds the supports
/// being built, to find cycles.
fn build_support(
    specs: &[SupportSpec],
    index: usize,
    built: &mut [Option<Support>],
    path: &mut Vec<usize>,
) -> Result<(), TreeError> {
    if built[index].is_some() {
        return Ok(());
    }
    let spec = &specs[index];
    let error = |field, message: String| TreeError { support: Some(index), field, message };
    // The parent a fork or an attached polyline grows from, built first.
    let mut parent_of = |parent: &str, built: &mut [Option<Support>]| {
        let Some(parent_index) = specs.iter().position(|s| s.name == parent) else {
            let known: Vec<&str> = specs.iter().map(|s| s.name.as_str()).take(24).collect();
            let message = format!("no support is named \"{parent}\" (supports: {})", known.join(", "));
            return Err(error("parent", message));
        };
        if parent_index == index || path.contains(&parent_index) {
            let message = format!("\"{}\" forks from itself through its parents", spec.name);
            return Err(error("parent", message));
        }
        path.push(index);
        build_support(specs, parent_index, built, path)?;
        path.pop();
        Ok(parent_index)
    };
    let (points, radii, parent) = match &spec.shape {
        Shape::Polyline { points, radii } => {
            check_polyline(points, radii).map_err(|(field, message)| error(field, message))?;
            (points.clone(), radii.clone(), None)
        }
        Shape::Attached { parent, points, radii } => {
            check_polyline(points, radii).map_err(|(field, message)| error(field, message))?;
            (points.clone(), radii.clone(), Some(parent_of(parent, built)?))
        }
        Shape::Fork { parent, at, yaw_deg, pitch_deg, length, radius, bend_deg, sections } => {
            let parent_index = parent_of(parent, built)?;
            let parent_support = built[parent_index].as_ref().expect("the parent was just built");
            let (start, _, _) = parent_support.at(*at);
            let sections = (*sections).max(1);
            let mut points = vec![start];
            for i in 0..sections {
                let middle = (i as f32 + 0.5) / sections as f32;
                let direction = heading(yaw_deg + bend_deg[0] * middle, pitch_deg + bend_deg[1] * middle);
                points.push(points[i as usize] + direction * (length / sections as f32));
            }
            let radii =
                (0..=sections).map(|i| radius[0] + (radius[1] - radius[0]) * i as f32 / sections as f32).collect();
            (points, radii, Some(parent_index))
        }
    };
    let kind = spec.kind.unwrap_or_else(|| SupportKind::of_direction(points[0], points[points.len() - 1]));
    built[index] = Some(Support { name: spec.name.clone(), kind, parent, points, radii });
    Ok(())
}

/// Whether `points` and `radii` make a polyline: at least two points, a radius for each, no two
/// consecutive points coincident; else the field at fault and why.
fn check_polyline(points: &[Vec3], radii: &[f32]) -> Result<(), (&'static str, String)> {
    if points.len() < 2 {
        return Err(("points", format!("expected at least two points, found {}", points.len())));
    }
    if radii.len() != points.len() {
        return Err(("radii", format!("expected one radius per point ({}), found {}", points.len(), radii.len())));
    }
    if let Some(i) = points.windows(2).position(|p| p[0].distance(p[1]) < COINCIDENT) {
        return Err(("points", format!("points {i} and {} coincide; consecutive points must differ", i + 1)));
    }
    Ok(())
}

/// The unit vector at `yaw_deg` about +y (0 towards +z, 90 towards +x) and `pitch_deg` above
/// the horizontal.
pub fn heading(yaw_deg: f32, pitch_deg: f32) -> Vec3 {
    let (yaw, pitch) = (yaw_deg.to_radians(), pitch_deg.to_radians());
    Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polyline(name: &str, points: &[[f32; 3]], radii: &[f32]) -> SupportSpec {
        SupportSpec {
            name: name.into(),
            shape: Shape::Polyline {
                points: points.iter().map(|&p| Vec3::from_array(p)).collect(),
                radii: radii.to_vec(),
            },
            kind: None,
        }
    }

    fn fork(name: &str, parent: &str, at: f32) -> SupportSpec {
        SupportSpec {
            name: name.into(),
            shape: Shape::Fork {
                parent: parent.into(),
                at,
                yaw_deg: 90.0,
                pitch_deg: 0.0,
                length: 2.0,
                radius: [0.1, 0.05],
                bend_deg: [0.0, 0.0],
                sections: 4,
            },
            kind: None,
        }
    }

    #[test]
    fn forks_start_on_their_parent_and_kinds_follow_the_tilt() {
        // The branch is described before its trunk.
        let tree = Tree::build(&[
            fork("limb", "trunk", 0.5),
            polyline("trunk", &[[0.0, 0.0, 0.0], [0.0, 4.0, 0.0]], &[0.3, 0.2]),
        ])
        .unwrap();
        let (limb, trunk) = (&tree.supports[0], &tree.supports[1]);
        assert_eq!((trunk.kind, limb.kind), (SupportKind::Trunk, SupportKind::Branch));
        assert_eq!(limb.parent, Some(1));
        assert!(limb.points[0].distance(Vec3::new(0.0, 2.0, 0.0)) < 1e-6);
        // Yaw 90 points along +x; four sections of 0.5 m.
        assert!(limb.points[4].distance(Vec3::new(2.0, 2.0, 0.0)) < 1e-5, "{:?}", limb.points);
        assert_eq!(limb.radii.len(), 5);
        assert!((limb.length() - 2.0).abs() < 1e-5);
        assert_eq!(tree.segments().count(), 1 + 4);
    }

    #[test]
    fn a_steep_branch_is_a_trunk_unless_overridden() {
        assert_eq!(SupportKind::of_direction(Vec3::ZERO, Vec3::new(0.3, 1.0, 0.0)), SupportKind::Trunk);
        assert_eq!(SupportKind::of_direction(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)), SupportKind::Branch);
        let mut spec = polyline("pole", &[[0.0, 0.0, 0.0], [0.0, 3.0, 0.0]], &[0.1, 0.1]);
        spec.kind = Some(SupportKind::Branch);
        assert_eq!(Tree::build(&[spec]).unwrap().supports[0].kind, SupportKind::Branch);
    }

    #[test]
    fn bad_descriptions_name_the_support_and_field() {
        let trunk = polyline("trunk", &[[0.0, 0.0, 0.0], [0.0, 4.0, 0.0]], &[0.3, 0.2]);
        let cases: Vec<(Vec<SupportSpec>, usize, &str, &str)> = vec![
            (vec![trunk.clone(), trunk.clone()], 1, "name", "used by an earlier support"),
            (
                vec![trunk.clone(), fork("limb", "oak", 0.5)],
                1,
                "parent",
                "no support is named \"oak\" (supports: trunk, limb)",
            ),
            (vec![fork("a", "b", 0.5), fork("b", "a", 0.5)], 1, "parent", "forks from itself"),
            (vec![fork("a", "a", 0.5)], 0, "parent", "forks from itself"),
            (vec![polyline("p", &[[0.0; 3]], &[0.1])], 0, "points", "at least two points"),
            (
                vec![polyline("p", &[[0.0; 3], [1.0, 0.0, 0.0]], &[0.1])],
                0,
                "radii",
                "one radius per point (2), found 1",
            ),
            (vec![polyline("p", &[[0.0; 3], [0.0; 3]], &[0.1, 0.1])], 0, "points", "points 0 and 1 coincide"),
        ];
        for (specs, support, field, words) in cases {
            let error = Tree::build(&specs).unwrap_err();
            assert_eq!((error.support, error.field), (Some(support), field), "{error}");
            assert!(error.message.contains(words), "{error}");
        }
    }
}
