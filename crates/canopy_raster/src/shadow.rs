//! Shadow maps for the directional light: where the map looks from, and how a pixel reads it.
//!
//! The map is a depth image seen from the light through an orthographic projection fitted to
//! the part of the scene the camera can see (see [`fit_light`]). It is drawn by the same tiled
//! rasterizer, depth only, with a slope-scaled bias added to every stored depth so that lit
//! surfaces do not shadow themselves. A pixel is lit when its own depth from the light is no
//! greater than what the map holds there, optionally filtered over the four nearest texels
//! (bilinear percentage-closer filtering). Its place in the map follows from its position on
//! the screen and its depth (see [`PixelsInMap`]), so a pixel looks the map up only once the
//! nearest surface is known.

use crate::camera::{Camera, Light};
use crate::lanes::{floats_of, lanes_of};
use bevy_math::{DMat4, DVec4, Mat4, Vec3, Vec4};
use wide::{f32x4, f32x8, i16x8, i32x4, i32x8};

/// Depth bias added to every shadow-map depth, in light depth units (the fitted depth range
/// is `[0, 1]`).
pub const CONSTANT_BIAS: f32 = 5e-4;

/// Bias per unit of depth slope, in shadow-map texels: a surface at a grazing angle to the light
/// changes depth quickly across a texel and needs more.
pub const SLOPE_BIAS: f32 = 1.5;

/// The light's depth image and the projection it was drawn with.
///
/// Texels are stored row by row inside a border (one texel before each row and column, several
/// after) that always holds an infinite depth: a lookup clamped into the border reads "lit",
/// so filtered and unfiltered lookups need no bounds test per texel.
///
/// For filtered lookups the map also keeps, in the same layout, the least depth of each
/// texel's two-by-two (the texel, its right neighbour and the two below them): a point no
/// deeper than that is lit in full, found with one read instead of four. Most of what a camera
/// sees is lit, so most lookups end there.
#[derive(Debug, Clone, Default)]
pub struct ShadowMap {
    size: u32,
    depth: Vec<f32>,
    /// The least depth of each two-by-two of `depth`, when lookups are filtered; empty
    /// otherwise.
    nearest_of_quads: Vec<QuadDepth>,
    clip_from_world: Mat4,
    active: bool,
    /// What every lookup multiplies a texel's (column, row) pair by to find its index: (1,
    /// stride) in each lane's pair. Kept with the map, so that lookups read it instead of
    /// building it.
    index_steps: i16x8,
    /// The side in texels as a float in every lane, the far border's position: kept for the
    /// same reason.
    far_border: Vec4,
}

/// Border texels before each row and above the first row.
const BORDER_BEFORE: usize = 1;

/// Texels of a row one step of the depth pass covers.
pub(crate) const WINDOW: usize = 8;

/// Border texels after each row (and below the map): a filtered lookup reads up to two past
/// the last texel, and the depth pass reads and writes back windows of [`WINDOW`] texels from
/// any texel of a row.
const BORDER_AFTER: usize = WINDOW - 1;

/// Border texels before plus after each row (and above plus below the map).
const BORDER: usize = BORDER_BEFORE + BORDER_AFTER;
const _: () = assert!(crate::MAX_TARGET_SIZE as usize + BORDER <= i16::MAX as usize, "map positions fit 16 bits");

impl ShadowMap {
    /// Edge length of the square map in texels.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Distance in the stored depths between vertically neighbouring texels.
    fn stride(&self) -> usize {
        self.size as usize + BORDER
    }

    /// The depth of texel (`x`, `y`), counted from the top-left corner.
    ///
    /// # Panics
    /// If the texel is outside the map.
    pub fn depth_at(&self, x: u32, y: u32) -> f32 {
        assert!(x < self.size && y < self.size, "texel ({x}, {y}) outside the shadow map");
        self.depth[(y as usize + BORDER_BEFORE) * self.stride() + x as usize + BORDER_BEFORE]
    }

