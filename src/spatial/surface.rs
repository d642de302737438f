//! A triangle surface as the deformers see it: positions and index triples, with the edges
//! (unique undirected pairs) and each vertex's neighbours derived once, and the measurable
//! facts a deformation is judged by.

use bevy::math::{DVec3, Vec3};

/// Why a surface cannot be deformed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// A position is not a finite number.
    #[error("vertex {0} has a position that is not a finite number")]
    NotFinite(usize),
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} names vertex {vertex}, but there are {count} vertices")]
    IndexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// The index it names.
        vertex: u32,
        /// Vertices there are.
        count: usize,
    },
    /// The movable mask does not have one entry per vertex.
    #[error("the movable mask has {mask} entries for {count} vertices")]
    MaskLength {
        /// Entries in the mask.
        mask: usize,
        /// Vertices there are.
        count: usize,
    },
}

/// A triangle surface, its edges and adjacency, and which vertices may move.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Vertex positions, metres.
    pub positions: Vec<Vec3>,
    /// Counter-clockwise index triples.
    pub triangles: Vec<[u32; 3]>,
    /// Whether each vertex may move (the region's border and everything outside it may not).
    pub movable: Vec<bool>,
    /// Unique undirected edges, the lower index first, sorted.
    edges: Vec<[u32; 2]>,
    /// Each vertex's neighbours: `neighbours[first[v]..first[v + 1]]`.
    first: Vec<u32>,
    neighbours: Vec<u32>,
}

impl Surface {
    /// A surface of `positions` and `triangles` in which the vertices `movable` says may move;
    /// degenerate triangles (a vertex twice) give no edges between equal indices.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, movable: Vec<bool>) -> Result<Self, SurfaceError> {
        let count = positions.len();
        if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
            return Err(SurfaceError::NotFinite(bad));
        }
        for (triangle, corners) in triangles.iter().enumerate() {
            if let Some(&vertex) = corners.iter().find(|&&v| v as usize >= count) {
                return Err(SurfaceError::IndexOutOfRange { triangle, vertex, count });
            }
        }
        if movable.len() != count {
            return Err(SurfaceError::MaskLength { mask: movable.len(), count });
        }
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .filter(|[a, b]| a != b)
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        // Neighbour lists in compressed rows, from the edges.
        let mut first = vec![0u32; count + 1];
        for &[a, b] in &edges {
            first[a as usize + 1] += 1;
            first[b as usize + 1] += 1;
        }
        for v in 0..count {
            first[v + 1] += first[v];
        }
        let mut filled = first.clone();
        let mut neighbours = vec![0u32; 2 * edges.len()];
        for &[a, b] in &edges {
            for (from, to) in [(a, b), (b, a)] {
                neighbours[filled[from as usize] as usize] = to;
                filled[from as usize] += 1;
            }
        }
        Ok(Self { positions, triangles, movable, edges, first, neighbours })
    }

    /// The same surface with its vertices at `positions` (one per vertex, finite): a
    /// deformed copy keeps the topology derived once.
    pub fn with_positions(&self, positions: Vec<Vec3>) -> Self {
        assert_eq!(positions.len(), self.positions.len(), "one position per vertex");
        Self {
            positions,
            triangles: self.triangles.clone(),
            movable: self.movable.clone(),
            edges: self.edges.clone(),
            first: self.first.clone(),
            neighbours: self.neighbours.clone(),
        }
    }

    /// The box holding every vertex: (min, max), metres.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let far = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        self.positions.iter().fold(far, |(low, high), &p| (low.min(p), high.max(p)))
    }

    /// The unique undirected edges, the lower index first.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// The neighbours of vertex `v`.
    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.neighbours[self.first[v] as usize..self.first[v + 1] as usize]
    }

    /// The sum of the edges' lengths at `positions` (one per vertex), metres.
    pub fn edge_sum(&self, positions: &[Vec3]) -> f64 {
        self.edges.iter().map(|&[a, b]| f64::from(positions[a as usize].distance(positions[b as usize]))).sum()
    }

    /// The surface's area at `positions`, square metres.
    pub fn area(&self, positions: &[Vec3]) -> f64 {
        self.triangles.iter().map(|&t| f64::from(triangle_cross(positions, t).length()) * 0.5).sum()
    }

    /// The net volume between the surface at `before` and at `after`, cubic metres, where its
    /// border is the same in both: the two then close a solid (or several), whose volume is the
    /// difference of their cones from any point by the divergence theorem. What a shrink of a
    /// region with its outline held removes; parts moved outwards count against parts moved in.
    pub fn volume_between(&self, before: &[Vec3], after: &[Vec3]) -> f64 {
        let origin = before.first().map_or(DVec3::ZERO, |p| p.as_dvec3());
        let cone = |positions: &[Vec3]| -> f64 {
            self.triangles
                .iter()
                .map(|&[a, b, c]| {
                    let [a, b, c] = [a, b, c].map(|v| positions[v as usize].as_dvec3() - origin);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum()
        };
        (cone(before) - cone(after)).abs()
    }
}

/// The triangles at each of `vertices` vertices, by their index in `triangles` (a corner
/// beyond the vertices is left out).
pub fn triangles_at(vertices: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut at = vec![Vec::new(); vertices];
    for (t, triangle) in triangles.iter().enumerate() {
        for &v in triangle {
            if let Some(list) = at.get_mut(v as usize) {
                list.push(t as u32);
            }
        }
    }
    at
}

/// Twice the area vector of triangle `t` at `positions`: its normal times twice its area.
pub fn triangle_cross(positions: &[Vec3], [a, b, c]: [u32; 3]) -> Vec3 {
    let [a, b, c] = [a, b, c].map(|v| positions[v as usize]);
    (b - a).cross(c - a)
}

/// What a deformation did, by measurable facts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Facts {
    /// Every fixed vertex kept its position bit for bit.
    pub fixed_unchanged: bool,
    /// The largest relative error of an edge's length against `k` times its length before,
    /// over the edges with an end that may move.
    pub max_edge_error: f64,
    /// The mean of those errors.
    pub mean_edge_error: f64,
    /// The sum of edge lengths after, over that before.
    pub edge_sum_ratio: f64,
    /// The area after, over that before.
    pub area_ratio: f64,
    /// Some position is not a finite number.
    pub has_nan: bool,
    /// Triangles whose normal turned against the one they had.
    pub inverted: usize,
    /// The net volume between the surface before and after, cubic metres (see
    /// [`Surface::volume_between`]; meaningful while the fixed vertices are held).
    pub volume_between_m3: f64,
}

