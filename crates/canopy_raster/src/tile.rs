//! The tile stage: triangle setup against one tile and the pixel loops.
//!
//! Coverage uses exact integer edge functions on screen coordinates snapped to
//! 1/[`SUBPIXEL_STEPS`] of a pixel, sampled at pixel centres and stepped incrementally, with the
//! top-left fill rule: a pixel whose centre lies on an edge shared by two triangles is drawn by
//! exactly one of them. Depth is interpolated linearly in screen space (as the projection
//! demands); every other value perspective-correctly: the pixel's barycentric weights are
//! divided by `w` at each vertex and renormalized with the interpolated `1/w`, then weigh the
//! vertex values. A triangle whose `w` varies too little for that to move any value beyond
//! its tolerance (a sixteenth of what a pixel shows of it) is interpolated in screen space.
//!
//! Each tile keeps a conservative farthest depth of what it holds; a triangle entirely behind
//! it is skipped before setup reaches its pixels.

use crate::framebuffer::{Band, FAR_DEPTH};
use crate::pipeline::{
    BinEntry, CLIPPED_BIT, Chunk, ClippedTriangle, Frame, PixelBounds, SUBPIXEL_STEPS, ScreenVertex, Span, TILE_WIDTH,
    edge, flat_diffuse, pixel_bounds,
};
use crate::shade::{Material, Pass, Shading, VARYINGS, Varyings, affine_tolerance, slot};
use crate::shadow::{CONSTANT_BIAS, SLOPE_BIAS, ShadowMap};
use bevy_math::{Vec2, Vec3, Vec4};
use std::ops::{Add, Mul};
use wide::i32x8;

/// A tile's farthest depth is read anew once this many pixels have been covered in it since the
/// last reading, times the tile's area: the reading then costs at most one depth read per
/// covered pixel.
const OCCLUSION_REFRESH: u64 = 1;

/// What the colour tiles read, shared by every band.
pub(crate) struct TileContext<'a> {
    pub frame: &'a Frame<'a>,
    pub chunks: &'a [Chunk],
    pub world: &'a [Vec3],
    pub vertices: &'a [ScreenVertex],
    pub varyings: &'a [Varyings],
    pub spans: &'a [Span],
    pub shadow: Option<&'a ShadowMap>,
    pub tiles_x: u32,
}

/// A horizontal band of the shadow map: rows `stride` apart, each with its `width` texels from
/// `first` on.
pub(crate) struct DepthBand<'a> {
    pub y0: u32,
    pub width: u32,
    pub stride: usize,
    pub first: usize,
    pub depth: &'a mut [f32],
}

/// A triangle as the tile stage sees it.
struct Triangle<'a> {
    vertices: [&'a ScreenVertex; 3],
    varyings: [&'a Varyings; 3],
    flat_diffuse: f32,
    material: &'a Material,
}

/// Where the corners of a binned triangle are kept.
enum Corners<'a> {
    /// A triangle made by clipping, kept whole in its chunk.
    Clipped(&'a ClippedTriangle),
    /// A mesh triangle: its vertices' indices in the frame's vertex arrays.
    Mesh([usize; 3]),
}

/// Finds the corners of the triangle `entry` of `chunk`.
#[inline(always)]
fn locate<'a>(frame: &Frame, spans: &[Span], chunk: &'a Chunk, entry: BinEntry) -> Corners<'a> {
    if entry.triangle & CLIPPED_BIT != 0 {
        return Corners::Clipped(&chunk.clipped[(entry.triangle & !CLIPPED_BIT) as usize]);
    }
    let first = spans[entry.instance as usize].first_vertex;
    let mesh = &frame.instances[entry.instance as usize].mesh;
    Corners::Mesh(mesh.triangles[entry.triangle as usize].map(|i| first + i as usize))
}

