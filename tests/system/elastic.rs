//! Elastic bodies: the shipped scenes run headless through the real plugins, checked at every
//! fixed step against the solids they rest on; a hanging fruit dropped by a timeline; a body
//! dragged through the view as the mouse would; the dump alike from run to run.

use super::common::{SMALL, entity, path, run, small_app, vec3};
use bevy::prelude::*;
use canopy::elastic::ElasticBody;
use canopy::elastic::plugin::Solids;
use canopy::foundation::messages::{DragPhase, ViewDragged, ViewGrab};
use canopy::view::CameraParams;

/// The deepest any particle of any elastic body lies inside any solid, metres. The particles
/// are taken as coming from above, so that a plane shape (which has no inside of its own)
/// counts what lies under it.
pub fn deepest(world: &mut World) -> f32 {
    let solids = world.resource::<Solids>().colliders.clone();
    let mut bodies = world.query::<&ElasticBody>();
    let mut worst = 0.0f32;
    for elastic in bodies.iter(world) {
        for &p in &elastic.body.positions {
            for solid in solids.iter() {
                if let Some((depth, _)) = solid.penetration(p, p + Vec3::Y * 1e-3) {
                    worst = worst.max(depth);
                }
            }
        }
    }
    worst
}

/// The body named `name`.
fn body<'a>(world: &'a mut World, name: &str) -> &'a ElasticBody {
    let mut query = world.query::<(&ElasticBody, &canopy::foundation::entity::SceneEntity)>();
    let found = query.iter(world).find(|(_, scene)| scene.name == name).map(|(body, _)| body);
    found.unwrap_or_else(|| panic!("no elastic body {name}"))
}

#[test]
fn the_jelly_and_the_cushion_come_to_rest_on_the_crate_and_the_floor_without_sinking_or_jitter() {
    let mut app = small_app(&path("scenes/softbody.yaml"));
    let mut lowest: Vec<[f32; 2]> = Vec::new();
    for step in 0..600 {
        app.update();
        let world = app.world_mut();
        let depth = deepest(world);
        assert!(depth < 1e-4, "step {step}: a particle {depth} m inside a solid");
        if step >= 300 {
            lowest.push(["jelly", "cushion"].map(|name| body(world, name).body.lowest().y));
        }
    }
    for (i, (name, rest)) in [("jelly", 0.2), ("cushion", 0.0)].into_iter().enumerate() {
        let (low, high) = lowest.iter().fold((f32::MAX, f32::MIN), |(l, h), y| (l.min(y[i]), h.max(y[i])));
        assert!((low - rest).abs() < 1e-4, "{name} rests at {rest} m: {low}");
        assert!(high - low < 1e-4, "{name} still over the last five seconds: {low} to {high}");
    }
    let world = app.world_mut();
    let jelly = &body(world, "jelly").body;
    let centre = jelly.centre_of_mass();
    assert!((0.15..0.55).contains(&centre.x) && centre.z.abs() < 0.2, "the jelly stays on the crate: {centre}");
    assert!(jelly.kinetic_energy() < 1e-4, "{}", jelly.kinetic_energy());
    assert!((jelly.volume_ratio() - 1.0).abs() < 0.05, "{}", jelly.volume_ratio());
    // The drop hangs below its stem's point.
    let drop = &body(world, "drop").body;
    assert!(!drop.stems.is_empty() && drop.positions.iter().all(|p| p.y < 1.0), "it hangs below its stem");
}

