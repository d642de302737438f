//! Frame times by phase over the last frames, for their means and 99th percentiles: the
//! window panel's frame budget and the headless measurement (`crates/canopy_bench/benches/headless_frames.rs`).
//! A frame rate is only as smooth as its slowest frames, so the budget is read at the 99th
//! percentile rather than from the mean.

use std::collections::VecDeque;
use std::time::Duration;

/// Frames the panel keeps: ten seconds at 60 frames a second.
pub const KEPT_FRAMES: usize = 600;

/// The last frames' times, milliseconds: each a whole frame and `N` phases.
#[derive(Debug, Clone)]
pub struct FrameLog<const N: usize> {
    frames: VecDeque<(f32, [f32; N])>,
    capacity: usize,
}

impl<const N: usize> Default for FrameLog<N> {
    fn default() -> Self {
        Self::new(KEPT_FRAMES)
    }
}

impl<const N: usize> FrameLog<N> {
    /// A log of the last `capacity` frames (at least one).
    pub fn new(capacity: usize) -> Self {
        Self { frames: VecDeque::with_capacity(capacity.max(1)), capacity: capacity.max(1) }
    }

    /// Takes in a frame of `frame` whole with its `phases`, letting the oldest go when full.
    pub fn push(&mut self, frame: Duration, phases: [Duration; N]) {
        if self.frames.len() == self.capacity {
            self.frames.pop_front();
        }
        let ms = |time: Duration| time.as_secs_f32() * 1000.0;
        self.frames.push_back((ms(frame), phases.map(ms)));
    }

    /// Frames held.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether no frame was taken in yet.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The whole frames' mean and `q` quantile (0 to 1, nearest rank), milliseconds.
    pub fn frame(&self, q: f32) -> Summary {
        summary(self.frames.iter().map(|(frame, _)| *frame), q)
    }

    /// Phase `phase`'s mean and `q` quantile, milliseconds.
    pub fn phase(&self, phase: usize, q: f32) -> Summary {
        summary(self.frames.iter().map(|(_, phases)| phases[phase]), q)
    }
}

/// A mean and a quantile of frame or phase times, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Summary {
    /// The mean.
    pub mean: f32,
    /// The quantile asked for.
    pub quantile: f32,
}

/// The mean and the `q` quantile by nearest rank (the smallest value at least a fraction `q`
/// of the values do not exceed); zeros for no values.
fn summary(values: impl Iterator<Item = f32>, q: f32) -> Summary {
    let mut sorted: Vec<f32> = values.collect();
    if sorted.is_empty() {
        return Summary::default();
    }
    sorted.sort_by(f32::total_cmp);
    let rank = ((q.clamp(0.0, 1.0) * sorted.len() as f32).ceil() as usize).clamp(1, sorted.len());
    Summary { mean: sorted.iter().sum::<f32>() / sorted.len() as f32, quantile: sorted[rank - 1] }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(value: u64) -> Duration {
        Duration::from_millis(value)
    }

    #[test]
    fn the_99th_percentile_is_the_slowest_frame_of_a_hundred_but_one() {
        let mut log = FrameLog::<1>::new(100);
        for i in 1..=100 {
            log.push(ms(i), [ms(2 * i)]);
        }
        assert_eq!(log.frame(0.99).quantile, 99.0);
        assert_eq!(log.frame(1.0).quantile, 100.0);
        assert_eq!(log.frame(0.5).quantile, 50.0);
        assert_eq!(log.phase(0, 0.99).quantile, 198.0);
        assert!((log.frame(0.99).mean - 50.5).abs() < 1e-4);
    }

    #[test]
    fn only_the_last_frames_are_kept() {
        let mut log = FrameLog::<0>::new(3);
        assert_eq!(log.frame(0.99), Summary::default());
        for i in [50, 1, 2, 3] {
            log.push(ms(i), []);
        }
        assert_eq!(log.len(), 3);
        assert_eq!(log.frame(1.0).quantile, 3.0, "the slow first frame has gone");
    }
}
