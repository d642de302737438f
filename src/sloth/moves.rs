//! A transfer's moves and their playback: the body carried from pose to pose, shoulders and
//! hips each on their own path, while the feet of a move swing to their new grips.

use super::body;
use super::feet::Step;
use super::rig::{BodyFrame, Limb};
use bevy::math::{Mat3, Quat, Vec3};
use std::f32::consts::PI;

/// Part of a move the shoulders wait before moving, while the body starts turning.
pub(super) const SHOULDER_DELAY: f32 = 0.3;

/// One move of a transfer: the body goes from one pose to another while some feet swing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Move {
    pub(super) from: BodyFrame,
    pub(super) to: BodyFrame,
    /// Where each foot swinging in this move lands, indexed like [`Limb::ALL`].
    pub(super) swings: [Option<Step>; 4],
    /// Which way and how far the hips bow out at mid-move.
    pub(super) bow: Vec3,
    /// Which way and how far the shoulders bow out at mid-move.
    pub(super) front_bow: Vec3,
    /// The part of the move by which the body has turned into its end pose.
    pub(super) turned_by: f32,
    /// Where the belly turns towards mid-move, if anywhere: the forelimbs' grips.
    pub(super) belly_towards: Option<Vec3>,
    /// Seconds.
    pub(super) duration: f32,
}

impl Move {
    /// A move from `from` to `to`, turning all through it and bowing nowhere, while the feet
    /// of `swings` swing.
    pub(super) fn plain(from: BodyFrame, to: BodyFrame, swings: [Option<Step>; 4], duration: f32) -> Self {
        let (bow, front_bow) = (Vec3::ZERO, Vec3::ZERO);
        Self { from, to, swings, bow, front_bow, turned_by: 1.0, belly_towards: None, duration }
    }

    /// The body at `t` (0 start to 1 end): the shoulders on the straight line between their
    /// two places, the hips following on theirs (bowed out), both eased in and out.
    pub(super) fn frame_at(&self, t: f32, half_torso: f32) -> BodyFrame {
        let t = t.clamp(0.0, 1.0);
        let eased = t * t * (3.0 - 2.0 * t);
        let shoulders = |f: &BodyFrame| f.centre + f.forward * half_torso;
        let hips = |f: &BodyFrame| f.centre - f.forward * half_torso;
        // The shoulders set off later than the hips: turning first swings the head away from
        // what is ahead before the shoulders close in on it.
        let late = ((t - SHOULDER_DELAY) / (1.0 - SHOULDER_DELAY)).clamp(0.0, 1.0);
        let late = late * late * (3.0 - 2.0 * late);
        let front = shoulders(&self.from).lerp(shoulders(&self.to), late) + self.front_bow * (PI * eased).sin();
        let back = hips(&self.from).lerp(hips(&self.to), eased) + self.bow * (PI * eased).sin();
        // The body's turn (done by `turned_by`), less whatever turns its long axis from the
        // eased turn's onto the line from hips to shoulders.
        let turned = (t / self.turned_by).clamp(0.0, 1.0);
        let turned = turned * turned * (3.0 - 2.0 * turned);
        let turn = orientation(&self.from).slerp(orientation(&self.to), turned);
        let forward = (front - back).try_normalize().unwrap_or(self.to.forward);
        let aligned = Quat::from_rotation_arc(turn * Vec3::Z, forward) * turn;
        let mut up = body::perpendicular_towards(aligned * Vec3::Y, forward);
        if let Some(grips) = self.belly_towards {
            let weight = (PI * eased).sin();
            let towards = body::perpendicular_towards(grips - front, forward);
            up = body::perpendicular_towards(up * (1.0 - weight) + towards * weight, forward);
        }
        BodyFrame { centre: front - forward * half_torso, forward, up }
    }
}

/// The rotation taking +z to the body's forward and +y to its up.
fn orientation(frame: &BodyFrame) -> Quat {
    Quat::from_mat3(&Mat3::from_cols(frame.up.cross(frame.forward), frame.up, frame.forward))
}

/// A transfer under way.
#[derive(Debug, Clone, PartialEq)]
pub struct Transfer {
    /// The support the sloth moves onto.
    pub target: usize,
    moves: Vec<Move>,
    /// The move under way.
    current: usize,
    /// Seconds into it; `None` before its feet have lifted.
    elapsed: Option<f32>,
}

/// What the sloth does in one step of a transfer.
pub(super) struct TransferStep {
    /// Feet lifting now, with where they land and how long they swing.
    pub lifts: Vec<(Limb, Step, f32)>,
    /// The body's pose.
    pub frame: BodyFrame,
    /// Whether the transfer is over.
    pub done: bool,
}

impl Transfer {
    /// A transfer onto support `target` by `moves`, in order, about to start.
    pub(super) fn new(target: usize, moves: Vec<Move>) -> Self {
        Self { target, moves, current: 0, elapsed: None }
    }

    /// Where the body's centre ends each move still to come, metres: the plan's path.
    pub fn path(&self, half_torso: f32) -> Vec<Vec3> {
        self.moves[self.current..].iter().map(|m| m.frame_at(1.0, half_torso).centre).collect()
    }

    /// The move under way (from 0) and how many there are.
    pub fn progress(&self) -> (usize, usize) {
        (self.current, self.moves.len())
    }

    /// Advances `dt` seconds.
    pub(super) fn advance(&mut self, dt: f32, half_torso: f32) -> TransferStep {
        let mut lifts = Vec::new();
        let elapsed = match self.elapsed {
            Some(elapsed) => elapsed + dt,
            None => {
                let current = &self.moves[self.current];
                for limb in Limb::ALL {
                    if let Some(step) = current.swings[limb.index()] {
                        lifts.push((limb, step, current.duration));
                    }
                }
                dt
            }
        };
        let current = self.moves[self.current];
        let frame = current.frame_at(elapsed / current.duration, half_torso);
        let mut done = false;
        if elapsed >= current.duration {
            self.elapsed = None;
            self.current += 1;
            done = self.current == self.moves.len();
        } else {
            self.elapsed = Some(elapsed);
        }
        TransferStep { lifts, frame, done }
    }
}
