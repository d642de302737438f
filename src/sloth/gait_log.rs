//! The gait measured as gait studies measure an animal's: each limb's contacts (touch-down to
//! lift-off) and swings, from which contact and swing durations, duty factor, stride length,
//! the footfall order, each joint's excursion during contact, and how far a planted foot slips.
//!
//! The log watches the feet a step at a time ([`GaitLog::observe`]) and keeps the last
//! [`MAX_CONTACTS`] contacts of each limb. A contact or swing counts only when both its ends
//! were seen: the contacts the sloth was placed in, and the one under way, do not.

use super::rig::{JOINTS, Limb};
use bevy::math::Vec3;
use std::collections::VecDeque;

/// Contacts (and swings) kept per limb.
pub const MAX_CONTACTS: usize = 256;

/// A limb as the log sees it at one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbState {
    /// Holding on (not swinging).
    pub planted: bool,
    /// Where the limb's grip point is, metres.
    pub position: Vec3,
    /// Its joint angles, radians.
    pub angles: [f32; JOINTS],
}

/// One contact of a foot with its support.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Touch-down, seconds; `None` for a foot planted when the log began.
    pub start: Option<f32>,
    /// Lift-off, seconds; `None` while it lasts.
    pub end: Option<f32>,
    /// Where the grip point was at touch-down, metres.
    pub at: Vec3,
    /// Farthest the grip point moved from `at` during the contact, metres.
    pub slip: f32,
    /// Each joint's smallest and largest angle during the contact, radians.
    pub range: [(f32, f32); JOINTS],
}

impl Contact {
    fn begin(start: Option<f32>, state: &LimbState) -> Self {
        Self { start, end: None, at: state.position, slip: 0.0, range: state.angles.map(|a| (a, a)) }
    }

    /// Seconds from touch-down to lift-off, when both were seen.
    pub fn duration(&self) -> Option<f32> {
        Some(self.end? - self.start?)
    }
}

/// One limb's record.
#[derive(Debug, Clone, Default, PartialEq)]
struct LimbLog {
    contacts: VecDeque<Contact>,
    /// Lift-off and touch-down times of each swing seen whole.
    swings: VecDeque<(f32, f32)>,
    /// Lift-off of the swing under way.
    lifted: Option<f32>,
}

/// The gait record of one animal.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GaitLog {
    limbs: [LimbLog; 4],
    /// Touch-downs in order, the last [`MAX_CONTACTS`] times four.
    landings: VecDeque<(Limb, f32)>,
}

/// One limb's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbFigures {
    /// Contacts counted.
    pub contacts: usize,
    /// Mean contact, seconds.
    pub contact_s: Option<f32>,
    /// Mean swing, seconds.
    pub swing_s: Option<f32>,
    /// Contact over contact plus swing.
    pub duty_factor: Option<f32>,
    /// Mean distance between successive touch-downs, metres.
    pub stride_m: Option<f32>,
    /// Each joint's mean excursion (largest less smallest angle) during contact, degrees.
    pub excursion_deg: [Option<f32>; JOINTS],
    /// The largest slip of a planted foot, metres.
    pub slip_max_m: f32,
}

/// The figures of a gait over a span of time.
#[derive(Debug, Clone, PartialEq)]
pub struct GaitFigures {
    /// Per limb, indexed like [`Limb::ALL`].
    pub limbs: [LimbFigures; 4],
    /// The touch-downs in order.
    pub footfalls: Vec<Limb>,
    /// Share of successive touch-downs that follow the diagonal sequence (right hind, left
    /// fore, left hind, right fore); `None` with fewer than two.
    pub diagonal_share: Option<f32>,
}

impl GaitLog {
    /// A log that starts watching the feet as they are at `time`.
    pub fn new(states: &[LimbState; 4]) -> Self {
        let mut log = Self::default();
        for (limb, state) in log.limbs.iter_mut().zip(states) {
            if state.planted {
                limb.contacts.push_back(Contact::begin(None, state));
            }
        }
        log
    }