impl TileContext<'_> {
    fn resolve<'b>(&'b self, chunk: &'b Chunk, entry: BinEntry, flat: bool) -> Triangle<'b> {
        let material = &self.frame.instances[entry.instance as usize].material;
        match locate(self.frame, self.spans, chunk, entry) {
            Corners::Clipped(clipped) => Triangle {
                vertices: clipped.vertices.each_ref(),
                varyings: clipped.varyings.each_ref(),
                flat_diffuse: clipped.flat_diffuse,
                material,
            },
            Corners::Mesh(indices) => Triangle {
                vertices: indices.map(|i| &self.vertices[i]),
                varyings: indices.map(|i| &self.varyings[i]),
                flat_diffuse: if flat { flat_diffuse(indices.map(|i| self.world[i]), &self.frame.light) } else { 0.0 },
                material,
            },
        }
    }

    /// Reads the corners of every triangle binned into `tile` before any of them is drawn.
    ///
    /// These reads depend on nothing but the bins, so their cache misses overlap; the drawing
    /// loop that follows then finds the scattered vertices cached instead of stalling on each
    /// triangle's in turn (about 6% of a frame on the standard scene).
    fn warm(&self, tile: usize) {
        let mut sum = 0.0;
        for chunk in self.chunks {
            for &entry in &chunk.bins[tile] {
                let triangle = self.resolve(chunk, entry, false);
                for (vertex, varyings) in triangle.vertices.iter().zip(triangle.varyings) {
                    sum += vertex.z + varyings[0];
                }
            }
        }
        std::hint::black_box(sum);
    }
}

/// The pixel rectangle of tile column `tx` in a band.
fn tile_rect(tx: u32, y0: u32, width: u32, rows: u32) -> PixelBounds {
    PixelBounds {
        min_x: tx * TILE_WIDTH,
        max_x: ((tx + 1) * TILE_WIDTH).min(width) - 1,
        min_y: y0,
        max_y: y0 + rows - 1,
    }
}

/// Clears one band of the framebuffer and draws every triangle binned into its tiles.
/// Returns the fragments covered and the triangle-tile pairs skipped as occluded.
pub(crate) fn draw_band(context: &TileContext, row: u32, band: Band) -> (u64, u64) {
    // Cleared sixteen pixels at a time from a repeated pattern.
    let pattern: [u8; 64] = std::array::from_fn(|i| context.frame.background[i % 4]);
    let mut runs = band.color.chunks_exact_mut(pattern.len());
    for run in &mut runs {
        run.copy_from_slice(&pattern);
    }
    let rest = runs.into_remainder();
    rest.copy_from_slice(&pattern[..rest.len()]);
    band.depth.fill(FAR_DEPTH);
    let pass =
        |textured: bool| Pass { shading: context.frame.settings.shading, textured, shadowed: context.shadow.is_some() };
    let flat = context.frame.settings.shading == Shading::Flat;
    let (rows, width) = (band.rows(), band.width);
    let mut target = band;
    let (mut fragments, mut occluded) = (0, 0);
    for tx in 0..context.tiles_x {
        let rect = tile_rect(tx, target.y0, width, rows);
        let tile = (row * context.tiles_x + tx) as usize;
        let mut farthest = FAR_DEPTH;
        let mut covered_since_refresh = 0;
        let area = u64::from(rect.max_x - rect.min_x + 1) * u64::from(rows);
        context.warm(tile);
        for chunk in context.chunks {
            for &entry in &chunk.bins[tile] {
                let triangle = context.resolve(chunk, entry, flat);
                let Some(setup) = Setup::new(triangle.vertices, rect, true) else { continue };
                if setup.nearest >= farthest {
                    occluded += 1;
                    continue;
                }
                let pass = pass(triangle.material.texture.is_some());
                let covered = fill(pass, &setup, &triangle, context, &mut target);
                fragments += covered;
                covered_since_refresh += covered;
                if covered_since_refresh >= area * OCCLUSION_REFRESH {
                    covered_since_refresh = 0;
                    farthest = farthest_depth(target.depth, width, target.y0, rect);
                }
            }
        }
    }
    (fragments, occluded)
}

/// The farthest depth held in `rect` of a band.
fn farthest_depth(depth: &[f32], width: u32, y0: u32, rect: PixelBounds) -> f32 {
    (rect.min_y..=rect.max_y)
        .map(|y| {
            let row = ((y - y0) * width) as usize;
            depth[row + rect.min_x as usize..=row + rect.max_x as usize]
                .iter()
                .fold(0.0f32, |m, &d| if d > m { d } else { m })
        })
        .fold(0.0, f32::max)
}

