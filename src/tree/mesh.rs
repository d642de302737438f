//! The render mesh of a tree, each support a tube around its polyline
//! ([`add_tube`](crate::spatial::tube::add_tube)), and its coarser levels: a support seen a few
//! pixels thick needs few sides and barely rounded tips, and a twig under a pixel three
//! sides and pointed ones.

use super::model::{Support, Tree};
use crate::raster::MeshData;
use crate::raster::levels::MeshLevels;
use crate::spatial::polyline::simplified;
use crate::spatial::tube::{TIP_RINGS, add_tube, add_tube_with_tips, tip_rings, tube_triangles};
use bevy::math::Vec3;
use std::f32::consts::PI;
use std::sync::Arc;

/// The most pixels a metre may span where each coarser level is drawn, finest first.
const LEVEL_PIXELS_PER_METRE: [f32; 5] = [1024.0, 256.0, 64.0, 16.0, 4.0];

/// How far a coarser level's surface may lie from the full mesh's where it is drawn, pixels.
const LEVEL_TOLERANCE_PX: f32 = 0.5;

/// A coarser level is kept only if it has at most this share of the triangles of the level
/// before it.
const LEVEL_SAVING: f32 = 0.8;

/// Most triangles a cluster of supports holds at full detail, unless one support alone has
/// more: small enough that the parts of a large tree out of view are skipped and those far off
/// drawn coarser, large enough that a small tree is one cluster.
const CLUSTER_TRIANGLES: usize = 4_096;

/// A group of a tree's supports drawn as one mesh, with its coarser levels.
#[derive(Debug, Clone)]
pub struct TreeCluster {
    /// The supports' tubes at full detail.
    pub mesh: MeshData,
    /// Its coarser levels.
    pub levels: MeshLevels,
}

/// The mesh of every support of `tree`, `sides` vertices around each ring (at least 3).
pub fn tree_mesh(tree: &Tree, sides: usize) -> MeshData {
    let supports: Vec<&Support> = tree.supports.iter().collect();
    supports_mesh(&supports, sides)
}

/// `tree`'s supports in clusters of neighbours, each at most [`CLUSTER_TRIANGLES`] at full
/// detail (`sides` vertices around each ring), with their coarser levels.
pub fn tree_clusters(tree: &Tree, sides: usize) -> Vec<TreeCluster> {
    let mut groups = Vec::new();
    split(tree.supports.iter().collect(), sides.max(3), &mut groups);
    groups
        .into_iter()
        .map(|supports| {
            let mesh = supports_mesh(&supports, sides);
            let levels = supports_levels(&supports, sides, mesh.triangles.len());
            TreeCluster { mesh, levels }
        })
        .collect()
}

/// Splits `supports` in two about the middle of their triangles along the longest side of
/// their centres' box, again and again, until each group is small enough; the groups go to
/// `groups`.
fn split<'a>(mut supports: Vec<&'a Support>, sides: usize, groups: &mut Vec<Vec<&'a Support>>) {
    let weight = |s: &Support| tube_triangles(s.points.len(), sides, TIP_RINGS);
    let total: usize = supports.iter().map(|s| weight(s)).sum();
    if total <= CLUSTER_TRIANGLES || supports.len() < 2 {
        groups.push(supports);
        return;
    }
    let centre = |s: &Support| s.points.iter().copied().sum::<Vec3>() / s.points.len() as f32;
    let (low, high) =
        supports.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), s| (l.min(centre(s)), h.max(centre(s))));
    let extent = high - low;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    supports.sort_by(|a, b| centre(a)[axis].total_cmp(&centre(b)[axis]));
    let mut running = 0;
    let half = supports.iter().position(|s| {
        running += weight(s);
        2 * running >= total
    });
    let at = half.map_or(1, |i| i + 1).clamp(1, supports.len() - 1);
    let upper = supports.split_off(at);
    split(supports, sides, groups);
    split(upper, sides, groups);
}

/// The tubes of `supports`, `sides` vertices around each ring (at least 3).
fn supports_mesh(supports: &[&Support], sides: usize) -> MeshData {
    let mut mesh = MeshData::default();
    for support in supports {
        add_tube(&mut mesh, &support.points, &support.radii, sides.max(3));
    }
    mesh
}

