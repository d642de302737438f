//! The shadow map's depth pass.
//!
//! Triangles are sorted into strips of [`STRIP_ROWS`] map rows (see [`sort`](crate::sort)),
//! and each strip sets its triangles up and draws them at once, with the same fixed-point edge
//! functions and fill rule as the colour image and the slope-scaled bias. A texel keeps the
//! least depth drawn into it, whatever the order, and only depth is drawn, so the map does not
//! need the colour image's tiles: a strip draws a triangle a window of [`WINDOW`] texels of a
//! row at a time. The map's triangles are a few texels across, so one window usually holds a
//! row of one.

use crate::clip::outside;
use crate::coverage::{RowMasks, Walk, covered, lane_multiples};
use crate::frame::View;
use crate::framebuffer::FAR_DEPTH;
use crate::lanes::{LANE_OFFSETS, LANES, lanes_of};
use crate::screen::{PixelBounds, ScreenVertex, TILE_HEIGHT, TILE_WIDTH, edge};
use crate::setup::{Edges, Plane, Viewport, Weights, greater, positive_order};
use crate::shade::VARYINGS;
use crate::shadow::{CONSTANT_BIAS, QuadDepth, SLOPE_BIAS, ShadowMap, WINDOW, nearest_of_quads};
use crate::sort::{Corners, Sorted};
use crate::work_queue::Schedule;
use bevy_math::{Vec3, Vec4};
use bevy_tasks::TaskPool;
use wide::{f32x4, f32x8, i32x8};

/// Map rows one strip task draws.
pub(crate) const STRIP_ROWS: u32 = 64;

/// The depth pass's buffers, kept between frames so that a scene of steady size does not
/// allocate.
#[derive(Debug, Default)]
pub(crate) struct DepthPass {
    /// The triangles reaching each strip: sorted for the light's view into strips of
    /// [`STRIP_ROWS`] rows before [`DepthPass::draw`] (together with the image's triangles).
    pub sorted: Sorted,
    schedule: Schedule,
}

/// What the depth pass draws its sorted triangles with: the frame's vertices as the light sees
/// them.
#[derive(Clone, Copy)]
pub(crate) struct DepthScene<'a> {
    /// World positions, for the triangles that need clipping.
    pub world: &'a [Vec3],
    /// The light's view: its projection, the projected vertices and the map as viewport.
    pub view: View<'a>,
}

impl DepthPass {
    /// Clears `map` and draws the depths of every triangle of `scene` into it, spreading the
    /// work over `pool`; the triangles are those of [`DepthPass::sorted`], sorted for `scene`'s
    /// view. Returns how many triangles were drawn (after clipping and culling).
    pub fn draw(&mut self, pool: &TaskPool, scene: DepthScene, map: &mut ShadowMap) -> usize {
        let size = map.size();
        let (stride, first) = map.row_layout();
        let sorted = &self.sorted;
        let strips = map.strips_mut(STRIP_ROWS as usize);
        let draw = |index: usize, (depth, quads): (&mut [f32], _)| {
            let rows = (depth.len() / stride) as u32;
            let band = DepthBand { y0: index as u32 * STRIP_ROWS, rows, width: size, stride, first, depth };
            draw_strip(scene, sorted.strip(index), band, quads)
        };
        let triangles = self.schedule.run(pool, strips, draw, |total, strip| *total += strip);
        map.join_strips(STRIP_ROWS as usize);
        triangles
    }
}

/// A horizontal band of the shadow map: rows `stride` apart, each with its `width` texels from
/// `first` on and at least [`WINDOW`] - 1 border texels after them.
struct DepthBand<'a> {
    y0: u32,
    /// Rows in the band (the last strip may be shorter).
    rows: u32,
    width: u32,
    stride: usize,
    first: usize,
    depth: &'a mut [f32],
}