/// Clears one band of the shadow map and draws the depths of every triangle binned into its
/// tiles, pushed back by the slope-scaled bias.
pub(crate) fn draw_depth_band<'a>(
    frame: &'a Frame,
    chunks: &'a [Chunk],
    vertices: &'a [ScreenVertex],
    spans: &'a [Span],
    row: u32,
    mut band: DepthBand,
) {
    let width = band.width;
    for row in band.depth.chunks_exact_mut(band.stride) {
        row[band.first..band.first + width as usize].fill(FAR_DEPTH);
    }
    let rows = (band.depth.len() / band.stride) as u32;
    let tiles_x = width.div_ceil(TILE_WIDTH);
    let corners = |chunk: &'a Chunk, entry: BinEntry| match locate(frame, spans, chunk, entry) {
        Corners::Clipped(clipped) => clipped.vertices.each_ref(),
        Corners::Mesh(indices) => indices.map(|i| &vertices[i]),
    };
    for tx in 0..tiles_x {
        let rect = tile_rect(tx, band.y0, width, rows);
        let tile = (row * tiles_x + tx) as usize;
        for chunk in chunks {
            for &entry in &chunk.bins[tile] {
                if let Some(setup) = Setup::new(corners(chunk, entry), rect, false) {
                    fill_depth(&setup, &mut band);
                }
            }
        }
    }
}

/// A triangle set up for one tile: its vertices reordered to a positive area, its edge
/// functions at the first pixel, and its depth and `1/w` at the vertices.
struct Setup {
    /// Vertex order: setup vertex `k` is input vertex `order[k]`.
    order: [usize; 3],
    /// The pixels to visit: the triangle's bounds within the tile.
    rect: PixelBounds,
    /// Edge functions at the centre of the rect's first pixel, top-left bias included; edge `k`
    /// is opposite vertex `k` and weighs it.
    start: [i64; 3],
    /// Edge function steps per pixel to the right.
    step_x: [i64; 3],
    /// Edge function steps per pixel down.
    step_y: [i64; 3],
    /// `1 / (2 * area)` in sub-pixel units squared.
    inv_area: f32,
    z: [f32; 3],
    inv_w: [f32; 3],
    /// The least depth of the three vertices.
    nearest: f32,
    /// Whether the edge functions fit `i32` over the walk (see [`fits_narrow`]).
    narrow: bool,
}

impl Setup {
    /// Sets the triangle up against `tile`; `None` when it is culled (zero area, or facing
    /// away when `cull_back_faces`) or covers no pixel centre of the tile.
    #[inline(always)]
    fn new(vertices: [&ScreenVertex; 3], tile: PixelBounds, cull_back_faces: bool) -> Option<Self> {
        let p = vertices.map(|v| (v.x as i64, v.y as i64));
        let area = edge(p[0], p[1], p[2]);
        // Front faces are negative on the y-down screen; swapping two vertices makes the area
        // positive, as the inside test expects.
        let order = match area {
            0 => return None,
            a if a < 0 => [0, 2, 1],
            _ if cull_back_faces => return None,
            _ => [0, 1, 2],
        };
        let p = order.map(|k| p[k]);
        let bounds = pixel_bounds(p, u32::MAX, u32::MAX)?;
        let rect = PixelBounds {
            min_x: bounds.min_x.max(tile.min_x),
            max_x: bounds.max_x.min(tile.max_x),
            min_y: bounds.min_y.max(tile.min_y),
            max_y: bounds.max_y.min(tile.max_y),
        };
        if rect.min_x > rect.max_x || rect.min_y > rect.max_y {
            return None;
        }
        let sample = (
            rect.min_x as i64 * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2,
            rect.min_y as i64 * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2,
        );
        let [a, b, c] = p;
        // Edge k runs between the two vertices other than k.
        let edges = [(b, c), (c, a), (a, b)];
        let start = edges.map(|(from, to)| edge(from, to, sample) + if is_top_left(from, to) { 0 } else { -1 });
        let z = order.map(|k| vertices[k].z);
        Some(Self {
            order,
            rect,
            start,
            step_x: edges.map(|(from, to)| (from.1 - to.1) * SUBPIXEL_STEPS),
            step_y: edges.map(|(from, to)| (to.0 - from.0) * SUBPIXEL_STEPS),
            inv_area: 1.0 / area.abs() as f32,
            z,
            inv_w: order.map(|k| vertices[k].inv_w),
            nearest: z[0].min(z[1]).min(z[2]),
            narrow: fits_narrow(p),
        })
    }
}

/// The pixels of one row inside a triangle, `first..end`, and the barycentric weights of
/// vertices 1 and 2 at `first`.
struct RowSpan {
    first: u32,
    end: u32,
    l1: f32,
    l2: f32,
}