/// The coarser levels of [`supports_mesh`]`(supports, sides)`, which has `full_triangles`: at
/// each of
/// [`LEVEL_PIXELS_PER_METRE`], every support with as few sides and tip rings as keep its
/// thickest ring within [`LEVEL_TOLERANCE_PX`] of round, and without the points of its axis
/// that lie as near the line through the points on either side; a level that saves too
/// little is left out.
fn supports_levels(supports: &[&Support], sides: usize, full_triangles: usize) -> MeshLevels {
    let sides = sides.max(3);
    let mut levels: Vec<(f32, Arc<MeshData>)> = Vec::new();
    let mut before = full_triangles;
    for pixels_per_metre in LEVEL_PIXELS_PER_METRE {
        let tolerance = LEVEL_TOLERANCE_PX / pixels_per_metre;
        let mut mesh = MeshData::default();
        for support in supports {
            let radius = support.radii.iter().copied().fold(0.0, f32::max);
            let (points, radii) = simplified(&support.points, &support.radii, tolerance);
            let tip = tip_rings(radius, tolerance);
            add_tube_with_tips(&mut mesh, &points, &radii, sides_within(radius, tolerance, sides), tip);
        }
        if (mesh.triangles.len() as f32) <= LEVEL_SAVING * before as f32 {
            before = mesh.triangles.len();
            levels.push((pixels_per_metre, Arc::new(mesh)));
        }
    }
    MeshLevels { bounds: bounds(supports), levels }
}

/// The fewest sides, from 3 to `most`, of a polygon within `tolerance` of a circle of
/// `radius` (its sagitta, `radius (1 - cos(pi / sides))`, at most the tolerance).
fn sides_within(radius: f32, tolerance: f32, most: usize) -> usize {
    if radius <= tolerance {
        return 3;
    }
    ((PI / (1.0 - tolerance / radius).acos()).ceil() as usize).clamp(3, most)
}

