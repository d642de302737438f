//! The frame rate cap. Without a GPU's vertical sync nothing else paces the window: an empty
//! scene would redraw as fast as the CPU allows and keep a core busy for pictures nobody can
//! see. Frames start at most every [`FramePacing::interval`]; the time left is slept.

use super::WindowTimes;
use bevy::prelude::*;
use std::time::{Duration, Instant};

/// The shortest time between the starts of two frames; `None` draws frames back to back.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct FramePacing {
    /// The frame interval.
    pub interval: Option<Duration>,
}

impl FramePacing {
    /// At most `fps` frames a second; 0 is no cap.
    pub fn max_fps(fps: u32) -> Self {
        Self { interval: (fps > 0).then(|| Duration::from_secs(1) / fps) }
    }
}

impl Default for FramePacing {
    /// 60 frames a second, the rate of the simulation's fixed steps: a faster window would
    /// show the same state again.
    fn default() -> Self {
        Self::max_fps(60)
    }
}

/// When the next frame may start, given when the last one was due to start and the time now:
/// one interval after the last, or now if the app fell behind (it does not race to catch up).
fn next_start(last: Instant, interval: Duration, now: Instant) -> Instant {
    (last + interval).max(now)
}

/// Sleeps until the next frame may start.
pub(super) fn pace_frames(pacing: Res<FramePacing>, mut times: ResMut<WindowTimes>, mut last: Local<Option<Instant>>) {
    let now = Instant::now();
    let (Some(interval), Some(previous)) = (pacing.interval, *last) else {
        times.wait = Duration::ZERO;
        *last = Some(now);
        return;
    };
    let start = next_start(previous, interval, now);
    times.wait = start - now;
    std::thread::sleep(times.wait);
    *last = Some(start);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_start_an_interval_apart_unless_late() {
        let t0 = Instant::now();
        let interval = Duration::from_millis(16);
        // Early: wait for the interval.
        assert_eq!(next_start(t0, interval, t0 + Duration::from_millis(5)), t0 + interval);
        // Late: start now, without a burst of frames to catch up.
        let late = t0 + Duration::from_millis(40);
        assert_eq!(next_start(t0, interval, late), late);
    }

    #[test]
    fn zero_is_no_cap() {
        assert_eq!(FramePacing::max_fps(0).interval, None);
        assert_eq!(FramePacing::max_fps(50).interval, Some(Duration::from_millis(20)));
    }
}
