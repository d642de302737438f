//! The sloth's scenario scenes, run headless through the real plugins with a timeline, checked
//! at every fixed step: planted feet on their support's surface, joints within limits, the body
//! never inside a support, no NaN, each forelimb's biceps keeping its volume at the length its
//! elbow gives; and at the end: no planted foot slipped, progress, speed, gait order.

use bevy::math::{UVec2, Vec3};
use canopy::controls::timeline::Timeline;
use canopy::sloth::biceps::{BICEPS_LIMBS, arm_points};
use canopy::sloth::rig::Limb;
use canopy::sloth::{SlothBody, SlothGait, SlothMuscles};
use std::path::PathBuf;

const SIZE: UVec2 = UVec2::new(64, 48);

/// Farthest a planted foot's grip point may be from its support's surface, metres.
const GRIP_LIMIT: f32 = 0.01;

/// Largest relative volume error a biceps may show.
const VOLUME_LIMIT: f64 = 1e-9;

/// Largest difference between a biceps' length and the distance between its attachments on
/// the posed arm, metres (the pose is f32).
const LENGTH_LIMIT: f64 = 1e-6;

/// Farthest a planted foot's grip point may slip between touch-down and lift-off, metres.
const SLIP_LIMIT: f32 = 0.001;

/// The same in a run with a transfer between a branch and a trunk, metres. A plan holds each
/// planted foot within 6 mm of its grip at the moments it checks, so a foot may move twice that
/// (up to 8.4 mm measured in the swept scenarios); between those moments the live IK may fall
/// further behind for a few steps (29 mm once in the generated forest, while a hind pair swings
/// over onto a trunk).
const TRANSFER_SLIP_LIMIT: f32 = 0.03;

/// The free speed and the tolerance the studies give, metres per second.
const FREE_SPEED: (f32, f32) = (0.11, 0.04);

fn scene_path(name: &str) -> PathBuf {
    super::common::path("scenes/sloth").join(name)
}

/// `text` with the number on the line marked `swept` replaced by `value`.
fn sweep(text: &str, value: f32) -> String {
    let lines: Vec<String> = text
        .lines()
        .map(|line| {
            if !line.contains("# swept") {
                return line.to_string();
            }
            let (key, _) = line.split_once(':').expect("a swept line is `key: value  # swept`");
            let (_, comment) = line.split_once('#').unwrap();
            format!("{key}: {value}   #{comment}")
        })
        .collect();
    assert!(lines.iter().filter(|l| l.contains("# swept")).count() == 1, "one swept line");
    lines.join("\n")
}

/// What a run recorded, step by step.
#[derive(Debug, Default)]
struct Record {
    /// Every violation of the per-step criteria, with its time.
    violations: Vec<String>,
    /// Footfalls in stretches of steady walking: every foot on one straight support, no
    /// foothold search failing, no change of branch under way.
    steady_footfalls: Vec<Vec<Limb>>,
    /// The supports of the four feet at the end.
    final_supports: Vec<String>,
    /// Each support all four feet held at once, in the order they came to hold it.
    visited: Vec<String>,
    /// Mean speed while moving, m/s.
    mean_speed: f32,
    /// Body path length, metres.
    distance: f32,
    /// Whether the sloth stopped for want of a foothold.
    blocked: bool,
    /// Whether autorun was still on at the end.
    autorun: bool,
    /// The sloth at the end.
    body: Option<SlothBody>,
}

