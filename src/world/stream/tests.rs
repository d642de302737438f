use super::*;

fn settings() -> StreamSettings {
    StreamSettings {
        chunk_m: 16.0,
        load_radius_m: 140.0,
        unload_radius_m: 170.0,
        level_distances_m: [30.0, 65.0, 100.0],
        bounds: None,
    }
}

#[test]
fn a_finite_world_wants_its_own_chunks_alone() {
    let settings = StreamSettings { bounds: Some([5, 3]), ..settings() };
    assert_eq!(settings.max_resident(), 15);
    // From inside, beside its edge, and from far outside it.
    for (camera, wanted) in [(Vec2::new(8.0, 8.0), 15), (Vec2::new(-60.0, 20.0), 15), (Vec2::new(-400.0, 0.0), 0)] {
        let plan = plan(&settings, camera, Vec2::X, &HashMap::new(), &HashMap::new());
        assert!(plan.requests.iter().all(|&(key, _)| settings.contains(key)), "{camera}: {plan:?}");
        assert_eq!(plan.requests.len(), wanted, "{camera}");
    }
    assert!(!settings.contains(ChunkKey { x: 5, z: 0 }) && !settings.contains(ChunkKey { x: 0, z: -1 }));
    assert!(settings.contains(ChunkKey { x: 4, z: 2 }));
}

#[test]
fn the_nearest_chunks_ahead_come_first_each_at_its_level() {
    let settings = settings();
    let (camera, forward) = (Vec2::new(8.0, 8.0), Vec2::X);
    let plan = plan(&settings, camera, forward, &HashMap::new(), &HashMap::new());
    assert_eq!(plan.requests[0], (ChunkKey { x: 0, z: 0 }, 0), "the chunk under the camera first");
    let distance = |key: ChunkKey| settings.centre(key).distance(camera);
    let ahead = |key: ChunkKey| (settings.centre(key) - camera).dot(forward) >= 0.0 || distance(key) <= 16.0;
    let first_behind = plan.requests.iter().position(|&(key, _)| !ahead(key)).unwrap();
    assert!(plan.requests[first_behind..].iter().all(|&(key, _)| !ahead(key)), "ahead before behind");
    for pair in plan.requests[..first_behind].windows(2) {
        assert!(distance(pair[0].0) <= distance(pair[1].0), "nearest first: {pair:?}");
    }
    for &(key, level) in &plan.requests {
        assert!(distance(key) < 140.0);
        assert_eq!(level, settings.level(settings.nearest_m(key, camera) - 8.0));
    }
    let levels: Vec<u8> = (0..LEVELS).collect();
    assert!(levels.iter().all(|l| plan.requests.iter().any(|r| r.1 == *l)), "every level used");
    assert!(plan.requests.len() <= settings.max_resident());
}

#[test]
fn chunks_between_the_radii_neither_load_nor_unload() {
    let settings = settings();
    let between = ChunkKey { x: 9, z: 0 };
    let distance = settings.centre(between).distance(Vec2::new(8.0, 8.0));
    assert!(distance > 140.0 && distance < 170.0, "{distance}");
    let resident = HashMap::from([(between, 3), (ChunkKey { x: 11, z: 0 }, 3)]);
    let plan = plan(&settings, Vec2::new(8.0, 8.0), Vec2::X, &resident, &HashMap::new());
    assert!(plan.requests.iter().all(|r| r.0 != between), "not wanted again");
    assert_eq!(plan.unload, vec![ChunkKey { x: 11, z: 0 }], "only beyond the unload radius");
    // Resident or pending at the right level: not asked for again; at another level: asked.
    let here = ChunkKey { x: 0, z: 0 };
    let done = HashMap::from([(here, 0)]);
    assert!(plan_for(&settings, &done, &HashMap::new()).iter().all(|r| r.0 != here));
    assert!(plan_for(&settings, &HashMap::new(), &done).iter().all(|r| r.0 != here));
    assert!(plan_for(&settings, &HashMap::from([(here, 2)]), &HashMap::new()).contains(&(here, 0)));
}

fn plan_for(
    settings: &StreamSettings,
    resident: &HashMap<ChunkKey, u8>,
    pending: &HashMap<ChunkKey, u8>,
) -> Vec<(ChunkKey, u8)> {
    plan(settings, Vec2::new(8.0, 8.0), Vec2::X, resident, pending).requests
}

