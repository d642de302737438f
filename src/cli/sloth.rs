//! `canopy sloth gait`: walks a scene's sloth headless and prints its gait beside the study's
//! steady-state figures (contact, swing and stride, its Table 1) and each joint's excursion
//! during contact beside the range of motion the study measured (its Table 2), and draws the
//! footfall diagram to a PNG. `canopy sloth survey`: which of a scene's boughs a sloth walks
//! from end to end, and why it stops where it stops.

use super::parse_seconds;
use crate::app::FIXED_HZ;
use crate::controls::timeline::Timeline;
use crate::foundation::entity::SceneEntity;
use crate::run::live_app;
use crate::sloth::gait::{FREE_SPEED, SPEED_RANGE};
use crate::sloth::gait::{Measured, STEADY_STATE};
use crate::sloth::gait_log::{GaitFigures, GaitLog, LimbFigures};
use crate::sloth::rig::Proportions;
use crate::sloth::rig::{FORE_AMPLITUDE_DEG, HIND_AMPLITUDE_DEG, Limb};
use crate::sloth::survey::{Outcome, survey};
use crate::sloth::{SlothGait, Supports};
use crate::tree::TreeBody;
use bevy::math::UVec2;
use clap::Subcommand;
use image::{Rgb, RgbImage};
use std::path::PathBuf;
use std::process::ExitCode;

/// Sloth tools.
#[derive(Subcommand, Debug)]
pub enum SlothCommand {
    /// Walk a scene's sloth headless and print its gait beside the study's (the pole of
    /// `scenes/sloth/pole.yaml` is the study's set-up).
    Gait(GaitArgs),
    /// Place a sloth near the start of each of a scene's branches in turn, walk it forward,
    /// and report which it walks from end to end and why it stops where it stops.
    Survey(SurveyArgs),
}

/// Arguments of `canopy sloth survey`.
#[derive(clap::Args, Debug)]
pub struct SurveyArgs {
    /// The scene file (its trees; any sloth in it is left out).
    scene: PathBuf,
    /// Simulated seconds each bough is walked at most.
    #[arg(long, default_value_t = 120.0, value_parser = |text: &str| parse_seconds(text, MAX_SECONDS))]
    seconds: f64,
    /// Branches shorter than this many metres are left out.
    #[arg(long, default_value_t = 1.0)]
    min_length: f32,
    /// Walking speed, metres per second.
    #[arg(long, default_value_t = FREE_SPEED)]
    speed: f32,
}

/// The longest walk measured, simulated seconds.
const MAX_SECONDS: f64 = 3600.0;

/// Arguments of `canopy sloth gait`.
#[derive(clap::Args, Debug)]
pub struct GaitArgs {
    /// The scene file.
    scene: PathBuf,
    /// Simulated seconds to walk.
    #[arg(long, default_value_t = 30.0, value_parser = |text: &str| parse_seconds(text, MAX_SECONDS))]
    seconds: f64,
    /// Seconds of starting up left out of the figures (steady state only).
    #[arg(long, default_value_t = 4.0, value_parser = |text: &str| parse_seconds(text, MAX_SECONDS))]
    skip: f64,
    /// The sloth to measure, by name [default: the first].
    #[arg(long)]
    sloth: Option<String>,
    /// A timeline of scripted input (the sloth walks on autorun without one).
    #[arg(long, value_name = "TIMELINE.yaml")]
    input: Option<PathBuf>,
    /// Draw the footfall diagram to this PNG file: a row per limb, top to bottom right hind,
    /// left fore, left hind, right fore, a bar for each contact, a tick every second.
    #[arg(long, value_name = "OUT.png")]
    plot: Option<PathBuf>,
}

impl SlothCommand {
    /// Runs the command.
    pub fn run(self) -> ExitCode {
        match self {
            SlothCommand::Gait(args) => match args.gait() {
                Ok(()) => ExitCode::SUCCESS,
                Err(error) => {
                    eprintln!("{error}");
                    ExitCode::from(1)
                }
            },
            SlothCommand::Survey(args) => match args.survey() {
                Ok(()) => ExitCode::SUCCESS,
                Err(error) => {
                    eprintln!("{error}");
                    ExitCode::from(1)
                }
            },
        }
    }
}