/// Checks a sloth's state after a fixed step, calling `fail` with each violation: no NaN,
/// joints within limits, planted grips on their support's surface, the body outside every
/// support, and each biceps keeping its volume at the length its elbow gives.
pub fn check_step(body: &SlothBody, muscles: &SlothMuscles, fail: &mut impl FnMut(String)) {
    let sloth = &body.sloth;
    for limb in Limb::ALL {
        let foot = &sloth.feet[limb.index()];
        let rig = &sloth.rigs[limb.index()];
        if !foot.position.is_finite() || foot.angles.iter().any(|a| !a.is_finite()) {
            fail(format!("{} is NaN", limb.key()));
        }
        if !rig.within_limits(&foot.angles, 1e-5) {
            fail(format!("{} joints {:?} outside limits", limb.key(), foot.angles));
        }
        let distance = body.supports.paths[foot.support].distance(foot.position);
        if foot.planted() && distance.abs() > GRIP_LIMIT {
            fail(format!("planted {} is {distance:.4} m from its support's surface", limb.key()));
        }
    }
    for (biceps, limb) in muscles.biceps.iter().zip(BICEPS_LIMBS) {
        let (start, end) = arm_points(sloth, limb).attachments(&biceps.carcass, biceps.metres_per_unit);
        if (start.distance(end) - biceps.length_m()).abs() > LENGTH_LIMIT || biceps.refusal.is_some() {
            fail(format!(
                "{} biceps {} m long between attachments {} m apart",
                limb.key(),
                biceps.length_m(),
                start.distance(end)
            ));
        }
        if biceps.relative_volume_error() > VOLUME_LIMIT {
            fail(format!("{} biceps volume off by {:e}", limb.key(), biceps.relative_volume_error()));
        }
    }
    if !sloth.frame.centre.is_finite() || !sloth.frame.forward.is_finite() {
        fail("body is NaN".into());
    }
    if sloth.clearance < 0.0 {
        fail(format!("body {:.4} m inside a support", -sloth.clearance));
    }
}

/// Runs `text` (a scene in `scenes/sloth`) for `seconds` with a timeline given as YAML.
fn run(text: &str, timeline: &str, seconds: f32) -> Record {
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("scene.yaml");
    std::fs::write(&scene, text).unwrap();
    let timeline_file = folder.path().join("timeline.yaml");
    std::fs::write(&timeline_file, timeline).unwrap();
    let mut app = super::common::live_app(&scene, SIZE);
    let timeline = Timeline::load(&timeline_file).unwrap();
    timeline.check(app.world_mut()).unwrap();
    app.insert_resource(timeline);

    let mut record = Record::default();
    let mut seen_footfalls = 0;
    let mut was_steady = false;
    let mut transferred = false;
    let steps = (seconds * 60.0).round() as usize;
    for _ in 0..steps {
        app.update();
        let world = app.world_mut();
        let (body, params, muscles) =
            world.query::<(&SlothBody, &canopy::sloth::SlothParams, &SlothMuscles)>().single(world).unwrap();
        let sloth = &body.sloth;
        let time = sloth.time;

        let mut fail = |what: String| record.violations.push(format!("t={time:.2}s: {what}"));
        check_step(body, muscles, &mut fail);
        let one_support = sloth.feet.iter().all(|f| f.support == sloth.feet[0].support);
        let straight = one_support && body.supports.paths[sloth.feet[0].support].is_straight();
        // A footfall counts when the sloth walked steadily both before and after the step it
        // fell in (the hind feet landing together at the end of a transfer do not).
        let steady_now =
            straight && sloth.change_to.is_none() && sloth.transfer.is_none() && !sloth.stuck.iter().any(|&s| s);
        let steady = steady_now && was_steady;
        was_steady = steady_now;
        if !steady && record.steady_footfalls.last().is_none_or(|stretch| !stretch.is_empty()) {
            record.steady_footfalls.push(Vec::new());
        }
        if steady {
            if record.steady_footfalls.is_empty() {
                record.steady_footfalls.push(Vec::new());
            }
            let stretch = record.steady_footfalls.last_mut().unwrap();
            stretch.extend(sloth.footfalls[seen_footfalls..].iter().map(|f| f.limb));
        }
        seen_footfalls = sloth.footfalls.len();
        transferred |= sloth.transfer.is_some();
        record.blocked = sloth.blocked.is_some();
        record.autorun = params.autorun;
        record.mean_speed = sloth.mean_speed();
        record.distance = sloth.distance;
        record.final_supports = sloth.feet.iter().map(|f| body.supports.paths[f.support].label.clone()).collect();
        if one_support && record.visited.last() != Some(&record.final_supports[0]) {
            record.visited.push(record.final_supports[0].clone());
        }
        record.body = Some(body.clone());
    }
    let world = app.world_mut();
    let gait = world.query::<&SlothGait>().single(world).unwrap();
    let slip = gait.0.figures(0.0).limbs.iter().map(|l| l.slip_max_m).fold(0.0, f32::max);
    if slip > if transferred { TRANSFER_SLIP_LIMIT } else { SLIP_LIMIT } {
        record.violations.push(format!("a planted foot slipped {:.2} mm between touch-down and lift-off", slip * 1e3));
    }
    record
}

