//! Triangle setup: everything needed to draw a triangle, worked out once per strip of rows it
//! reaches, right before it is drawn there.
//!
//! A setup holds the triangle's pixel bounds, its exact integer edge functions at the first
//! pixel of those bounds with their steps per pixel, and the planes of the values its pixels
//! interpolate. The strips take their triangles in mesh order, so the vertices a setup reads
//! are mostly neighbours in memory.
//!
//! Coverage uses exact integer edge functions on screen coordinates snapped to
//! 1/[`SUBPIXEL_STEPS`] of a pixel, sampled at pixel centres, with the top-left fill rule: a
//! pixel whose centre lies on an edge shared by two triangles is drawn by exactly one of them.
//! Depth is interpolated linearly in screen space (as the projection demands); every other
//! value perspective-correctly, as the screen-space plane of the value divided by `w` over the
//! plane of `1/w`. A triangle whose `w` varies too little for that to move any value beyond its
//! tolerance (a sixteenth of what a pixel shows of it) is interpolated in screen space.

use crate::lanes::{LANE_OFFSETS, LANES, MASK_PIXELS};
use crate::screen::{MAX_TARGET_SIZE, PixelBounds, SUBPIXEL_STEPS, ScreenVertex, edge, pixel_span, range_of};
use crate::shade::{CompiledPass, Pass, VARYINGS, Varyings};
use bevy_math::Vec4;
use std::ops::{Add, Mul, Sub};

/// Four-value packs of interpolated values: the [`Varyings`] four to a pack, then depth and
/// `1/w` (sharing the last pack of varyings when it has room).
pub(crate) const PACKS: usize = (VARYINGS + 2).div_ceil(LANES);

/// Where depth and `1/w` are, counted over all packs.
pub(crate) const DEPTH: usize = VARYINGS;
pub(crate) const INV_W: usize = VARYINGS + 1;
const _: () = assert!(DEPTH / LANES == INV_W / LANES, "depth and 1/w share a pack");

/// Pack `pack` of a vertex's varyings, with zeros in the lanes past the last varying.
#[inline(always)]
fn pack_of(varyings: &Varyings, pack: usize) -> Vec4 {
    let first = pack * LANES;
    match varyings.get(first..first + LANES) {
        Some(values) => Vec4::from_slice(values),
        None => Vec4::from_array(std::array::from_fn(|lane| varyings.get(first + lane).copied().unwrap_or(0.0))),
    }
}

/// A target triangles are set up for.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Viewport {
    pub width: u32,
    pub height: u32,
    /// Whether triangles facing away are dropped.
    pub cull_back_faces: bool,
}

/// What a triangle is drawn with.
#[derive(Clone, Copy)]
pub(crate) struct Surface<'a> {
    /// How far each value may be off when interpolated in screen space (see
    /// [`affine_tolerances`](crate::shade::affine_tolerances)).
    pub tolerance: &'a Varyings,
    /// The flat-shading diffuse term of the triangle (or of the one it was clipped from).
    pub flat_diffuse: f32,
}

/// A plane of values over the screen: their values at the centre of the first pixel of a
/// triangle's bounds and their change per pixel right and down. `T` is [`Vec4`] for four values
/// at once (the colour passes' packs) or `f32` for one (the shadow map's depth).
///
/// Depth and `1/w` are linear in screen space; the other values are too when the triangle is
/// drawn affinely, and otherwise their planes hold the values divided by `w`, to be multiplied
/// by the pixel's `w` (the reciprocal of the interpolated `1/w`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Plane<T = Vec4> {
    pub origin: T,
    pub dx: T,
    pub dy: T,
}

impl<T: Copy + Add<Output = T> + Sub<Output = T> + Mul<f32, Output = T>> Plane<T> {
    /// The plane through `values` at the three vertices, given each vertex's barycentric
    /// weight at the origin and its steps (vertex 0's weight is what the other two leave).
    #[inline(always)]
    pub(crate) fn through(values: [T; 3], weights: &Weights) -> Self {
        let [v0, v1, v2] = values;
        let (to_1, to_2) = (v1 - v0, v2 - v0);
        let [o, x, y] = weights.0;
        Self { origin: v0 + to_1 * o[0] + to_2 * o[1], dx: to_1 * x[0] + to_2 * x[1], dy: to_1 * y[0] + to_2 * y[1] }
    }