    /// Whether the last frame drew a map (shadows on and something in view to shadow).
    pub fn is_active(&self) -> bool {
        self.active
    }

    /// The light's world-to-clip matrix the map was drawn with.
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_world
    }

    /// Prepares a map of `size` x `size` texels drawn through `clip_from_world`, or marks it
    /// inactive, for `filtered` lookups or not. Keeps the allocations and the border; the
    /// texels are cleared as they are drawn.
    pub(crate) fn reset(&mut self, size: u32, clip_from_world: Option<Mat4>, filtered: bool) {
        self.active = clip_from_world.is_some();
        self.clip_from_world = clip_from_world.unwrap_or(Mat4::IDENTITY);
        if self.size != size || self.depth.is_empty() {
            self.size = size;
            let stride = self.stride();
            // Column, row and stride all fit 16 bits (the map is at most `MAX_TARGET_SIZE` a side).
            let stride_i16 = stride as i16;
            self.index_steps = i16x8::from([1, stride_i16, 1, stride_i16, 1, stride_i16, 1, stride_i16]);
            self.far_border = Vec4::splat(size as f32);
            self.depth.clear();
            self.depth.resize(stride * stride, f32::INFINITY);
            self.nearest_of_quads.clear();
        }
        if !filtered {
            self.nearest_of_quads.clear();
        } else if self.nearest_of_quads.is_empty() {
            // Those of the border past where lookups start are never written.
            self.nearest_of_quads.resize(self.depth.len(), QuadDepth::MIN);
        }
    }

    /// The map's rows for drawing in strips of `rows` rows, [`ShadowMap::row_layout`] apart,
    /// with their texels at `BORDER_BEFORE..BORDER_BEFORE + size`: each strip's depths and,
    /// for filtered lookups, the same rows of the two-by-twos' least depths. Once the strips are
    /// drawn, [`nearest_of_quads`] fills each strip's two-by-twos but its last row, and
    /// [`ShadowMap::join_strips`] those left.
    pub(crate) fn strips_mut(&mut self, rows: usize) -> impl Iterator<Item = (&mut [f32], Option<&mut [QuadDepth]>)> {
        let (stride, size) = (self.stride(), self.size as usize);
        let texels = BORDER_BEFORE * stride..(BORDER_BEFORE + size) * stride;
        let mut quads = self.nearest_of_quads.get_mut(texels.clone()).map(|quads| quads.chunks_mut(stride * rows));
        self.depth[texels].chunks_mut(stride * rows).map(move |depth| (depth, quads.as_mut().and_then(Iterator::next)))
    }

    /// Fills the two-by-twos [`ShadowMap::strips_mut`]'s strips of `rows` rows leave to it: those
    /// of the top border row, of each strip's last row, which reach into the next strip (or the
    /// bottom border), and of the first row of the bottom border, the last one a lookup starts
    /// on.
    pub(crate) fn join_strips(&mut self, rows: usize) {
        if self.nearest_of_quads.is_empty() {
            return;
        }
        let (stride, size) = (self.stride(), self.size as usize);
        let last_rows = (BORDER_BEFORE..=size).step_by(rows).map(|first| (first + rows - 1).min(size));
        for row in std::iter::once(0).chain(last_rows).chain([size + 1]) {
            let quads = &mut self.nearest_of_quads[row * stride..(row + 1) * stride];
            nearest_of_quads(&self.depth[row * stride..(row + 2) * stride], quads, stride);
        }
    }

    /// Distance between the rows [`ShadowMap::strips_mut`] returns, and where a row's first
    /// texel is.
    pub(crate) fn row_layout(&self) -> (usize, usize) {
        (self.stride(), BORDER_BEFORE)
    }

    /// Where a world point falls in the map: texel x, texel y (from the top-left corner) and
    /// light depth, as [`ShadowMap::visibility`] reads them.
    pub fn locate(&self, world: Vec3) -> Vec3 {
        let clip = self.clip_from_world * world.extend(1.0);
        let size = self.size as f32;
        Vec3::new((clip.x + 1.0) * 0.5 * size, (1.0 - clip.y) * 0.5 * size, clip.z)
    }

    /// How much light reaches a point located at `at` (see [`ShadowMap::locate`]): 1 lit, 0 in
    /// shadow. Filtered, the four texels around the point are compared and their results
    /// weighted bilinearly, so shadow edges fade over a texel instead of stepping. Points
    /// outside the map are lit.
    pub fn visibility(&self, at: Vec3, filtered: bool) -> f32 {
        self.visibility_lanes(Vec4::splat(at.x), Vec4::splat(at.y), Vec4::splat(at.z), filtered).x
    }

    /// [`ShadowMap::visibility`] of four points at once, given as texel x, texel y and light
    /// depth per lane. Any input, even NaN, reads inside the stored depths.
    #[inline(always)]
    pub fn visibility_lanes(&self, x: Vec4, y: Vec4, depth: Vec4, filtered: bool) -> Vec4 {
        self.read(&self.taps(x, y, depth, filtered), filtered)
    }

    /// Where the lookups of four points (as in [`ShadowMap::visibility_lanes`]) read the map,
    /// before any texel is read: finding the taps of many lookups first lets their reads wait
    /// on memory together.
    #[inline(always)]
    pub(crate) fn taps(&self, x: Vec4, y: Vec4, depth: Vec4, filtered: bool) -> Taps {
        let (x, y) = if filtered { (x - 0.5, y - 0.5) } else { (x, y) };
        // Clamped into the border: a point off the map reads only border texels (with a zero
        // weight on the second texel of a pair when it sits on the far border).
        let (low, high) = (Vec4::splat(-1.0), self.far_border);
        // Counted from the border's first texel, the clamped positions are not negative: their
        // whole part is the stored column and row, found four at a time by truncation.
        let (x, y) = (x.max(low).min(high) + 1.0, y.max(low).min(high) + 1.0);
        let (column, row) = (lanes_of(x).fast_trunc_int(), lanes_of(y).fast_trunc_int());
        // Each lane's (column, row) pair times (1, stride), summed, in one multiply-add.
        let first = bytemuck::cast::<_, i16x8>(row << 16 | column).dot(self.index_steps);
        Taps { first, x, y, depth }
    }

    /// Which of the four points of `taps` the light reaches in full, found with one read each:
    /// those strictly nearer than every texel they read (see [`QuadDepth`]; [`ShadowMap::read`]
    /// tells the others).
    #[inline(always)]
    pub(crate) fn lit_in_full(&self, taps: &Taps, filtered: bool) -> f32x4 {
        let first = taps.first.to_array().map(|i| i as usize);
        if !filtered {
            let texels = Vec4::from_array(std::array::from_fn(|lane| self.depth[first[lane]]));
            return lanes_of(taps.depth).simd_le(lanes_of(texels));
        }
        let quads = Vec4::from_array(std::array::from_fn(|lane| f32::from(self.nearest_of_quads[first[lane]])));
        lanes_of(taps.depth * QUAD_STEPS).simd_le(lanes_of(quads))
    }

    /// The light reaching the four points of `taps` (see [`ShadowMap::visibility_lanes`]).
    #[inline(always)]
    pub(crate) fn read(&self, taps: &Taps, filtered: bool) -> Vec4 {
        if !filtered {
            // One texel each: the one-read test is the whole lookup.
            return Vec4::from_array((self.lit_in_full(taps, false) & f32x4::ONE).to_array());
        }
        let first = taps.first.to_array().map(|i| i as usize);
        // Each lane's two-by-two texels, from one slice of the stored depths.
        let stride = self.stride();
        let quads: [&[f32]; 4] = std::array::from_fn(|lane| &self.depth[first[lane]..][..stride + 2]);
        // The weight of a texel nearer to the light than the point, zero for one that is not.
        let shadowed = |k: usize, weight: Vec4| {
            let texels = Vec4::from_array(std::array::from_fn(|lane| quads[lane][k]));
            Vec4::select(taps.depth.cmpgt(texels), weight, Vec4::ZERO)
        };
        // The weights of the right and the lower texels: the positions' fractions, found only
        // for the lookups the one-read test leaves.
        let fraction = |at: Vec4| at - floats_of(lanes_of(at).fast_trunc_int());
        let (tx, ty) = (fraction(taps.x), fraction(taps.y));
        let (sx, sy) = (Vec4::ONE - tx, Vec4::ONE - ty);
        // What the shadowed texels take away from full light: a point no texel shadows gets
        // exactly 1.
        let dark =
            shadowed(0, sx * sy) + shadowed(1, tx * sy) + shadowed(stride, sx * ty) + shadowed(stride + 1, tx * ty);
        Vec4::ONE - dark
    }
}