impl GaitArgs {
    fn gait(&self) -> Result<(), String> {
        let log = self.walk()?;
        let since = self.skip as f32;
        let figures = log.figures(since);
        println!(
            "{} walking {} s on {}; figures from {} s on, beside the study's steady state at 0.2-0.3 m/s (mean +- s.d.; * outside one s.d.)\n",
            self.sloth.as_deref().unwrap_or("the sloth"),
            self.seconds,
            self.scene.display(),
            self.skip
        );
        print!("{}", gait_table(&figures));
        println!();
        print!("{}", excursion_table(&figures));
        if let Some(share) = figures.diagonal_share {
            println!(
                "\nfootfalls: {}, {:.0} % of successive ones in the diagonal sequence",
                figures.footfalls.len(),
                share * 100.0
            );
        }
        let slip: Vec<String> = Limb::ALL
            .iter()
            .map(|l| format!("{} {:.2} mm", l.key(), figures.limbs[l.index()].slip_max_m * 1000.0))
            .collect();
        println!("largest slip of a planted foot: {}", slip.join(", "));
        if let Some(path) = &self.plot {
            footfall_diagram(&log, since, self.seconds as f32)
                .save(path)
                .map_err(|error| format!("{}: cannot write the diagram: {error}", path.display()))?;
            println!("footfall diagram: {}", path.display());
        }
        Ok(())
    }

    /// Walks the scene and returns the sloth's gait log.
    fn walk(&self) -> Result<GaitLog, String> {
        let scene = &self.scene;
        let timeline = match &self.input {
            Some(path) => Some((Timeline::load(path).map_err(|e| e.to_string())?, path.as_path())),
            None => None,
        };
        let mut app = live_app(scene, UVec2::new(64, 36), timeline, true).map_err(|e| e.to_string())?;
        for _ in 0..(self.seconds * FIXED_HZ).round() as u64 {
            app.update();
        }
        let world = app.world_mut();
        let mut sloths: Vec<(usize, String, GaitLog)> = world
            .query::<(&SceneEntity, &SlothGait)>()
            .iter(world)
            .map(|(entity, gait)| (entity.index, entity.name.clone(), gait.0.clone()))
            .collect();
        sloths.sort_by_key(|(index, ..)| *index);
        let names: Vec<String> = sloths.iter().map(|(_, name, _)| name.clone()).collect();
        let found = match &self.sloth {
            Some(wanted) => sloths.into_iter().find(|(_, name, _)| name == wanted),
            None => sloths.into_iter().next(),
        };
        found.map(|(.., log)| log).ok_or_else(|| match &self.sloth {
            Some(wanted) => format!("{}: no sloth is named `{wanted}` (sloths: {})", scene.display(), names.join(", ")),
            None => format!("{}: the scene has no sloth", scene.display()),
        })
    }
}

impl SurveyArgs {
    fn survey(&self) -> Result<(), String> {
        if !(SPEED_RANGE.0..=SPEED_RANGE.1).contains(&self.speed) {
            return Err(format!("--speed: expected {} to {} m/s, found {}", SPEED_RANGE.0, SPEED_RANGE.1, self.speed));
        }
        let mut app = live_app(&self.scene, UVec2::new(16, 16), None, false).map_err(|e| e.to_string())?;
        let world = app.world_mut();
        let mut trees: Vec<(usize, String, TreeBody)> = world
            .query::<(&SceneEntity, &TreeBody)>()
            .iter(world)
            .map(|(entity, body)| (entity.index, entity.name.clone(), body.clone()))
            .collect();
        trees.sort_by_key(|(index, ..)| *index);
        if trees.is_empty() {
            return Err(format!("{}: the scene has no tree", self.scene.display()));
        }
        let supports = Supports::new(trees.iter().map(|(_, name, body)| (name.as_str(), &body.tree)));
        let walks = survey(&supports, Proportions::default(), self.speed, self.min_length, self.seconds as f32);
        println!(
            "{}: a sloth at {} m/s on each branch at least {} m long, walked forward for at most {} s\n",
            self.scene.display(),
            self.speed,
            self.min_length,
            self.seconds
        );
        println!("{:<28} {:>8} {:>9}  ending", "branch", "length m", "radius cm");
        let (mut placed, mut through, mut on) = (0, 0, 0);
        for walk in &walks {
            let ending = match &walk.outcome {
                Outcome::NotPlaced(why) => format!("not placed: {why}"),
                Outcome::ReachedEnd => "walked to its end".to_string(),
                Outcome::WentOn(other) => format!("walked on onto {other}"),
                Outcome::Stopped { at, reasons } => {
                    let why: Vec<String> = reasons.iter().map(|(reason, n)| format!("{reason} {n}")).collect();
                    format!("stopped {at:.2} m along; grips refused: {}", why.join(", "))
                }
                Outcome::StillWalking { at } => format!("still walking, {at:.2} m along"),
            };
            placed += usize::from(!matches!(walk.outcome, Outcome::NotPlaced(_)));
            through += usize::from(walk.outcome == Outcome::ReachedEnd);
            on += usize::from(matches!(walk.outcome, Outcome::WentOn(_)));
            println!("{:<28} {:>8.2} {:>9.1}  {ending}", walk.label, walk.length, walk.radius * 100.0);
        }
        println!(
            "\n{} branches: the sloth hangs from {placed}, walks {through} from end to end, walks on from {on} onto \
             another support",
            walks.len()
        );
        Ok(())
    }
}

