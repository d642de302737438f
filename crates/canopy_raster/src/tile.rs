//! The tile stage: triangle setup against one tile and the pixel loops.
//!
//! Coverage uses exact integer edge functions on screen coordinates snapped to
//! 1/[`SUBPIXEL_STEPS`] of a pixel, sampled at pixel centres and stepped incrementally, with the
//! top-left fill rule: a pixel whose centre lies on an edge shared by two triangles is drawn by
//! exactly one of them. Depth is interpolated linearly in screen space (as the projection
//! demands); every other value perspective-correctly, as the screen-space plane of the value
//! divided by `w` over the plane of `1/w`. A triangle whose `w` varies too little for that to
//! move any value beyond its tolerance (a sixteenth of what a pixel shows of it) is
//! interpolated in screen space.
//!
//! Pixels are depth-tested, shaded and stored in runs of [`LANES`] along a row, with lane masks
//! instead of a branch per pixel; a run is read and written whole unless it reaches past the
//! end of its row.
//!
//! Each tile keeps a conservative farthest depth of what it holds; a triangle entirely behind
//! it is skipped before setup reaches its pixels.

use crate::framebuffer::{Band, FAR_DEPTH};
use crate::pipeline::{
    BinEntry, CLIPPED_BIT, Chunk, ClippedTriangle, Frame, PixelBounds, SUBPIXEL_STEPS, ScreenVertex, Span, TILE_HEIGHT,
    TILE_WIDTH, edge, flat_diffuse, pixel_bounds,
};
use crate::shade::{Material, Pass, Shading, VARYINGS, Varyings, affine_tolerance, lanes_of, slot};
use crate::shadow::{CONSTANT_BIAS, SLOPE_BIAS, ShadowMap};
use bevy_math::{Vec2, Vec3, Vec4};
use std::ops::{Add, Mul};
use wide::{f32x4, i32x8, u32x4};

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
    band.color.fill(context.frame.background);
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