/// Whole steps of [`QuadDepth`] per unit of depth.
const QUAD_STEPS: f32 = i16::MAX as f32;

/// The least depth of a two-by-two of texels, rounded down to a whole number of
/// 1/[`QUAD_STEPS`] and then one step lower, so that a point whose depth in those steps is no
/// greater is strictly nearer than every texel, whatever the rounding of either product.
/// Depths past the map's range (the far depth is 1) are kept as 1.
pub(crate) type QuadDepth = i16;

/// Writes into the rows of `quads` the [`QuadDepth`] of each two-by-two of texels of `depth`
/// (rows `stride` apart) with its top-left texel at the same index, for every row `depth` holds
/// the row below of: a strip's last row is left for [`ShadowMap::join_strips`]. The last texel
/// of a row has no right neighbour and is left as it is: it is a border texel, and no lookup
/// starts a two-by-two on it.
///
/// # Panics
/// If a row holds fewer than [`QUAD_LANES`] two-by-twos.
pub(crate) fn nearest_of_quads(depth: &[f32], quads: &mut [QuadDepth], stride: usize) {
    let count = stride - 1;
    assert!(count >= QUAD_LANES, "rows of at least {QUAD_LANES} two-by-twos");
    let rows = (depth.len() / stride).saturating_sub(1);
    for (row, quads) in quads.chunks_exact_mut(stride).take(rows).enumerate() {
        let (top, bottom) = (&depth[row * stride..][..stride], &depth[(row + 1) * stride..][..stride]);
        let quads_of = |top: [&[f32]; 2], bottom: [&[f32]; 2]| {
            let texels = |at: &[f32]| f32x8::new(at[..QUAD_LANES].try_into().expect("a window"));
            let least = texels(top[0]).fast_min(texels(top[1])).fast_min(texels(bottom[0]).fast_min(texels(bottom[1])));
            // Depths are never NaN: the plain minimum is exact.
            let whole = (least.fast_min(f32x8::ONE) * QUAD_STEPS).fast_trunc_int() - i32x8::ONE;
            i16x8::from_i32x8_saturate(whole).to_array()
        };
        let windows = windows(top, count).zip(windows(bottom, count));
        for (quads, ((top_left, top_right), (bottom_left, bottom_right))) in
            quads[..count].chunks_exact_mut(QUAD_LANES).zip(windows)
        {
            quads.copy_from_slice(&quads_of([top_left, top_right], [bottom_left, bottom_right]));
        }
        // The rest of the row: its last two-by-twos' window, again.
        let last = count - QUAD_LANES;
        let [left, right] = [last, last + 1];
        let window = quads_of([&top[left..], &top[right..]], [&bottom[left..], &bottom[right..]]);
        quads[last..count].copy_from_slice(&window);
    }
}

