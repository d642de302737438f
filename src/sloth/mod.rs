//! The `sloth` entity kind: a two-toed sloth that hangs under branches and climbs trunks.

pub mod body;
pub mod ccd;
pub mod foothold;
pub mod gait;
pub mod locomotion;
pub mod rig;
pub mod supports;

#[cfg(test)]
mod probe {
    use super::locomotion::{Drive, Sloth};
    use super::rig::Proportions;
    use super::supports::Supports;
    use crate::tree::{Shape, SupportSpec, Tree};
    use bevy::math::Vec3;

    fn run(points: Vec<Vec3>, seconds: f32) -> String {
        let n = points.len();
        let shape = Shape::Polyline { points, radii: vec![0.04; n] };
        let tree = Tree::build(&[SupportSpec { name: "b".into(), shape, kind: Some(crate::tree::SupportKind::Branch) }]).unwrap();
        run_tree(tree, seconds)
    }

    fn run_tree(tree: Tree, seconds: f32) -> String {
        let supports = Supports::new([("t", &tree)]);
        let mut sloth = match Sloth::place(&supports, 0, 0.15, 1.0, Proportions::default(), 0.11) { Ok(s) => s, Err(e) => return format!("{e}") };
        let mut worst = 0.0f32;
        let mut blocked_at = None;
        for _ in 0..(60.0 * seconds) as usize {
            sloth.step(1.0 / 60.0, Drive { direction: 1.0, change: None }, &supports);
            for f in &sloth.feet {
                if f.planted() {
                    let d = supports.paths[f.support].distance(f.position).abs();
                    if d > 0.01 && d > worst && false {
                        let i = sloth.feet.iter().position(|g| g == f).unwrap();
                        let rig = &sloth.rigs[i];
                        let at: Vec<String> = (0..5).map(|j| format!("{:.0}[{:.0},{:.0}]", f.angles[j].to_degrees(), rig.min[j].to_degrees(), rig.max[j].to_degrees())).collect();
                        println!("  t {:.2} limb {:?} d {:.3} angles {:?} rel {:.3}", sloth.time, rig.limb, d, at, f.grip - rig.root_in(&sloth.frame));
                    }
                    worst = worst.max(d);
                }
            }
            if sloth.blocked.is_some() && blocked_at.is_none() { blocked_at = Some(sloth.time); }
            if false && sloth.stuck[1] && (sloth.time * 60.0).round() as i32 % 30 == 0 && sloth.time < 20.0 {
                println!("  LF stuck t {:.2} feet {:?} change {:?} fwd {:.2}", sloth.time, sloth.feet.map(|f| (f.support, (f.s * 100.0).round() / 100.0, f.planted())), sloth.change_to, sloth.frame.forward);
            }
        }
        let l = supports.paths[0].length();
        format!("worst {:.4} minclear {:.3} speed {:.3} hind s {:.2}/{:.2} on {:?} blocked {:?}", worst, sloth.min_clearance, sloth.mean_speed(), sloth.feet[0].s, l, sloth.feet.map(|f| f.support), blocked_at)
    }

    #[test]
    fn parallel() {
        for gap in [0.15f32, 0.2, 0.25, 0.3, 0.35] {
            let mk = |z: f32| Shape::Polyline { points: vec![Vec3::new(-3.0, 2.0, z), Vec3::new(3.0, 2.0, z)], radii: vec![0.04, 0.04] };
            let tree = Tree::build(&[SupportSpec { name: "a".into(), shape: mk(0.0), kind: None }, SupportSpec { name: "b".into(), shape: mk(-gap), kind: None }]).unwrap();
            let supports = Supports::new([("t", &tree)]);
            let mut sloth = Sloth::place(&supports, 0, 0.2, 1.0, Proportions::default(), 0.11).unwrap();
            let mut worst = 0.0f32;
            for i in 0..(60 * 30) {
                let change = if i == 120 { Some(1.0) } else { None };
                sloth.step(1.0 / 60.0, Drive { direction: 1.0, change }, &supports);
                if i == 121 { println!("change to {:?}", sloth.change_to); }
                for f in &sloth.feet {
                    if f.planted() {
                        worst = worst.max(supports.paths[f.support].distance(f.position).abs());
                    }
                }
            }
            println!("gap {gap}: worst {worst:.4} clear {:.3} feet on {:?} blocked {:?} speed {:.3}", sloth.min_clearance, sloth.feet.map(|f| f.support), sloth.blocked, sloth.mean_speed());
        }
    }

    #[test]
    fn sweep() {
        for angle in (80..=185).step_by(5) {
            let turn = (180.0 - angle as f32).to_radians();
            let corner = Vec3::new(0.0, 2.0, 0.0);
            let points = vec![Vec3::new(-1.5, 2.0, 0.0), corner, corner + Vec3::new(turn.cos(), 0.0, turn.sin()) * 1.5];
            println!("turn {angle}: {}", run(points, 40.0));
        }
        for angle in (80..=185).step_by(5) {
            let t = (180.0 - angle as f32);
            let tree = Tree::build(&[
                SupportSpec { name: "a".into(), shape: Shape::Polyline { points: vec![Vec3::new(-1.5, 2.0, 0.0), Vec3::new(0.0, 2.0, 0.0)], radii: vec![0.04, 0.04] }, kind: None },
                SupportSpec { name: "b".into(), shape: Shape::Fork { parent: "a".into(), at: 1.0, yaw_deg: 90.0 - t, pitch_deg: 0.0, length: 1.5, radius: [0.04, 0.03], bend_deg: [0.0, 0.0], sections: 1 }, kind: None },
            ]).unwrap();
            println!("fork {angle}: {}", run_tree(tree, 40.0));
        }
        for angle in (120..=210).step_by(5) {
            let pitch = (180.0 - angle as f32).to_radians();
            let corner = Vec3::new(0.0, 2.0, 0.0);
            let points = vec![Vec3::new(-1.5, 2.0, 0.0), corner, corner + Vec3::new(pitch.cos(), pitch.sin(), 0.0) * 1.5];
            println!("rise {angle}: {}", run(points, 40.0));
        }
    }
}
