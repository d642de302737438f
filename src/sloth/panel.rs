//! The sloth's section of the window's panel: where it is and what it is doing, each limb's
//! state, every joint's angle against its limits, the footfall diagram of the last cycles and
//! the gait measured so far. (Its parameters, speed and the rest, are edited above it with
//! every entity's.)

use super::gait::lift_phase;
use super::gait_log::GaitLog;
use super::locomotion::Sloth;
use super::plugin::{SlothBody, SlothGait, SlothInput, SlothParams};
use super::rig::{JOINTS, Limb};
use super::supports::Supports;
use crate::tree::SupportKind;
use bevy::prelude::*;
use bevy_egui::egui;
use egui_plot::{Line, Plot, PlotPoints};

/// Each limb's colour in the footfall diagram, in [`Limb::ALL`] order.
const LIMB_COLORS: [egui::Color32; 4] = [
    egui::Color32::from_rgb(190, 100, 60),
    egui::Color32::from_rgb(70, 140, 200),
    egui::Color32::from_rgb(230, 150, 80),
    egui::Color32::from_rgb(100, 190, 230),
];

/// Gait cycles the footfall diagram spans.
const DIAGRAM_CYCLES: f32 = 3.0;

/// Draws the sloth section for `entity`.
pub fn sloth_section(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Ok(entity) = world.get_entity(entity) else { return };
    let (Some(body), Some(gait)) = (entity.get::<SlothBody>(), entity.get::<SlothGait>()) else {
        ui.colored_label(egui::Color32::LIGHT_RED, "not placed: its support is gone");
        return;
    };
    let walking = entity.get::<SlothInput>().is_some_and(|i| i.hold != 0.0)
        || entity.get::<SlothParams>().is_some_and(|p| p.autorun);
    status(ui, &body.sloth, &body.supports, walking);
    ui.separator();
    limbs(ui, &body.sloth, &body.supports);
    ui.separator();
    joints(ui, &body.sloth);
    ui.separator();
    footfall_diagram(ui, &gait.0, body.sloth.time, body.sloth.timing().cycle);
    figures(ui, &gait.0);
}

/// What the sloth is doing: `blocked going forward: no foothold ahead of the leading feet`.
fn activity(sloth: &Sloth, supports: &Supports, walking: bool) -> String {
    let label = |support: usize| supports.paths[support].label.clone();
    if let Some(transfer) = &sloth.transfer {
        let (current, total) = transfer.progress();
        return format!("transferring onto {}: move {} of {total}", label(transfer.target), current + 1);
    }
    if let Some(direction) = sloth.blocked {
        let way = if direction > 0.0 { "forward" } else { "back" };
        return format!("blocked going {way}: no foothold for the leading feet");
    }
    match (sloth.change_to, walking) {
        (Some(target), _) => format!("changing to {}", label(target)),
        (None, true) => "walking".to_string(),
        (None, false) if sloth.feet.iter().any(|f| !f.planted()) => "landing its last steps".to_string(),
        (None, false) => "holding still".to_string(),
    }
}

fn status(ui: &mut egui::Ui, sloth: &Sloth, supports: &Supports, walking: bool) {
    let path = &supports.paths[sloth.support()];
    let fore = &sloth.feet[Limb::RightFore.index()];
    let kind = match path.kind {
        SupportKind::Branch => "branch",
        SupportKind::Trunk => "trunk",
    };
    egui::Grid::new("sloth-status").num_columns(2).show(ui, |ui| {
        ui.label("on");
        ui.label(format!("{} ({kind}), {:.0} % along", path.label, 100.0 * fore.s / path.length().max(1e-6)));
        ui.end_row();
        ui.label("doing");
        ui.label(activity(sloth, supports, walking));
        ui.end_row();
        ui.label("speed");
        ui.label(format!("{:.3} m/s asked, {:.3} m/s mean", sloth.speed, sloth.mean_speed()));
        ui.end_row();
        ui.label("distance");
        ui.label(format!("{:.2} m", sloth.distance));
        ui.end_row();
        ui.label("clearance");
        ui.label(format!("{:.1} mm now, {:.1} mm least", sloth.clearance * 1e3, sloth.min_clearance * 1e3));
        ui.end_row();
    });
}

