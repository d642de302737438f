//! The surface deformers: each shrinks the movable part of a [`Surface`] towards `k` times its
//! size while the fixed vertices stay where they are, bit for bit, and reports how many
//! iterations it took, the error it ended with and why it stopped. None loops forever.
//!
//! - [`Method::EdgeLengths`]: every edge its own length constraint, `d_e = k |p1 - p2|`,
//!   projected in turn as in position-based dynamics (Mueller et al. 2006); the error is the
//!   sum of the shifts' lengths in an iteration. With vertices fixed the constraints cannot
//!   all be met and the error tends to a bound above zero: it stops when the error has
//!   settled ([`Stop::Settled`]). Over-relaxing the projections does not help: it settles
//!   higher, or never, and folds triangles.
//! - [`Method::EdgeSum`]: one constraint on the sum of edge lengths, `C = sum |e| - k sum |e0|`,
//!   whose gradient at a vertex is the sum of the unit vectors from its neighbours. The
//!   projection of that one constraint moves vertex `i` by `-w_i C n_i / sum_j w_j |n_j|^2`;
//!   the source's variant moves it by `-C n_i / (its neighbour count)`, which can overshoot.
//!   Stops when `|C| < eps k sum |e0|`.
//! - [`Method::Area`]: one constraint on the area, `C = area - k area0` (`0 < k < 1`), projected
//!   along the area's gradient (per triangle `1/2 n x (c - b)` at `a`). Stops when
//!   `|C| < eps k area0`. The source's variant is not the gradient: it draws every edge's ends
//!   together along the edge, by `C` over the current area (a quarter of that each, so that
//!   a shrink of every edge by `C / 2A` would remove `C` from a flat surface), and applies the
//!   same shift again while `C` keeps falling by more than the shift's error (the sum of its
//!   squared lengths) times `eps`. Its pseudocode has the shift's sign reversed, which would
//!   grow the surface; this follows its intent, a shrink.
//!
//! Neither global constraint is linear: their projections search back along the step (halving
//! it while `|C|` does not fall), where the source's edge-sum step goes as it is.

mod descent;

use crate::spatial::surface::Surface;
use bevy::math::Vec3;
use descent::{Area, Descent, EdgeSum, GlobalConstraint, Rule};

/// Which deformer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// A length constraint per edge.
    EdgeLengths,
    /// One constraint on the sum of edge lengths.
    EdgeSum(Variant),
    /// One constraint on the surface's area.
    Area(Variant),
}

/// How a single global constraint is stepped: by its projection (with a halving line
/// search), by the source program's own step, or by one of the step rules of the source's
/// theory (see [`descent`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, bevy::reflect::Reflect)]
#[serde(rename_all = "snake_case")]
pub enum Variant {
    /// The projection of the constraint, its step halved while `|C|` does not fall.
    Projection,
    /// The source's step: for the edge sum, each vertex by `C` over its neighbour count along
    /// the gradient; for the area, every edge's ends drawn together along it.
    Source,
    /// Descent on `C^2 / 2` by a constant step.
    Constant,
    /// Descent by a step divided by a factor whenever it does not lower `|C|`.
    Decreasing,
    /// Steepest descent: the best step along the gradient, by line search.
    Steepest,
    /// Descent coordinate by coordinate.
    Coordinate,
}

impl Variant {
    /// Every variant, in the panel's order.
    pub const ALL: [Variant; 6] = [
        Variant::Projection,
        Variant::Source,
        Variant::Constant,
        Variant::Decreasing,
        Variant::Steepest,
        Variant::Coordinate,
    ];

    /// Its name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Projection => "projection",
            Variant::Source => "source",
            Variant::Constant => "constant",
            Variant::Decreasing => "decreasing",
            Variant::Steepest => "steepest",
            Variant::Coordinate => "coordinate",
        }
    }

    /// Its name in the panel.
    pub fn label(self) -> &'static str {
        match self {
            Variant::Source => "source's step",
            Variant::Decreasing => "decreasing step",
            Variant::Steepest => "steepest descent",
            Variant::Coordinate => "by coordinate",
            other => other.name(),
        }
    }

    /// The step rule of the source's theory it is, if it is one.
    fn rule(self) -> Option<Rule> {
        match self {
            Variant::Projection | Variant::Source => None,
            Variant::Constant => Some(Rule::Constant),
            Variant::Decreasing => Some(Rule::Decreasing),
            Variant::Steepest => Some(Rule::Steepest),
            Variant::Coordinate => Some(Rule::Coordinate),
        }
    }
}