/// Clears one strip of the map and draws into it the triangles of `sorted`, then the least
/// depths of its two-by-twos into `quads` when lookups are filtered (all but those of its last
/// row, which reach into the next strip); returns how many triangles were set up with their
/// first row in the strip.
fn draw_strip<'a>(
    scene: DepthScene,
    sorted: impl Iterator<Item = &'a Corners>,
    mut band: DepthBand,
    quads: Option<&mut [QuadDepth]>,
) -> usize {
    for row in band.depth.chunks_exact_mut(band.stride) {
        row[band.first..band.first + band.width as usize].fill(FAR_DEPTH);
    }
    let mut masks = [0; TILE_HEIGHT as usize];
    let view = scene.view;
    let mut triangles = 0;
    let mut draw = |vertices: [&ScreenVertex; 3], band: &mut DepthBand| {
        if let Some(triangle) = DepthTriangle::new(vertices, view.viewport) {
            let first_row = triangle.edges.bounds.min_y;
            fill_triangle(triangle, &mut masks, band);
            triangles += usize::from((band.y0..band.y0 + band.rows).contains(&first_row));
        }
    };
    for corners in sorted {
        let vertices = corners.map(|i| &view.vertices[i as usize]);
        if (vertices[0].code | vertices[1].code | vertices[2].code) & outside::CLIPPED == 0 {
            draw(vertices, &mut band);
        } else {
            let no_varyings = |_| &[0.0; VARYINGS];
            let indices = corners.map(|i| i as usize);
            view.clip(scene.world, indices, no_varyings, |vertices, _| draw(vertices, &mut band));
        }
    }
    if let Some(quads) = quads {
        nearest_of_quads(band.depth, quads, band.stride);
    }
    triangles
}

/// A triangle as the depth pass draws it: the texels it covers and the plane of its depth,
/// pushed back by the slope-scaled bias.
struct DepthTriangle {
    edges: Edges,
    plane: Plane<f32>,
}

impl DepthTriangle {
    /// The projected triangle `vertices` on the map `viewport`; `None` when it is culled or
    /// covers no texel centre.
    #[inline(always)]
    fn new(vertices: [&ScreenVertex; 3], viewport: Viewport) -> Option<Self> {
        let p = vertices.map(|v| (i64::from(v.x), i64::from(v.y)));
        let area = edge(p[0], p[1], p[2]);
        let z = vertices.map(|v| v.z);
        // The two orders there are, written out rather than indexed: the corners stay in
        // registers.
        let (p, depths) = match positive_order(area, viewport)? {
            [0, 1, 2] => (p, z),
            [0, 2, 1] => ([p[0], p[2], p[1]], [z[0], z[2], z[1]]),
            order => (order.map(|k| p[k]), order.map(|k| z[k])),
        };
        let edges = Edges::new(p, viewport)?;
        let mut plane = Plane::through(depths, &Weights::new(&edges, area));
        // The slopes are finite.
        plane.origin += CONSTANT_BIAS + SLOPE_BIAS * greater(plane.dx.abs(), plane.dy.abs());
        Some(Self { edges, plane })
    }
}

/// Draws the depths of `triangle` into the rows of `band` it covers.
///
/// Taken by value: only the out-of-line call for wide triangles then needs it in memory, and
/// the common ones' setup stays in registers (a reference made every setup store it).
#[inline(always)]
fn fill_triangle(triangle: DepthTriangle, masks: &mut RowMasks, band: &mut DepthBand) {
    let bounds = triangle.edges.bounds;
    let rows = (bounds.min_y.max(band.y0), bounds.max_y.min(band.y0 + band.rows - 1));
    if rows.0 > rows.1 {
        return;
    }
    if triangle.edges.narrow && bounds.max_x - bounds.min_x < WINDOW as u32 {
        fill_column(&triangle, rows, band);
    } else {
        fill_wide(triangle, rows, masks, band);
    }
}

/// Each lane's offset in a window, in texels.
const WINDOW_LANES: [i32; WINDOW] = [0, 1, 2, 3, 4, 5, 6, 7];

