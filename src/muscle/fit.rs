//! Growth multipliers fitted to the real biceps: beyond the source's model, whose hand-set
//! multipliers grow the muscle five to six times less than the measurements.
//!
//! The fit chooses the multipliers of the nine measured nodes (the end nodes keep theirs)
//! that bring the model's radii at 0, 30, 60 and 90 degrees of flexion nearest the real ones
//! in least squares, by Levenberg-Marquardt. The volume stays exact: every candidate is the
//! node model itself, its radii the root of its volume equation. Scaling every multiplier by
//! one factor leaves the radii as they are (the root scales by its inverse), so only the
//! multipliers' proportions are fitted; they are kept at the size of the model's own.
//!
//! What the fit cannot change is how much the muscle grows in all: the volume fixes that, and
//! the real biceps' cross-sections add up to more volume as the elbow bends. Nor can a node
//! first grow and then shrink, since every radius moves with the one root. The measure of how
//! far it gets is [`GrowthFit::gap_closed`].

use super::carcass::Carcass;
use super::comparison::{MEASURED_NODES, REAL_BICEPS_RADII, model_radii};
use super::model::Muscle;
use canopy_vision::least_squares::{Settings, minimise};

/// How the multipliers are stepped: Levenberg-Marquardt's steps at most, and each central
/// difference a millionth of its multiplier (of 1 for a multiplier below that).
const SETTINGS: Settings = Settings { max_steps: 200, step_rate: 1e-6, least_step: 1.0 };

/// Multipliers fitted to the measurements, and how near they bring the model.
#[derive(Debug, Clone, PartialEq)]
pub struct GrowthFit {
    /// The model's own multipliers, which the fit started from.
    pub configured: Vec<f64>,
    /// One per node: the ends' as the model has them, the measured nodes' fitted.
    pub mults: Vec<f64>,
    /// Root-mean-square difference of the model's radii from the real ones, over the measured
    /// nodes at the four flexions, with the model's own multipliers (config units).
    pub rms_before: f64,
    /// The same with the fitted multipliers.
    pub rms_after: f64,
}

impl GrowthFit {
    /// The share of the model's difference from the measurements that the fit removes, 0 to 1.
    pub fn gap_closed(&self) -> f64 {
        if self.rms_before > 0.0 { 1.0 - self.rms_after / self.rms_before } else { 0.0 }
    }
}

/// The differences of the model's radii from the real ones, measured node by measured node
/// at each flexion; `None` where the model cannot reach one of the flexions.
fn residuals(model: &Muscle, carcass: &Carcass) -> Option<Vec<f64>> {
    let mut out = Vec::with_capacity(REAL_BICEPS_RADII.len() * MEASURED_NODES);
    for (radii, (_, real)) in model_radii(model, carcass).into_iter().zip(&REAL_BICEPS_RADII) {
        let radii = radii?;
        out.extend(real.iter().enumerate().map(|(i, real)| radii[i + 1] - real));
    }
    Some(out)
}

/// The root-mean-square of `residuals`.
fn rms(residuals: &[f64]) -> f64 {
    (residuals.iter().map(|r| r * r).sum::<f64>() / residuals.len() as f64).sqrt()
}

/// The multipliers of a model laid out as the measurements are (eleven nodes) fitted to
/// them; `None` for another layout, or when the model's own multipliers cannot reach every
/// flexion to start from.
pub fn fit_growth(model: &Muscle, carcass: &Carcass) -> Option<GrowthFit> {
    if model.nodes() != MEASURED_NODES + 2 {
        return None;
    }
    let configured = model.mults().to_vec();
    // The measured nodes' multipliers in, the whole model's out: the ends keep theirs.
    let with = |free: &[f64; MEASURED_NODES]| {
        let mut mults = configured.clone();
        mults[1..=MEASURED_NODES].copy_from_slice(free);
        mults
    };
    let evaluate = |free: &[f64; MEASURED_NODES]| {
        model.with_mults(with(free)).ok().and_then(|candidate| residuals(&candidate, carcass))
    };
    let start: [f64; MEASURED_NODES] = std::array::from_fn(|i| configured[i + 1]);
    let rms_before = rms(&evaluate(&start)?);
    let size = start.iter().map(|m| m * m).sum::<f64>().sqrt();
    if size == 0.0 {
        // No node grows: there are no proportions to fit.
        return Some(GrowthFit { mults: configured.clone(), configured, rms_before, rms_after: rms_before });
    }
    // Only the proportions count: every candidate is brought back to the model's own size.
    let resize = |free: [f64; MEASURED_NODES]| {
        let norm = free.iter().map(|m| m * m).sum::<f64>().sqrt();
        free.map(|m| m * size / norm)
    };
    let free = minimise(start, evaluate, resize, SETTINGS)?;
    let rms_after = rms(&evaluate(&free)?);
    Some(GrowthFit { mults: with(&free), configured, rms_before, rms_after })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::muscle::comparison::tests::real_config;

    fn squared(residuals: &[f64]) -> f64 {
        residuals.iter().map(|r| r * r).sum()
    }

    #[test]
    fn the_fit_keeps_the_volume_and_comes_nearer_the_real_biceps() {
        let (model, carcass) = real_config();
        let fit = fit_growth(&model, &carcass).unwrap();
        assert!(fit.rms_after < fit.rms_before, "{fit:?}");
        assert!(fit.gap_closed() > 0.0 && fit.gap_closed() < 1.0, "{fit:?}");
        assert_eq!((fit.mults[0], fit.mults[10]), (0.0, 0.0), "the ends keep their multipliers");
        let fitted = model.with_mults(fit.mults.clone()).unwrap();
        // The figures are the fitted model's own.
        let residuals = residuals(&fitted, &carcass).unwrap();
        assert!((rms(&residuals) - fit.rms_after).abs() < 1e-12 && residuals.len() == 36);
        for angle in [0.0f64, 30.0, 60.0, 90.0] {
            let mut flexed = fitted.clone();
            flexed.set_length(carcass.length_from_flexion(angle.to_radians()).value).unwrap();
            let error = (flexed.volume() - fitted.rest_volume()).abs() / fitted.rest_volume();
            assert!(error < 1e-12, "{angle} deg: relative volume error {error}");
        }
    }

    #[test]
    fn no_nearby_choice_of_proportions_does_better() {
        let (model, carcass) = real_config();
        let fit = fit_growth(&model, &carcass).unwrap();
        let best = squared(&residuals(&model.with_mults(fit.mults.clone()).unwrap(), &carcass).unwrap());
        for node in 1..=MEASURED_NODES {
            for by in [-0.05, 0.05] {
                let mut mults = fit.mults.clone();
                mults[node] *= 1.0 + by;
                if let Some(nearby) = model.with_mults(mults).ok().and_then(|m| residuals(&m, &carcass)) {
                    assert!(squared(&nearby) >= best * (1.0 - 1e-9), "node {node} by {by}");
                }
            }
        }
    }

    #[test]
    fn only_the_measured_layout_is_fitted() {
        let (_, carcass) = real_config();
        let model = Muscle::new(vec![5.0, 10.0, 5.0], vec![0.0, 1.0, 0.0], 250.0, 0.5, 1.5).unwrap();
        assert!(fit_growth(&model, &carcass).is_none());
    }
}