impl Setup {
    /// Walks each row's covered span in runs of up to [`LANES`] pixels, calling
    /// `visit(y, x, lanes, l1, l2)` for each: `x` is the run's first pixel, `lanes` how many
    /// of its pixels are covered, and `l1`, `l2` the barycentric weights of vertices 1 and 2
    /// at the run's pixels (one per lane). Returns the pixels covered.
    #[inline(always)]
    fn covered_runs(&self, mut visit: impl FnMut(u32, u32, usize, Vec4, Vec4)) -> u64 {
        // Barycentric weights of vertices 1 and 2 change by these per pixel to the right.
        let step_l1 = self.step_x[1] as f32 * self.inv_area;
        let step_l2 = self.step_x[2] as f32 * self.inv_area;
        let narrow = |edges: [i64; 3]| edges.map(|e| e as i32);
        let narrow_steps = narrow(self.step_x);
        let narrow_mask_steps = i32::mask_steps(narrow_steps);
        let wide_mask_steps = i64::mask_steps(self.step_x);
        let mut row_edges = self.start;
        let mut fragments = 0;
        for py in self.rect.min_y..=self.rect.max_y {
            let span = if self.narrow {
                self.span(narrow(row_edges), narrow_steps, &narrow_mask_steps)
            } else {
                self.span(row_edges, self.step_x, &wide_mask_steps)
            };
            row_edges = add(row_edges, self.step_y);
            let Some(RowSpan { first, end, l1: l1_first, l2: l2_first }) = span else { continue };
            fragments += u64::from(end - first);
            for run in (first..end).step_by(LANES) {
                let offset = (run - first) as f32;
                let l1 = Vec4::splat(l1_first + offset * step_l1) + LANE_OFFSETS * step_l1;
                let l2 = Vec4::splat(l2_first + offset * step_l2) + LANE_OFFSETS * step_l2;
                visit(py, run, ((end - run) as usize).min(LANES), l1, l2);
            }
        }
        fragments
    }

    /// The covered pixels of the row whose first pixel (at `rect.min_x`) has edge functions
    /// `row_edges`. They form one interval (the triangle is convex), found from coverage masks
    /// of [`EdgeValue::MASK_PIXELS`] pixels at a time, without a branch per pixel.
    #[inline(always)]
    fn span<E: EdgeValue>(&self, row_edges: [E; 3], step_x: [E; 3], mask_steps: &E::MaskSteps) -> Option<RowSpan> {
        let pixels = E::MASK_PIXELS;
        let mut x = self.rect.min_x;
        let remaining = self.rect.max_x - x + 1;
        if remaining <= pixels {
            // The whole row in one mask: no loop to leave.
            let mask = E::coverage(row_edges, mask_steps) & ((1 << remaining) - 1);
            if mask == 0 {
                return None;
            }
            let offset = mask.trailing_zeros();
            return Some(self.row_span(row_edges, step_x, x + offset, x + 32 - mask.leading_zeros()));
        }
        let mask_step = step_x.map(|s| s * E::from_u32(pixels));
        let mut e = row_edges;
        let mut first = None;
        let mut end = x;
        while x <= self.rect.max_x {
            let remaining = self.rect.max_x - x + 1;
            let valid = if remaining >= pixels { u32::MAX >> (32 - pixels) } else { (1 << remaining) - 1 };
            let mask = E::coverage(e, mask_steps) & valid;
            if mask != 0 {
                first.get_or_insert(x + mask.trailing_zeros());
                end = x + 32 - mask.leading_zeros();
                if end < x + remaining.min(pixels) {
                    break;
                }
            } else if first.is_some() {
                break;
            }
            x += pixels;
            e = add(e, mask_step);
        }
        Some(self.row_span(row_edges, step_x, first?, end))
    }

    /// The span `first..end` of the row whose first pixel has edge functions `row_edges`.
    #[inline(always)]
    fn row_span<E: EdgeValue>(&self, row_edges: [E; 3], step_x: [E; 3], first: u32, end: u32) -> RowSpan {
        let offset = E::from_u32(first - self.rect.min_x);
        let weight = |k: usize| (row_edges[k] + offset * step_x[k]).to_f32() * self.inv_area;
        RowSpan { first, end, l1: weight(1), l2: weight(2) }
    }
}

/// Whether the edge `a -> b` of a positive-area triangle is a top or a left edge, whose
/// pixels are drawn (the top-left fill rule).
#[inline(always)]
fn is_top_left(a: (i64, i64), b: (i64, i64)) -> bool {
    (a.1 == b.1 && b.0 > a.0) || b.1 < a.1
}