    /// Takes in the feet as they are at `time`, seconds.
    pub fn observe(&mut self, time: f32, states: &[LimbState; 4]) {
        for (limb, (log, state)) in Limb::ALL.into_iter().zip(self.limbs.iter_mut().zip(states)) {
            let open = log.contacts.back_mut().filter(|c| c.end.is_none());
            match (open, state.planted) {
                (Some(contact), true) => {
                    contact.slip = contact.slip.max(contact.at.distance(state.position));
                    for (range, angle) in contact.range.iter_mut().zip(state.angles) {
                        *range = (range.0.min(angle), range.1.max(angle));
                    }
                }
                (Some(contact), false) => {
                    contact.end = Some(time);
                    log.lifted = Some(time);
                }
                (None, true) => {
                    if let Some(lifted) = log.lifted.take() {
                        push_bounded(&mut log.swings, (lifted, time), MAX_CONTACTS);
                    }
                    push_bounded(&mut log.contacts, Contact::begin(Some(time), state), MAX_CONTACTS);
                    push_bounded(&mut self.landings, (limb, time), 4 * MAX_CONTACTS);
                }
                (None, false) => {
                    log.lifted.get_or_insert(time);
                }
            }
        }
    }

    /// The contacts of `limb` kept, oldest first, as start and end seconds cut to the span
    /// from `since` to `until` (one under way ends at `until`, one from placing starts at 0):
    /// the bars of a footfall diagram.
    pub fn contact_spans(&self, limb: Limb, since: f32, until: f32) -> impl Iterator<Item = (f32, f32)> + '_ {
        self.limbs[limb.index()].contacts.iter().filter_map(move |contact| {
            let start = contact.start.unwrap_or(0.0).max(since);
            let end = contact.end.unwrap_or(until).min(until);
            (end > start).then_some((start, end))
        })
    }

    /// The figures of the contacts and swings that began at or after `since`, seconds.
    pub fn figures(&self, since: f32) -> GaitFigures {
        let limbs = Limb::ALL.map(|limb| {
            let log = &self.limbs[limb.index()];
            let whole: Vec<&Contact> =
                log.contacts.iter().filter(|c| c.start.is_some_and(|s| s >= since) && c.end.is_some()).collect();
            let contact_s = mean(whole.iter().filter_map(|c| c.duration()));
            let swing_s = mean(log.swings.iter().filter(|(lift, _)| *lift >= since).map(|(lift, land)| land - lift));
            let landed: Vec<&Contact> = log.contacts.iter().filter(|c| c.start.is_some_and(|s| s >= since)).collect();
            let stride_m = mean(landed.windows(2).map(|pair| pair[0].at.distance(pair[1].at)));
            let excursion_deg =
                std::array::from_fn(|j| mean(whole.iter().map(|c| (c.range[j].1 - c.range[j].0).to_degrees())));
            LimbFigures {
                contacts: whole.len(),
                contact_s,
                swing_s,
                duty_factor: contact_s.zip(swing_s).map(|(c, s)| c / (c + s)),
                stride_m,
                excursion_deg,
                slip_max_m: whole.iter().map(|c| c.slip).fold(0.0, f32::max),
            }
        });
        let footfalls: Vec<Limb> = self.landings.iter().filter(|(_, t)| *t >= since).map(|(limb, _)| *limb).collect();
        let pairs = footfalls.len().saturating_sub(1);
        let diagonal = footfalls.windows(2).filter(|p| p[1].index() == (p[0].index() + 1) % 4).count();
        let diagonal_share = (pairs > 0).then(|| diagonal as f32 / pairs as f32);
        GaitFigures { limbs, footfalls, diagonal_share }
    }
}

fn push_bounded<T>(queue: &mut VecDeque<T>, item: T, bound: usize) {
    if queue.len() == bound {
        queue.pop_front();
    }
    queue.push_back(item);
}

