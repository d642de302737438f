//! Which chunks of a world to have, around a camera: the plan that streaming carries out each
//! frame.
//!
//! Chunks whose centre lies within the load radius of the camera (and, in a finite world,
//! within its bounds) are wanted, each at the level
//! of detail its distance asks for; they are requested nearest first, those ahead of the camera
//! before those behind. A chunk is let go only beyond the unload radius, larger than the load
//! radius, so that a camera moving back and forth across the border makes no churn. Resident
//! chunks then stay within [`StreamSettings::max_resident`].
//!
//! # Levels without popping
//!
//! A chunk's level follows the distance of its *nearest* point, less a lead of half a chunk
//! ([`StreamSettings::lead_m`]), and the vertices of a level-`l` chunk morph into the shape of
//! level `l + 1` over the band of distances [`StreamSettings::morph_band`] that ends at the
//! next level's distance. Hence:
//! - a chunk changes level only while all of it lies beyond that distance, where the finer
//!   mesh already has the coarser one's shape: going coarser because its nearest point has
//!   moved past it by the lead; going finer because the finer mesh is asked for when its
//!   nearest point comes within the lead of it, and arrives before the camera has covered the
//!   lead;
//! - where chunks of levels `l` and `l + 1` meet, the finer one has fully morphed along the
//!   shared edge (all of the coarser chunk lies beyond the distance) and the coarser one has
//!   not begun to (the levels lie far enough apart for a chunk's diagonal, the lead and the
//!   morph band, which [`StreamSettings::check`] asks of them), so both edges have the coarser
//!   level's heights and normals.

use super::chunk::{ChunkKey, LEVELS, MorphBand};
use bevy::math::Vec2;
use std::collections::HashMap;

/// Where chunks are wanted and at what detail.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamSettings {
    /// A chunk's side in metres.
    pub chunk_m: f32,
    /// Chunks whose centre is nearer than this (metres, horizontally) are wanted.
    pub load_radius_m: f32,
    /// Chunks whose centre is farther than this are let go; more than the load radius.
    pub unload_radius_m: f32,
    /// From these distances on (metres, rising) chunks take levels 1, 2, ... of detail.
    pub level_distances_m: [f32; LEVELS as usize - 1],
    /// Chunks along x and z of a finite world, from chunk `(0, 0)`; `None` without bounds.
    pub bounds: Option<[u32; 2]>,
}

impl StreamSettings {
    /// Why the settings make no sense, if they do not: the field at fault and what is wrong.
    pub fn check(&self) -> Result<(), StreamError> {
        let refuse = |field: &'static str, message: String| Err(StreamError { field, message });
        let positive = |v: f32| v.is_finite() && v > 0.0;
        if !positive(self.chunk_m) {
            return refuse("chunk_m", format!("expected a side in metres greater than 0, found {}", self.chunk_m));
        }
        if !(positive(self.load_radius_m) && self.load_radius_m <= 1e5) {
            return refuse(
                "load_radius_m",
                format!("expected a distance greater than 0 and at most 1e5, found {}", self.load_radius_m),
            );
        }
        if !(self.unload_radius_m.is_finite() && self.unload_radius_m > self.load_radius_m) {
            return refuse(
                "unload_radius_m",
                format!(
                    "expected a distance greater than the load radius ({}), found {}",
                    self.load_radius_m, self.unload_radius_m
                ),
            );
        }
        // Beyond this many chunks across the unload radius, a world would hold too many.
        if self.unload_radius_m / self.chunk_m > 64.0 {
            return refuse(
                "unload_radius_m",
                format!("at most 64 chunks of {} m, found {} m", self.chunk_m, self.unload_radius_m),
            );
        }
        let rising = self.level_distances_m.windows(2).all(|w| w[0] <= w[1]);
        if !(self.level_distances_m.iter().all(|&d| positive(d) && d <= 1e5) && rising) {
            return refuse(
                "level_distances_m",
                format!("expected {} rising distances greater than 0, found {:?}", LEVELS - 1, self.level_distances_m),
            );
        }
        let need = self.chunk_m * std::f32::consts::SQRT_2 + self.lead_m() + self.min_morph_m();
        if let Some(pair) = self.level_distances_m.windows(2).find(|pair| pair[1] - pair[0] < need) {
            return refuse(
                "level_distances_m",
                format!(
                    "levels at {} m and {} m lie {} m apart: chunks of {} m need {need:.1} m between levels \
                     (a chunk's diagonal, half a chunk of lead and a quarter of a chunk to morph over)",
                    pair[0],
                    pair[1],
                    pair[1] - pair[0],
                    self.chunk_m
                ),
            );
        }
        Ok(())
    }

    /// How far ahead of its distance a chunk is made at a finer level: half a chunk.
    pub fn lead_m(&self) -> f32 {
        self.chunk_m * 0.5
    }

    /// The narrowest morph band the settings may leave: a quarter of a chunk.
    fn min_morph_m(&self) -> f32 {
        self.chunk_m * 0.25
    }