/// Whether every edge function value a walk over `rect` computes for the triangle `p`
/// (sub-pixel units) fits an `i32`.
///
/// A value at pixel centre `s` is `(b - a) x (s - a)` for two corners `a`, `b`: at most
/// `w h + h |s.x - a.x|` for the triangle's bounding box `w` by `h`. The walk reads up to two
/// mask widths past the rect's last pixel (the last mask's lanes, then one more step) and one
/// row past its last row, all inside the bounding box widened by [`NARROW_MARGIN`] pixels.
fn fits_narrow(p: [(i64, i64); 3]) -> bool {
    let extent = |c: [i64; 3]| c[0].max(c[1]).max(c[2]) - c[0].min(c[1]).min(c[2]);
    let margin = NARROW_MARGIN * SUBPIXEL_STEPS;
    let (w, h) = (extent(p.map(|c| c.0)), extent(p.map(|c| c.1)) + margin);
    h * (2 * w + margin) + 1 < i64::from(i32::MAX)
}

/// Pixels past a triangle's bounding box that a narrow walk may evaluate edge functions at.
const NARROW_MARGIN: i64 = 2 * <i32 as EdgeValue>::MASK_PIXELS as i64;

/// An integer type edge functions are stepped in: `i32` for the triangles whose values fit
/// (see [`fits_narrow`]), eight pixels to a SIMD coverage mask; `i64` for the rest.
trait EdgeValue: Copy + Add<Output = Self> + Mul<Output = Self> {
    /// Pixels one coverage mask holds.
    const MASK_PIXELS: u32;
    /// Each edge's steps to the pixels of a mask, prepared once per triangle.
    type MaskSteps;
    fn mask_steps(step_x: [Self; 3]) -> Self::MaskSteps;
    /// Which of the mask's pixels, the first with edge functions `e`, are inside: bit `k` for
    /// pixel `k`.
    fn coverage(e: [Self; 3], steps: &Self::MaskSteps) -> u32;
    fn from_u32(value: u32) -> Self;
    fn to_f32(self) -> f32;
}

impl EdgeValue for i64 {
    /// A little wider than most rows of the standard scene's triangles (about 3 pixels), which
    /// then take one mask; 8 was 4% slower on it.
    const MASK_PIXELS: u32 = 6;
    type MaskSteps = [i64; 3];

    fn mask_steps(step_x: [i64; 3]) -> [i64; 3] {
        step_x
    }

    #[inline(always)]
    fn coverage(e: [i64; 3], step: &[i64; 3]) -> u32 {
        let mut mask = 0;
        for k in 0..i64::from(Self::MASK_PIXELS) {
            let edges = (e[0] + k * step[0]) | (e[1] + k * step[1]) | (e[2] + k * step[2]);
            mask |= u32::from(edges >= 0) << k;
        }
        mask
    }

    fn from_u32(value: u32) -> Self {
        value.into()
    }

    fn to_f32(self) -> f32 {
        self as f32
    }
}

impl EdgeValue for i32 {
    const MASK_PIXELS: u32 = 8;
    /// Each edge's offsets from the mask's first pixel, one lane per pixel.
    type MaskSteps = [i32x8; 3];

    #[inline(always)]
    fn mask_steps(step_x: [i32; 3]) -> [i32x8; 3] {
        step_x.map(|s| i32x8::new(std::array::from_fn(|k| k as i32 * s)))
    }

    #[inline(always)]
    fn coverage(e: [i32; 3], steps: &[i32x8; 3]) -> u32 {
        let lanes = |k: usize| i32x8::splat(e[k]) + steps[k];
        // A pixel is inside when no edge function is negative: no sign bit in their union.
        !(lanes(0) | lanes(1) | lanes(2)).to_bitmask() & 0xff
    }

    fn from_u32(value: u32) -> Self {
        value as i32
    }

    fn to_f32(self) -> f32 {
        self as f32
    }
}

/// Edge functions advanced by one step.
#[inline(always)]
fn add<E: EdgeValue>(edges: [E; 3], by: [E; 3]) -> [E; 3] {
    [edges[0] + by[0], edges[1] + by[1], edges[2] + by[2]]
}

/// Shading mode numbers for the const-generic pixel loops.
const FLAT: u8 = 0;
const GOURAUD: u8 = 1;
const PHONG: u8 = 2;

