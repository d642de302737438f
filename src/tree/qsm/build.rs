//! A model's cylinders as a tree's supports.
//!
//! Each support follows one branch of the model: from a cylinder that starts a branch along the
//! cylinders that continue it (the format's `extension`, or else the child on the same
//! `branch`, or else the child that carries on most nearly in the same direction). Every
//! other child starts a support of its own, attached to the support it grows from: its first
//! point is where its base's centre projects onto the parent cylinder's axis, inside the
//! parent's wood, as the sloth's rules for forks expect. The model's z up becomes y up, and the
//! tree stands on the origin unless its base is kept.

use super::Qsm;
use crate::spatial::polyline::simplified;
use crate::tree::{Shape, SupportSpec};
use bevy::math::Vec3;

/// What to keep of a model and how to place it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImportOptions {
    /// Cylinders thinner than this, metres of radius, are dropped with everything growing from
    /// them (or, with `draw_thin`, made supports of their own); 0 keeps every twig.
    pub min_radius_m: f32,
    /// Keep the cylinders thinner than `min_radius_m`, each run of them a support of its own
    /// that no support thicker than `min_radius_m` carries on into, so that the tree can draw
    /// them without offering them to grip.
    pub draw_thin: bool,
    /// Points of a support within this distance of the line through their neighbours are
    /// dropped, metres; 0 keeps every cylinder's joint.
    pub simplify_m: f32,
    /// Keep the model's coordinates (y up) instead of standing the tree on the origin.
    pub keep_base: bool,
}

/// Below this cosine between two cylinders' axes, a child does not carry its parent's branch
/// on when the format does not say which child does.
const CONTINUES_COS: f32 = 0.7;

/// A model as supports, and what was left out.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    /// The supports, the stem first, each after the support it grows from.
    pub supports: Vec<SupportSpec>,
    /// Cylinders kept.
    pub cylinders: usize,
    /// Cylinders thinner than the least radius (dropped with what grows from them, or kept to
    /// draw).
    pub thin: usize,
    /// Cylinders dropped as fragments connected to nothing (the other roots' pieces).
    pub fragments: usize,
}

/// The model's z-up frame turned y up: x stays, y becomes -z, z becomes y.
fn y_up(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.z, -v.y)
}