/// Figures pooled over a pair of limbs, weighted by their contacts.
fn pooled(figures: &GaitFigures, pair: [Limb; 2], pick: impl Fn(&LimbFigures) -> Option<f32>) -> Option<f32> {
    let (sum, weight) = pair.iter().fold((0.0, 0usize), |(sum, weight), limb| {
        let limb = &figures.limbs[limb.index()];
        match pick(limb) {
            Some(value) => (sum + value * limb.contacts as f32, weight + limb.contacts),
            None => (sum, weight),
        }
    });
    (weight > 0).then(|| sum / weight as f32)
}

fn cell(value: Option<f32>, study: Measured, digits: usize) -> String {
    let (mean, sd) = (study.mean, study.sd);
    match value {
        Some(v) => {
            let mark = if study.within(v) { " " } else { "*" };
            format!("{v:.digits$}{mark} ({mean:.2} +- {sd:.2})")
        }
        None => format!("-  ({mean:.2} +- {sd:.2})"),
    }
}

const PAIRS: [(&str, [Limb; 2]); 2] =
    [("forelimb", [Limb::LeftFore, Limb::RightFore]), ("hindlimb", [Limb::LeftHind, Limb::RightHind])];

/// Contact, swing, duty factor and stride per limb pair, beside the study's Table 1.
fn gait_table(figures: &GaitFigures) -> String {
    let mut out = format!(
        "{:<10}{:>9}  {:<22}{:<22}{:<6}{:<22}\n",
        "limbs", "contacts", "contact s", "swing s", "duty", "stride m"
    );
    for ((name, pair), study) in PAIRS.into_iter().zip(STEADY_STATE) {
        let contacts: usize = pair.iter().map(|l| figures.limbs[l.index()].contacts).sum();
        let duty = pooled(figures, pair, |l| l.duty_factor).map_or("-".into(), |d| format!("{d:.2}"));
        out += &format!(
            "{name:<10}{contacts:>9}  {:<22}{:<22}{duty:<6}{:<22}\n",
            cell(pooled(figures, pair, |l| l.contact_s), study.contact_s, 2),
            cell(pooled(figures, pair, |l| l.swing_s), study.swing_s, 2),
            cell(pooled(figures, pair, |l| l.stride_m), study.stride_m, 2),
        );
    }
    out
}

/// Each joint's mean excursion during contact beside the amplitude the study measured.
fn excursion_table(figures: &GaitFigures) -> String {
    let mut out = format!("{:<16}{:>14}{:>14}\n", "joint", "excursion deg", "study deg");
    for ((_, pair), amplitudes) in PAIRS.into_iter().zip([FORE_AMPLITUDE_DEG, HIND_AMPLITUDE_DEG]) {
        let names = pair[0].joint_names();
        // Joint 0 (abduction) is not in the study's table.
        for (j, name) in names.iter().enumerate() {
            let measured = pooled(figures, pair, |l| l.excursion_deg[j]).map_or("-".into(), |e| format!("{e:.1}"));
            let study = if j == 0 { "-".to_string() } else { format!("{:.1}", amplitudes[j - 1]) };
            out += &format!("{name:<16}{measured:>14}{study:>14}\n");
        }
    }
    out
}