/// Draws a set-up triangle with the pixel loop compiled for `pass`; returns the fragments.
fn fill(pass: Pass, setup: &Setup, triangle: &Triangle, context: &TileContext, band: &mut Band) -> u64 {
    macro_rules! dispatch {
        ($($shading:ident => $mode:ident),*) => {
            match (pass.shading, pass.textured, pass.shadowed) {
                $(
                    (Shading::$shading, false, false) => fill_pass::<$mode, false, false>(setup, triangle, context, band),
                    (Shading::$shading, true, false) => fill_pass::<$mode, true, false>(setup, triangle, context, band),
                    (Shading::$shading, false, true) => fill_pass::<$mode, false, true>(setup, triangle, context, band),
                    (Shading::$shading, true, true) => fill_pass::<$mode, true, true>(setup, triangle, context, band),
                )*
            }
        };
    }
    dispatch!(Flat => FLAT, Gouraud => GOURAUD, Phong => PHONG)
}

/// The shading mode number of a [`Shading`].
const fn shading_of(mode: u8) -> Shading {
    match mode {
        FLAT => Shading::Flat,
        GOURAUD => Shading::Gouraud,
        _ => Shading::Phong,
    }
}

/// Pixels shaded together: a horizontal run of four, one per SIMD lane of a [`Vec4`].
const LANES: usize = 4;

/// 2^23: added to a float in `[0, 2^23)`, it leaves the rounded whole number in the low bits.
const ROUNDING_BIAS: f32 = 8_388_608.0;

/// Each lane's offset from the run's first pixel.
const LANE_OFFSETS: Vec4 = Vec4::new(0.0, 1.0, 2.0, 3.0);

/// The colour pixel loop for one combination of shading mode, texture and shadows.
///
/// Coverage is decided per pixel, exactly, as one interval per row; depth tests, interpolation
/// and lighting run on runs of [`LANES`] pixels of that interval at once.
fn fill_pass<const MODE: u8, const TEXTURED: bool, const SHADOWED: bool>(
    setup: &Setup,
    triangle: &Triangle,
    context: &TileContext,
    band: &mut Band,
) -> u64 {
    let pass = Pass { shading: shading_of(MODE), textured: TEXTURED, shadowed: SHADOWED };
    let light = &context.frame.light;
    let material = triangle.material;
    let texture = material.texture.as_deref();
    let pcf = context.frame.settings.pcf;
    let [v0, v1, v2] = setup.order.map(|k| triangle.varyings[k]);
    // Vertex 0's values and the differences to vertices 1 and 2, for the values this pass reads.
    let mut base = [0.0; VARYINGS];
    let mut to_1 = [0.0; VARYINGS];
    let mut to_2 = [0.0; VARYINGS];
    for k in 0..VARYINGS {
        if pass.uses(k) {
            base[k] = v0[k];
            to_1[k] = v1[k] - v0[k];
            to_2[k] = v2[k] - v0[k];
        }
    }
    let [z0, z1, z2] = setup.z;
    let [w0, w1, w2] = setup.inv_w;
    let (dz1, dz2, dw1, dw2) = (z1 - z0, z2 - z0, w1 - w0, w2 - w0);
    // Small or distant triangles skip the per-pixel division.
    let affine = affine_is_close(setup.inv_w, &to_1, &to_2, |k| pass.uses(k).then(|| affine_tolerance(k, texture)));
    let width = band.width as usize;
    setup.covered_runs(|py, run, lanes, l1, l2| {
        let z = (Vec4::splat(z0) + l1 * dz1 + l2 * dz2).to_array();
        let at = (py - band.y0) as usize * width + run as usize;
        let mut drawn = [false; LANES];
        for (lane, (depth, z)) in band.depth[at..at + lanes].iter_mut().zip(z).enumerate() {
            if z < *depth {
                *depth = z;
                drawn[lane] = true;
            }
        }
        if drawn.contains(&true) {
            let (p1, p2) = if affine {
                (l1, l2)
            } else {
                let w = (Vec4::splat(w0) + l1 * dw1 + l2 * dw2).recip();
                (l1 * w1 * w, l2 * w2 * w)
            };
            let value = |k: usize| Vec4::splat(base[k]) + p1 * to_1[k] + p2 * to_2[k];
            let diffuse = match MODE {
                FLAT => Vec4::splat(triangle.flat_diffuse),
                GOURAUD if !SHADOWED => Vec4::ZERO,
                GOURAUD => value(slot::DIFFUSE),
                _ => {
                    let (nx, ny, nz) = (value(slot::NORMAL), value(slot::NORMAL + 1), value(slot::NORMAL + 2));
                    let towards = -light.direction;
                    let cosine = (nx * towards.x + ny * towards.y + nz * towards.z)
                        / (nx * nx + ny * ny + nz * nz).max(Vec4::splat(1e-12)).sqrt();
                    cosine.max(Vec4::ZERO) * light.diffuse
                }
            };
            let mut visibility = Vec4::ONE;
            if SHADOWED && let Some(map) = context.shadow {
                let (x, y, depth) = (value(slot::SHADOW), value(slot::SHADOW + 1), value(slot::SHADOW + 2));
                visibility = map.visibility_lanes(x, y, depth, pcf);
            }
            let mut rgb = [value(slot::COLOR), value(slot::COLOR + 1), value(slot::COLOR + 2)];
            if MODE != GOURAUD || SHADOWED {
                let intensity = (Vec4::splat(light.fill) + diffuse * visibility).max(Vec4::splat(light.ambient));
                for c in &mut rgb {
                    *c *= intensity;
                }
            }
            if TEXTURED && let Some(texture) = texture {
                let (u, v) = (value(slot::UV).to_array(), value(slot::UV + 1).to_array());
                let mut texels = [[0.0; LANES]; 3];
                for lane in 0..LANES {
                    if drawn[lane] {
                        let texel = texture.sample(Vec2::new(u[lane], v[lane]), material.sampler);
                        for (channel, texels) in texels.iter_mut().enumerate() {
                            texels[lane] = texel[channel];
                        }
                    }
                }
                for (c, texels) in rgb.iter_mut().zip(texels) {
                    *c *= Vec4::from_array(texels);
                }
            }
            // Adding 2^23 to a number in [0, 255] leaves it, rounded to the nearest whole
            // number, in the low mantissa bits: a cheap exact conversion to bytes.
            let [r, g, b] = rgb.map(|c| (c.clamp(Vec4::ZERO, Vec4::ONE) * 255.0 + ROUNDING_BIAS).to_array());
            for lane in 0..LANES {
                if drawn[lane] {
                    let byte = |c: f32| c.to_bits() as u8;
                    let pixel = (at + lane) * 4;
                    band.color[pixel..pixel + 4].copy_from_slice(&[byte(r[lane]), byte(g[lane]), byte(b[lane]), 255]);
                }
            }
        }
    })
}