    /// The values at pixel offset (`x`, `y`) from the first pixel of the triangle's bounds.
    #[inline(always)]
    pub fn at(&self, x: f32, y: f32) -> T {
        self.at_row(x, self.dy * y)
    }

    /// [`Plane::at`] in a row whose offset's share, `dy * y`, is `row`: the same values, with
    /// the row's share worked out once for all its pixels.
    #[inline(always)]
    pub fn at_row(&self, x: f32, row: T) -> T {
        self.origin + self.dx * x + row
    }
}

impl Plane {
    /// Value `lane`'s change from a run's first pixel to each of its pixels.
    #[inline(always)]
    pub fn lane_steps(&self, lane: usize) -> Vec4 {
        LANE_OFFSETS * self.dx[lane]
    }
}

/// The barycentric weights of vertices 1 and 2 at the origin, and their steps per pixel right
/// and down.
pub(crate) struct Weights([[f32; 2]; 3]);

impl Weights {
    /// The weights of the triangle of `edges`, whose area (twice it, in squared sub-pixel units)
    /// is `area`: its edge functions over the area.
    #[inline(always)]
    pub(crate) fn new(edges: &Edges, area: i64) -> Self {
        let inv_area = 1.0 / area.abs() as f32;
        let weight = |e: i64| e as f32 * inv_area;
        let Edges { start, step_x, step_y, .. } = edges;
        Self([
            [weight(start[1]), weight(start[2])],
            [weight(step_x[1].into()), weight(step_x[2].into())],
            [weight(step_y[1].into()), weight(step_y[2].into())],
        ])
    }
}

/// Which packs `pass` reads (the depth pack always).
pub(crate) const fn packs_read(pass: Pass) -> [bool; PACKS] {
    let mut read = [false; PACKS];
    let mut pack = 0;
    while pack < PACKS {
        read[pack] = pack == DEPTH / LANES;
        let mut k = pack * LANES;
        while k < (pack + 1) * LANES && k < VARYINGS {
            read[pack] |= pass.uses(k);
            k += 1;
        }
        pack += 1;
    }
    read
}

/// The planes of a triangle's values, one per pack; those of the packs its pass does not read
/// are zero.
pub(crate) type Planes = [Plane; PACKS];

/// Which pixels a triangle covers: its pixel bounds and its exact integer edge functions.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Edges {
    /// The pixels whose centres its bounding box holds, within the target.
    pub bounds: PixelBounds,
    /// Edge functions at the centre of the first pixel of `bounds`, top-left bias included;
    /// edge `k` is opposite vertex `k` (in the positive-area order) and weighs it.
    pub start: [i64; 3],
    /// Edge function steps per pixel to the right (they fit `i32`, see [`MAX_STEP`]).
    pub step_x: [i32; 3],
    /// Edge function steps per pixel down.
    pub step_y: [i32; 3],
    /// Whether the edge functions fit `i32` over any walk inside `bounds` (see
    /// [`fits_narrow`]).
    pub narrow: bool,
}

impl Edges {
    /// The edges of the triangle with corners `p` (sub-pixel units, in positive-area order) on
    /// `viewport`; `None` when it covers no pixel centre of the target.
    #[inline(always)]
    pub(crate) fn new(p: [(i64, i64); 3], viewport: Viewport) -> Option<Self> {
        let (x_range, y_range) = (range_of(p.map(|c| c.0)), range_of(p.map(|c| c.1)));
        let (min_x, max_x) = pixel_span(x_range, viewport.width)?;
        let (min_y, max_y) = pixel_span(y_range, viewport.height)?;
        let bounds = PixelBounds { min_x, max_x, min_y, max_y };
        let sample = (
            i64::from(bounds.min_x) * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2,
            i64::from(bounds.min_y) * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2,
        );
        let [a, b, c] = p;
        // Edge k runs between the two vertices other than k.
        let edges = [(b, c), (c, a), (a, b)];
        let start = edges.map(|(from, to)| edge(from, to, sample) + top_left_bias(from, to));
        let step_x = edges.map(|(from, to)| ((from.1 - to.1) * SUBPIXEL_STEPS) as i32);
        let step_y = edges.map(|(from, to)| ((to.0 - from.0) * SUBPIXEL_STEPS) as i32);
        let narrow = fits_narrow(x_range.1 - x_range.0, y_range.1 - y_range.0);
        Some(Self { bounds, start, step_x, step_y, narrow })
    }
}