#[test]
fn a_hanging_plum_swings_then_falls_onto_the_terrain_when_the_timeline_drops_it() {
    let mut app = small_app(&path("scenes/fruit.yaml"));
    let timeline = canopy::controls::timeline::Timeline::load(&path("timelines/fruit_drop.yaml")).unwrap();
    timeline.check(app.world_mut()).unwrap();
    app.insert_resource(timeline);
    let (mut xs, mut fell_from, mut resting) = (Vec::new(), None, Vec::new());
    for step in 0..600 {
        app.update();
        let world = app.world_mut();
        let depth = deepest(world);
        assert!(depth < 1e-3, "step {step}: a particle {depth} m inside a solid");
        if step >= 300 {
            let fallen = &body(world, "fallen").body;
            resting.push((fallen.lowest().y, fallen.centre_of_mass()));
        }
        let plum = &body(world, "plum_1").body;
        if step < 115 {
            assert!(!plum.stems.is_empty(), "on its stem until the timeline drops it");
            let anchor = plum.stems[0].anchor;
            assert!(plum.centre_of_mass().y < anchor.y - 0.05, "below its stem");
            xs.push(plum.centre_of_mass().z);
        } else if fell_from.is_none() && plum.stems.is_empty() {
            fell_from = Some(plum.centre_of_mass().y);
        }
    }
    let (low, high) = xs.iter().fold((f32::MAX, f32::MIN), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(high - low > 0.01, "it swings: z from {low} to {high}");
    let world = app.world_mut();
    let names = world.resource::<Solids>().names.clone();
    let plum = body(world, "plum_1");
    assert!(plum.dropped && fell_from.is_some());
    let touching: Vec<&String> =
        names.iter().zip(plum.body.contacts()).filter(|(_, n)| **n > 0).map(|(n, _)| n).collect();
    assert!(touching.contains(&&"meadow".to_string()), "it lies on the terrain: {touching:?}");
    assert!(plum.body.centre_of_mass().y < fell_from.unwrap() - 0.8, "it fell");
    // The plum that fell at the start lies on the terrain for the last five seconds, rocking
    // in its hollow (a ball rolls) but neither sinking nor bouncing.
    let fallen = body(world, "fallen");
    let on_meadow = names.iter().zip(fallen.body.contacts()).any(|(n, &c)| n == "meadow" && c > 0);
    assert!(on_meadow, "the fallen plum touches the terrain");
    let (low, high) = resting.iter().fold((f32::MAX, f32::MIN), |(l, h), (y, _)| (l.min(*y), h.max(*y)));
    let wandered = resting.iter().map(|(_, c)| c.distance(resting[0].1)).fold(0.0f32, f32::max);
    assert!(high - low < 1e-3 && wandered < 0.1, "it stays in its hollow: lowest {low} to {high}, {wandered} m away");
    // The third was pulled aside by a hand, then let go and dropped.
    let third = body(world, "plum_3");
    assert!(third.dropped && third.body.grab.is_empty());
}

#[test]
fn the_dump_of_a_run_is_alike_every_time_and_holds_each_body_s_figures() {
    let timeline = std::fs::read_to_string(path("timelines/fruit_drop.yaml")).unwrap();
    let first = run("scenes/fruit.yaml", 300, Some(&timeline), SMALL);
    let second = run("scenes/fruit.yaml", 300, Some(&timeline), SMALL);
    assert_eq!(first.dump, second.dump);
    let plum = entity(&first.dump, "plum_2");
    for field in ["centre_of_mass", "volume_ratio", "max_strain", "kinetic_energy_j", "lowest", "contacts"] {
        assert!(!plum[field].is_null(), "{field} in {plum}");
    }
    assert_eq!((plum["stems"].as_u64(), plum["dropped"].as_bool()), (Some(0), Some(true)));
    let ratio = plum["volume_ratio"].as_f64().unwrap();
    assert!((ratio - 1.0).abs() < 0.1, "{ratio}");
    assert!(vec3(&plum["lowest"]).y < vec3(&plum["centre_of_mass"]).y);
}

#[test]
fn a_drag_on_the_view_grabs_the_jelly_and_moves_it_with_the_pointer() {
    let mut app = small_app(&path("scenes/softbody.yaml"));
    for _ in 0..120 {
        app.update();
    }
    let world = app.world_mut();
    let camera = world.query::<&CameraParams>().single(world).unwrap().camera();
    let aspect = SMALL.x as f32 / SMALL.y as f32;
    let jelly = body(world, "jelly").body.centre_of_mass();
    let to_ndc = |p: Vec3| camera.view_projection(aspect).project_point3(p).truncate();
    let start = to_ndc(jelly + Vec3::Y * 0.06);
    world.write_message(ViewDragged { phase: DragPhase::Start, ndc: start, aspect });
    app.update();
    assert!(app.world().resource::<ViewGrab>().held, "the jelly holds the drag");
    assert!(!body(app.world_mut(), "jelly").body.grab.is_empty());
    // Up and to the left in small moves, as a pointer goes.
    let target = to_ndc(jelly + Vec3::new(-0.3, 0.4, 0.0));
    for i in 1..=30 {
        let ndc = start.lerp(target, i as f32 / 30.0);
        app.world_mut().write_message(ViewDragged { phase: DragPhase::Move, ndc, aspect });
        app.update();
    }
    for _ in 0..60 {
        app.update();
    }
    let held = &body(app.world_mut(), "jelly").body;
    let lifted = held.centre_of_mass();
    assert!(lifted.y > jelly.y + 0.12 && lifted.x < jelly.x - 0.15, "it follows the hand: {jelly} to {lifted}");
    // The grabbed particles hang where the hand holds them, sagging a little on it.
    let count = held.grab.len() as f32;
    let hand = held.grab.iter().map(|a| a.anchor).sum::<Vec3>() / count;
    let grabbed = held.grab.iter().map(|a| held.positions[a.particle as usize]).sum::<Vec3>() / count;
    assert!(hand.distance(grabbed) < 0.05, "the hand at {hand} holds the body at {grabbed}");
    app.world_mut().write_message(ViewDragged { phase: DragPhase::End, ndc: target, aspect });
    app.update();
    assert!(!app.world().resource::<ViewGrab>().held);
    for _ in 0..30 {
        app.update();
    }
    let falling = body(app.world_mut(), "jelly").body.centre_of_mass();
    assert!(falling.y < lifted.y - 0.1, "let go, it falls: {lifted} to {falling}");
}

#[test]
fn the_sloth_s_hands_shake_the_plums_loose_as_it_passes_and_they_fall_onto_the_meadow() {
    use canopy::sloth::plugin::SlothBody;
    let mut app = small_app(&path("scenes/sloth_fruit.yaml"));
    let hand_reach = |world: &mut World, name: &str| {
        // The nearest a forehand's grip came to this plum's stem anchor.
        let anchor = body(world, name).start.shaken_loose.unwrap().0;
        let mut sloths = world.query::<&SlothBody>();
        let sloth = &sloths.single(world).unwrap().sloth;
        [1, 3].map(|limb| sloth.feet[limb].grip.distance(anchor)).into_iter().fold(f32::MAX, f32::min)
    };
    let mut dropped_at = [None; 3];
    for step in 0..840 {
        app.update();
        let world = app.world_mut();
        let depth = deepest(world);
        assert!(depth < 1e-3, "step {step}: a particle {depth} m inside a solid");
        for (i, name) in ["plum_1", "plum_2", "plum_3"].into_iter().enumerate() {
            if dropped_at[i].is_none() && body(world, name).dropped {
                // Shaken loose by a hand that had just taken hold within its reach.
                let reach = hand_reach(world, name);
                assert!(reach <= 0.25, "{name} dropped with the nearest hand {reach} m from its stem");
                dropped_at[i] = Some(step);
            }
        }
    }
    assert!(dropped_at[0].is_some_and(|s| s > 60), "the first plum hangs until the sloth comes: {dropped_at:?}");
    assert!(dropped_at[1] > dropped_at[0], "the second falls later, further along: {dropped_at:?}");
    assert_eq!(dropped_at[2], None, "the third, beyond where the sloth has walked, still hangs");
    let world = app.world_mut();
    let names = world.resource::<Solids>().names.clone();
    for name in ["plum_1", "plum_2"] {
        let plum = body(world, name);
        let on_meadow = names.iter().zip(plum.body.contacts()).any(|(n, &c)| n == "meadow" && c > 0);
        assert!(on_meadow && plum.body.centre_of_mass().y < 1.0, "{name} lies on the meadow");
    }
}