/// `qsm`'s supports, kept and placed as `options` say.
pub fn supports(qsm: &Qsm, options: &ImportOptions) -> Result<Imported, String> {
    let cylinders = &qsm.cylinders;
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); cylinders.len()];
    for (index, cylinder) in cylinders.iter().enumerate() {
        if let Some(parent) = cylinder.parent {
            children[parent].push(index);
        }
    }
    // The kept piece: from the root whose piece holds the most wood (the others are fragments
    // the reconstruction left unconnected), without the cylinders below the least radius.
    let thick = |index: usize| cylinders[index].radius >= options.min_radius_m;
    let piece = |root: usize| {
        let mut stack = vec![root];
        let mut members = Vec::new();
        while let Some(index) = stack.pop() {
            members.push(index);
            stack.extend(children[index].iter().copied());
        }
        members
    };
    let wood =
        |members: &[usize]| members.iter().map(|&i| cylinders[i].radius.powi(2) * cylinders[i].length).sum::<f32>();
    let (root, in_piece, _) = (0..cylinders.len())
        .filter(|&i| cylinders[i].parent.is_none())
        .map(|root| {
            let members = piece(root);
            let wood = wood(&members);
            (root, members, wood)
        })
        .max_by(|a, b| a.2.total_cmp(&b.2))
        .ok_or("the model has no root cylinder")?;
    if !thick(root) {
        return Err(format!(
            "the stem's first cylinder is {:.4} m thick, thinner than min_radius_m {}",
            cylinders[root].radius, options.min_radius_m
        ));
    }
    let mut kept = vec![false; cylinders.len()];
    let mut stack = vec![root];
    while let Some(index) = stack.pop() {
        kept[index] = true;
        stack.extend(children[index].iter().copied().filter(|&c| options.draw_thin || thick(c)));
    }
    let kept_count = kept.iter().filter(|&&k| k).count();
    let thin = match options.draw_thin {
        true => in_piece.iter().filter(|&&i| !thick(i)).count(),
        false => in_piece.len() - kept_count,
    };
    let fragments = cylinders.len() - in_piece.len();

    // The child that carries each cylinder's branch on, among the kept ones as thick as it
    // (a thick run ends where its twig begins).
    let continuation = |index: usize| -> Option<usize> {
        let cylinder = &cylinders[index];
        let kept_children = children[index].iter().copied().filter(|&c| kept[c] && thick(c) == thick(index));
        if let Some(extension) = cylinder.extension {
            return (kept[extension] && thick(extension) == thick(index)).then_some(extension);
        }
        if let Some(branch) = cylinder.branch
            && let Some(same) = kept_children.clone().find(|&c| cylinders[c].branch == Some(branch))
        {
            return Some(same);
        }
        kept_children
            .map(|c| (c, cylinders[c].axis.dot(cylinder.axis)))
            .filter(|&(_, cos)| cos >= CONTINUES_COS)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(c, _)| c)
    };

    // Where the tree stands: its stem's base on the origin, or the model's own coordinates.
    let offset = if options.keep_base { y_up(qsm.origin.as_vec3()) } else { -y_up(cylinders[root].start) };
    let place = |p: Vec3| y_up(p) + offset;

    let mut supports: Vec<SupportSpec> = Vec::new();
    // Supports to make: the cylinder that starts each, and the support and cylinder it grows from.
    let mut pending: Vec<(usize, Option<(usize, usize)>)> = vec![(root, None)];
    let mut cursor = 0;
    while cursor < pending.len() {
        let (first, grows_from) = pending[cursor];
        cursor += 1;
        let support_index = supports.len();
        let name = if support_index == 0 { "stem".to_string() } else { format!("b{support_index}") };
        let mut chain = vec![first];
        while let Some(next) = continuation(*chain.last().expect("a chain has a first cylinder")) {
            chain.push(next);
        }
        for (k, &index) in chain.iter().enumerate() {
            let carried_on = chain.get(k + 1).copied();
            for &child in children[index].iter().filter(|&&c| kept[c] && Some(c) != carried_on) {
                pending.push((child, Some((support_index, index))));
            }
        }
        let mut points: Vec<Vec3> = Vec::with_capacity(chain.len() + 2);
        let mut radii: Vec<f32> = Vec::with_capacity(chain.len() + 2);
        if let Some((_, parent_cylinder)) = grows_from {
            // Into the parent's wood: the base's centre projected onto the parent's axis.
            let parent = &cylinders[parent_cylinder];
            let along = (cylinders[first].start - parent.start).dot(parent.axis).clamp(0.0, parent.length);
            points.push(place(parent.start + parent.axis * along));
            radii.push(cylinders[first].radius);
        }
        for &index in &chain {
            points.push(place(cylinders[index].start));
            radii.push(cylinders[index].radius);
        }
        let last = &cylinders[*chain.last().expect("a chain has a last cylinder")];
        points.push(place(last.end()));
        radii.push(last.radius);
        let (points, radii) = simplified(&points, &radii, options.simplify_m);
        let shape = match grows_from {
            None => Shape::Polyline { points, radii },
            Some((parent, _)) => Shape::Attached { parent: supports[parent].name.clone(), points, radii },
        };
        supports.push(SupportSpec { name, shape, kind: None });
    }
    Ok(Imported { supports, cylinders: kept_count, thin, fragments })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::Tree;
    use crate::tree::qsm::{Cylinder, QsmFormat};
    use bevy::math::DVec3;

    fn cylinder(start: [f32; 3], axis: [f32; 3], length: f32, radius: f32, parent: Option<usize>) -> Cylinder {
        Cylinder {
            start: Vec3::from(start),
            axis: Vec3::from(axis).normalize(),
            length,
            radius,
            parent,
            extension: None,
            branch: None,
        }
    }

    /// A stem of three cylinders up z, a bough of two leaving its second sideways and carried
    /// on by a thin tip, a twig off the bough, and a loose fragment.
    fn model() -> Qsm {
        let cylinders = vec![
            cylinder([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0, 0.2, None),
            cylinder([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 1.0, 0.18, Some(0)),
            cylinder([0.0, 0.0, 2.0], [0.0, 0.0, 1.0], 1.0, 0.15, Some(1)),
            cylinder([0.15, 0.0, 1.5], [1.0, 0.0, 0.2], 1.0, 0.06, Some(1)),
            cylinder([1.13, 0.0, 1.7], [1.0, 0.0, 0.1], 1.0, 0.05, Some(3)),
            cylinder([1.6, 0.0, 1.75], [0.0, 1.0, 0.5], 0.5, 0.004, Some(4)),
            cylinder([5.0, 5.0, 5.0], [0.0, 0.0, 1.0], 0.3, 0.01, None),
            cylinder([2.12, 0.0, 1.8], [1.0, 0.0, 0.1], 0.4, 0.003, Some(4)),
        ];
        Qsm { cylinders, origin: DVec3::new(100.0, 200.0, 250.0), format: QsmFormat::TreeqsmText }
    }

    #[test]
    fn branches_become_supports_attached_where_they_leave_their_parent() {
        let imported = supports(&model(), &ImportOptions::default()).unwrap();
        assert_eq!((imported.cylinders, imported.thin, imported.fragments), (7, 0, 1));
        let names: Vec<&str> = imported.supports.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["stem", "b1", "b2"]);
        let Shape::Polyline { points, radii } = &imported.supports[0].shape else { panic!("the stem is a polyline") };
        // Up z becomes up y, the base stands on the origin; a point per joint and the top.
        assert_eq!(points.len(), 4);
        assert!(points[0].length() < 1e-6 && (points[3] - Vec3::new(0.0, 3.0, 0.0)).length() < 1e-5, "{points:?}");
        assert_eq!(radii, &[0.2, 0.18, 0.15, 0.15]);
        let Shape::Attached { parent, points, .. } = &imported.supports[1].shape else {
            panic!("the bough is attached")
        };
        assert_eq!(parent, "stem");
        // It starts on the stem's axis at the height its base leaves it, then its base.
        assert!((points[0] - Vec3::new(0.0, 1.5, 0.0)).length() < 1e-5, "{points:?}");
        assert!((points[1] - Vec3::new(0.15, 1.5, 0.0)).length() < 1e-5, "{points:?}");
        let Shape::Attached { parent, .. } = &imported.supports[2].shape else { panic!("the twig is attached") };
        assert_eq!(parent, "b1");
        // They make a tree whose forks know their parents.
        let tree = Tree::build(&imported.supports).unwrap();
        assert_eq!(tree.supports[1].parent, Some(0));
        assert_eq!(tree.supports[2].parent, Some(1));
    }

    #[test]
    fn thin_twigs_are_dropped_and_the_base_can_be_kept() {
        let options = ImportOptions { min_radius_m: 0.005, keep_base: true, ..ImportOptions::default() };
        let imported = supports(&model(), &options).unwrap();
        assert_eq!((imported.cylinders, imported.thin, imported.supports.len()), (5, 2, 2));
        let Shape::Polyline { points, .. } = &imported.supports[0].shape else { panic!("the stem is a polyline") };
        // The model's origin, y up: x 100, height 250, z -200.
        assert!((points[0] - Vec3::new(100.0, 250.0, -200.0)).length() < 1e-3, "{points:?}");
        // Kept to draw: the bough ends where its thin tip begins, the tip and the twig are
        // supports of their own, none of whose radii reaches the least radius.
        let drawn = ImportOptions { min_radius_m: 0.005, draw_thin: true, ..ImportOptions::default() };
        let imported = supports(&model(), &drawn).unwrap();
        assert_eq!((imported.cylinders, imported.thin, imported.supports.len()), (7, 2, 4));
        let radii = |k: usize| match &imported.supports[k].shape {
            Shape::Polyline { radii, .. } | Shape::Attached { radii, .. } => radii.clone(),
            Shape::Fork { .. } => Vec::new(),
        };
        assert_eq!(radii(1), [0.06, 0.06, 0.05, 0.05], "the bough, without its tip");
        for twig in [2, 3] {
            assert!(radii(twig).iter().all(|&r| r < 0.005), "{:?}", radii(twig));
        }
        let too_thick = ImportOptions { min_radius_m: 0.5, ..ImportOptions::default() };
        assert!(supports(&model(), &too_thick).unwrap_err().contains("thinner than min_radius_m"));
    }
}