/// Pixels per second of the diagram, and per limb row.
const DIAGRAM_PX_PER_S: f32 = 40.0;
const DIAGRAM_ROW_PX: u32 = 24;

/// The footfall diagram from `since` to `until` seconds: a row per limb in the diagonal
/// sequence's order, a bar for each contact, a tick every second.
fn footfall_diagram(log: &GaitLog, since: f32, until: f32) -> RgbImage {
    let span = (until - since).max(1.0);
    let width = (span * DIAGRAM_PX_PER_S).ceil() as u32 + 20;
    let height = 4 * DIAGRAM_ROW_PX + 20;
    let mut image = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
    let x_of = |t: f32| 10.0 + (t - since) * DIAGRAM_PX_PER_S;
    for second in 0..=span as u32 {
        let x = x_of(since + second as f32) as u32;
        for y in 5..height - 5 {
            image.put_pixel(x.min(width - 1), y, Rgb([225, 225, 225]));
        }
    }
    let colours = [[150, 70, 40], [40, 110, 160], [200, 120, 60], [60, 160, 200]];
    for limb in Limb::ALL {
        let top = 10 + limb.index() as u32 * DIAGRAM_ROW_PX + 3;
        for (start, end) in log.contact_spans(limb, since, until) {
            let (x0, x1) = (x_of(start) as u32, (x_of(end) as u32).min(width - 1));
            for x in x0..=x1 {
                for y in top..top + DIAGRAM_ROW_PX - 6 {
                    image.put_pixel(x, y, Rgb(colours[limb.index()]));
                }
            }
        }
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sloth::gait_log::LimbState;
    use crate::sloth::rig::JOINTS;
    use bevy::math::Vec3;

    #[test]
    fn tables_pool_the_pairs_and_mark_what_falls_outside_the_study() {
        let still = LimbState { planted: true, position: Vec3::ZERO, angles: [0.0; JOINTS] };
        let lifted = LimbState { planted: false, ..still };
        let mut log = GaitLog::new(&[lifted; 4]);
        // Every limb: swing 0.8 s, then 1.5 s of contact, twice.
        for cycle in 0..2 {
            let t = cycle as f32 * 2.3;
            log.observe(t + 0.8, &[still; 4]);
            log.observe(t + 2.3, &[lifted; 4]);
        }
        let table = gait_table(&log.figures(0.0));
        assert!(table.contains("forelimb          4  1.50  (1.50 +- 0.20)"), "{table}");
        assert!(table.contains("0.80  (0.84 +- 0.20)"), "{table}");
        assert!(table.contains("hindlimb          4  1.50  (1.66 +- 0.25)"), "{table}");
        assert!(table.contains("0.80  (0.67 +- 0.15)"), "{table}");
        assert!(table.contains("0.00* (0.59 +- 0.05)"), "{table}");
        let excursions = excursion_table(&log.figures(0.0));
        let row = |name: &str| {
            let line = excursions.lines().find(|l| l.starts_with(name)).unwrap_or_default();
            line.split_whitespace().map(str::to_string).collect::<Vec<_>>()
        };
        assert_eq!(row("shoulder_blade"), ["shoulder_blade", "0.0", "41.5"], "{excursions}");
        assert_eq!(row("abduction"), ["abduction", "0.0", "-"], "{excursions}");
        let diagram = footfall_diagram(&log, 0.0, 4.6);
        assert_eq!(diagram.height(), 4 * DIAGRAM_ROW_PX + 20);
        assert_ne!(diagram.get_pixel(x_at(1.0), 20), &Rgb([255, 255, 255]), "a contact bar at 1 s");
        assert_eq!(diagram.get_pixel(x_at(0.4), 20), &Rgb([255, 255, 255]), "a swing at 0.4 s");
    }

    fn x_at(t: f32) -> u32 {
        (10.0 + t * DIAGRAM_PX_PER_S) as u32
    }
}
