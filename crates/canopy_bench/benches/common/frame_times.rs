//! Figures of a run of frame times, for the benchmarks that time whole frames.

use std::time::Duration;

/// Median, 99th percentile and maximum of `times` (not empty), milliseconds.
pub fn figures(times: &[Duration]) -> [f64; 3] {
    let mut ms: Vec<f64> = times.iter().map(|t| t.as_secs_f64() * 1e3).collect();
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.99), ms[ms.len() - 1]]
}