impl Record {
    /// Whether the footfalls on straight supports keep the diagonal sequence RH, LF, LH, RF.
    fn gait_kept(&self) -> bool {
        let in_order =
            |stretch: &Vec<Limb>| stretch.windows(2).all(|pair| (pair[0].index() + 1) % 4 == pair[1].index());
        self.steady_footfalls.iter().map(Vec::len).sum::<usize>() >= 8 && self.steady_footfalls.iter().all(in_order)
    }

    /// Every failed criterion, per step and overall, for a run that should end with all four
    /// feet on `support`.
    fn failures(&self, support: &str) -> Vec<String> {
        let mut failures: Vec<String> = self.violations.iter().take(3).cloned().collect();
        if self.final_supports.iter().any(|s| s != support) {
            failures.push(format!("ended on {:?}, not all on {support}", self.final_supports));
        }
        if !self.gait_kept() {
            failures.push(format!("gait order broken: {:?}", self.steady_footfalls));
        }
        if (self.mean_speed - FREE_SPEED.0).abs() > FREE_SPEED.1 {
            failures.push(format!("mean speed {:.3} m/s", self.mean_speed));
        }
        failures
    }
}

/// Runs the scene `name` with the swept value for each angle, and returns the angles that
/// failed with why (see [`failed_runs`]).
fn sweep_scene(
    name: &str,
    angles: impl Iterator<Item = i32>,
    value: impl Fn(i32) -> f32,
    via: &[&str],
    support: &str,
) -> Vec<String> {
    let text = std::fs::read_to_string(scene_path(name)).unwrap();
    failed_runs(angles.map(|angle| (format!("{angle} deg"), sweep(&text, value(angle)))), via, support)
}

/// Runs each named scene of `scenes` on autorun for a minute, and returns the names of those
/// that failed with why. Each run must end stopped at the end of `support`, all four feet
/// having held each support of `via` on the way, in order.
fn failed_runs(scenes: impl Iterator<Item = (String, String)>, via: &[&str], support: &str) -> Vec<String> {
    let mut failed = Vec::new();
    for (name, text) in scenes {
        let record = run(&text, "[]", 60.0);
        let mut failures = record.failures(support);
        let mut visits = record.visited.iter();
        if !via.iter().all(|wanted| visits.any(|v| v == wanted)) {
            failures.push(format!("went by {:?}, not by {via:?}", record.visited));
        }
        let body = record.body.as_ref().unwrap();
        let sloth = &body.sloth;
        let end = body.supports.paths[sloth.support()].length();
        let reach = end - sloth.feet[Limb::RightFore.index()].s.max(sloth.feet[Limb::LeftFore.index()].s);
        if !record.blocked || record.autorun || reach > sloth.timing().stride + 0.1 {
            failures.push(format!("did not stop at the end of the branch ({reach:.2} m short)"));
        }
        if !failures.is_empty() {
            failed.push(format!("{name}: {}", failures.join("; ")));
        }
    }
    failed
}