/// Whether interpolating in screen space keeps every value within `tolerance` of its
/// perspective-correct interpolation, for a triangle with `1/w` of `inv_w` at its vertices and
/// values differing by `to_1` and `to_2` from vertex 0 to vertices 1 and 2.
///
/// Write the vertices' `1/w` as `m (1 + s_k)` with `0 <= s_k <= spread`, `spread` the ratio of
/// the largest to the least less one. At a point with screen-space weights `b_k`, the
/// perspective-correct weights are `b_k (1 + s_k) / (1 + sum(b_j s_j))`, so a value moves by
/// the covariance of `s` and the value under the weights `b`, divided by at least one: at
/// most `spread / 2` times half the value's range over the three vertices (Popoviciu).
/// Values whose `tolerance` is `None` are not interpolated and not checked.
#[inline(always)]
fn affine_is_close(
    inv_w: [f32; 3],
    to_1: &Varyings,
    to_2: &Varyings,
    tolerance: impl Fn(usize) -> Option<f32>,
) -> bool {
    let spread = inv_w[0].max(inv_w[1]).max(inv_w[2]) / inv_w[0].min(inv_w[1]).min(inv_w[2]) - 1.0;
    (0..VARYINGS).all(|k| {
        tolerance(k).is_none_or(|tolerance| {
            let range = to_1[k].max(to_2[k]).max(0.0) - to_1[k].min(to_2[k]).min(0.0);
            spread * range * 0.25 <= tolerance
        })
    })
}