/// A sphere holding `supports`, tips included: the centre of their box and the farthest
/// surface from it.
fn bounds(supports: &[&Support]) -> (Vec3, f32) {
    let points = supports.iter().flat_map(|s| s.points.iter().zip(&s.radii));
    let (low, high) =
        points.clone().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(low, high), (p, _)| (low.min(*p), high.max(*p)));
    let centre = (low + high) * 0.5;
    (centre, points.map(|(p, r)| p.distance(centre) + r).fold(0.0, f32::max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::model::{Shape, SupportSpec, Tree};
    use bevy::math::Vec3;

    fn bent_tree() -> Tree {
        let spec = SupportSpec {
            name: "bough".into(),
            shape: Shape::Polyline {
                points: vec![Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.8, 1.6, 0.2), Vec3::new(1.5, 1.7, 0.9)],
                radii: vec![0.2, 0.15, 0.1, 0.05],
            },
            kind: None,
        };
        Tree::build(&[spec]).unwrap()
    }

    #[test]
    fn faces_point_outwards_and_normals_are_unit() {
        let tree = bent_tree();
        let mesh = tree_mesh(&tree, 12);
        for n in &mesh.normals {
            assert!((n.length() - 1.0).abs() < 1e-4);
        }
        let mut faces = 0;
        for &[a, b, c] in &mesh.triangles {
            let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
            let face = (pb - pa).cross(pc - pa);
            if face.length() < 1e-9 {
                continue; // the degenerate fans at the poles
            }
            let mean = mesh.normals[a as usize] + mesh.normals[b as usize] + mesh.normals[c as usize];
            assert!(face.dot(mean) > 0.0, "triangle {a} {b} {c} faces inwards");
            faces += 1;
        }
        assert!(faces > 100);
    }

    #[test]
    fn coarser_levels_keep_the_surface_within_their_tolerance_and_save_triangles() {
        let tree = bent_tree();
        let mut clusters = tree_clusters(&tree, 12);
        assert_eq!(clusters.len(), 1, "a small tree is one cluster");
        let TreeCluster { mesh: full, levels } = clusters.remove(0);
        assert_eq!(full, tree_mesh(&tree, 12));
        assert_eq!(tube_triangles(4, 12, TIP_RINGS), full.triangles.len(), "the count the clusters weigh by");
        let segments: Vec<_> = tree.segments().map(|(_, s)| s).collect();
        let mut before = full.triangles.len();
        assert!(!levels.levels.is_empty());
        for (pixels_per_metre, mesh) in &levels.levels {
            assert!((mesh.triangles.len() as f32) <= LEVEL_SAVING * before as f32);
            before = mesh.triangles.len();
            // Every vertex on the round surface (flat sides meet it at their corners), and the
            // middle of every side within the level's tolerance of it.
            let tolerance = LEVEL_TOLERANCE_PX / pixels_per_metre;
            let off = |p: Vec3| segments.iter().map(|s| s.closest(p).distance).fold(f32::INFINITY, f32::min);
            for &[a, b, _] in &mesh.triangles {
                let [pa, pb] = [a, b].map(|i| mesh.positions[i as usize]);
                assert!(off(pa).abs() < 0.02, "a vertex {} m off", off(pa));
                assert!(
                    off((pa + pb) * 0.5) > -tolerance - 0.02,
                    "a side {} m inside at {pixels_per_metre} px/m",
                    -off((pa + pb) * 0.5)
                );
            }
        }
        // The bounds hold every vertex of the full mesh.
        let (centre, radius) = levels.bounds;
        assert!(full.positions.iter().all(|p| p.distance(centre) <= radius + 1e-4));
        // The thinnest rings keep three sides; a thick one seen large keeps all twelve.
        assert_eq!(sides_within(0.01, 0.05, 12), 3);
        assert_eq!(sides_within(0.2, 0.0005, 12), 12);
        assert_eq!(tip_rings(0.2, 0.1), 0);
        assert_eq!(tip_rings(0.2, 0.001), 3);
    }

    #[test]
    fn a_large_tree_splits_into_clusters_of_neighbours_that_hold_every_support_once() {
        // Two hundred twigs of ten points in a row, 12 sides: about 200 x 456 triangles.
        let specs: Vec<SupportSpec> = (0..200)
            .map(|i| SupportSpec {
                name: format!("t{i}"),
                shape: Shape::Polyline {
                    points: (0..10).map(|k| Vec3::new(i as f32, k as f32 * 0.1, 0.0)).collect(),
                    radii: vec![0.02; 10],
                },
                kind: None,
            })
            .collect();
        let tree = Tree::build(&specs).unwrap();
        let clusters = tree_clusters(&tree, 12);
        let counts: Vec<usize> = clusters.iter().map(|c| c.mesh.triangles.len()).collect();
        assert!(clusters.len() >= 3 && counts.iter().all(|&n| n <= CLUSTER_TRIANGLES), "{counts:?}");
        assert_eq!(counts.iter().sum::<usize>(), tree_mesh(&tree, 12).triangles.len());
        // Neighbours: each cluster's bounds are a stretch of the row, not the whole of it.
        assert!(
            clusters.iter().all(|c| c.levels.bounds.1 < 0.75 * 100.0),
            "{:?}",
            clusters.iter().map(|c| c.levels.bounds).collect::<Vec<_>>()
        );
    }

    #[test]
    fn the_surface_matches_the_query_geometry() {
        // Every vertex lies on the surface the geometry queries use, to within the error of
        // a straight tube against the round cone between rings.
        let tree = bent_tree();
        let mesh = tree_mesh(&tree, 16);
        let segments: Vec<_> = tree.segments().map(|(_, s)| s).collect();
        for (p, normal) in mesh.positions.iter().zip(&mesh.normals) {
            let nearest =
                segments.iter().map(|s| s.closest(*p)).min_by(|a, b| a.distance.total_cmp(&b.distance)).unwrap();
            assert!(nearest.distance.abs() < 0.02, "{p} is {} m off the surface", nearest.distance);
            // Normals point out of the surface, as the geometry's do.
            assert!(normal.dot(nearest.normal) > 0.7, "normal {normal} at {p}, surface normal {}", nearest.normal);
        }
    }
}