/// The farthest depth held in `rect` of a band, four depths at a time.
fn farthest_depth(depth: &[f32], width: u32, y0: u32, rect: PixelBounds) -> f32 {
    let mut farthest = Vec4::ZERO;
    let mut rest = 0.0f32;
    for y in rect.min_y..=rect.max_y {
        let row = ((y - y0) * width) as usize;
        let depths = &depth[row + rect.min_x as usize..=row + rect.max_x as usize];
        let runs = depths.chunks_exact(LANES);
        rest = runs.remainder().iter().fold(rest, |m, &d| m.max(d));
        farthest = runs.fold(farthest, |m, run| m.max(Vec4::from_slice(run)));
    }
    farthest.max_element().max(rest)
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

impl Setup {
    /// Walks each row's covered span in runs of up to [`LANES`] pixels, calling
    /// `visit(y, x, lanes)` for each: `x` is the run's first pixel and bit `k` of `lanes` is
    /// set when pixel `x + k` is covered. Returns the pixels covered.
    #[inline(always)]
    fn covered_runs(&self, mut visit: impl FnMut(u32, u32, u32)) -> u64 {
        let mut rows = [0; TILE_HEIGHT as usize];
        if self.narrow {
            let narrow = |edges: [i64; 3]| edges.map(|e| e as i32);
            self.coverage(narrow(self.start), narrow(self.step_x), narrow(self.step_y), &mut rows);
        } else {
            self.coverage(self.start, self.step_x, self.step_y, &mut rows);
        }
        let mut fragments = 0;
        for (y, &coverage) in (self.rect.min_y..=self.rect.max_y).zip(&rows) {
            if coverage == 0 {
                continue;
            }
            let mut x = coverage.trailing_zeros();
            fragments += u64::from(u64::BITS - coverage.leading_zeros() - x);
            let mut rest = coverage >> x;
            while rest != 0 {
                visit(y, self.rect.min_x + x, (rest & RUN_MASK) as u32);
                rest >>= LANES;
                x += LANES as u32;
            }
        }
        fragments
    }

    /// Writes which pixels of the rect the triangle covers into `rows`, with edge functions
    /// stepped in `E`: one bit per pixel (at most [`TILE_WIDTH`] of them) and a word per row
    /// (at most [`TILE_HEIGHT`]), found [`MASK_PIXELS`] pixels at a time without a branch per
    /// pixel.
    ///
    /// The triangle is convex, so each row's covered pixels run from its lowest set bit to its
    /// highest.
    #[inline(always)]
    fn coverage<E: EdgeValue>(
        &self,
        start: [E; 3],
        step_x: [E; 3],
        step_y: [E; 3],
        rows: &mut [u64; TILE_HEIGHT as usize],
    ) {
        const { assert!(TILE_WIDTH <= u64::BITS) };
        let mask_steps = E::mask_steps(step_x);
        let group_step = step_x.map(|s| s * E::from_u32(MASK_PIXELS));
        let width = self.rect.max_x - self.rect.min_x + 1;
        let groups = width.div_ceil(MASK_PIXELS);
        let valid = u64::MAX >> (u64::BITS - width);
        let mut row_edges = start;
        for row in &mut rows[..(self.rect.max_y - self.rect.min_y + 1) as usize] {
            let mut coverage = 0u64;
            let mut edges = row_edges;
            for group in 0..groups {
                coverage |= u64::from(E::coverage(edges, &mask_steps)) << (group * MASK_PIXELS);
                edges = add(edges, group_step);
            }
            *row = coverage & valid;
            row_edges = add(row_edges, step_y);
        }
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
const NARROW_MARGIN: i64 = 2 * MASK_PIXELS as i64;

/// Pixels one coverage mask holds.
const MASK_PIXELS: u32 = 8;

/// An integer type edge functions are stepped in: `i32` for the triangles whose values fit
/// (see [`fits_narrow`]), eight pixels to a SIMD coverage mask; `i64` for the rest.
trait EdgeValue: Copy + Add<Output = Self> + Mul<Output = Self> {
    /// Each edge's steps to the pixels of a mask, prepared once per triangle.
    type MaskSteps;
    fn mask_steps(step_x: [Self; 3]) -> Self::MaskSteps;
    /// Which of the mask's pixels, the first with edge functions `e`, are inside: bit `k` for
    /// pixel `k`.
    fn coverage(e: [Self; 3], steps: &Self::MaskSteps) -> u32;
    fn from_u32(value: u32) -> Self;
}

impl EdgeValue for i64 {
    type MaskSteps = [i64; 3];

    fn mask_steps(step_x: [i64; 3]) -> [i64; 3] {
        step_x
    }

    #[inline(always)]
    fn coverage(e: [i64; 3], step: &[i64; 3]) -> u32 {
        let mut mask = 0;
        for k in 0..i64::from(MASK_PIXELS) {
            let edges = (e[0] + k * step[0]) | (e[1] + k * step[1]) | (e[2] + k * step[2]);
            mask |= u32::from(edges >= 0) << k;
        }
        mask
    }

    fn from_u32(value: u32) -> Self {
        value.into()
    }
}

impl EdgeValue for i32 {
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

/// The coverage bits of one run.
const RUN_MASK: u64 = (1 << LANES) - 1;

/// Four-lane packs of interpolated values: the [`Varyings`] four to a pack, then depth and
/// `1/w`.
const PACKS: usize = VARYINGS / LANES + 1;

/// Where depth and `1/w` are in the last pack.
const DEPTH: usize = VARYINGS;
const INV_W: usize = VARYINGS + 1;

/// A triangle's interpolated values as planes over the pixels of its rect: each value at the
/// centre of the rect's first pixel and its change per pixel right and down, in packs of four.
///
/// Depth and `1/w` are linear in screen space; the other values are too when the triangle is
/// drawn affinely, and otherwise their planes hold the values divided by `w`, to be
/// multiplied by the pixel's `w` (the reciprocal of the interpolated `1/w`).
struct Planes<const N: usize> {
    origin: [Vec4; N],
    dx: [Vec4; N],
    dy: [Vec4; N],
}

impl<const N: usize> Planes<N> {
    /// The planes through `values` at the setup's vertices (in its order), for the packs
    /// `used` accepts (the others stay zero).
    #[inline(always)]
    fn new(setup: &Setup, values: [[Vec4; N]; 3], used: impl Fn(usize) -> bool) -> Self {
        let weight = |edge: i64| edge as f32 * setup.inv_area;
        // Barycentric weights of vertices 1 and 2 at the rect's first pixel, and their steps.
        let (o1, o2) = (weight(setup.start[1]), weight(setup.start[2]));
        let (x1, x2) = (weight(setup.step_x[1]), weight(setup.step_x[2]));
        let (y1, y2) = (weight(setup.step_y[1]), weight(setup.step_y[2]));
        let [v0, v1, v2] = values;
        let to_1: [Vec4; N] = std::array::from_fn(|p| v1[p] - v0[p]);
        let to_2: [Vec4; N] = std::array::from_fn(|p| v2[p] - v0[p]);
        let plane = |p: usize, w1: f32, w2: f32, base: Vec4| {
            if used(p) { base + to_1[p] * w1 + to_2[p] * w2 } else { Vec4::ZERO }
        };
        Self {
            origin: std::array::from_fn(|p| plane(p, o1, o2, v0[p])),
            dx: std::array::from_fn(|p| plane(p, x1, x2, Vec4::ZERO)),
            dy: std::array::from_fn(|p| plane(p, y1, y2, Vec4::ZERO)),
        }
    }

    /// Every value at pixel offset (`x`, `y`) from the rect's first pixel.
    #[inline(always)]
    fn at(&self, x: f32, y: f32) -> [Vec4; N] {
        std::array::from_fn(|p| self.origin[p] + self.dx[p] * x + self.dy[p] * y)
    }

    /// Value `k`'s change from a run's first pixel to each lane.
    #[inline(always)]
    fn lane_steps(&self, k: usize) -> Vec4 {
        LANE_OFFSETS * self.dx[k / LANES][k % LANES]
    }
}

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
    let texture = triangle.material.texture.as_deref();
    let varyings = setup.order.map(|k| triangle.varyings[k]);
    // Small or distant triangles skip the per-pixel division.
    let affine = {
        let [v0, v1, v2] = varyings;
        let to_1 = std::array::from_fn(|k| v1[k] - v0[k]);
        let to_2 = std::array::from_fn(|k| v2[k] - v0[k]);
        affine_is_close(setup.inv_w, &to_1, &to_2, |k| pass.uses(k).then(|| affine_tolerance(k, texture)))
    };
    let values: [[Vec4; PACKS]; 3] = std::array::from_fn(|vertex| {
        let (varyings, z, inv_w) = (varyings[vertex], setup.z[vertex], setup.inv_w[vertex]);
        let scale = if affine { 1.0 } else { inv_w };
        std::array::from_fn(|p| match p {
            _ if p * LANES < VARYINGS => Vec4::from_slice(&varyings[p * LANES..]) * scale,
            _ => Vec4::new(z, inv_w, 0.0, 0.0),
        })
    });
    let uses = |k: usize| k >= VARYINGS || pass.uses(k);
    let planes = Planes::new(setup, values, |p| (p * LANES..(p + 1) * LANES).any(uses));
    let shading = TriangleShading {
        lane_steps: std::array::from_fn(|k| if uses(k) { planes.lane_steps(k) } else { Vec4::ZERO }),
        planes,
        affine,
        origin: (setup.rect.min_x, setup.rect.min_y),
        triangle,
        context,
    };
    setup.covered_runs(|py, run, lanes| shade_run::<MODE, TEXTURED, SHADOWED>(&shading, band, py, run, lanes))
}

/// What the runs of a triangle share.
struct TriangleShading<'a> {
    planes: Planes<PACKS>,
    /// Each value's change from a run's first pixel to its lanes.
    lane_steps: [Vec4; VARYINGS + 2],
    /// Whether the values are interpolated in screen space.
    affine: bool,
    /// The first pixel of the planes' rect.
    origin: (u32, u32),
    triangle: &'a Triangle<'a>,
    context: &'a TileContext<'a>,
}

/// Depth-tests, shades and stores one run of [`LANES`] pixels from `(x, y)`, those of `lanes`'
/// set bits.
#[inline(always)]
fn shade_run<const MODE: u8, const TEXTURED: bool, const SHADOWED: bool>(
    shading: &TriangleShading,
    band: &mut Band,
    y: u32,
    x: u32,
    lanes: u32,
) {
    let TriangleShading { planes, lane_steps, affine, origin, triangle, context } = shading;
    let light = &context.frame.light;
    let material = triangle.material;
    let at_run = planes.at((x - origin.0) as f32, (y - origin.1) as f32);
    let lane_value = |k: usize| Vec4::splat(at_run[k / LANES][k % LANES]) + lane_steps[k];
    let z = lanes_of(lane_value(DEPTH));
    let width = band.width as usize;
    let at = (y - band.y0) as usize * width + x as usize;
    let valid = (width - x as usize).min(LANES);
    let depth = f32x4::new(read_run(band.depth, at, valid, 0.0));
    let drawn = z.simd_lt(depth) & covered(lanes);
    let drawn_lanes = drawn.to_bitmask();
    if drawn_lanes == 0 {
        return;
    }
    write_run(band.depth, at, valid, drawn.bitselect(z, depth).to_array());
    let w = if *affine { Vec4::ONE } else { lane_value(INV_W).recip() };
    let value = |k: usize| if *affine { lane_value(k) } else { lane_value(k) * w };
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
        let (sx, sy, depth) = (value(slot::SHADOW), value(slot::SHADOW + 1), value(slot::SHADOW + 2));
        visibility = map.visibility_lanes(sx, sy, depth, context.frame.settings.pcf);
    }
    let mut rgb = [value(slot::COLOR), value(slot::COLOR + 1), value(slot::COLOR + 2)];
    if MODE != GOURAUD || SHADOWED {
        let intensity = (Vec4::splat(light.fill) + diffuse * visibility).max(Vec4::splat(light.ambient));
        for c in &mut rgb {
            *c *= intensity;
        }
    }
    if TEXTURED && let Some(texture) = material.texture.as_deref() {
        let (u, v) = (value(slot::UV).to_array(), value(slot::UV + 1).to_array());
        let mut texels = [[0.0; LANES]; 3];
        for lane in 0..LANES {
            if drawn_lanes & 1 << lane != 0 {
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
    // Adding 2^23 to a number in [0, 255] leaves it, rounded to the nearest whole number,
    // in the low mantissa bits: a cheap exact conversion to bytes.
    let [r, g, b] = rgb.map(|c| lanes_of(c.clamp(Vec4::ZERO, Vec4::ONE) * 255.0 + ROUNDING_BIAS).to_bits());
    let byte = u32x4::splat(0xff);
    let pixels = (r & byte) | (g & byte) << 8 | (b & byte) << 16 | byte << 24;
    let old = u32x4::from(bytemuck::cast::<_, [u32; LANES]>(read_run(band.color, at, valid, [0; 4])).map(u32::from_le));
    let blended = drawn.to_bits().bitselect(pixels, old);
    write_run(band.color, at, valid, bytemuck::cast(blended.to_array().map(u32::to_le)));
}

/// The lane mask with lane `k` set when bit `k` of `lanes` is.
#[inline(always)]
fn covered(lanes: u32) -> f32x4 {
    const MASKS: [[u32; LANES]; 1 << LANES] = {
        let mut masks = [[0; LANES]; 1 << LANES];
        let mut bits = 0;
        while bits < masks.len() {
            let mut lane = 0;
            while lane < LANES {
                if bits & 1 << lane != 0 {
                    masks[bits][lane] = !0;
                }
                lane += 1;
            }
            bits += 1;
        }
        masks
    };
    f32x4::from_bits(u32x4::new(MASKS[lanes as usize & (MASKS.len() - 1)]))
}

/// The [`LANES`] values of a run starting at `at`, of which the first `valid` lie in the row
/// (the rest, past the row's end, read as `fill`).
#[inline(always)]
fn read_run<T: Copy>(values: &[T], at: usize, valid: usize, fill: T) -> [T; LANES] {
    if valid == LANES {
        values[at..at + LANES].try_into().expect("a run is LANES long")
    } else {
        std::array::from_fn(|k| if k < valid { values[at + k] } else { fill })
    }
}

/// Stores a run read by [`read_run`]: its first `valid` values.
#[inline(always)]
fn write_run<T: Copy>(values: &mut [T], at: usize, valid: usize, run: [T; LANES]) {
    if valid == LANES {
        values[at..at + LANES].copy_from_slice(&run);
    } else {
        values[at..at + valid].copy_from_slice(&run[..valid]);
    }
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
    // Plain comparisons: the values are finite, so the NaN handling of `f32::max` is not needed.
    let (max, min) = (|a: f32, b: f32| if a > b { a } else { b }, |a: f32, b: f32| if a < b { a } else { b });
    let spread = max(max(inv_w[0], inv_w[1]), inv_w[2]) / min(min(inv_w[0], inv_w[1]), inv_w[2]) - 1.0;
    (0..VARYINGS).all(|k| {
        tolerance(k).is_none_or(|tolerance| {
            let range = max(max(to_1[k], to_2[k]), 0.0) - min(min(to_1[k], to_2[k]), 0.0);
            spread * range * 0.25 <= tolerance
        })
    })
}

/// The depth-only pixel loop of the shadow map, with the slope-scaled bias.
fn fill_depth(setup: &Setup, band: &mut DepthBand) {
    let planes = Planes::new(setup, setup.z.map(|z| [Vec4::new(z, 0.0, 0.0, 0.0)]), |_| true);
    let (dx, dy) = (planes.dx[0].x, planes.dy[0].x);
    let bias = CONSTANT_BIAS + SLOPE_BIAS * dx.abs().max(dy.abs());
    let lane_steps = planes.lane_steps(0);
    let (min_x, min_y) = (setup.rect.min_x, setup.rect.min_y);
    setup.covered_runs(|py, run, lanes| {
        let z = planes.at((run - min_x) as f32, (py - min_y) as f32)[0].x + bias;
        let z = lanes_of(Vec4::splat(z) + lane_steps);
        let at = (py - band.y0) as usize * band.stride + band.first + run as usize;
        let valid = (band.width - run).min(LANES as u32) as usize;
        let depth = f32x4::new(read_run(band.depth, at, valid, 0.0));
        write_run(band.depth, at, valid, covered(lanes).bitselect(depth.min(z), depth).to_array());
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

    /// Every run a walk visits: row, first pixel and coverage bits.
    fn runs(setup: &Setup) -> Vec<(u32, u32, u32)> {
        let mut runs = Vec::new();
        setup.covered_runs(|y, x, lanes| runs.push((y, x, lanes)));
        runs
    }

    const TILE: PixelBounds = PixelBounds { min_x: 64, max_x: 127, min_y: 32, max_y: 63 };

    #[test]
    fn the_farthest_depth_is_found_in_whole_runs_and_in_the_rest_of_a_row() {
        // A band 13 pixels wide from row 8 on; the rect's rows are 6 pixels long: one run of
        // four and a rest of two.
        let (width, y0) = (13, 8);
        let rect = PixelBounds { min_x: 3, max_x: 8, min_y: 9, max_y: 11 };
        let mut depth = vec![0.9; width as usize * 4];
        for y in rect.min_y..=rect.max_y {
            let row = ((y - y0) * width) as usize;
            depth[row + 3..=row + 8].fill(0.25);
        }
        let at = |x: u32, y: u32| ((y - y0) * width + x) as usize;
        assert_eq!(farthest_depth(&depth, width, y0, rect), 0.25, "pixels outside the rect do not count");
        depth[at(5, 10)] = 0.5;
        assert_eq!(farthest_depth(&depth, width, y0, rect), 0.5, "inside a run");
        depth[at(8, 11)] = 0.75;
        assert_eq!(farthest_depth(&depth, width, y0, rect), 0.75, "in the rest of a row");
    }

    #[test]
    fn small_triangles_walk_narrow_and_large_ones_wide() {
        let steps = SUBPIXEL_STEPS as i32;
        let small = [(70, 35), (90, 40), (75, 60)].map(|(x, y)| vertex((x * steps, y * steps)));
        let large = [(0, 0), (900, 40), (100, 600)].map(|(x, y)| vertex((x * steps, y * steps)));
        assert!(Setup::new(small.each_ref(), TILE, false).unwrap().narrow);
        assert!(!Setup::new(large.each_ref(), TILE, false).unwrap().narrow);
    }

    proptest! {
        /// The `i32` walk visits exactly the pixels of the `i64` one.
        #[test]
        fn narrow_walks_match_wide_ones(
            corners in prop::array::uniform3((40 * 256..150 * 256i32, 20 * 256..80 * 256i32)),
        ) {
            let vertices = corners.map(vertex);
            let Some(narrow) = Setup::new(vertices.each_ref(), TILE, false) else { return Ok(()) };
            prop_assume!(narrow.narrow);
            let wide = Setup { narrow: false, ..narrow };
            prop_assert_eq!(runs(&narrow), runs(&wide));
        }

        /// The runs hold exactly the pixels of the rect whose edge functions are all
        /// non-negative, each once.
        #[test]
        fn runs_cover_exactly_the_inside_pixels(
            corners in prop::array::uniform3((40 * 256..150 * 256i32, 20 * 256..80 * 256i32)),
        ) {
            let vertices = corners.map(vertex);
            let Some(setup) = Setup::new(vertices.each_ref(), TILE, false) else { return Ok(()) };
            let mut visited = Vec::new();
            for (y, x, lanes) in runs(&setup) {
                visited.extend((0..LANES as u32).filter(|k| lanes & 1 << k != 0).map(|k| (x + k, y)));
            }
            let rect = setup.rect;
            let inside: Vec<(u32, u32)> = (rect.min_y..=rect.max_y)
                .flat_map(|y| (rect.min_x..=rect.max_x).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let (dx, dy) = (i64::from(x - rect.min_x), i64::from(y - rect.min_y));
                    (0..3).all(|k| setup.start[k] + dx * setup.step_x[k] + dy * setup.step_y[k] >= 0)
                })
                .collect();
            prop_assert_eq!(visited, inside);
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