/// The depth-only pixel loop of the shadow map, with the slope-scaled bias.
fn fill_depth(setup: &Setup, band: &mut DepthBand) {
    let [z0, z1, z2] = setup.z;
    let (dz1, dz2) = (z1 - z0, z2 - z0);
    // Depth changes by these per pixel right and down.
    let slope = |step: [i64; 3]| (step[1] as f32 * dz1 + step[2] as f32 * dz2) * setup.inv_area;
    let bias = CONSTANT_BIAS + SLOPE_BIAS * slope(setup.step_x).abs().max(slope(setup.step_y).abs());
    setup.covered_runs(|py, run, lanes, l1, l2| {
        let z = (Vec4::splat(z0 + bias) + l1 * dz1 + l2 * dz2).to_array();
        let at = (py - band.y0) as usize * band.stride + band.first + run as usize;
        for (texel, z) in band.depth[at..at + lanes].iter_mut().zip(z) {
            *texel = texel.min(z);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A screen vertex at whole sub-pixel position `(x, y)`.
    fn vertex((x, y): (i32, i32)) -> ScreenVertex {
        ScreenVertex { code: 0, x, y, z: 0.5, inv_w: 1.0 }
    }

    /// Every run a walk visits: row, first pixel, covered pixels, and the weights at them.
    fn runs(setup: &Setup) -> Vec<(u32, u32, usize, Vec4, Vec4)> {
        let mut runs = Vec::new();
        setup.covered_runs(|y, x, lanes, l1, l2| runs.push((y, x, lanes, l1, l2)));
        runs
    }

    const TILE: PixelBounds = PixelBounds { min_x: 64, max_x: 127, min_y: 32, max_y: 63 };

    #[test]
    fn small_triangles_walk_narrow_and_large_ones_wide() {
        let steps = SUBPIXEL_STEPS as i32;
        let small = [(70, 35), (90, 40), (75, 60)].map(|(x, y)| vertex((x * steps, y * steps)));
        let large = [(0, 0), (900, 40), (100, 600)].map(|(x, y)| vertex((x * steps, y * steps)));
        assert!(Setup::new(small.each_ref(), TILE, false).unwrap().narrow);
        assert!(!Setup::new(large.each_ref(), TILE, false).unwrap().narrow);
    }

    proptest! {
        /// The `i32` walk visits exactly the pixels of the `i64` one, with the same weights.
        #[test]
        fn narrow_walks_match_wide_ones(
            corners in prop::array::uniform3((40 * 256..150 * 256i32, 20 * 256..80 * 256i32)),
        ) {
            let vertices = corners.map(vertex);
            let Some(narrow) = Setup::new(vertices.each_ref(), TILE, false) else { return Ok(()) };
            prop_assume!(narrow.narrow);
            let wide = Setup { narrow: false, ..narrow };
            let (a, b) = (runs(&narrow), runs(&wide));
            prop_assert_eq!(a.len(), b.len());
            for (a, b) in a.iter().zip(&b) {
                prop_assert_eq!((a.0, a.1, a.2), (b.0, b.1, b.2));
                prop_assert!(a.3.abs_diff_eq(b.3, 1e-5) && a.4.abs_diff_eq(b.4, 1e-5));
            }
        }

        /// When a triangle is judged close enough to affine, every value at every point inside
        /// it is within its tolerance of the perspective-correct value.
        #[test]
        fn affine_interpolation_stays_within_tolerance(
            inv_w in 0.2f32..5.0,
            spread in prop::array::uniform3(0.0f32..0.01),
            to_1 in prop::array::uniform12(-1.0f32..1.0),
            to_2 in prop::array::uniform12(-1.0f32..1.0),
            weights in (0.0f32..1.0, 0.0f32..1.0),
        ) {
            let inv_w = spread.map(|s| inv_w * (1.0 + s));
            let tolerance = [0.002; VARYINGS];
            prop_assume!(affine_is_close(inv_w, &to_1, &to_2, |k| Some(tolerance[k])));
            let (b1, b2) = if weights.0 + weights.1 > 1.0 { (1.0 - weights.0, 1.0 - weights.1) } else { weights };
            let error = affine_error(inv_w, [1.0 - b1 - b2, b1, b2]);
            for k in 0..VARYINGS {
                let error = error.0 * to_1[k] + error.1 * to_2[k];
                prop_assert!(error.abs() <= tolerance[k] * (1.0 + 1e-3) + 1e-7, "slot {k}: {error}");
            }
        }
    }

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
        let mut to_1 = [0.0; VARYINGS];
        to_1[0] = 1.0;
        let error = affine_error(inv_w, [0.5, 0.5, 0.0]).0;
        assert!((error - 0.0025 / 1.005).abs() < 1e-6, "{error}");
        assert!(affine_is_close(inv_w, &to_1, &[0.0; VARYINGS], |_| Some(0.0026)));
        assert!(!affine_is_close(inv_w, &to_1, &[0.0; VARYINGS], |_| Some(0.0024)));
    }
}