fn mean(values: impl Iterator<Item = f32>) -> Option<f32> {
    let (sum, count) = values.fold((0.0, 0usize), |(sum, n), v| (sum + v, n + 1));
    (count > 0).then(|| sum / count as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic walk: each limb lifts a quarter cycle after the one before it in the
    /// diagonal sequence, swings `swing` seconds of each `cycle`, lands `stride` further along
    /// x, and bends its second joint by 0.3 rad over each contact; sampled every `dt`.
    fn walk(cycle: f32, swing: f32, stride: f32, seconds: f32, dt: f32) -> GaitLog {
        let state = |limb: Limb, t: f32| {
            let phase = (t / cycle - limb.index() as f32 * 0.25).rem_euclid(1.0);
            let cycles = (t / cycle - limb.index() as f32 * 0.25 - phase).round();
            let planted = phase >= swing / cycle;
            let contact = (phase - swing / cycle) / (1.0 - swing / cycle);
            let mut angles = [0.0; JOINTS];
            angles[1] = if planted { 0.3 * contact } else { 0.0 };
            LimbState { planted, position: Vec3::new(stride * (cycles + 1.0), 0.0, 0.0), angles }
        };
        let mut log = GaitLog::new(&Limb::ALL.map(|l| state(l, 0.0)));
        let mut t = 0.0;
        while t < seconds {
            t += dt;
            log.observe(t, &Limb::ALL.map(|l| state(l, t)));
        }
        log
    }

    #[test]
    fn measures_a_known_walk() {
        let dt = 1.0 / 60.0;
        let figures = walk(2.4, 0.8, 0.6, 30.0, dt).figures(3.0);
        for limb in figures.limbs {
            assert!(limb.contacts >= 9, "{limb:?}");
            assert!((limb.contact_s.unwrap() - 1.6).abs() < 2.0 * dt, "{limb:?}");
            assert!((limb.swing_s.unwrap() - 0.8).abs() < 2.0 * dt, "{limb:?}");
            assert!((limb.duty_factor.unwrap() - 2.0 / 3.0).abs() < 0.02, "{limb:?}");
            assert!((limb.stride_m.unwrap() - 0.6).abs() < 1e-5, "{limb:?}");
            assert!((limb.excursion_deg[1].unwrap() - 0.3f32.to_degrees()).abs() < 0.5, "{limb:?}");
            assert_eq!(limb.excursion_deg[0], Some(0.0));
            assert_eq!(limb.slip_max_m, 0.0);
        }
        assert_eq!(figures.diagonal_share, Some(1.0));
        let first = figures.footfalls.iter().position(|&l| l == Limb::RightHind).unwrap();
        assert_eq!(figures.footfalls[first..first + 4], Limb::ALL);
    }

    #[test]
    fn slip_and_another_order_are_seen() {
        let still = LimbState { planted: true, position: Vec3::ZERO, angles: [0.0; JOINTS] };
        let mut log = GaitLog::new(&[still; 4]);
        let lifted = LimbState { planted: false, ..still };
        // The right fore lifts, lands, slides 3 mm while planted, lifts again.
        log.observe(1.0, &[still, still, still, lifted]);
        log.observe(2.0, &[still, still, still, still]);
        let slid = LimbState { position: Vec3::new(0.003, 0.0, 0.0), ..still };
        log.observe(3.0, &[still, still, still, slid]);
        log.observe(4.0, &[still, still, still, lifted]);
        let figures = log.figures(0.0);
        let rf = figures.limbs[Limb::RightFore.index()];
        assert_eq!((rf.contacts, rf.contact_s, rf.swing_s), (1, Some(2.0), Some(1.0)));
        assert!((rf.slip_max_m - 0.003).abs() < 1e-6);
        assert_eq!(figures.limbs[Limb::RightHind.index()].contacts, 0, "a contact from placing does not count");
        assert_eq!(figures.diagonal_share, None);
        // Lateral sequence: right hind, right fore, left hind, left fore.
        let mut log = GaitLog::new(&[lifted; 4]);
        let mut t = 0.0;
        for _ in 0..3 {
            for limb in [Limb::RightHind, Limb::RightFore, Limb::LeftHind, Limb::LeftFore] {
                t += 1.0;
                let mut states = [lifted; 4];
                states[limb.index()] = still;
                log.observe(t, &states);
            }
        }
        assert_eq!(log.figures(0.0).diagonal_share, Some(0.0));
    }
}