    /// The width of the morph bands: as wide as the levels leave room for (see the module's
    /// docs), at most the first level's distance.
    pub fn morph_m(&self) -> f32 {
        let room = self.level_distances_m.windows(2).map(|pair| pair[1] - pair[0]).fold(f32::MAX, f32::min);
        (room - self.chunk_m * std::f32::consts::SQRT_2 - self.lead_m()).min(self.level_distances_m[0])
    }

    /// The distances over which a chunk at `level` morphs into the next level's shape; `None`
    /// for the coarsest level.
    pub fn morph_band(&self, level: u8) -> Option<MorphBand> {
        let end_m = *self.level_distances_m.get(usize::from(level))?;
        Some(MorphBand { start_m: end_m - self.morph_m(), end_m })
    }

    /// The most chunks that can be resident at once: those whose centres lie within the unload
    /// radius of some point, at most a square of chunks around it.
    pub fn max_resident(&self) -> usize {
        let across = 2 * (self.unload_radius_m / self.chunk_m).ceil() as usize + 1;
        let [x, z] = self.bounds.map_or([across; 2], |bounds| bounds.map(|b| (b as usize).min(across)));
        x * z
    }

    /// Whether chunk `key` is part of the world.
    pub fn contains(&self, key: ChunkKey) -> bool {
        self.bounds
            .is_none_or(|[x, z]| (0..x as i64).contains(&i64::from(key.x)) && (0..z as i64).contains(&i64::from(key.z)))
    }

    /// The centre of chunk `key`, in metres.
    pub fn centre(&self, key: ChunkKey) -> Vec2 {
        (Vec2::new(key.x as f32, key.z as f32) + 0.5) * self.chunk_m
    }

    /// The level of detail `distance` metres away.
    pub fn level(&self, distance: f32) -> u8 {
        self.level_distances_m.iter().take_while(|&&d| distance >= d).count() as u8
    }

    /// The distance from `camera` to the nearest point of chunk `key` (0 inside it), metres.
    pub fn nearest_m(&self, key: ChunkKey, camera: Vec2) -> f32 {
        let half = Vec2::splat(self.chunk_m * 0.5);
        ((camera - self.centre(key)).abs() - half).max(Vec2::ZERO).length()
    }

    /// The level of detail chunk `key` takes for a camera at `camera`: that of its nearest
    /// point, taken the lead nearer.
    pub fn chunk_level(&self, key: ChunkKey, camera: Vec2) -> u8 {
        self.level(self.nearest_m(key, camera) - self.lead_m())
    }
}

/// Why streaming settings make no sense: the field at fault and what is wrong with it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct StreamError {
    /// The setting's name.
    pub field: &'static str,
    /// What is wrong.
    pub message: String,
}

/// What to do this frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plan {
    /// Chunks to make, with their level, in the order to make them.
    pub requests: Vec<(ChunkKey, u8)>,
    /// Resident chunks to let go.
    pub unload: Vec<ChunkKey>,
}

/// The plan for a camera at `camera` (metres, horizontally) looking along `forward` (need not
/// be a unit vector), given the chunks `resident` (with their levels) and those already
/// being made (`pending`, with the level asked for).
pub fn plan(
    settings: &StreamSettings,
    camera: Vec2,
    forward: Vec2,
    resident: &HashMap<ChunkKey, u8>,
    pending: &HashMap<ChunkKey, u8>,
) -> Plan {
    let distance = |key: ChunkKey| settings.centre(key).distance(camera);
    let reach = (settings.load_radius_m / settings.chunk_m).ceil() as i32 + 1;
    let around = ((camera / settings.chunk_m).floor()).as_ivec2();
    // Every chunk wanted whose level is neither resident nor asked for yet.
    let mut requests: Vec<(ChunkKey, u8, bool, f32)> = (-reach..=reach)
        .flat_map(|dz| (-reach..=reach).map(move |dx| ChunkKey { x: around.x + dx, z: around.y + dz }))
        .filter(|&key| settings.contains(key))
        .filter_map(|key| {
            let d = distance(key);
            (d < settings.load_radius_m).then(|| (key, settings.chunk_level(key, camera), d))
        })
        .filter(|&(key, level, _)| resident.get(&key) != Some(&level) && pending.get(&key) != Some(&level))
        .map(|(key, level, d)| {
            let behind = (settings.centre(key) - camera).dot(forward) < 0.0 && d > settings.chunk_m;
            (key, level, behind, d)
        })
        .collect();
    requests.sort_by(|a, b| a.2.cmp(&b.2).then(a.3.total_cmp(&b.3)).then(a.0.cmp(&b.0)));
    let mut unload: Vec<ChunkKey> =
        resident.keys().copied().filter(|&key| distance(key) > settings.unload_radius_m).collect();
    unload.sort();
    Plan { requests: requests.into_iter().map(|(key, level, ..)| (key, level)).collect(), unload }
}

#[cfg(test)]
mod tests {
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
}