/// Draws the rows `first..=last` of a triangle whose edge functions fit `i32` (see
/// [`Edges::narrow`]) and whose bounds are at most [`WINDOW`] texels wide (most of the map's
/// triangles), one window a row: the texels inside the triangle and its bounds keep the lesser
/// of their depth and the triangle's.
///
/// Edge functions and depths are stepped across lanes and down the rows by additions alone
/// (over a few rows, rounding stays far below the bias), and everything stays in registers;
/// a lane outside the triangle or its bounds gets an infinite depth, which changes nothing.
#[inline(always)]
fn fill_column(triangle: &DepthTriangle, (first, last): (u32, u32), band: &mut DepthBand) {
    let DepthTriangle { edges, plane } = triangle;
    let bounds = edges.bounds;
    let mut row_edges = window_edges(edges, first);
    let row_step = each_edge(|k| i32x8::splat(edges.step_y[k]));
    // The lanes past the bounds start, and stay, infinitely deep.
    let past_bounds = i32x8::new(WINDOW_LANES).simd_gt(i32x8::splat((bounds.max_x - bounds.min_x) as i32));
    let mut depth = beyond(past_bounds, window_depths(plane, bounds, first));
    let depth_step = f32x8::splat(plane.dy);
    let mut at = (first - band.y0) as usize * band.stride + band.first + bounds.min_x as usize;
    for _ in 0..last - first + 1 {
        fill_window(band, at, beyond(row_edges[0] | row_edges[1] | row_edges[2], depth));
        row_edges = each_edge(|k| row_edges[k] + row_step[k]);
        depth += depth_step;
        at += band.stride;
    }
}

/// Draws the rows `first..=last` of a triangle wider than a window, or whose edge functions
/// do not fit `i32` (both rare in a shadow map). Kept out of line, so that the loops of the
/// common triangles keep their values in registers.
#[inline(never)]
fn fill_wide(triangle: DepthTriangle, (first, last): (u32, u32), masks: &mut RowMasks, band: &mut DepthBand) {
    let DepthTriangle { edges, plane } = &triangle;
    let bounds = edges.bounds;
    if !edges.narrow {
        // Edge functions beyond `i32` (large triangles): the colour tiles' walk, one
        // tile-sized block at a time.
        for min_y in (first..=last).step_by(TILE_HEIGHT as usize) {
            for min_x in (bounds.min_x..=bounds.max_x).step_by(TILE_WIDTH as usize) {
                let block = PixelBounds {
                    min_x,
                    max_x: (min_x + TILE_WIDTH - 1).min(bounds.max_x),
                    min_y,
                    max_y: (min_y + TILE_HEIGHT - 1).min(last),
                };
                if let Some(walk) = Walk::new(edges, block) {
                    fill_runs(&walk, masks, bounds, plane, band);
                }
            }
        }
        return;
    }
    // Several windows a row, stepped across the row and down the rows by additions.
    let width = bounds.max_x - bounds.min_x + 1;
    let windows = width.div_ceil(WINDOW as u32);
    // Lanes of the last window past the bounds, with their sign bit set.
    let past_bounds = i32x8::new(WINDOW_LANES).simd_ge(i32x8::splat((width - (windows - 1) * WINDOW as u32) as i32));
    let mut row_edges = window_edges(edges, first);
    let row_step = each_edge(|k| i32x8::splat(edges.step_y[k]));
    let window_step = each_edge(|k| i32x8::splat(edges.step_x[k] * WINDOW as i32));
    let window_depth_step = f32x8::splat(plane.dx * WINDOW as f32);
    let mut at = (first - band.y0) as usize * band.stride + band.first + bounds.min_x as usize;
    for y in first..=last {
        let (mut lanes, mut depths) = (row_edges, window_depths(plane, bounds, y));
        for last in (1..=windows).map(|window| window == windows) {
            let outside = lanes[0] | lanes[1] | lanes[2] | if last { past_bounds } else { i32x8::ZERO };
            fill_window(band, at, beyond(outside, depths));
            at += WINDOW;
            lanes = each_edge(|k| lanes[k] + window_step[k]);
            depths += window_depth_step;
        }
        row_edges = each_edge(|k| row_edges[k] + row_step[k]);
        at += band.stride - windows as usize * WINDOW;
    }
}

