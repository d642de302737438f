//! Shadow maps for the directional light: where the map looks from, and how a pixel reads it.
//!
//! The map is a depth image seen from the light through an orthographic projection fitted to
//! the part of the scene the camera can see (see [`fit_light`]). It is drawn by the same tiled
//! rasterizer, depth only, with a slope-scaled bias added to every stored depth so that lit
//! surfaces do not shadow themselves. A pixel is lit when its own depth from the light is no
//! greater than what the map holds there, optionally filtered over the four nearest texels
//! (bilinear percentage-closer filtering).

use crate::camera::{Camera, Light};
use crate::pipeline::floor_i32;
use bevy_math::{Mat4, Vec3, Vec4};

/// Depth bias added to every shadow-map depth, in light depth units (the fitted depth range
/// is `[0, 1]`).
pub const CONSTANT_BIAS: f32 = 5e-4;

/// Bias per unit of depth slope, in shadow-map texels: a surface at a grazing angle to the light
/// changes depth quickly across a texel and needs more.
pub const SLOPE_BIAS: f32 = 1.5;

/// The light's depth image and the projection it was drawn with.
#[derive(Debug, Clone, Default)]
pub struct ShadowMap {
    size: u32,
    depth: Vec<f32>,
    clip_from_world: Mat4,
    active: bool,
}

impl ShadowMap {
    /// Edge length of the square map in texels.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// The depth of texel (`x`, `y`), counted from the top-left corner.
    ///
    /// # Panics
    /// If the texel is outside the map.
    pub fn depth_at(&self, x: u32, y: u32) -> f32 {
        assert!(x < self.size && y < self.size, "texel ({x}, {y}) outside the shadow map");
        self.depth[texel_index(x as usize, y as usize, self.size as usize)]
    }

    /// Whether the last frame drew a map (shadows on and something in view to shadow).
    pub fn is_active(&self) -> bool {
        self.active
    }

    /// The light's world-to-clip matrix the map was drawn with.
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_world
    }

    /// Prepares an empty map of `size` x `size` texels drawn through `clip_from_world`, or
    /// marks it inactive. Keeps the allocation.
    ///
    /// # Panics
    /// If `size` is not a positive multiple of [`BLOCK`].
    pub(crate) fn reset(&mut self, size: u32, clip_from_world: Option<Mat4>) {
        assert!(size > 0 && size.is_multiple_of(BLOCK as u32), "shadow maps are a multiple of {BLOCK} texels a side");
        self.active = clip_from_world.is_some();
        self.clip_from_world = clip_from_world.unwrap_or(Mat4::IDENTITY);
        self.size = size;
        let texels = size as usize * size as usize;
        if self.depth.len() != texels {
            self.depth.clear();
            self.depth.resize(texels, 1.0);
        }
    }

    /// Mutable depths for drawing the map in bands of whole block rows (see [`texel_index`]).
    pub(crate) fn depth_mut(&mut self) -> &mut [f32] {
        &mut self.depth
    }

    /// Where a world point falls in the map: texel x, texel y (from the top-left corner) and
    /// light depth, the values the pixel stage interpolates.
    pub fn locate(&self, world: Vec3) -> Vec3 {
        let clip = self.clip_from_world * world.extend(1.0);
        let size = self.size as f32;
        Vec3::new((clip.x + 1.0) * 0.5 * size, (1.0 - clip.y) * 0.5 * size, clip.z)
    }

    /// How much light reaches a point located at `at` (see [`ShadowMap::locate`]): 1 lit, 0 in
    /// shadow. Filtered, the four texels around the point are compared and their results
    /// weighted bilinearly, so shadow edges fade over a texel instead of stepping. Points
    /// outside the map are lit.
    #[inline(always)]
    pub fn visibility(&self, at: Vec3, filtered: bool) -> f32 {
        if !filtered {
            return self.lit(floor_i32(at.x), floor_i32(at.y), at.z);
        }
        let (x, y) = (at.x - 0.5, at.y - 0.5);
        let (x0, y0) = (floor_i32(x), floor_i32(y));
        let (tx, ty) = (x - x0 as f32, y - y0 as f32);
        let top = self.lit(x0, y0, at.z) * (1.0 - tx) + self.lit(x0 + 1, y0, at.z) * tx;
        let bottom = self.lit(x0, y0 + 1, at.z) * (1.0 - tx) + self.lit(x0 + 1, y0 + 1, at.z) * tx;
        top * (1.0 - ty) + bottom * ty
    }

    #[inline(always)]
    fn lit(&self, x: i32, y: i32, depth: f32) -> f32 {
        let size = self.size as i32;
        if x < 0 || y < 0 || x >= size || y >= size {
            return 1.0;
        }
        if depth <= self.depth[texel_index(x as usize, y as usize, size as usize)] { 1.0 } else { 0.0 }
    }
}