impl Facts {
    /// The facts of `after` (one position per vertex of `surface`, whose own positions are
    /// those before) for the coefficient `k`.
    pub fn of(surface: &Surface, after: &[Vec3], k: f32) -> Self {
        let before = &surface.positions;
        let fixed_unchanged = before
            .iter()
            .zip(after)
            .zip(&surface.movable)
            .all(|((p, q), &movable)| movable || p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits));
        let errors: Vec<f64> = surface
            .edges
            .iter()
            .filter(|&&[a, b]| surface.movable[a as usize] || surface.movable[b as usize])
            .filter_map(|&[a, b]| {
                let (a, b) = (a as usize, b as usize);
                let rest = f64::from(k) * f64::from(before[a].distance(before[b]));
                (rest > 0.0).then(|| (f64::from(after[a].distance(after[b])) / rest - 1.0).abs())
            })
            .collect();
        let ratio = |after: f64, before: f64| if before > 0.0 { after / before } else { 1.0 };
        Self {
            fixed_unchanged,
            max_edge_error: errors.iter().copied().fold(0.0, f64::max),
            mean_edge_error: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
            edge_sum_ratio: ratio(surface.edge_sum(after), surface.edge_sum(before)),
            area_ratio: ratio(surface.area(after), surface.area(before)),
            has_nan: after.iter().any(|p| !p.is_finite()),
            inverted: surface
                .triangles
                .iter()
                .filter(|&&t| triangle_cross(before, t).dot(triangle_cross(after, t)) < 0.0)
                .count(),
            volume_between_m3: surface.volume_between(before, after),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing the edge 1-2: a unit square split along its diagonal.
    fn square() -> Surface {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(1.0, 0.0, 1.0)];
        Surface::new(positions, vec![[0, 2, 1], [1, 2, 3]], vec![true; 4]).unwrap()
    }

