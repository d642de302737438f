//! Which of a tree's boughs a sloth walks from end to end, and why it stops where it stops: a
//! sloth placed near the start of each branch in turn walks it forward until it stops, leaves
//! it for another support, or runs out of time.

use super::feet::Refusal;
use super::locomotion::{Drive, Placement, Sloth, Tuning};
use super::rig::{Limb, Proportions};
use super::supports::Supports;
use crate::tree::SupportKind;

/// Where along a bough the sloth is placed, metres from its start.
const START_M: f32 = 0.4;

/// Simulated step, seconds.
const STEP_S: f32 = 1.0 / 60.0;

/// How a walk along one bough ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The sloth cannot hang there (too thick for its feet to reach round, no grip clear of
    /// another support's wood, ...).
    NotPlaced(String),
    /// It stopped at the bough's end: walked from end to end.
    ReachedEnd,
    /// It walked on onto another support (a branch it turns onto, or a trunk it transfers to).
    WentOn(String),
    /// It stopped short of the end, `at` metres along, the leading feet's searches refused for
    /// these reasons (most often first).
    Stopped {
        /// Metres along the bough the leading forefoot stood.
        at: f32,
        /// Why the leading feet's last searches refused each grip tried, with how often.
        reasons: Vec<(&'static str, usize)>,
    },
    /// Still walking when the time ran out, `at` metres along.
    StillWalking {
        /// Metres along the bough the leading forefoot stood.
        at: f32,
    },
}

/// One bough's walk.
#[derive(Debug, Clone, PartialEq)]
pub struct BoughWalk {
    /// The support's label.
    pub label: String,
    /// Its length, metres.
    pub length: f32,
    /// Where along it the sloth was placed, 0 to 1 of its length.
    pub fraction: f32,
    /// Its radius where the sloth was placed, metres.
    pub radius: f32,
    /// How the walk ended.
    pub outcome: Outcome,
}

/// Walks a sloth of `proportions` at `speed` (m/s) along every branch of `supports` at least
/// `min_length` metres long, for at most `seconds` each.
pub fn survey(
    supports: &Supports,
    proportions: Proportions,
    speed: f32,
    min_length: f32,
    seconds: f32,
) -> Vec<BoughWalk> {
    (0..supports.paths.len())
        .filter(|&i| supports.paths[i].kind == SupportKind::Branch && supports.paths[i].length() >= min_length)
        .map(|support| walk(supports, support, proportions, speed, seconds))
        .collect()
}

/// One bough's walk.
fn walk(supports: &Supports, support: usize, proportions: Proportions, speed: f32, seconds: f32) -> BoughWalk {
    let path = &supports.paths[support];
    let length = path.length();
    let fraction = (START_M / length).min(0.5);
    let radius = path.at(fraction * length).radius;
    let bough = |outcome| BoughWalk { label: path.label.clone(), length, fraction, radius, outcome };
    let placement = Placement { support, fraction, facing: 1.0, around: 0.0 };
    let mut sloth = match Sloth::place(supports, placement, proportions, Tuning::animal(speed, &proportions)) {
        Ok(sloth) => sloth,
        Err(error) => return bough(Outcome::NotPlaced(error.to_string())),
    };
    let forward = Drive { direction: 1.0, ..Drive::default() };
    let lead = |sloth: &Sloth| {
        [Limb::LeftFore, Limb::RightFore].map(|l| &sloth.feet[l.index()]).iter().map(|f| f.s).fold(0.0, f32::max)
    };
    for _ in 0..(seconds / STEP_S) as usize {
        sloth.step(STEP_S, forward, supports);
        if let Some(other) = sloth.feet.iter().map(|f| f.support).find(|&s| s != support) {
            return bough(Outcome::WentOn(supports.paths[other].label.clone()));
        }
        if sloth.blocked.is_some() {
            let at = lead(&sloth);
            // Stopped within a stride of the end (and the margin feet keep from it): the end.
            if length - at <= sloth.timing().stride + 0.1 {
                return bough(Outcome::ReachedEnd);
            }
            return bough(Outcome::Stopped { at, reasons: reasons(&sloth) });
        }
    }
    bough(Outcome::StillWalking { at: lead(&sloth) })
}

/// Why the leading feet's last searches refused the grips they tried, most often first.
fn reasons(sloth: &Sloth) -> Vec<(&'static str, usize)> {
    let mut counts: Vec<(&'static str, usize)> = Vec::new();
    for limb in [Limb::LeftFore, Limb::RightFore] {
        for refusal in sloth.probes[limb.index()].iter().filter_map(|p| p.refusal).map(Refusal::reason) {
            match counts.iter_mut().find(|(reason, _)| *reason == refusal) {
                Some((_, n)) => *n += 1,
                None => counts.push((refusal, 1)),
            }
        }
    }
    counts.sort_by_key(|&(_, n)| std::cmp::Reverse(n));
    counts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::{Shape, SupportSpec, Tree};
    use bevy::math::Vec3;

    #[test]
    fn each_bough_is_walked_and_its_ending_told() {
        let polyline = |name: &str, points: Vec<Vec3>, radius: f32| SupportSpec {
            name: name.into(),
            shape: Shape::Polyline { radii: vec![radius; points.len()], points },
            kind: None,
        };
        let tree = Tree::build(&[
            // A level bough: walked to its end.
            polyline("level", vec![Vec3::new(0.0, 2.0, 0.0), Vec3::new(3.0, 2.0, 0.0)], 0.03),
            // Too thick for the feet to reach round.
            polyline("thick", vec![Vec3::new(0.0, 2.0, 4.0), Vec3::new(3.0, 2.0, 4.0)], 0.6),
            // Too short to be surveyed.
            polyline("stub", vec![Vec3::new(0.0, 2.0, 8.0), Vec3::new(0.5, 2.0, 8.0)], 0.03),
        ])
        .unwrap();
        let supports = Supports::new([("t", &tree)]);
        let walks = survey(&supports, Proportions::default(), 0.11, 1.0, 60.0);
        let outcome = |label: &str| walks.iter().find(|w| w.label == label).map(|w| w.outcome.clone());
        assert_eq!(walks.len(), 2);
        assert_eq!(outcome("t/level"), Some(Outcome::ReachedEnd));
        assert!(matches!(outcome("t/thick"), Some(Outcome::NotPlaced(_))), "{:?}", outcome("t/thick"));
        // Given too little time, the level bough is still being walked.
        let short = survey(&supports, Proportions::default(), 0.11, 1.0, 5.0);
        assert!(matches!(short[0].outcome, Outcome::StillWalking { at } if at > 0.4 && at < 2.5), "{:?}", short[0]);
    }
}