/// The edge functions of the lanes of the first window of row `y` of a narrow triangle (the
/// walk stays inside the bounding box widened by the narrow margin, where every value fits
/// `i32`).
#[inline(always)]
fn window_edges(edges: &Edges, y: u32) -> [i32x8; 3] {
    let down = i64::from(y - edges.bounds.min_y);
    each_edge(|k| {
        let start = edges.start[k] + down * i64::from(edges.step_y[k]);
        i32x8::splat(start as i32) + lane_multiples(edges.step_x[k])
    })
}

/// The depths of `plane` at the lanes of the first window of row `y` of `bounds`.
#[inline(always)]
fn window_depths(plane: &Plane<f32>, bounds: PixelBounds, y: u32) -> f32x8 {
    let lanes = f32x8::new(WINDOW_LANES.map(|k| k as f32)) * plane.dx;
    f32x8::splat(plane.at(0.0, (y - bounds.min_y) as f32)) + lanes
}

/// `depths` where the lanes of `outside` have their sign bit clear, infinity on the others.
#[inline(always)]
fn beyond(outside: i32x8, depths: f32x8) -> f32x8 {
    depths + bytemuck::cast::<i32x8, f32x8>((outside >> 31) & i32x8::splat(f32::INFINITY.to_bits() as i32))
}

/// Keeps in each texel of the window from `at` the lesser of its depth and `depths`'.
#[inline(always)]
fn fill_window(band: &mut DepthBand, at: usize, depths: f32x8) {
    let texels: &mut [f32; WINDOW] = (&mut band.depth[at..at + WINDOW]).try_into().expect("a window");
    // No value is NaN: the plain minimum is exact.
    *texels = depths.fast_min(f32x8::new(*texels)).to_array();
}

/// `value(k)` for each of a triangle's three edges, written out so that it stays in the
/// caller's registers.
#[inline(always)]
fn each_edge<T>(value: impl Fn(usize) -> T) -> [T; 3] {
    [value(0), value(1), value(2)]
}