fn limbs(ui: &mut egui::Ui, sloth: &Sloth, supports: &Supports) {
    egui::Grid::new("sloth-limbs").num_columns(5).striped(true).show(ui, |ui| {
        for heading in ["limb", "foot", "cycle", "grip to surface", "reach used"] {
            ui.strong(heading);
        }
        ui.end_row();
        for limb in Limb::ALL {
            let foot = &sloth.feet[limb.index()];
            let rig = &sloth.rigs[limb.index()];
            ui.label(limb.key());
            ui.label(if foot.planted() { "planted" } else { "swinging" });
            ui.label(format!("{:.0} %", 100.0 * (sloth.phase - lift_phase(limb)).rem_euclid(1.0)));
            ui.label(format!("{:.2} mm", supports.paths[foot.support].distance(foot.position) * 1e3));
            let reach = rig.root_in(&sloth.frame).distance(foot.position) / rig.bones.iter().sum::<f32>();
            ui.label(format!("{:.0} %", reach * 100.0));
            ui.end_row();
        }
    });
}

/// Every joint's angle as a marker on the bar of its range; red at a limit.
fn joints(ui: &mut egui::Ui, sloth: &Sloth) {
    ui.label("joints: each angle within its limits");
    egui::Grid::new("sloth-joints").num_columns(3).show(ui, |ui| {
        for limb in Limb::ALL {
            let (foot, rig) = (&sloth.feet[limb.index()], &sloth.rigs[limb.index()]);
            for j in 0..JOINTS {
                ui.label(format!("{} {}", limb.key(), limb.joint_names()[j]));
                let (size, painter) = ui.allocate_painter(egui::vec2(120.0, 12.0), egui::Sense::hover());
                let rect = size.rect;
                let share = ((foot.angles[j] - rig.min[j]) / (rig.max[j] - rig.min[j]).max(1e-6)).clamp(0.0, 1.0);
                let at_limit = !(0.01..=0.99).contains(&share);
                painter.rect_filled(rect.shrink2(egui::vec2(0.0, 4.0)), 2.0, egui::Color32::from_gray(70));
                let x = rect.left() + share * rect.width();
                let color = if at_limit { egui::Color32::LIGHT_RED } else { egui::Color32::WHITE };
                painter.circle_filled(egui::pos2(x, rect.center().y), 4.0, color);
                ui.label(format!(
                    "{:.0} deg ({:.0} to {:.0})",
                    foot.angles[j].to_degrees(),
                    rig.min[j].to_degrees(),
                    rig.max[j].to_degrees()
                ));
                ui.end_row();
            }
        }
    });
}

/// The limbs' contacts over the last cycles, a row each, right hind on top: the diagonal
/// sequence shows as a staircase.
fn footfall_diagram(ui: &mut egui::Ui, log: &GaitLog, now: f32, cycle: f32) {
    ui.label("footfalls, top to bottom rh, lf, lh, rf: each contact over the last cycles (s)");
    let since = now - DIAGRAM_CYCLES * cycle;
    Plot::new("sloth-footfalls")
        .height(110.0)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .show_y(false)
        .include_x(f64::from(since))
        .include_x(f64::from(now))
        .include_y(-0.5)
        .include_y(3.5)
        .show(ui, |plot| {
            for limb in Limb::ALL {
                let row = f64::from(3 - limb.index() as u8);
                for (start, end) in log.contact_spans(limb, since, now) {
                    let points = PlotPoints::from(vec![[f64::from(start), row], [f64::from(end), row]]);
                    plot.line(Line::new(limb.key(), points).color(LIMB_COLORS[limb.index()]).width(9.0));
                }
            }
        });
}

/// Contact, swing, duty factor, stride and slip per limb, over the walk so far.
fn figures(ui: &mut egui::Ui, log: &GaitLog) {
    let figures = log.figures(0.0);
    let seconds = |v: Option<f32>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    egui::Grid::new("sloth-gait").num_columns(6).striped(true).show(ui, |ui| {
        for heading in ["limb", "contact s", "swing s", "duty", "stride m", "slip mm"] {
            ui.strong(heading);
        }
        ui.end_row();
        for limb in Limb::ALL {
            let f = &figures.limbs[limb.index()];
            ui.label(limb.key());
            ui.label(seconds(f.contact_s));
            ui.label(seconds(f.swing_s));
            ui.label(seconds(f.duty_factor));
            ui.label(seconds(f.stride_m));
            ui.label(format!("{:.2}", f.slip_max_m * 1e3));
            ui.end_row();
        }
    });
    if let Some(share) = figures.diagonal_share {
        ui.label(format!("{:.0} % of touch-downs in the diagonal sequence", share * 100.0));
    }
}
