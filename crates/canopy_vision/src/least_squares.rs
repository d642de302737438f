//! Levenberg-Marquardt on a small dense problem whose residuals are a function of `N`
//! parameters, the Jacobian found by central differences: as a marker's pose is refined on
//! its reprojection error (and, outside tracking, the muscle's growth is fitted).

use crate::linear::solve;

/// How a problem is stepped.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Steps at most.
    pub max_steps: usize,
    /// A central difference's step for a parameter is this share of its size...
    pub step_rate: f64,
    /// ...but never of less than this size.
    pub least_step: f64,
}

/// The parameters from `start` that bring the sum of the squared `residuals` lowest, as far as
/// Levenberg-Marquardt gets: Marquardt's damping of the normal equations' diagonal, divided by
/// 10 after a step that lowers the cost and multiplied by 10 while one does not (up to 1e10).
/// Every candidate passes through `project` (onto whatever the parameters must keep, the
/// identity where nothing), and `residuals` may refuse one (`None`): a refused candidate is
/// not taken, and one refused while differencing stops the search where it is. It stops when
/// no step lowers the cost or a step moves the parameters by less than 1e-12. `None` when
/// `residuals` refuses `start` itself.
pub fn minimise<const N: usize>(
    start: [f64; N],
    residuals: impl Fn(&[f64; N]) -> Option<Vec<f64>>,
    project: impl Fn([f64; N]) -> [f64; N],
    settings: Settings,
) -> Option<[f64; N]> {
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut x = start;
    let mut r = residuals(&x)?;
    let mut lambda = 1e-3;
    let mut jacobian = vec![[0.0; N]; r.len()];
    for _ in 0..settings.max_steps {
        for k in 0..N {
            let step = settings.step_rate * x[k].abs().max(settings.least_step);
            let (mut plus, mut minus) = (x, x);
            plus[k] += step;
            minus[k] -= step;
            let (Some(rp), Some(rm)) = (residuals(&plus), residuals(&minus)) else { return Some(x) };
            for (row, (p, m)) in jacobian.iter_mut().zip(rp.iter().zip(&rm)) {
                row[k] = (p - m) / (2.0 * step);
            }
        }
        let mut jtj = [[0.0; N]; N];
        let mut jtr = [0.0; N];
        for (row, residual) in jacobian.iter().zip(&r) {
            for a in 0..N {
                jtr[a] += row[a] * residual;
                for b in 0..N {
                    jtj[a][b] += row[a] * row[b];
                }
            }
        }
        let mut improved = false;
        while lambda < 1e10 {
            let mut system = jtj;
            for (a, row) in system.iter_mut().enumerate() {
                row[a] *= 1.0 + lambda;
            }
            let Some(delta) = solve(&mut system, &mut jtr.clone(), 1e-30) else { break };
            let candidate = project(std::array::from_fn(|k| x[k] - delta[k]));
            if let Some(rc) = residuals(&candidate)
                && cost(&rc) < cost(&r)
            {
                let small = delta.iter().map(|d| d * d).sum::<f64>() < 1e-24;
                x = candidate;
                r = rc;
                lambda = (lambda * 0.1).max(1e-12);
                improved = !small;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some(x)
}
