//! The source's step rules for a single global constraint (its section 2.3), beside the
//! projection with its halving line search: descent on `f = C^2 / 2`, whose gradient at a
//! movable vertex is `C g_i` (`g` the constraint's gradient), by
//!
//! - [`Rule::Constant`]: a constant step `h`, `x -= h C g`, with `h = 1 / sum w |g|^2` taken
//!   at the start (the step that meets a linear constraint at once) and kept;
//! - [`Rule::Decreasing`]: the same step, multiplied by a factor whenever it would not lower
//!   `|C|`, and kept so from then on;
//! - [`Rule::Steepest`]: steepest descent, the step along `-C g` that brings `|C|` lowest,
//!   found by golden-section search;
//! - [`Rule::Coordinate`]: descent coordinate by coordinate, each vertex's x, y and z in
//!   turn by the constant step, `C` and the vertex's gradient brought up to date after each
//!   from the vertex's own edges or triangles; a sweep that does not lower `|C|` is undone and
//!   the step divided as the decreasing step's is. (Moved alone, one vertex at the step that
//!   suits the whole surface crumples its neighbourhood: the first sweeps are undone until the
//!   step is small enough.)

use super::relative;
use crate::spatial::surface::{Surface, triangle_cross, triangles_at};
use bevy::math::Vec3;

/// One of the source's step rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Rule {
    /// A constant step.
    Constant,
    /// A step divided by a factor when it does not help.
    Decreasing,
    /// The best step along the direction, by line search.
    Steepest,
    /// Coordinate by coordinate.
    Coordinate,
}

/// What the factor of [`Rule::Decreasing`] divides its step by when it does not help.
const DECREASE: f64 = 0.5;

/// Times the decreasing step is divided before an iteration gives up.
const DIVISIONS: u32 = 30;

/// Golden-section iterations of the steepest descent's line search: the bracket shrinks to
/// 0.618^40, about 4e-9, of its width.
const GOLDEN_STEPS: u32 = 40;

/// A single constraint `measure(x) = target` on the whole surface, with what its vertices
/// contribute to it one at a time.
pub(super) trait GlobalConstraint {
    /// The measured quantity.
    fn measure(&self, positions: &[Vec3]) -> f64;
    /// Its gradient at every vertex.
    fn gradient(&self, positions: &[Vec3]) -> Vec<Vec3>;
    /// The part of the measure that moves with vertex `v` (its edges' lengths or its
    /// triangles' area).
    fn around(&self, v: usize, positions: &[Vec3]) -> f64;
    /// The gradient at vertex `v` alone.
    fn gradient_at(&self, v: usize, positions: &[Vec3]) -> Vec3;
}

/// The sum of edge lengths.
pub(super) struct EdgeSum<'a>(pub &'a Surface);

impl GlobalConstraint for EdgeSum<'_> {
    fn measure(&self, positions: &[Vec3]) -> f64 {
        self.0.edge_sum(positions)
    }

    fn gradient(&self, positions: &[Vec3]) -> Vec<Vec3> {
        (0..positions.len()).map(|v| self.gradient_at(v, positions)).collect()
    }

    fn around(&self, v: usize, positions: &[Vec3]) -> f64 {
        self.0.neighbours(v).iter().map(|&n| f64::from(positions[v].distance(positions[n as usize]))).sum()
    }

    /// The sum of the unit vectors from its neighbours to it.
    fn gradient_at(&self, v: usize, positions: &[Vec3]) -> Vec3 {
        self.0.neighbours(v).iter().map(|&n| (positions[v] - positions[n as usize]).normalize_or_zero()).sum()
    }
}

/// The area, with each vertex's triangles.
pub(super) struct Area<'a> {
    surface: &'a Surface,
    /// The triangles at each vertex, by index.
    triangles_of: Vec<Vec<u32>>,
}

impl<'a> Area<'a> {
    pub(super) fn new(surface: &'a Surface) -> Self {
        Self { surface, triangles_of: triangles_at(surface.positions.len(), &surface.triangles) }
    }
}

/// Triangle `t`'s share of the area's gradient at its `corner`-th corner: `1/2 n x (c - b)`
/// for the counter-clockwise triangle `a b c` (`a` that corner) with unit normal `n`.
fn corner_gradient(n: Vec3, t: [u32; 3], corner: usize, positions: &[Vec3]) -> Vec3 {
    let (b, c) = (t[(corner + 1) % 3] as usize, t[(corner + 2) % 3] as usize);
    n.cross(positions[c] - positions[b]) * 0.5
}