#[cfg(test)]
impl Edges {
    /// The edges of the triangle with corners `corners` (whole sub-pixel units) on `viewport`;
    /// `None` when it is culled or covers no pixel centre.
    pub(crate) fn of_corners(corners: [(i32, i32); 3], viewport: Viewport) -> Option<Self> {
        let p = corners.map(|(x, y)| (i64::from(x), i64::from(y)));
        let order = positive_order(edge(p[0], p[1], p[2]), viewport)?;
        Self::new(order.map(|k| p[k]), viewport)
    }
}

/// The order of a projected triangle's corners that gives it a positive area (`area` is
/// twice its signed area on the screen, see [`edge`]); `None` when it is culled: zero area,
/// or facing away when `viewport` culls back faces.
#[inline(always)]
pub(crate) fn positive_order(area: i64, viewport: Viewport) -> Option<[usize; 3]> {
    // Front faces wind counter-clockwise in NDC (y up): clockwise, negative, on the screen.
    // Swapping two vertices makes the area positive, as the inside test expects.
    match area {
        0 => None,
        a if a < 0 => Some([0, 2, 1]),
        _ if viewport.cull_back_faces => None,
        _ => Some([0, 1, 2]),
    }
}

/// A triangle ready for every tile it touches.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TriangleSetup {
    pub edges: Edges,
    /// The least depth of its vertices.
    pub nearest: f32,
    /// The flat-shading diffuse term of the triangle (or of the one it was clipped from).
    pub flat_diffuse: f32,
    /// Whether its values are interpolated in screen space.
    pub affine: bool,
}

/// The largest edge function step: coordinates stay within three target sizes of the origin,
/// so two of them differ by at most six, times [`SUBPIXEL_STEPS`] for a pixel's step.
const MAX_STEP: i64 = 6 * MAX_TARGET_SIZE as i64 * SUBPIXEL_STEPS * SUBPIXEL_STEPS;
const _: () = assert!(MAX_STEP <= i32::MAX as i64, "edge steps must fit i32");

impl TriangleSetup {
    /// Sets a projected triangle with vertex `varyings` up for `viewport`, with the planes of
    /// the values pass `C` interpolates; `None` when it is culled (see [`positive_order`]) or
    /// covers no pixel centre of the target.
    #[inline(always)]
    pub fn new<C: CompiledPass>(
        vertices: [&ScreenVertex; 3],
        varyings: [&Varyings; 3],
        viewport: Viewport,
        surface: Surface,
    ) -> Option<(Self, Planes)> {
        let p = vertices.map(|v| (i64::from(v.x), i64::from(v.y)));
        let area = edge(p[0], p[1], p[2]);
        let order = positive_order(area, viewport)?;
        let edges = Edges::new(order.map(|k| p[k]), viewport)?;
        let weights = Weights::new(&edges, area);
        let z = order.map(|k| vertices[k].z);
        let inv_w = order.map(|k| vertices[k].inv_w);
        let read = const { packs_read(C::PASS) };
        let varyings = order.map(|k| varyings[k]);
        // Small or distant triangles skip the per-pixel division.
        let affine = affine_is_close(inv_w, varyings, surface.tolerance, read);
        let mut planes = Planes::default();
        for (pack, plane) in planes.iter_mut().enumerate() {
            if !read[pack] {
                continue;
            }
            let values = std::array::from_fn(|vertex| {
                let scale = if affine { 1.0 } else { inv_w[vertex] };
                let mut values = pack_of(varyings[vertex], pack) * scale;
                if pack == DEPTH / LANES {
                    values[DEPTH % LANES] = z[vertex];
                    values[INV_W % LANES] = inv_w[vertex];
                }
                values
            });
            *plane = Plane::through(values, &weights);
        }
        // Depths are never NaN.
        let nearest = lesser(lesser(z[0], z[1]), z[2]);
        let setup = Self { edges, nearest, flat_diffuse: surface.flat_diffuse, affine };
        Some((setup, planes))
    }
}