/// How far to go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The coefficient: the movable part's edges or area become `k` times what they were; in
    /// `(0, 1]` (the area method needs `k < 1`), and 1 changes nothing.
    pub k: f32,
    /// The convergence threshold: metres of shift for the edge lengths, a share of the
    /// target for the global constraints.
    pub eps: f64,
    /// Iterations at most.
    pub max_iterations: u32,
}

/// Why a deformer stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// The error fell below the threshold.
    Converged,
    /// The error stopped falling.
    Stalled,
    /// The per-edge constraints' error, which the fixed vertices keep above zero (they
    /// cannot all be met), fell by less than [`SETTLED`] of itself over the last iterations:
    /// it has come near the bound they put on it.
    Settled,
    /// The iteration cap was reached.
    Cap,
}

/// What a deformer did.
#[derive(Debug, Clone, PartialEq)]
pub struct Deformed {
    /// The new positions, one per vertex: those of the iteration with the least error.
    pub positions: Vec<Vec3>,
    /// Iterations used.
    pub iterations: u32,
    /// The least error reached: metres of shift in an iteration for the edge lengths, the
    /// constraint's `|C|` over its target for the global ones.
    pub error: f64,
    /// Why it stopped.
    pub stop: Stop,
}

/// Why settings make no sense.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// `k` is outside the range the method allows.
    #[error("expected k greater than 0 and at most 1 (below 1 for the area method), found {0}")]
    K(f32),
    /// The threshold is not a positive number.
    #[error("expected a convergence threshold greater than 0, found {0}")]
    Eps(f64),
}

impl Settings {
    /// Why these settings cannot drive `method`, if they cannot.
    pub fn check(&self, method: Method) -> Result<(), SettingsError> {
        let below = if matches!(method, Method::Area(_)) { self.k < 1.0 } else { self.k <= 1.0 };
        if !(self.k > 0.0 && below) {
            return Err(SettingsError::K(self.k));
        }
        if !(self.eps.is_finite() && self.eps > 0.0) {
            return Err(SettingsError::Eps(self.eps));
        }
        Ok(())
    }
}

/// One iteration of a deformer on the positions; returns its error.
trait Step: FnMut(&mut Vec<Vec3>) -> f64 {}
impl<F: FnMut(&mut Vec<Vec3>) -> f64> Step for F {}

/// Deforms `surface` by `method` with `settings` (checked with [`Settings::check`]).
pub fn deform(surface: &Surface, method: Method, settings: Settings) -> Deformed {
    let mut positions = surface.positions.clone();
    let mut stepper: Box<dyn Step + '_> = match method {
        Method::EdgeLengths => Box::new(edge_lengths(surface, settings.k)),
        Method::EdgeSum(variant) => Box::new(edge_sum(surface, settings.k, variant)),
        Method::Area(Variant::Source) => Box::new(area_by_edges(surface, settings.k, settings.eps)),
        Method::Area(variant) => Box::new(area(surface, settings.k, variant)),
    };
    // The positions with the least error so far: a solver that stalls, or whose steps run
    // away (the source's edge-sum step can), returns those.
    let (mut best, mut best_error, mut since_best) = (positions.clone(), f64::INFINITY, 0);
    let patience = PATIENCE.max((surface.positions.len() as f64).sqrt() as u32);
    // The per-edge error over the last `patience` iterations, to tell when it has settled.
    let settles = method == Method::EdgeLengths;
    let mut recent = std::collections::VecDeque::with_capacity(patience as usize + 1);
    for iteration in 1..=settings.max_iterations {
        let error = stepper(&mut positions);
        if settles {
            recent.push_back(error);
        }
        let settled = recent.len() > patience as usize
            && recent.pop_front().is_some_and(|earlier| earlier - error < SETTLED * error);
        let finite = error.is_finite() && positions.iter().all(|p| p.is_finite());
        if finite && error < best_error {
            best.clone_from(&positions);
            (best_error, since_best) = (error, 0);
        } else {
            since_best += 1;
        }
        let stop = if finite && error < settings.eps {
            Some(Stop::Converged)
        } else if !finite || since_best >= patience {
            Some(Stop::Stalled)
        } else if settled {
            Some(Stop::Settled)
        } else {
            None
        };
        if let Some(stop) = stop {
            return Deformed { positions: best, iterations: iteration, error: best_error, stop };
        }
    }
    Deformed { positions: best, iterations: settings.max_iterations, error: best_error, stop: Stop::Cap }
}