/// Two-by-twos [`nearest_of_quads`] works through at once.
const QUAD_LANES: usize = 8;

/// The windows of [`QUAD_LANES`] texels of a row's first `count` texels, each with the window
/// one texel to its right.
fn windows(row: &[f32], count: usize) -> impl Iterator<Item = (&[f32], &[f32])> {
    std::iter::zip(row[..count].chunks_exact(QUAD_LANES), row[1..].chunks_exact(QUAD_LANES))
}

/// Where the lookups of four points read a [`ShadowMap`] (see [`ShadowMap::taps`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Taps {
    /// Each lane's texel, the top-left one of its two-by-two when filtered, as an index into
    /// the stored depths.
    first: i32x4,
    /// The points' clamped positions in texels, counted from the border's first texel (not
    /// negative): their whole parts are the stored column and row, their fractions the weights
    /// of a two-by-two's right and lower texels.
    x: Vec4,
    y: Vec4,
    /// The points' light depths.
    depth: Vec4,
}

/// Where the camera's pixels fall in a shadow map: the projective map from a pixel's position
/// and depth to its texel position and light depth.
///
/// A pixel's depth and position on the screen determine the world point it shows, so its place
/// in the map follows from them alone, exactly (the light's projection is orthographic, the
/// camera's perspective: one division per pixel). Lookups can then wait until a band is drawn
/// and be made once per visible pixel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PixelsInMap {
    /// The homogeneous map position (texel x, texel y, light depth, all times `w`, then `w`)
    /// of a pixel centre, as lanes of those four: its change per pixel to the right, per pixel
    /// down and per unit of depth, and its value at pixel (0, 0) at depth 0.
    per_x: Vec4,
    per_y: Vec4,
    per_depth: Vec4,
    origin: Vec4,
}

