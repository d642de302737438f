//! A streamed world's ground as the solids' height field: its heights everywhere, as its
//! finest level draws them.

use super::chunk::WorldHeights;
use crate::spatial::solid::HeightField;
use crate::terrain::section::Geometry;
use bevy::math::Vec3;

/// The ground of a world: its heights and its metres between samples and for a height of 1.
#[derive(Debug, Clone)]
pub struct WorldGround {
    /// The world's heights.
    pub heights: WorldHeights,
    /// Its metres between samples and for a height of 1.
    pub geometry: Geometry,
}

impl HeightField for WorldGround {
    fn may_touch(&self, min: Vec3, max: Vec3) -> bool {
        min.y <= self.heights.highest_over([min.x, min.z], [max.x, max.z], self.geometry)
    }

    fn penetration(&self, p: Vec3) -> Option<(f32, Vec3)> {
        let (height, normal) = self.heights.ground_surface(p.x, p.z, self.geometry);
        // Out along the normal to the triangle's plane.
        let depth = (height - p.y) * normal.y;
        (depth > 0.0).then_some((depth, normal))
    }

    fn height(&self, x: f32, z: f32) -> Option<f32> {
        Some(self.heights.ground_height(x, z, self.geometry))
    }
}