/// Iterations without a new least error after which a deformer has stalled, at least: the
/// per-edge projections' error does not fall every iteration on its way down, and rises for a
/// while as corrections cross the surface, which takes about as many iterations as it is edges
/// across (the square root of its vertex count, when that is more).
const PATIENCE: u32 = 32;

/// The share of itself by which the per-edge error must fall over `patience` iterations not to
/// have settled. On the belly patch of 33 x 33 vertices at k = 0.97 that is after 2,876
/// iterations, 8 % above the error it tends to (docs/performance.md has the figures).
pub const SETTLED: f64 = 1e-3;

/// The inverse masses: 1 for a vertex that may move, 0 for a fixed one.
fn weights(surface: &Surface) -> Vec<f32> {
    surface.movable.iter().map(|&movable| f32::from(u8::from(movable))).collect()
}

/// An edge's length constraint, ready for the inner loop: its ends, rest length and each
/// end's share of a correction (its weight over the two weights).
#[derive(Debug, Clone, Copy)]
struct EdgeConstraint {
    a: u32,
    b: u32,
    rest: f32,
    share: [f32; 2],
}

/// One iteration of the per-edge constraints: every edge projected onto its rest length in
/// turn (in the edges' sorted order, so that neighbouring constraints touch neighbouring
/// memory); returns the sum of the shifts' lengths.
fn edge_lengths(surface: &Surface, k: f32) -> impl FnMut(&mut Vec<Vec3>) -> f64 + '_ {
    let w = weights(surface);
    // Edges with both ends fixed can do nothing: they are left out.
    let constraints: Vec<EdgeConstraint> = surface
        .edges()
        .iter()
        .filter(|&&[a, b]| w[a as usize] + w[b as usize] > 0.0)
        .map(|&[a, b]| {
            let (wa, wb) = (w[a as usize], w[b as usize]);
            let rest = k * surface.positions[a as usize].distance(surface.positions[b as usize]);
            EdgeConstraint { a, b, rest, share: [wa / (wa + wb), wb / (wa + wb)] }
        })
        .collect();
    move |positions| {
        let mut shifted = 0.0;
        for edge in &constraints {
            let (a, b) = (edge.a as usize, edge.b as usize);
            let delta = positions[a] - positions[b];
            let length = delta.length();
            if length == 0.0 {
                continue;
            }
            let c = length - edge.rest;
            let correction = delta * (c / length);
            // A fixed end has no share: it is not written at all, so it keeps its bits.
            if edge.share[0] > 0.0 {
                positions[a] -= correction * edge.share[0];
            }
            if edge.share[1] > 0.0 {
                positions[b] += correction * edge.share[1];
            }
            // The two shifts' lengths add up to the constraint's error.
            shifted += f64::from(c.abs());
        }
        shifted
    }
}

/// One step of the edge-sum constraint; returns `|C|` over its target.
fn edge_sum(surface: &Surface, k: f32, variant: Variant) -> impl FnMut(&mut Vec<Vec3>) -> f64 + '_ {
    let w = weights(surface);
    let constraint = EdgeSum(surface);
    let target = f64::from(k) * constraint.measure(&surface.positions);
    let mut descent = variant.rule().map(Descent::new);
    move |positions| match (&mut descent, variant) {
        (Some(descent), _) => descent.iterate(&constraint, positions, &w, target),
        (None, Variant::Source) => {
            let gradient = constraint.gradient(positions);
            let c = constraint.measure(positions) - target;
            for (v, p) in positions.iter_mut().enumerate() {
                if w[v] > 0.0 {
                    *p -= gradient[v] * (c / surface.neighbours(v).len().max(1) as f64) as f32;
                }
            }
            relative(constraint.measure(positions) - target, target)
        }
        (None, _) => project(positions, &constraint, &w, target),
    }
}

/// A constraint's error `difference` (its value less its `target`) over the target.
fn relative(difference: f64, target: f64) -> f64 {
    difference.abs() / target.max(f64::MIN_POSITIVE)
}

/// Step halvings a projection's line search tries before it gives the step up.
const HALVINGS: u32 = 30;