impl PixelsInMap {
    /// The map of pixels of a `width` x `height` image seen through `clip_from_world` onto
    /// `map`.
    pub(crate) fn new(map: &ShadowMap, clip_from_world: Mat4, width: u32, height: u32) -> Self {
        // Composed in double precision: the camera's inverse projection is ill-conditioned
        // near the far plane.
        let size = f64::from(map.size);
        let texel_from_clip = DMat4::from_cols(
            DVec4::new(size * 0.5, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -size * 0.5, 0.0, 0.0),
            DVec4::Z,
            DVec4::new(size * 0.5, size * 0.5, 0.0, 1.0),
        );
        let (w, h) = (f64::from(width.max(1)), f64::from(height.max(1)));
        // Pixel (x, y) is sampled at its centre, (x + 1/2, y + 1/2).
        let ndc_from_pixel = DMat4::from_cols(
            DVec4::new(2.0 / w, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -2.0 / h, 0.0, 0.0),
            DVec4::Z,
            DVec4::new(1.0 / w - 1.0, 1.0 - 1.0 / h, 0.0, 1.0),
        );
        let map_from_pixel =
            texel_from_clip * map.clip_from_world.as_dmat4() * clip_from_world.as_dmat4().inverse() * ndc_from_pixel;
        let column = |k: usize| map_from_pixel.col(k).as_vec4();
        Self { per_x: column(0), per_y: column(1), per_depth: column(2), origin: column(3) }
    }

    /// The homogeneous map position of the pixel column 0 of row `y` at depth 0, before the
    /// row's pixels and depths are added (see [`PixelsInMap::locate`]).
    #[inline(always)]
    pub(crate) fn row(&self, y: u32) -> Vec4 {
        self.origin + self.per_y * y as f32
    }

    /// Texel x, texel y and light depth of four pixels of the row whose
    /// [`PixelsInMap::row`] is `row`, at columns `x` and depths `depth` (one pixel per lane),
    /// as [`ShadowMap::visibility_lanes`] reads them.
    #[inline(always)]
    pub(crate) fn locate(&self, row: Vec4, x: Vec4, depth: Vec4) -> [Vec4; 3] {
        let at = |k: usize| Vec4::splat(row[k]) + x * self.per_x[k] + depth * self.per_depth[k];
        let inv_w = at(3).recip();
        [at(0) * inv_w, at(1) * inv_w, at(2) * inv_w]
    }
}

