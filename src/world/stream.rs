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
mod tests;