/// The depth-only pixel loop of the tile walk; `plane`, the biased depth, starts at the first
/// pixel of `bounds`.
#[inline(never)]
fn fill_runs(walk: &Walk, rows: &mut RowMasks, bounds: PixelBounds, plane: &Plane<f32>, band: &mut DepthBand) {
    let lane_steps = LANE_OFFSETS * plane.dx;
    walk.covered_runs(rows, |py, run, lanes| {
        let z = plane.at((run - bounds.min_x) as f32, (py - bounds.min_y) as f32);
        let z = lanes_of(Vec4::splat(z) + lane_steps);
        let at = (py - band.y0) as usize * band.stride + band.first + run as usize;
        // The border after each row holds the run's lanes past the row's end.
        let texels: &mut [f32; LANES] = (&mut band.depth[at..at + LANES]).try_into().unwrap();
        let held = f32x4::new(*texels);
        *texels = covered(lanes).bitselect(held.min(z), held).to_array();
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::screen::SUBPIXEL_STEPS;
    use proptest::prelude::*;

    /// The side of the test map, in texels.
    const SIZE: u32 = 96;

    /// The first row and the rows of the test band: triangles reach past both of its ends.
    const BAND: (u32, u32) = (32, 40);

    const MAP: Viewport = Viewport { width: SIZE, height: SIZE, cull_back_faces: false };

    /// The triangle with corners `corners` (sub-pixel units) at depths `z`, if it covers a
    /// texel centre.
    fn triangle(corners: [(i32, i32); 3], z: [f32; 3]) -> Option<DepthTriangle> {
        let vertices =
            [0, 1, 2].map(|k| ScreenVertex { code: 0, x: corners[k].0, y: corners[k].1, z: z[k], inv_w: 1.0 });
        DepthTriangle::new(vertices.each_ref(), MAP)
    }

    /// The stored rows of a band laid out as the shadow map's: texels at the far depth, one
    /// border texel before each row and [`WINDOW`] - 1 after, at infinity.
    fn empty_band() -> (usize, Vec<f32>) {
        let stride = SIZE as usize + WINDOW;
        let mut depth = vec![f32::INFINITY; stride * BAND.1 as usize];
        for row in depth.chunks_exact_mut(stride) {
            row[1..=SIZE as usize].fill(FAR_DEPTH);
        }
        (stride, depth)
    }

    /// The band after drawing the triangle `corners` (sub-pixel units) at depths `z`, walked
    /// as `narrow` says; `None` when it covers no texel centre or does not fit `i32`.
    fn draw(corners: [(i32, i32); 3], z: [f32; 3], narrow: bool) -> Option<Vec<f32>> {
        let DepthTriangle { edges, plane } = triangle(corners, z)?;
        if !edges.narrow {
            return None;
        }
        let (stride, mut depth) = empty_band();
        let mut band = DepthBand { y0: BAND.0, rows: BAND.1, width: SIZE, stride, first: 1, depth: &mut depth };
        let triangle = DepthTriangle { edges: Edges { narrow, ..edges }, plane };
        fill_triangle(triangle, &mut [0; TILE_HEIGHT as usize], &mut band);
        Some(depth)
    }

    /// Checks that drawing `corners` at depths `z` one window a row or several (as its width
    /// asks) draws the texels the tile walk draws (whose pixels the tile tests check against
    /// the edge functions' definition), with the same depths, and leaves the borders alone.
    fn windows_match_the_walk(corners: [(i32, i32); 3], z: [f32; 3]) -> Result<(), TestCaseError> {
        let Some(windows) = draw(corners, z, true) else { return Ok(()) };
        let walked = draw(corners, z, false).expect("the same triangle");
        let (stride, empty) = empty_band();
        for (i, ((&w, &t), &e)) in windows.iter().zip(&walked).zip(&empty).enumerate() {
            let (row, column) = (i / stride, i % stride);
            prop_assert_eq!(w == e, t == e, "texel {} of row {}: {} against {}", column, row, w, t);
            prop_assert!(w == t || (w - t).abs() <= 1e-5, "texel {} of row {}: {} against {}", column, row, w, t);
            if !(1..=SIZE as usize).contains(&column) {
                prop_assert_eq!(w, f32::INFINITY, "border texel {} of row {}", column, row);
            }
        }
        Ok(())
    }

    #[test]
    fn depths_are_pushed_back_by_the_slope_scaled_bias() {
        let steps = SUBPIXEL_STEPS as i32;
        // Depth grows by 0.01 per texel to the right, not at all downwards.
        let corners = [(0, 0), (0, 100 * steps), (100 * steps, 0)];
        let plane = triangle(corners, [0.2, 0.2, 1.2]).expect("a visible triangle").plane;
        assert!((plane.dx - 0.01).abs() < 1e-6 && plane.dy.abs() < 1e-6, "{plane:?}");
        // At the centre of texel (0, 0) the plane's depth is 0.2 + 0.005, plus the bias.
        let bias = CONSTANT_BIAS + SLOPE_BIAS * 0.01;
        assert!((plane.origin - (0.205 + bias)).abs() < 1e-6, "{}", plane.origin);
    }

    proptest! {
        /// Triangles up to a hundred texels wide: several windows a row.
        #[test]
        fn windows_draw_what_the_tile_walk_draws(
            corners in prop::array::uniform3((-4 * 256..100 * 256i32, 20 * 256..84 * 256i32)),
            z in prop::array::uniform3(0.0f32..1.0),
        ) {
            windows_match_the_walk(corners, z)?;
        }

        /// Triangles a few texels across, as most of a shadow map's: one window a row.
        #[test]
        fn one_window_a_row_draws_what_the_tile_walk_draws(
            origin in (-4 * 256..96 * 256i32, 20 * 256..84 * 256i32),
            offsets in prop::array::uniform3((0..9 * 256i32, 0..9 * 256i32)),
            z in prop::array::uniform3(0.0f32..1.0),
        ) {
            windows_match_the_walk(offsets.map(|(x, y)| (origin.0 + x, origin.1 + y)), z)?;
        }
    }
}