/// The light's world-to-clip matrix for a frame: an orthographic view along the light's
/// direction whose x/y window is the part of the scene's bounds the camera can see, and whose
/// depth range holds the whole scene so that casters outside the view still cast.
///
/// `bounds` are the scene's world bounds; `None` when nothing visible can be shadowed. With a
/// `shadow_distance`, only the part of the view nearer than that many metres is fitted (the map
/// keeps its detail for a large world; what lies beyond the map is lit).
pub fn fit_light(
    camera: &Camera,
    aspect: f32,
    light: &Light,
    bounds: (Vec3, Vec3),
    shadow_distance: Option<f32>,
) -> Option<Mat4> {
    let direction = light.direction.try_normalize()?;
    // The map's rows run along the image's rows as far as the light allows: the pixels of an
    // image row then read texels of a few map rows, next to each other in memory.
    let camera_view = camera.view();
    let image_right = Vec3::new(camera_view.x_axis.x, camera_view.y_axis.x, camera_view.z_axis.x);
    let map_right = (image_right - direction * direction.dot(image_right)).try_normalize();
    let up = match map_right {
        // Looking along `direction`, `up` crossed with it points right.
        Some(right) => right.cross(direction),
        None if direction.y.abs() > 0.999 => Vec3::Z,
        None => Vec3::Y,
    };
    let view = Mat4::look_to_rh(Vec3::ZERO, direction, up);
    let scene_corners = corners(bounds.0, bounds.1);
    let (scene_min, scene_max) = light_bounds(view, &scene_corners);

    // The camera's frustum, cut at the farthest scene corner so that an unused far plane does
    // not spread the map thin.
    let farthest = scene_corners.iter().map(|c| c.distance(camera.eye)).fold(0.0, f32::max);
    let far = farthest.min(shadow_distance.unwrap_or(f32::INFINITY)).clamp(camera.near * 1.001, camera.far);
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
    use crate::camera::Lens;
    use proptest::prelude::*;

    fn overhead() -> (Camera, Light) {
        let camera = Camera {
            eye: Vec3::new(0.0, 3.0, 4.0),
            target: Vec3::ZERO,
            lens: Lens::FieldOfView(1.0),
            near: 0.1,
            far: 100.0,
        };
        let light = Light { direction: Vec3::new(0.2, -1.0, 0.1).normalize(), diffuse: 1.0, fill: 0.0, ambient: 0.2 };
        (camera, light)
    }

    #[test]
    fn the_fitted_projection_holds_the_visible_scene() {
        let (camera, light) = overhead();
        let bounds = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.5, 1.0));
        let clip = fit_light(&camera, 1.5, &light, bounds, None).unwrap();
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
        let clip = fit_light(&camera, 1.5, &light, bounds, None).unwrap();
        let far_corner = clip.project_point3(Vec3::new(-500.0, 0.0, 500.0));
        assert!(far_corner.x.abs() > 1.0 || far_corner.y.abs() > 1.0);
        let origin = clip.project_point3(Vec3::ZERO);
        assert!(origin.x.abs() < 1.0 && origin.y.abs() < 1.0);
    }

    #[test]
    fn a_shadow_distance_fits_the_map_to_the_near_part_of_the_view() {
        // Looking level over a floor 1 km across.
        let camera = Camera {
            eye: Vec3::new(0.0, 2.0, 0.0),
            target: Vec3::new(0.0, 0.0, -20.0),
            lens: Lens::FieldOfView(1.0),
            near: 0.1,
            far: 1000.0,
        };
        let light = Light { direction: Vec3::new(0.2, -1.0, 0.1).normalize(), diffuse: 1.0, fill: 0.0, ambient: 0.2 };
        let bounds = (Vec3::new(-500.0, 0.0, -500.0), Vec3::new(500.0, 0.0, 500.0));
        let whole = fit_light(&camera, 1.5, &light, bounds, None).unwrap();
        let near = fit_light(&camera, 1.5, &light, bounds, Some(50.0)).unwrap();
        let inside = |clip: Mat4, p: Vec3| {
            let q = clip.project_point3(p);
            q.x.abs() <= 1.0 && q.y.abs() <= 1.0
        };
        let (close, far) = (Vec3::new(0.0, 0.0, -30.0), Vec3::new(0.0, 0.0, -300.0));
        assert!(inside(whole, close) && inside(whole, far));
        assert!(inside(near, close) && !inside(near, far), "the map ends near the distance");
        // The same map, a smaller window: more texels per metre near the camera.
        let span = |clip: Mat4| {
            clip.project_point3(Vec3::new(1.0, 0.0, -30.0)).x - clip.project_point3(Vec3::new(0.0, 0.0, -30.0)).x
        };
        assert!(span(near).abs() > 4.0 * span(whole).abs(), "{} vs {}", span(near), span(whole));
    }

    #[test]
    fn nothing_in_view_gives_no_map() {
        let (camera, light) = overhead();
        let behind = (Vec3::new(-1.0, 0.0, 50.0), Vec3::new(1.0, 1.0, 52.0));
        assert!(fit_light(&camera, 1.5, &light, behind, None).is_none());
    }

    #[test]
    fn pixels_find_in_the_map_where_their_world_points_fall() {
        let (camera, light) = overhead();
        let (width, height) = (97, 61);
        let aspect = width as f32 / height as f32;
        let bounds = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.5, 1.0));
        let mut map = ShadowMap::default();
        map.reset(512, fit_light(&camera, aspect, &light, bounds, None), true);
        let clip_from_world = camera.view_projection(aspect);
        let pixels = PixelsInMap::new(&map, clip_from_world, width, height);
        // Points near and far: each seen at some pixel position and depth, which must lead
        // back to the map position of the point itself.
        for world in [Vec3::new(0.3, 0.2, 0.5), Vec3::new(-0.9, 0.0, -0.8), Vec3::new(0.7, 0.45, -0.95)] {
            let ndc = clip_from_world.project_point3(world);
            // Pixel x covers [x, x + 1) and is sampled at its centre.
            let x = (ndc.x + 1.0) * 0.5 * width as f32 - 0.5;
            let y = (1.0 - ndc.y) * 0.5 * height as f32 - 0.5;
            let row = y.floor() as u32;
            let rest_of_row = pixels.per_y * (y - row as f32);
            let [tx, ty, depth] = pixels.locate(pixels.row(row) + rest_of_row, Vec4::splat(x), Vec4::splat(ndc.z));
            let expected = map.locate(world);
            assert!(
                (tx.x - expected.x).abs() < 0.01 && (ty.x - expected.y).abs() < 0.01,
                "{world}: {tx} {ty} {expected}"
            );
            // Far from the camera, depth resolves its distance coarsely: still far below the
            // bias.
            assert!((depth.x - expected.z).abs() < CONSTANT_BIAS / 20.0, "{world}: {depth} {expected}");
        }
    }

    /// A map of `size` texels a side for filtered lookups, drawn as the depth pass draws one
    /// in strips of `strip_rows`: `draw(y, texels)` fills the texels of row `y`.
    fn drawn(size: u32, strip_rows: usize, draw: impl Fn(usize, &mut [f32])) -> ShadowMap {
        let mut map = ShadowMap::default();
        map.reset(size, Some(Mat4::IDENTITY), true);
        let (stride, first) = map.row_layout();
        for (strip, (depth, quads)) in map.strips_mut(strip_rows).enumerate() {
            for (row, texels) in depth.chunks_mut(stride).enumerate() {
                draw(strip * strip_rows + row, &mut texels[first..first + size as usize]);
            }
            nearest_of_quads(depth, quads.expect("filtered"), stride);
        }
        map.join_strips(strip_rows);
        map
    }

    proptest! {
        /// Drawn in strips of any height, every two-by-two a lookup can start on keeps a
        /// depth strictly below its four texels', by at most two steps: what one read finds lit
        /// in full, the full filtered read finds lit exactly, and it misses only points within
        /// two steps of a texel.
        #[test]
        fn one_read_finds_what_four_find_lit_in_full(
            texels in prop::collection::vec(prop_oneof![0.0f32..1.0, Just(1.0), Just(0.25)], 24 * 24),
            strip_rows in 1usize..30,
            points in prop::collection::vec((-2.0f32..27.0, -2.0f32..27.0, 0.0f32..1.0), 64),
        ) {
            let size = 24;
            let map = drawn(size, strip_rows, |y, row| row.copy_from_slice(&texels[y * 24..][..24]));
            let stride = map.stride();
            for y in 0..=size as usize + 1 {
                for x in 0..=size as usize + 1 {
                    let at = y * stride + x;
                    let least = [at, at + 1, at + stride, at + stride + 1].map(|i| map.depth[i]).into_iter().fold(f32::INFINITY, f32::min);
                    let quad = f32::from(map.nearest_of_quads[at]);
                    prop_assert!(quad < least.min(1.0) * QUAD_STEPS, "({x}, {y}): {quad} {least}");
                    prop_assert!(quad >= (least.min(1.0) * QUAD_STEPS).floor() - 1.0, "({x}, {y}): {quad} {least}");
                }
            }
            for (x, y, depth) in points {
                let taps = map.taps(Vec4::splat(x), Vec4::splat(y), Vec4::splat(depth), true);
                if map.lit_in_full(&taps, true).any() {
                    prop_assert_eq!(map.read(&taps, true).x, 1.0, "({}, {}) at {}", x, y, depth);
                }
            }
        }
    }

    #[test]
    fn visibility_compares_depths_and_filters() {
        // Columns 0 and 1 hold an occluder at depth 0.3.
        let map = drawn(8, 8, |_, row| {
            row[..2].fill(0.3);
            row[2..].fill(1.0);
        });
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
        // Where no texel shadows it, a point is lit exactly, wherever it falls between them.
        for (x, y) in [(3.37, 1.81), (4.5, 2.05), (5.93, 6.21)] {
            assert_eq!(map.visibility(Vec3::new(x, y, 0.6), true), 1.0, "({x}, {y})");
        }
        // One read tells those points lit in full, and the occluded ones not; unfiltered, it
        // reads the texel itself.
        let lit_in_full = |x: f32, filtered: bool| {
            let taps =
                map.taps(Vec4::new(x, 3.37, 4.5, 5.93), Vec4::new(1.5, 1.81, 2.05, 6.21), Vec4::splat(0.6), filtered);
            map.lit_in_full(&taps, filtered).to_bitmask()
        };
        assert_eq!(lit_in_full(2.75, true), 0b1111);
        assert_eq!(lit_in_full(2.25, true), 0b1110);
        assert_eq!(lit_in_full(1.75, false), 0b1110);
        assert_eq!(lit_in_full(2.25, false), 0b1111);
        // Negative coordinates round down: the texel left of 0 is outside, so lit.
        assert_eq!(map.visibility(Vec3::new(-0.5, 1.5, 0.6), false), 1.0);
        // Far off the map, or not a number at all, reads the border: lit, never out of bounds.
        for at in [Vec3::new(1e30, -1e30, 0.6), Vec3::new(f32::NAN, 1.5, 0.6), Vec3::new(7.9, 7.9, 0.6)] {
            for filtered in [false, true] {
                assert_eq!(map.visibility(at, filtered), 1.0, "{at} {filtered}");
            }
        }
        // Four points at once agree with one at a time.
        let (xs, ys) = (Vec4::new(0.5, 1.75, 2.25, 9.0), Vec4::splat(1.5));
        let lanes = map.visibility_lanes(xs, ys, Vec4::splat(0.6), true).to_array();
        for (lane, x) in xs.to_array().into_iter().enumerate() {
            assert_eq!(lanes[lane], at(x));
        }
    }
}
