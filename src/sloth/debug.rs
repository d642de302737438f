//! The sloth's debug view, as its source drew its debug traces: every grip the last foothold
//! search of each limb tried (green where it took one, a colour per reason where it refused
//! one), each foot's target, the limb chains, the body's frame and heading, and a transfer's
//! planned path, drawn by the rasterizer into the frame.

use super::feet::Refusal;
use super::plugin::{DEBUG_KEY, SlothBody, SlothSystems};
use super::rig::Limb;
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, RenderSystems};
use crate::raster::lines::Lines;
use bevy::prelude::*;

/// Adds the debug view's parameters, its key and its drawing to the sloth kind.
pub struct SlothDebugPlugin;

impl Plugin for SlothDebugPlugin {
    fn build(&self, app: &mut App) {
        app.register_params::<SlothDebug>()
            .add_systems(RunFixedMainLoop, debug_key.in_set(ControlSystems::Input).in_set(SlothSystems))
            .add_systems(PostUpdate, draw_debug_views.in_set(RenderSystems::Collect).in_set(SlothSystems));
    }
}

/// F3 switches every sloth's debug view.
fn debug_key(keys: Res<ButtonInput<KeyCode>>, mut sloths: Query<&mut SlothDebug>) {
    if keys.just_pressed(DEBUG_KEY) {
        for mut debug in &mut sloths {
            debug.debug_view = !debug.debug_view;
        }
    }
}

/// The debug view's switches, parameters of each sloth: `<name>.debug_view`,
/// `<name>.debug_on_top` (lines over every surface instead of hidden behind nearer ones).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component)]
pub struct SlothDebug {
    /// Draw the debug view.
    pub debug_view: bool,
    /// Draw its lines on top of every surface.
    pub debug_on_top: bool,
}

/// The grip a search took.
pub const TAKEN: [u8; 4] = [40, 230, 90, 255];
/// Each foot's target (the grip, or the point of its swing).
pub const TARGET: [u8; 4] = [255, 255, 255, 255];
/// The limb chains, girdle to grip.
pub const CHAIN: [u8; 4] = [120, 200, 255, 255];
/// A transfer's planned path of the body's centre.
pub const PLAN: [u8; 4] = [255, 120, 220, 255];

/// The colour of a refused grip, by reason.
pub fn refused(refusal: Refusal) -> [u8; 4] {
    match refusal {
        Refusal::OffSupport => [150, 150, 150, 255],
        Refusal::TooShort => [250, 230, 60, 255],
        Refusal::LegOrder => [255, 150, 30, 255],
        Refusal::TooFarAhead => [170, 90, 255, 255],
        Refusal::InWood => [200, 60, 200, 255],
        Refusal::PressesBody => [60, 220, 220, 255],
        Refusal::OutOfReach => [240, 50, 50, 255],
    }
}

/// Size of the crosses marking grips and targets, metres.
const MARK_M: f32 = 0.025;

/// Adds the debug view of every sloth that shows it to the frame's lines.
fn draw_debug_views(sloths: Query<(&SlothBody, &SlothDebug)>, mut lines: ResMut<Lines>) {
    for (body, debug) in &sloths {
        if !debug.debug_view {
            continue;
        }
        let (sloth, top) = (&body.sloth, debug.debug_on_top);
        for limb in Limb::ALL {
            let foot = &sloth.feet[limb.index()];
            lines.cross(foot.target(), MARK_M * 0.6, TARGET, top);
            let rig = &sloth.rigs[limb.index()];
            let mut chain = vec![rig.root_in(&sloth.frame)];
            chain.extend(rig.points(&sloth.frame, &foot.angles));
            lines.polyline(&chain, CHAIN, top);
        }
        let frame = &sloth.frame;
        let size = sloth.proportions.torso_length;
        lines.polyline(&[frame.centre, frame.centre + frame.forward * size], [60, 90, 255, 255], top);
        lines.polyline(&[frame.centre, frame.centre + frame.up * size * 0.5], [60, 220, 60, 255], top);
        lines.polyline(&[frame.centre, frame.centre + frame.right() * size * 0.5], [230, 60, 60, 255], top);
        if let Some(transfer) = &sloth.transfer {
            let mut path = vec![frame.centre];
            path.extend(transfer.path(size * 0.5));
            lines.polyline(&path, PLAN, top);
        }
        // The probes last, so that nothing hides them.
        for probe in sloth.probes.iter().flatten() {
            let rgba = probe.refusal.map_or(TAKEN, refused);
            lines.cross(probe.grip, MARK_M, rgba, top);
            if probe.refusal.is_none() {
                lines.polyline(&[probe.from, probe.grip], TAKEN, top);
            }
        }
    }
}