/// Side of the square blocks the map is stored in.
pub(crate) const BLOCK: usize = 8;

/// Where texel (`x`, `y`) of a map `size` texels wide is stored: the map is kept in
/// [`BLOCK`] x [`BLOCK`] blocks, block rows top to bottom, so that the texels a pixel's
/// neighbourhood reads share cache lines whichever way the light looks. A band of whole block
/// rows is one contiguous slice.
#[inline(always)]
pub(crate) fn texel_index(x: usize, y: usize, size: usize) -> usize {
    ((y / BLOCK) * (size / BLOCK) + x / BLOCK) * BLOCK * BLOCK + (y % BLOCK) * BLOCK + x % BLOCK
}

/// The light's world-to-clip matrix for a frame: an orthographic view along the light's
/// direction whose x/y window is the part of the scene's bounds the camera can see, and whose
/// depth range holds the whole scene so that casters outside the view still cast.
///
/// `bounds` are the scene's world bounds; `None` when nothing visible can be shadowed.
pub fn fit_light(camera: &Camera, aspect: f32, light: &Light, bounds: (Vec3, Vec3)) -> Option<Mat4> {
    let direction = light.direction.try_normalize()?;
    let up = if direction.y.abs() > 0.999 { Vec3::Z } else { Vec3::Y };
    let view = Mat4::look_to_rh(Vec3::ZERO, direction, up);
    let scene_corners = corners(bounds.0, bounds.1);
    let (scene_min, scene_max) = light_bounds(view, &scene_corners);

    // The camera's frustum, cut at the farthest scene corner so that an unused far plane does
    // not spread the map thin.
    let farthest = scene_corners.iter().map(|c| c.distance(camera.eye)).fold(0.0, f32::max);
    let far = farthest.clamp(camera.near * 1.001, camera.far);
    let frustum_camera = Camera { far, ..*camera };
    let ndc_to_world = frustum_camera.view_projection(aspect).inverse();
    let frustum_corners =
        corners(Vec3::new(-1.0, -1.0, 0.0), Vec3::ONE).map(|ndc| ndc_to_world.project_point3(ndc)).to_vec();
    let (view_min, view_max) = light_bounds(view, &frustum_corners);

    let min = scene_min.max(view_min);
    let max = scene_max.min(view_max);
    if min.x >= max.x || min.y >= max.y {
        return None;
    }
    // Light depth is -z in view space; a margin keeps the nearest and farthest casters inside.
    let (near, far) = (-scene_max.z, -scene_min.z);
    let margin = (far - near) * 0.01 + 1e-3;
    Some(Mat4::orthographic_rh(min.x, max.x, min.y, max.y, near - margin, far + margin) * view)
}

/// The eight corners of an axis-aligned box.
fn corners(min: Vec3, max: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    })
}