/// The lesser of two numbers that are not NaN: one comparison, where `f32::min` also handles
/// NaN and compiles to several instructions more.
#[inline(always)]
pub(crate) fn lesser(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The greater of two numbers that are not NaN (see [`lesser`]).
#[inline(always)]
pub(crate) fn greater(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// What the fill rule adds to the edge function of the edge `a -> b` of a positive-area
/// triangle: nothing for a top or a left edge (see [`is_top_left`]), whose pixels on the edge
/// are drawn, and -1 for the others, whose pixels on the edge are not.
///
/// Found with arithmetic instead of comparisons: the edge is top or left exactly when
/// `(a.y - b.y, b.x - a.x)` is lexicographically positive, and, the second difference being far
/// below 2^32 in size, exactly when the first times 2^32 plus the second is positive.
#[inline(always)]
fn top_left_bias(a: (i64, i64), b: (i64, i64)) -> i64 {
    let key = ((a.1 - b.1) << 32) + (b.0 - a.0);
    (key - 1) >> 63
}

/// Whether the edge `a -> b` of a positive-area triangle is a top or a left edge, whose
/// pixels are drawn (the top-left fill rule): the definition [`top_left_bias`] is tested
/// against.
#[cfg(test)]
pub(crate) fn is_top_left(a: (i64, i64), b: (i64, i64)) -> bool {
    (a.1 == b.1 && b.0 > a.0) || b.1 < a.1
}

/// Whether every edge function value a walk inside the bounds of a triangle whose bounding box
/// is `w` by `h` (sub-pixel units) computes fits an `i32`.
///
/// A value at pixel centre `s` is `(b - a) x (s - a)` for two corners `a`, `b`: at most
/// `w h + h |s.x - a.x|` for the triangle's bounding box `w` by `h`. A walk reads up to two
/// mask widths past its last pixel (the last mask's lanes, then one more step) and one row
/// past its last row, all inside the bounding box widened by [`NARROW_MARGIN`] pixels.
fn fits_narrow(w: i64, h: i64) -> bool {
    let margin = NARROW_MARGIN * SUBPIXEL_STEPS;
    (h + margin) * (2 * w + margin) + 1 < i64::from(i32::MAX)
}

/// Pixels past a triangle's bounding box that a narrow walk may evaluate edge functions at.
const NARROW_MARGIN: i64 = 2 * MASK_PIXELS as i64;

/// Whether interpolating in screen space keeps every value within `tolerance` of its
/// perspective-correct interpolation, for a triangle with `1/w` of `inv_w` and values
/// `varyings` at its vertices. Only the packs of `read` are checked (the others' tolerances
/// are infinite).
///
/// Write the vertices' `1/w` as `m (1 + s_k)` with `0 <= s_k <= spread`, `spread` the ratio of
/// the largest to the least less one. At a point with screen-space weights `b_k`, the
/// perspective-correct weights are `b_k (1 + s_k) / (1 + sum(b_j s_j))`, so a value moves by
/// the covariance of `s` and the value under the weights `b`, divided by at least one: at
/// most `spread / 2` times half the value's range over the three vertices (Popoviciu).
#[inline(always)]
fn affine_is_close(inv_w: [f32; 3], varyings: [&Varyings; 3], tolerance: &Varyings, read: [bool; PACKS]) -> bool {
    // `1/w` is finite.
    let spread = greater(greater(inv_w[0], inv_w[1]), inv_w[2]) / lesser(lesser(inv_w[0], inv_w[1]), inv_w[2]) - 1.0;
    let quarter_spread = Vec4::splat(spread * 0.25);
    (0..VARYINGS.div_ceil(LANES)).filter(|&pack| read[pack]).all(|pack| {
        let [v0, v1, v2] = varyings.map(|v| pack_of(v, pack));
        let range = v0.max(v1).max(v2) - v0.min(v1).min(v2);
        // Lanes past the last varying have no range, and pass against a zero tolerance.
        (quarter_spread * range).cmple(pack_of(tolerance, pack)).all()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shade::{Compiled, Shading, mode};
    use proptest::prelude::*;

    /// A screen vertex at whole sub-pixel position `(x, y)` with depth `z`.
    fn vertex((x, y): (i32, i32), z: f32) -> ScreenVertex {
        ScreenVertex { code: 0, x, y, z, inv_w: 1.0 }
    }

    const TARGET: Viewport = Viewport { width: 4096, height: 4096, cull_back_faces: false };

    const SURFACE: Surface = Surface { tolerance: &[0.001; VARYINGS], flat_diffuse: 0.25 };

    /// The edges of the triangle with corners `corners` (sub-pixel units).
    fn edges(corners: [(i32, i32); 3]) -> Edges {
        Edges::of_corners(corners, TARGET).expect("a visible triangle")
    }

    #[test]
    fn small_triangles_walk_narrow_and_large_ones_wide() {
        let steps = SUBPIXEL_STEPS as i32;
        let small = [(70, 35), (90, 40), (75, 60)].map(|(x, y)| (x * steps, y * steps));
        let large = [(0, 0), (900, 40), (100, 600)].map(|(x, y)| (x * steps, y * steps));
        assert!(edges(small).narrow);
        assert!(!edges(large).narrow);
    }

    #[test]
    fn back_faces_are_culled_only_where_the_viewport_says() {
        let culling = Viewport { cull_back_faces: true, ..TARGET };
        // Clockwise on a y-down screen: negative area, a front face.
        assert_eq!(positive_order(-5, culling), Some([0, 2, 1]));
        assert_eq!(positive_order(5, culling), None);
        assert_eq!(positive_order(5, TARGET), Some([0, 1, 2]));
        assert_eq!(positive_order(0, TARGET), None);
    }

    #[test]
    fn a_setup_computes_only_the_packs_its_pass_reads() {
        let pass = |shading, textured, shadowed| Pass { shading, textured, shadowed };
        let read = |pass: Pass| packs_read(pass).iter().filter(|&&read| read).count();
        // Colour (and diffuse term), and v with depth and 1/w; then normals and u too.
        assert_eq!(read(pass(Shading::Gouraud, false, false)), 2);
        assert_eq!(read(pass(Shading::Gouraud, false, true)), 2);
        assert_eq!(read(pass(Shading::Phong, false, false)), 3);
        assert_eq!(read(pass(Shading::Gouraud, true, false)), 3);
        let plain = pass(Shading::Gouraud, false, false);
        assert_eq!(packs_read(plain), [true, false, true]);

        let varyings: [Varyings; 3] =
            std::array::from_fn(|k| std::array::from_fn(|i| (k * VARYINGS + i) as f32 * 0.01));
        let steps = SUBPIXEL_STEPS as i32;
        let vertices = [(0, 0), (0, 40 * steps), (40 * steps, 0)].map(|c| vertex(c, 0.5));
        let (setup, planes) = TriangleSetup::new::<Compiled<{ mode::GOURAUD }, false, false>>(
            vertices.each_ref(),
            varyings.each_ref(),
            TARGET,
            SURFACE,
        )
        .unwrap();
        assert_eq!(setup.flat_diffuse, 0.25);
        // A pack of values the pass does not read (non-zero at the vertices) stays zero.
        assert_eq!(planes[1], Plane::default());
        // The colour plane reproduces vertex 0's colour at its corner, the pixel offset
        // (-1/2, -1/2) from the first pixel's centre.
        let colour = planes[0].at(-0.5, -0.5);
        assert!((colour.x - varyings[0][0]).abs() < 1e-5 && (colour.z - varyings[0][2]).abs() < 1e-5, "{colour}");
        assert_eq!(planes[DEPTH / LANES].at(3.0, 7.0)[DEPTH % LANES], 0.5, "constant depth");
    }

    proptest! {
        /// Over the whole range of projected coordinates (three target sizes either side of
        /// the origin), the arithmetic bias is -1 exactly for the edges that are neither top nor
        /// left. Often drawn: a shared coordinate, where the rule looks at the other one, and
        /// nearly level edges, whose long horizontal difference must not outweigh a step in y.
        #[test]
        fn the_top_left_bias_follows_the_fill_rule(
            a in prop::array::uniform2(-COORDINATE..=COORDINATE),
            b in prop::array::uniform2(-COORDINATE..=COORDINATE),
            kind in 0..5usize,
        ) {
            let (a, mut b) = ((a[0], a[1]), (b[0], b[1]));
            match kind {
                0 => b.0 = a.0,
                1 => b.1 = a.1,
                2 => b.1 = a.1 + 1,
                3 => b.1 = a.1 - 1,
                _ => {}
            }
            prop_assert_eq!(top_left_bias(a, b), -i64::from(!is_top_left(a, b)), "{:?} -> {:?}", a, b);
        }

        /// When a triangle is judged close enough to affine, every value at every point inside
        /// it is within its tolerance of the perspective-correct value.
        #[test]
        fn affine_interpolation_stays_within_tolerance(
            inv_w in 0.2f32..5.0,
            spread in prop::array::uniform3(0.0f32..0.01),
            v1 in prop::array::uniform::<_, VARYINGS>(-1.0f32..1.0),
            v2 in prop::array::uniform::<_, VARYINGS>(-1.0f32..1.0),
            weights in (0.0f32..1.0, 0.0f32..1.0),
        ) {
            let inv_w = spread.map(|s| inv_w * (1.0 + s));
            let tolerance = [0.002; VARYINGS];
            prop_assume!(affine_is_close(inv_w, [&[0.0; VARYINGS], &v1, &v2], &tolerance, [true; PACKS]));
            let (b1, b2) = if weights.0 + weights.1 > 1.0 { (1.0 - weights.0, 1.0 - weights.1) } else { weights };
            let error = affine_error(inv_w, [1.0 - b1 - b2, b1, b2]);
            for k in 0..VARYINGS {
                let error = error.0 * v1[k] + error.1 * v2[k];
                prop_assert!(error.abs() <= tolerance[k] * (1.0 + 1e-3) + 1e-7, "slot {k}: {error}");
            }
        }
    }

    /// The largest projected coordinate, in sub-pixel units: three of the largest targets.
    const COORDINATE: i64 = 3 * MAX_TARGET_SIZE as i64 * SUBPIXEL_STEPS;

    /// How far the perspective-correct weights of vertices 1 and 2 are from the screen-space
    /// weights `b`.
    fn affine_error(inv_w: [f32; 3], b: [f32; 3]) -> (f32, f32) {
        let total = b[0] * inv_w[0] + b[1] * inv_w[1] + b[2] * inv_w[2];
        (b[1] * inv_w[1] / total - b[1], b[2] * inv_w[2] / total - b[2])
    }

    #[test]
    fn the_affine_bound_is_nearly_reached_midway_along_an_edge() {
        // One vertex 1% nearer; a value changing by one along that edge: at the edge's middle
        // the error is 0.01 / 4 / 1.005, and the criterion accepts exactly up to 0.01 / 4.
        let inv_w = [1.0, 1.01, 1.0];
        let mut v1 = [0.0; VARYINGS];
        v1[0] = 1.0;
        let error = affine_error(inv_w, [0.5, 0.5, 0.0]).0;
        assert!((error - 0.0025 / 1.005).abs() < 1e-6, "{error}");
        let zero = [0.0; VARYINGS];
        let all = [true; PACKS];
        assert!(affine_is_close(inv_w, [&zero, &v1, &zero], &[0.0026; VARYINGS], all));
        assert!(!affine_is_close(inv_w, [&zero, &v1, &zero], &[0.0024; VARYINGS], all));
        // Values not interpolated are not checked.
        let mut tolerance = [0.0024; VARYINGS];
        tolerance[0] = f32::INFINITY;
        assert!(affine_is_close(inv_w, [&zero, &v1, &zero], &tolerance, all));
        let mut read = all;
        read[0] = false;
        assert!(affine_is_close(inv_w, [&zero, &v1, &zero], &[0.0024; VARYINGS], read));
    }
}