impl GlobalConstraint for Area<'_> {
    fn measure(&self, positions: &[Vec3]) -> f64 {
        self.surface.area(positions)
    }

    fn gradient(&self, positions: &[Vec3]) -> Vec<Vec3> {
        let mut gradient = vec![Vec3::ZERO; positions.len()];
        for &t in &self.surface.triangles {
            let n = triangle_cross(positions, t).normalize_or_zero();
            for (corner, v) in t.into_iter().enumerate() {
                gradient[v as usize] += corner_gradient(n, t, corner, positions);
            }
        }
        gradient
    }

    fn around(&self, v: usize, positions: &[Vec3]) -> f64 {
        let triangles = &self.surface.triangles;
        self.triangles_of[v]
            .iter()
            .map(|&t| f64::from(triangle_cross(positions, triangles[t as usize]).length()) * 0.5)
            .sum()
    }

    fn gradient_at(&self, v: usize, positions: &[Vec3]) -> Vec3 {
        self.triangles_of[v]
            .iter()
            .map(|&t| {
                let t = self.surface.triangles[t as usize];
                let corner = t.iter().position(|&c| c as usize == v).unwrap_or(0);
                corner_gradient(triangle_cross(positions, t).normalize_or_zero(), t, corner, positions)
            })
            .sum()
    }
}

/// A descent by one of the source's step rules, with the step it carries from iteration to
/// iteration.
pub(super) struct Descent {
    rule: Rule,
    /// The step `h`, once the first iteration has set it.
    step: Option<f64>,
}

impl Descent {
    /// A descent by `rule`.
    pub(super) fn new(rule: Rule) -> Self {
        Self { rule, step: None }
    }

    /// One iteration towards `constraint = target`, moving the vertices whose inverse mass
    /// `w` is not 0; returns `|C|` over the target at the positions kept.
    pub(super) fn iterate(
        &mut self,
        constraint: &impl GlobalConstraint,
        positions: &mut Vec<Vec3>,
        w: &[f32],
        target: f64,
    ) -> f64 {
        let c = constraint.measure(positions) - target;
        let before = relative(c, target);
        let gradient = constraint.gradient(positions);
        let norm: f64 = gradient.iter().zip(w).map(|(g, &w)| f64::from(w * g.length_squared())).sum();
        if norm == 0.0 {
            return before;
        }
        let h = *self.step.get_or_insert(1.0 / norm);
        // The positions moved by `by` times the descent direction `-C g`.
        let moved = |by: f64| -> Vec<Vec3> {
            let scale = (by * c) as f32;
            positions
                .iter()
                .zip(&gradient)
                .zip(w)
                .map(|((p, g), &w)| if w > 0.0 { *p - *g * (scale * w) } else { *p })
                .collect()
        };
        let error_at = |trial: &[Vec3]| relative(constraint.measure(trial) - target, target);
        match self.rule {
            Rule::Constant => {
                *positions = moved(h);
                error_at(positions)
            }
            Rule::Decreasing => {
                let mut h = h;
                for _ in 0..DIVISIONS {
                    let trial = moved(h);
                    let after = error_at(&trial);
                    if after < before {
                        self.step = Some(h);
                        *positions = trial;
                        return after;
                    }
                    h *= DECREASE;
                }
                self.step = Some(h);
                before
            }
            Rule::Steepest => {
                // |C| along the line is least where C crosses 0, within twice the step that
                // meets a linear constraint.
                let (mut low, mut high) = (0.0, 2.0 / norm);
                let golden = (5f64.sqrt() - 1.0) / 2.0;
                for _ in 0..GOLDEN_STEPS {
                    let (a, b) = (high - golden * (high - low), low + golden * (high - low));
                    if error_at(&moved(a)) < error_at(&moved(b)) {
                        high = b;
                    } else {
                        low = a;
                    }
                }
                let trial = moved((low + high) / 2.0);
                let after = error_at(&trial);
                if after < before {
                    *positions = trial;
                    return after;
                }
                before
            }
            Rule::Coordinate => {
                let kept = positions.clone();
                let mut c = c;
                for v in (0..positions.len()).filter(|&v| w[v] > 0.0) {
                    for axis in 0..3 {
                        let slope = f64::from(constraint.gradient_at(v, positions)[axis]);
                        let own = constraint.around(v, positions);
                        positions[v][axis] -= (h * c * slope * f64::from(w[v])) as f32;
                        c += constraint.around(v, positions) - own;
                    }
                }
                let after = error_at(positions);
                if after < before {
                    return after;
                }
                // A sweep that did not help is undone, and the next one takes half the step.
                *positions = kept;
                self.step = Some(h * DECREASE);
                before
            }
        }
    }
}