/// Projects `constraint = target` with inverse masses `w`: every vertex moved by
/// `-w_i C g_i / sum_j w_j |g_j|^2` (`g` the constraint's gradient), the step halved while the
/// constraint's relative error does not fall, as the constraint is not linear. Returns that
/// error at the positions kept.
fn project(positions: &mut Vec<Vec3>, constraint: &impl GlobalConstraint, w: &[f32], target: f64) -> f64 {
    let measure = |p: &[Vec3]| constraint.measure(p);
    let gradient = constraint.gradient(positions);
    let c = measure(positions) - target;
    let before = relative(c, target);
    let norm: f64 = gradient.iter().zip(w).map(|(g, &w)| f64::from(w * g.length_squared())).sum();
    if norm == 0.0 {
        return before;
    }
    let mut step = (c / norm) as f32;
    let mut trial = positions.clone();
    for _ in 0..HALVINGS {
        for (v, p) in trial.iter_mut().enumerate() {
            if w[v] > 0.0 {
                *p = positions[v] - gradient[v] * (step * w[v]);
            }
        }
        let after = relative(measure(&trial) - target, target);
        if after < before {
            *positions = trial;
            return after;
        }
        step *= 0.5;
    }
    before
}

/// Repetitions of one shift the source's area step makes at most.
const REPEATS: u32 = 64;

/// One step of the source's area method: every edge's ends drawn together along the edge
/// by `C` over the current area (a quarter each), the same shift applied again while `C`
/// keeps falling by more than its squared length times `eps`; returns `|C|` over its target.
fn area_by_edges(surface: &Surface, k: f32, eps: f64) -> impl FnMut(&mut Vec<Vec3>) -> f64 + '_ {
    let w = weights(surface);
    let target = f64::from(k) * surface.area(&surface.positions);
    move |positions| {
        let area = surface.area(positions);
        let c = area - target;
        let mut shift = vec![Vec3::ZERO; positions.len()];
        let scale = (c / area.max(f64::MIN_POSITIVE) * 0.25) as f32;
        for &[a, b] in surface.edges() {
            let (a, b) = (a as usize, b as usize);
            let edge = positions[b] - positions[a];
            shift[a] += edge * (scale * w[a]);
            shift[b] -= edge * (scale * w[b]);
        }
        let error: f64 = shift.iter().map(|s| f64::from(s.length_squared())).sum();
        let mut last = c.abs();
        for _ in 0..REPEATS {
            let trial: Vec<Vec3> = positions.iter().zip(&shift).map(|(p, s)| *p + *s).collect();
            let now = (surface.area(&trial) - target).abs();
            if last - now <= error * eps {
                break;
            }
            *positions = trial;
            last = now;
        }
        relative(last, target)
    }
}

/// One step of the area constraint along the area's gradient, projected or by a step rule;
/// returns `|C|` over its target.
fn area(surface: &Surface, k: f32, variant: Variant) -> impl FnMut(&mut Vec<Vec3>) -> f64 + '_ {
    let w = weights(surface);
    let constraint = Area::new(surface);
    let target = f64::from(k) * constraint.measure(&surface.positions);
    let mut descent = variant.rule().map(Descent::new);
    move |positions| match &mut descent {
        Some(descent) => descent.iterate(&constraint, positions, &w, target),
        None => project(positions, &constraint, &w, target),
    }
}

/// Which deformer shrinks a region, as a parameter (`torso.method: area`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, bevy::reflect::Reflect)]
#[serde(rename_all = "snake_case")]
pub enum Deformer {
    /// A length constraint per edge.
    EdgeLengths,
    /// One constraint on the sum of edge lengths.
    EdgeSum,
    /// One constraint on the area.
    Area,
}

impl Deformer {
    /// Every deformer, in the panel's order.
    pub const ALL: [Deformer; 3] = [Deformer::EdgeLengths, Deformer::EdgeSum, Deformer::Area];

    /// The deformer stepped as `variant` (which the per-edge constraint does not take).
    pub fn method(self, variant: Variant) -> Method {
        match self {
            Deformer::EdgeLengths => Method::EdgeLengths,
            Deformer::EdgeSum => Method::EdgeSum(variant),
            Deformer::Area => Method::Area(variant),
        }
    }

    /// Its name in the panel.
    pub fn label(self) -> &'static str {
        match self {
            Deformer::EdgeLengths => "edge lengths",
            Deformer::EdgeSum => "edge sum",
            Deformer::Area => "area",
        }
    }
}

#[cfg(test)]
mod tests;