    #[test]
    fn edges_and_neighbours_are_derived_once_and_unique() {
        let square = square();
        assert_eq!(square.edges(), &[[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]);
        assert_eq!(square.neighbours(1), &[0, 2, 3]);
        assert_eq!(square.neighbours(3), &[1, 2]);
        assert!((square.area(&square.positions) - 1.0).abs() < 1e-9);
        assert!((square.edge_sum(&square.positions) - (4.0 + 2f64.sqrt())).abs() < 1e-6);
    }

    #[test]
    fn bad_surfaces_are_refused() {
        let nan = Surface::new(vec![Vec3::ZERO, Vec3::NAN, Vec3::X], vec![[0, 1, 2]], vec![true; 3]);
        assert_eq!(nan.unwrap_err(), SurfaceError::NotFinite(1));
        let out = Surface::new(vec![Vec3::ZERO, Vec3::Y, Vec3::X], vec![[0, 1, 3]], vec![true; 3]);
        assert_eq!(out.unwrap_err(), SurfaceError::IndexOutOfRange { triangle: 0, vertex: 3, count: 3 });
        let mask = Surface::new(vec![Vec3::ZERO, Vec3::Y, Vec3::X], vec![[0, 1, 2]], vec![true; 2]);
        assert_eq!(mask.unwrap_err(), SurfaceError::MaskLength { mask: 2, count: 3 });
    }

    #[test]
    fn facts_see_a_uniform_shrink_and_a_flipped_triangle() {
        let square = square();
        let half: Vec<Vec3> = square.positions.iter().map(|p| *p * 0.5).collect();
        let facts = Facts::of(&square, &half, 0.5);
        assert!(facts.max_edge_error < 1e-6 && (facts.area_ratio - 0.25).abs() < 1e-6);
        assert!((facts.edge_sum_ratio - 0.5).abs() < 1e-6);
        assert!(facts.fixed_unchanged, "nothing is fixed");
        let mut pinned = square.clone();
        pinned.movable[0] = false;
        let lifted: Vec<Vec3> = square.positions.iter().map(|p| *p + Vec3::Y).collect();
        assert!(!Facts::of(&pinned, &lifted, 1.0).fixed_unchanged, "vertex 0 is fixed and moved");
        assert!(Facts::of(&pinned, &pinned.positions, 1.0).fixed_unchanged);
        let mut flipped = square.positions.clone();
        flipped[3] = Vec3::new(-1.0, 0.0, -1.0);
        assert_eq!(Facts::of(&square, &flipped, 1.0).inverted, 1);
    }

    #[test]
    fn the_volume_between_a_patch_and_its_pressed_centre_is_a_pyramid() {
        // A unit square of four triangles round its centre, the centre pressed 0.3 m down: a
        // pyramid of base 1 and height 0.3 lies between, 0.1 cubic metres.
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z, Vec3::new(0.5, 0.0, 0.5)];
        let triangles = vec![[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]];
        let movable = vec![false, false, false, false, true];
        let patch = Surface::new(positions.clone(), triangles, movable).unwrap();
        let mut pressed = positions.clone();
        pressed[4].y -= 0.3;
        let facts = Facts::of(&patch, &pressed, 1.0);
        assert!((facts.volume_between_m3 - 0.1).abs() < 1e-6, "{}", facts.volume_between_m3);
        // Wherever the patch lies.
        let moved = |p: &Vec3| *p + Vec3::new(40.0, -7.0, 3.0);
        let (far, far_pressed): (Vec<Vec3>, Vec<Vec3>) =
            (positions.iter().map(moved).collect(), pressed.iter().map(moved).collect());
        assert!((patch.volume_between(&far, &far_pressed) - 0.1).abs() < 1e-6);
        assert_eq!(patch.volume_between(&positions, &positions), 0.0);
    }
}