#[test]
fn a_wandering_camera_keeps_resident_chunks_within_the_bound() {
    let settings = settings();
    let mut resident: HashMap<ChunkKey, u8> = HashMap::new();
    let mut camera = Vec2::ZERO;
    for step in 0..400 {
        // A path that turns and doubles back across chunk borders.
        let angle = step as f32 * 0.05;
        let forward = Vec2::new(angle.cos(), (angle * 0.7).sin());
        camera += forward * 6.0;
        let plan = plan(&settings, camera, forward, &resident, &HashMap::new());
        for key in &plan.unload {
            resident.remove(key);
        }
        resident.extend(plan.requests);
        assert!(resident.len() <= settings.max_resident(), "step {step}: {}", resident.len());
        assert!(resident.keys().all(|&k| settings.centre(k).distance(camera) <= 170.0));
    }
}

#[test]
fn settings_that_make_no_sense_are_refused() {
    let good = settings();
    assert!(good.check().is_ok());
    for bad in [
        StreamSettings { load_radius_m: 0.0, ..good },
        StreamSettings { unload_radius_m: 90.0, ..good },
        StreamSettings { unload_radius_m: f32::NAN, ..good },
        StreamSettings { chunk_m: -1.0, ..good },
        StreamSettings { unload_radius_m: 5000.0, ..good },
        StreamSettings { level_distances_m: [60.0, 30.0, 90.0], ..good },
        // Too close for a chunk's diagonal, the lead and a morph band between them.
        StreamSettings { level_distances_m: [30.0, 60.0, 100.0], ..good },
    ] {
        assert!(bad.check().is_err(), "{bad:?}");
    }
}

/// The chunks within the load radius of `camera` with the levels the plan gives them.
fn levels_around(settings: &StreamSettings, camera: Vec2) -> HashMap<ChunkKey, u8> {
    plan(settings, camera, Vec2::X, &HashMap::new(), &HashMap::new()).requests.into_iter().collect()
}

#[test]
fn neighbours_of_two_levels_both_have_the_coarser_shape_along_their_edge() {
    let settings = settings();
    let morph = settings.morph_m();
    assert!(morph >= 4.0, "{morph}");
    for step in 0..60 {
        let camera = Vec2::new(step as f32 * 0.77, step as f32 * 0.31 - 9.0);
        let levels = levels_around(&settings, camera);
        for (&key, &level) in &levels {
            for east in [ChunkKey { x: key.x + 1, ..key }, ChunkKey { z: key.z + 1, ..key }] {
                let Some(&other) = levels.get(&east) else { continue };
                assert!(level.abs_diff(other) <= 1, "{key:?} at {level}, {east:?} at {other}");
                if level == other {
                    continue;
                }
                let (fine, coarse) = (level.min(other), level.max(other));
                // Points along the shared edge, from one end to the other.
                let (a, b) = (settings.centre(key), settings.centre(east));
                let middle = (a + b) * 0.5;
                let along = (b - a).perp() * 0.5;
                for k in 0..=8 {
                    let d = (middle + along * (k as f32 / 4.0 - 1.0)).distance(camera);
                    assert!(d >= settings.morph_band(fine).unwrap().end_m, "the finer chunk morphed through");
                    if let Some(band) = settings.morph_band(coarse) {
                        assert!(d <= band.start_m, "the coarser chunk not morphing yet");
                    }
                }
            }
        }
    }
}

#[test]
fn a_chunk_changes_level_only_beyond_the_finer_levels_morph() {
    // The camera flies out and back across the levels at up to 0.8 m a frame (about 30 m/s
    // at 40 frames a second); a chunk asked for arrives four frames later.
    let settings = settings();
    let latency = 4;
    let mut resident: HashMap<ChunkKey, u8> = HashMap::new();
    let mut asked: Vec<(usize, ChunkKey, u8)> = Vec::new();
    let mut changes = 0;
    for frame in 0..1200 {
        let angle = frame as f32 * 0.004;
        let out_and_back = 150.0 - ((frame as f32 * 0.5).rem_euclid(300.0) - 150.0).abs();
        let camera = Vec2::new(angle.cos(), angle.sin()) * (20.0 + out_and_back);
        for &(_, key, level) in asked.iter().filter(|a| a.0 + latency == frame) {
            if let Some(old) = resident.insert(key, level).filter(|&old| old != level) {
                let finer = settings.morph_band(old.min(level)).unwrap();
                let nearest = settings.nearest_m(key, camera);
                assert!(nearest >= finer.end_m, "frame {frame}: {key:?} {old} -> {level} at {nearest} m");
                changes += 1;
            }
        }
        asked.retain(|a| a.0 + latency > frame);
        let pending: HashMap<ChunkKey, u8> = asked.iter().map(|a| (a.1, a.2)).collect();
        let plan = plan(&settings, camera, Vec2::X, &resident, &pending);
        for key in plan.unload {
            resident.remove(&key);
        }
        asked.retain(|a| plan.requests.iter().all(|r| r.0 != a.1));
        asked.extend(plan.requests.into_iter().map(|(key, level)| (frame, key, level)));
    }
    assert!(changes > 100, "{changes} changes of level");
}