/// Bounds of `points` in the light's view space.
fn light_bounds(view: Mat4, points: &[Vec3]) -> (Vec3, Vec3) {
    points
        .iter()
        .map(|&p| (view * Vec4::from((p, 1.0))).truncate())
        .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(min, max), p| (min.min(p), max.max(p)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn overhead() -> (Camera, Light) {
        let camera = Camera { eye: Vec3::new(0.0, 3.0, 4.0), target: Vec3::ZERO, fov_y: 1.0, near: 0.1, far: 100.0 };
        let light = Light { direction: Vec3::new(0.2, -1.0, 0.1).normalize(), diffuse: 1.0, fill: 0.0, ambient: 0.2 };
        (camera, light)
    }

    #[test]
    fn the_fitted_projection_holds_the_visible_scene() {
        let (camera, light) = overhead();
        let bounds = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.5, 1.0));
        let clip = fit_light(&camera, 1.5, &light, bounds).unwrap();
        for corner in corners(bounds.0, bounds.1) {
            let p = clip.project_point3(corner);
            assert!(p.x.abs() <= 1.0001 && p.y.abs() <= 1.0001, "{corner} -> {p}");
            assert!((0.0..=1.0).contains(&p.z), "{corner} -> {p}");
        }
        // A higher point along the light's path is nearer to the light.
        let low = clip.project_point3(Vec3::ZERO).z;
        let high = clip.project_point3(-light.direction * 0.4).z;
        assert!(high < low);
    }

    #[test]
    fn the_window_shrinks_to_what_the_camera_sees() {
        let (camera, light) = overhead();
        // A huge floor: the map covers the visible part, not all of it.
        let bounds = (Vec3::new(-500.0, 0.0, -500.0), Vec3::new(500.0, 0.0, 500.0));
        let clip = fit_light(&camera, 1.5, &light, bounds).unwrap();
        let far_corner = clip.project_point3(Vec3::new(-500.0, 0.0, 500.0));
        assert!(far_corner.x.abs() > 1.0 || far_corner.y.abs() > 1.0);
        let origin = clip.project_point3(Vec3::ZERO);
        assert!(origin.x.abs() < 1.0 && origin.y.abs() < 1.0);
    }

    #[test]
    fn nothing_in_view_gives_no_map() {
        let (camera, light) = overhead();
        let behind = (Vec3::new(-1.0, 0.0, 50.0), Vec3::new(1.0, 1.0, 52.0));
        assert!(fit_light(&camera, 1.5, &light, behind).is_none());
    }

    #[test]
    fn blocks_store_every_texel_once() {
        let size = 24;
        let mut seen = vec![false; size * size];
        for y in 0..size {
            for x in 0..size {
                let index = texel_index(x, y, size);
                assert!(!seen[index], "({x}, {y})");
                seen[index] = true;
            }
        }
        // A band of eight rows is one contiguous slice.
        assert!((0..size).flat_map(|x| (8..16).map(move |y| texel_index(x, y, size))).all(|i| (192..384).contains(&i)));
    }

    #[test]
    fn visibility_compares_depths_and_filters() {
        let mut map = ShadowMap::default();
        map.reset(8, Some(Mat4::IDENTITY));
        // Columns 0 and 1 hold an occluder at depth 0.3.
        for y in 0..8 {
            for x in 0..2 {
                map.depth_mut()[texel_index(x, y, 8)] = 0.3;
            }
        }
        assert_eq!(map.depth_at(1, 5), 0.3);
        assert_eq!(map.depth_at(2, 5), 1.0);
        assert_eq!(map.visibility(Vec3::new(0.5, 1.5, 0.6), false), 0.0);
        assert_eq!(map.visibility(Vec3::new(0.5, 1.5, 0.2), false), 1.0);
        assert_eq!(map.visibility(Vec3::new(3.5, 1.5, 0.6), false), 1.0);
        assert_eq!(map.visibility(Vec3::new(9.5, 1.5, 0.6), false), 1.0);
        assert_eq!(map.visibility(Vec3::new(-3.0, 1.5, 0.6), false), 1.0);
        // Filtered, the light fades across the boundary between texel columns 1 and 2.
        let at = |x: f32| map.visibility(Vec3::new(x, 1.5, 0.6), true);
        assert_eq!(at(1.5), 0.0);
        assert!((at(2.0) - 0.5).abs() < 1e-6, "{}", at(2.0));
        assert!((at(2.25) - 0.75).abs() < 1e-6, "{}", at(2.25));
        assert_eq!(at(2.5), 1.0);
        // Negative coordinates round down: the texel left of 0 is outside, so lit.
        assert_eq!(map.visibility(Vec3::new(-0.5, 1.5, 0.6), false), 1.0);
    }
}