#[test]
fn turns_onto_a_branch_at_90_to_185_degrees() {
    let failed =
        sweep_scene("turn.yaml", (90..=185).step_by(5), |angle| 90.0 - (180.0 - angle as f32), &[], "tree/turn");
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn follows_a_branch_rising_or_falling_at_125_to_205_degrees_and_stops_at_its_end() {
    let failed = sweep_scene("height.yaml", (125..=205).step_by(5), |angle| 180.0 - angle as f32, &[], "tree/next");
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn walks_from_a_branch_onto_its_trunk_and_back_at_85_to_150_degrees() {
    let route = ["tree/limb", "tree/trunk", "tree/limb"];
    let failed = sweep_scene("transfer.yaml", (85..=150).step_by(5), |angle| angle as f32 - 90.0, &route, "tree/limb");
    assert!(failed.is_empty(), "{failed:#?}");
}

/// The trunk radii the thick-trunk sweeps try at the junction, metres: the trunk tapers from
/// 1.15 times that at its foot to 0.77 times at its top, as the scene's own does.
const THICK_TRUNKS: [f32; 5] = [0.15, 0.2, 0.25, 0.3, 0.35];

/// The branch angles the thick-trunk sweeps try at each radius, degrees to the trunk below:
/// a generated forest's branches leave their trunks at 85 to 130 degrees.
const THICK_TRUNK_ANGLES: [i32; 3] = [90, 110, 130];

/// `transfer.yaml` with its trunk `radius` metres thick at the junction and its branch at
/// `angle` degrees to the trunk below.
fn thick_trunk(radius: f32, angle: i32) -> String {
    let text = std::fs::read_to_string(scene_path("transfer.yaml")).unwrap();
    let radii = "radii: [0.15, 0.13, 0.1]";
    assert!(text.contains(radii), "transfer.yaml's trunk radii changed");
    let text = text.replace(radii, &format!("radii: [{}, {radius}, {}]", radius * 1.15, radius * 0.77));
    sweep(&text, angle as f32 - 90.0)
}

/// Every [`thick_trunk`] scene of the sweeps, named by its radius and angle.
fn thick_trunk_scenes() -> impl Iterator<Item = (String, String)> {
    THICK_TRUNKS.into_iter().flat_map(|radius| {
        THICK_TRUNK_ANGLES.map(|angle| (format!("{radius} m, {angle} deg"), thick_trunk(radius, angle)))
    })
}

#[test]
fn walks_from_a_branch_onto_a_thick_trunk_and_back_at_radii_up_to_35_cm() {
    let route = ["tree/limb", "tree/trunk", "tree/limb"];
    let failed = failed_runs(thick_trunk_scenes(), &route, "tree/limb");
    assert!(failed.is_empty(), "{failed:#?}");
}

/// The names of the scenes of `scenes` in which the sloth, placed on the trunk round from
/// the branch and climbing, did not move onto the branch or broke a per-step criterion.
fn failed_climbs(scenes: impl Iterator<Item = (String, String)>) -> Vec<String> {
    let mut failed = Vec::new();
    for (name, text) in scenes {
        let placed = "sloth: { support: limb, at: 0.6, facing: backward, autorun: true }";
        assert!(text.contains(placed), "transfer.yaml's sloth changed");
        let text = text.replace(placed, "sloth: { support: trunk, at: 0.3, around_deg: 90 }");
        let record = run(&text, "- { at: 0, press: [KeyW] }\n", 20.0);
        let mut failures: Vec<String> = record.violations.iter().take(3).cloned().collect();
        if record.visited != ["tree/trunk", "tree/limb"] {
            failures.push(format!("went by {:?}", record.visited));
        }
        if !failures.is_empty() {
            failed.push(format!("{name}: {}", failures.join("; ")));
        }
    }
    failed
}

#[test]
fn climbs_from_a_trunk_onto_the_branch_above_at_85_to_150_degrees() {
    let text = std::fs::read_to_string(scene_path("transfer.yaml")).unwrap();
    let failed =
        failed_climbs((85..=150).step_by(5).map(|angle| (format!("{angle} deg"), sweep(&text, angle as f32 - 90.0))));
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn climbs_from_a_thick_trunk_onto_the_branch_above_at_radii_up_to_35_cm() {
    let failed = failed_climbs(thick_trunk_scenes());
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn changes_to_a_parallel_branch_on_the_right() {
    let text = std::fs::read_to_string(scene_path("parallel.yaml")).unwrap();
    let timeline = "- { at: 0, press: [KeyW] }\n- { at: 4, press: [KeyD] }\n- { at: 4.2, release: [KeyD] }\n";
    let record = run(&text, timeline, 30.0);
    let failures = record.failures("tree/far");
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(record.distance > 2.0, "walked {} m", record.distance);
}

#[test]
fn holding_back_walks_tail_first_and_releasing_stops() {
    let text = std::fs::read_to_string(scene_path("parallel.yaml")).unwrap();
    let text = text.replace("at: 0.2", "at: 0.6");
    let timeline = "- { at: 0, press: [KeyS] }\n- { at: 12, release: [KeyS] }\n";
    let record = run(&text, timeline, 16.0);
    assert!(record.violations.is_empty(), "{:#?}", record.violations);
    let body = record.body.unwrap();
    let start = -2.0 + 4.0 * 0.6;
    let moved = body.sloth.frame.centre.x - start;
    assert!(moved < -0.8, "moved {moved} m along x: backwards is -x");
    assert!(body.sloth.frame.forward.dot(Vec3::X) > 0.95, "still faces +x");
    assert!(body.sloth.feet.iter().all(|f| f.planted()), "stands still after release");
}

/// The body's angle round the vertical axis through the origin, radians.
fn bearing(p: Vec3) -> f32 {
    p.x.atan2(p.z)
}

#[test]
fn climbs_a_trunk_head_up_down_tail_first_and_round_it() {
    let text = std::fs::read_to_string(scene_path("trunk.yaml")).unwrap();
    let phases = [("up", "KeyW", 0.0, 10.0), ("down", "KeyS", 10.0, 16.0), ("round", "KeyD", 16.0, 30.0)];
    let mut timeline = String::new();
    for (_, key, from, to) in phases {
        timeline += &format!("- {{ at: {from}, press: [{key}] }}\n- {{ at: {to}, release: [{key}] }}\n");
    }
    let at = |seconds: f32| {
        let record = run(&text, &timeline, seconds);
        assert!(record.violations.is_empty(), "{:#?}", record.violations);
        let body = record.body.unwrap();
        assert!(body.sloth.frame.forward.y > 0.9, "head up: {}", body.sloth.frame.forward);
        body.sloth.frame.centre
    };
    let start = at(0.1);
    let up = at(10.0);
    let down = at(16.0);
    let round = at(30.0);
    assert!(up.y - start.y > 0.8, "climbed {} m", up.y - start.y);
    assert!(up.y - down.y > 0.4, "came down {} m", up.y - down.y);
    let turned = (bearing(round) - bearing(down)).abs().to_degrees();
    assert!(turned > 60.0, "went {turned} degrees round");
}

fn forest() -> String {
    std::fs::read_to_string(super::common::path("scenes/forest.yaml")).unwrap()
}

#[test]
fn in_the_forest_the_sloth_walks_onto_the_limb_in_to_the_trunk_down_it_and_up_again() {
    // W to the trunk (over onto it by 23 s), S down for 4 s, then W up and over onto the limb.
    let timeline = "- { at: 0, press: [KeyW] }\n- { at: 23, release: [KeyW] }\n- { at: 23, press: [KeyS] }\n\
                    - { at: 27, release: [KeyS] }\n- { at: 27, press: [KeyW] }\n";
    let record = run(&forest(), timeline, 45.0);
    assert!(record.violations.is_empty(), "{:#?}", record.violations);
    let route = ["cecropia/side", "cecropia/limb", "cecropia/trunk", "cecropia/limb"];
    assert_eq!(record.visited, route);
    let height = |seconds: f32| run(&forest(), timeline, seconds).body.unwrap().sloth.frame.centre.y;
    let (arrived, down, back) = (height(23.0), height(27.0), height(45.0));
    assert!(arrived - down > 0.2, "climbed down {} m", arrived - down);
    assert!(back > arrived, "back up on the limb: {back} m, {arrived} m on arriving at the trunk");
}

#[test]
fn in_the_forest_the_sloth_walks_along_a_bough_and_changes_to_the_branch_beside_it() {
    let text = forest().replace(
        "sloth: { support: cecropia/side, at: 0.7, facing: backward }",
        "sloth: { support: oak/west, at: 0.45 }",
    );
    let timeline = "- { at: 0, press: [KeyW] }\n- { at: 2, press: [KeyD] }\n- { at: 2.2, release: [KeyD] }\n";
    let record = run(&text, timeline, 20.0);
    assert!(record.violations.is_empty(), "{:#?}", record.violations);
    assert!(record.final_supports.iter().all(|s| s == "oak/west_twin"), "{:?}", record.final_supports);
    assert!(record.distance > 1.0, "walked {} m", record.distance);
}

#[test]
fn walks_across_the_biological_range_of_speeds_at_the_speed_asked() {
    let text = std::fs::read_to_string(scene_path("parallel.yaml")).unwrap();
    for speed in [0.07f32, 0.15, 0.25, 0.3] {
        let fast = text.replace(
            "sloth: { support: near, at: 0.2 }",
            &format!("sloth: {{ support: near, at: 0.2, speed: {speed} }}"),
        );
        let record = run(&fast, "- { at: 0, press: [KeyW] }\n", 12.0);
        assert!(record.violations.is_empty(), "{speed} m/s: {:#?}", record.violations);
        assert!(record.gait_kept(), "{speed} m/s: {:?}", record.steady_footfalls);
        let error = (record.mean_speed - speed).abs() / speed;
        assert!(error < 0.2, "asked {speed} m/s, walked {} m/s", record.mean_speed);
    }
}

#[test]
fn walks_in_from_each_bough_of_the_forest_onto_its_thick_or_leaning_trunk() {
    let forest = forest();
    let placed = "sloth: { support: cecropia/side, at: 0.7, facing: backward }";
    assert!(forest.contains(placed), "forest.yaml's sloth changed");
    let mut failed = Vec::new();
    // The oak's trunk is 0.22-0.3 m thick with two boughs leaving it side by side.
    for (bough, trunk) in [
        ("oak/west", "oak/trunk"),
        ("oak/west_twin", "oak/trunk"),
        ("oak/east", "oak/trunk"),
        ("leaning/bough", "leaning/trunk"),
    ] {
        let text =
            forest.replace(placed, &format!("sloth: {{ support: {bough}, at: 0.6, facing: backward, autorun: true }}"));
        failed.extend(failed_walk_in(&run(&text, "[]", 30.0), bough, trunk));
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// Why the sloth of `record`, on autorun from `bough`, did not walk in onto `trunk` next
/// keeping every per-step criterion; `None` when it did.
fn failed_walk_in(record: &Record, bough: &str, trunk: &str) -> Option<String> {
    let walked_in = record.visited.get(..2) == Some(&[bough.to_string(), trunk.to_string()]);
    (!record.violations.is_empty() || !walked_in)
        .then(|| format!("{bough}: went by {:?}; {:?}", record.visited, record.violations.first()))
}

/// How far out along the branch above, metres, the forefeet have walked by the end.
const OUT_ALONG: f32 = 1.0;

#[test]
fn walks_in_from_the_first_branch_of_every_generated_tree_onto_its_trunk_and_on_up_onto_a_branch() {
    let forest = std::fs::read_to_string(super::common::path("scenes/generated_forest.yaml")).unwrap();
    let mut failed = Vec::new();
    for tree in 1..=16 {
        let (branch, trunk) = (format!("forest/t{tree}-trunk-1"), format!("forest/t{tree}-trunk"));
        let text = format!(
            "{forest}\n  - name: sloth\n    sloth: {{ support: {branch}, at: 0.6, facing: backward, autorun: true }}\n"
        );
        let record = run(&text, "[]", 40.0);
        if let Some(failure) = failed_walk_in(&record, &branch, &trunk) {
            failed.push(failure);
            continue;
        }
        let sloth = &record.body.as_ref().unwrap().sloth;
        let fore_s = sloth.feet[Limb::LeftFore.index()].s.min(sloth.feet[Limb::RightFore.index()].s);
        let above = record.visited.get(2).filter(|support| support.starts_with(&format!("{trunk}-")));
        if above.is_none() || record.visited.len() != 3 || fore_s < OUT_ALONG {
            failed.push(format!("{trunk}: went by {:?}, the forefeet {fore_s} m out", record.visited));
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}
