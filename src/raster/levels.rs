//! Meshes drawn coarser as they shrink on screen: an entity's [`MeshLevels`] replace its
//! [`RasterMesh`](super::RasterMesh) in the frame wherever a coarser level cannot be told
//! from it at the size the entity is seen.

use super::{Camera, MeshData};
use bevy::math::{Mat4, Vec3};
use bevy::prelude::*;
use std::sync::Arc;

/// Coarser versions of an entity's mesh, each fit to be drawn wherever a metre at the mesh's
/// nearest point spans at most its pixels.
#[derive(Component, Debug, Clone, Default)]
pub struct MeshLevels {
    /// A sphere holding the mesh in its own coordinates: its centre and radius, metres.
    pub bounds: (Vec3, f32),
    /// The coarser meshes, finest first, each with the most pixels a metre may span where it
    /// is drawn.
    pub levels: Vec<(f32, Arc<MeshData>)>,
}

impl MeshLevels {
    /// The mesh to draw, placed by `model` and seen by `camera` in an image `height` pixels
    /// high: the coarsest level fine enough for the size a metre is seen at the nearest
    /// point of the mesh's bounds, or `full` where none is (and wherever the eye is within
    /// the bounds).
    pub fn choose<'a>(
        &'a self,
        full: &'a Arc<MeshData>,
        model: Mat4,
        camera: &Camera,
        height: u32,
    ) -> &'a Arc<MeshData> {
        let scale = model
            .x_axis
            .truncate()
            .length()
            .max(model.y_axis.truncate().length())
            .max(model.z_axis.truncate().length());
        let centre = model.transform_point3(self.bounds.0);
        let distance = camera.eye.distance(centre) - self.bounds.1 * scale;
        if distance <= camera.near {
            return full;
        }
        let pixels_per_metre = camera.focal_px(height) / distance;
        self.levels.iter().rev().find(|(most, _)| pixels_per_metre <= *most).map_or(full, |(_, mesh)| mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::Lens;

    #[test]
    fn the_coarsest_level_fine_enough_for_the_distance_is_drawn() {
        let mesh = |n: u32| Arc::new(MeshData { triangles: vec![[0, 0, 0]; n as usize], ..MeshData::default() });
        let (full, fine, coarse) = (mesh(100), mesh(10), mesh(1));
        let levels =
            MeshLevels { bounds: (Vec3::ZERO, 1.0), levels: vec![(100.0, fine.clone()), (10.0, coarse.clone())] };
        // A 90 degree view 200 pixels high: 100 pixels per metre at 1 m.
        let camera = |z: f32| Camera {
            eye: Vec3::new(0.0, 0.0, z),
            target: Vec3::ZERO,
            lens: Lens::FieldOfView(90f32.to_radians()),
            near: 0.1,
            far: 1000.0,
        };
        let drawn = |z: f32, model: Mat4| levels.choose(&full, model, &camera(z), 200).triangles.len();
        assert_eq!(drawn(0.5, Mat4::IDENTITY), 100, "the eye within the bounds");
        assert_eq!(drawn(1.5, Mat4::IDENTITY), 100, "200 pixels a metre at the nearest point");
        assert_eq!(drawn(3.0, Mat4::IDENTITY), 10, "50 pixels a metre");
        assert_eq!(drawn(50.0, Mat4::IDENTITY), 1, "2 pixels a metre");
        // Moved away, or grown to reach the eye.
        assert_eq!(drawn(3.0, Mat4::from_translation(Vec3::new(0.0, 0.0, -40.0))), 1);
        assert_eq!(drawn(3.0, Mat4::from_scale(Vec3::splat(5.0))), 100);
    }
}
