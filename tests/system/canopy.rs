//! The default scene, the living canopy, for a minute of simulated time through the real
//! plugins: the sloth's invariants and its biceps at every step, the fruit never inside a
//! support or the ground, the trees standing on the world's ground, and the dump alike from
//! run to run.

use super::common::{SMALL, path, run, small_app};
use super::elastic::deepest;
use super::sloth::check_step;
use bevy::prelude::*;
use canopy::elastic::ElasticBody;
use canopy::foundation::dump::dump_state;
use canopy::foundation::entity::SceneEntity;
use canopy::sloth::{SlothBody, SlothMuscles};
use canopy::tree::TreeBody;
use canopy::world::WorldBody;

const SCENE: &str = "scenes/canopy.yaml";

/// Fixed steps in a minute.
const MINUTE: u64 = 3600;

/// Farthest a trunk's base may lie from the ground under it, metres.
const ROOT_LIMIT: f32 = 1e-4;

/// How far each support that forks from no other starts from the world's ground under it,
/// the largest over the scene's trees, metres.
fn farthest_root(world: &mut World) -> f32 {
    let mut worlds = world.query::<&WorldBody>();
    let (heights, geometry) = worlds.single(world).unwrap().ground();
    let heights = heights.clone();
    let mut trees = world.query::<&TreeBody>();
    let roots: Vec<Vec3> = trees
        .iter(world)
        .flat_map(|body| body.tree.supports.iter().filter(|s| s.parent.is_none()).map(|s| s.points[0]))
        .collect();
    assert!(roots.len() >= 17, "the fig and the forest's trunks: {}", roots.len());
    roots.iter().map(|p| (p.y - heights.ground_height(p.x, p.z, geometry)).abs()).fold(0.0, f32::max)
}

#[test]
fn a_minute_of_the_living_canopy_keeps_every_invariant_and_plays_alike_each_time() {
    let mut app = small_app(&path(SCENE));
    let mut violations = Vec::new();
    for step in 0..MINUTE {
        app.update();
        let world = app.world_mut();
        let (body, muscles) = world.query::<(&SlothBody, &SlothMuscles)>().single(world).unwrap();
        let time = body.sloth.time;
        check_step(body, muscles, &mut |what| violations.push(format!("t={time:.2}s: {what}")));
        let depth = deepest(world);
        if depth > 1e-3 {
            violations.push(format!("step {step}: a fruit's particle {depth} m inside a support or the ground"));
        }
        if step % 600 == 0 {
            let root = farthest_root(world);
            assert!(root < ROOT_LIMIT, "step {step}: a trunk starts {root} m off the ground");
        }
    }
    assert!(
        violations.is_empty(),
        "{} violations, the first: {:?}",
        violations.len(),
        &violations[..violations.len().min(3)]
    );

    let world = app.world_mut();
    let (body, _) = world.query::<(&SlothBody, &SlothMuscles)>().single(world).unwrap();
    // It walked on by itself, at about its speed, and had not come to the end of the limb.
    let sloth = &body.sloth;
    assert!(
        sloth.distance > 5.0 && sloth.blocked.is_none(),
        "walked {} m, blocked {:?}",
        sloth.distance,
        sloth.blocked
    );
    // The minute's walk passes every plum: each was shaken loose and lies on the ground.
    let mut plums = world.query::<(&ElasticBody, &SceneEntity)>();
    let mut dropped: Vec<&str> = plums.iter(world).filter(|(b, _)| b.dropped).map(|(_, s)| s.name.as_str()).collect();
    dropped.sort();
    assert_eq!(dropped, ["plum_1", "plum_2", "plum_3"], "the plums along the walk fell");
    let names = world.resource::<canopy::elastic::plugin::Solids>().names.clone();
    for (plum, scene) in plums.iter(world).filter(|(b, _)| b.dropped) {
        let on_land = names.iter().zip(plum.body.contacts()).any(|(n, &c)| n == "land" && c > 0);
        assert!(on_land, "{} lies on the ground", scene.name);
    }

    // A second run of as many steps, through the command line's headless run, ends alike.
    let first = dump_state(app.world_mut());
    let steps = first["frame"].as_u64().unwrap();
    let second = run(SCENE, steps, None, SMALL).dump;
    assert!(first == second, "two runs of the default scene differ after {steps} steps");
}
