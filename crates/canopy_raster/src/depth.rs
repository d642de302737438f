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
use crate::framebuffer::FAR_DEPTH;
use crate::pipeline::{Instance, PixelBounds, ScreenVertex, Span, TILE_HEIGHT, TILE_WIDTH, View};
use crate::schedule::Schedule;
use crate::setup::{BiasedDepth, DEPTH, LANES, Plane, Surface, TriangleSetup};
use crate::shade::{VARYINGS, Varyings, lanes_of};
use crate::shadow::{QuadDepth, ShadowMap, nearest_of_quads};
use crate::sort::{Corners, Sorted};
use crate::tile::{RowMasks, Walk, covered, lane_multiples};
use bevy_math::{Vec3, Vec4};
use bevy_tasks::TaskPool;
use wide::{f32x4, f32x8, i32x8};

/// Map rows one strip task draws.
const STRIP_ROWS: u32 = 64;

/// Texels of a row one step of the depth pass covers.
pub(crate) const WINDOW: usize = 8;

/// The depth pass's buffers, kept between frames so that a scene of steady size does not
/// allocate.
#[derive(Debug, Default)]
pub(crate) struct DepthPass {
    /// The triangles reaching each strip.
    sorted: Sorted,
    schedule: Schedule,
}

/// What the depth pass draws: the frame's instances and their vertices as the light sees them.
#[derive(Clone, Copy)]
pub(crate) struct DepthScene<'a> {
    pub spans: &'a [Span],
    pub instances: &'a [Instance],
    /// World positions, for the triangles that need clipping.
    pub world: &'a [Vec3],
    /// The light's view: its projection, the projected vertices and the map as viewport.
    pub view: View<'a>,
}

impl DepthPass {
    /// Clears `map` and draws the depths of every triangle of `scene` into it, spreading the
    /// work over `pool`. Returns how many triangles were drawn (after clipping and culling).
    pub fn draw(&mut self, pool: &TaskPool, scene: DepthScene, map: &mut ShadowMap) -> usize {
        let size = map.size();
        self.sorted.sort::<STRIP_ROWS>(pool, scene.spans, scene.instances, scene.view);
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
        const NO_VARYINGS: Varyings = [0.0; VARYINGS];
        let surface = Surface { tolerance: &NO_VARYINGS, flat_diffuse: 0.0 };
        let varyings = [&NO_VARYINGS; 3];
        if let Some((setup, planes)) = TriangleSetup::new::<BiasedDepth>(vertices, varyings, view.viewport, surface) {
            fill_triangle(&setup, &planes[DEPTH / LANES], &mut masks, band);
            triangles += usize::from((band.y0..band.y0 + band.rows).contains(&setup.bounds.min_y));
        }
    };
    for corners in sorted {
        let indices = corners.map(|i| i as usize);
        let vertices = indices.map(|i| &view.vertices[i]);
        if (vertices[0].code | vertices[1].code | vertices[2].code) & outside::CLIPPED == 0 {
            draw(vertices, &mut band);
        } else {
            let no_varyings = |_| &[0.0; VARYINGS];
            view.clip(scene.world, indices, no_varyings, |vertices, _| draw(vertices, &mut band));
        }
    }
    if let Some(quads) = quads {
        nearest_of_quads(band.depth, quads, band.stride);
    }
    triangles
}

/// Draws the depths of `setup`, whose biased depth is the first lane of `plane`, into the rows
/// of `band` it covers.
fn fill_triangle(setup: &TriangleSetup, plane: &Plane, masks: &mut RowMasks, band: &mut DepthBand) {
    let bounds = setup.bounds;
    let rect =
        PixelBounds { min_y: bounds.min_y.max(band.y0), max_y: bounds.max_y.min(band.y0 + band.rows - 1), ..bounds };
    if rect.min_y > rect.max_y {
        return;
    }
    if setup.narrow {
        fill_windows(setup, plane, rect, band);
        return;
    }
    // Edge functions beyond `i32` (large triangles, rare in a shadow map): the colour tiles'
    // walk, one tile-sized block at a time.
    for min_y in (rect.min_y..=rect.max_y).step_by(TILE_HEIGHT as usize) {
        for min_x in (rect.min_x..=rect.max_x).step_by(TILE_WIDTH as usize) {
            let block = PixelBounds {
                min_x,
                max_x: (min_x + TILE_WIDTH - 1).min(rect.max_x),
                min_y,
                max_y: (min_y + TILE_HEIGHT - 1).min(rect.max_y),
            };
            if let Some(walk) = Walk::new(setup, block) {
                fill_runs(&walk, masks, bounds, plane, band);
            }
        }
    }
}

/// Each lane's offset in a window, in texels.
const WINDOW_LANES: [i32; WINDOW] = [0, 1, 2, 3, 4, 5, 6, 7];

/// Draws the rows `rect` of a triangle whose edge functions fit `i32` (see
/// [`TriangleSetup::narrow`]), [`WINDOW`] texels at a time: in each window the texels inside
/// the triangle and within the rect keep the lesser of their depth and the triangle's.
///
/// Edge functions and depths are stepped across lanes, windows and rows by additions alone;
/// a lane outside the triangle or the rect gets an infinite depth, which changes nothing.
fn fill_windows(setup: &TriangleSetup, plane: &Plane, rect: PixelBounds, band: &mut DepthBand) {
    let bounds = setup.bounds;
    let (x0, y0) = (rect.min_x - bounds.min_x, rect.min_y - bounds.min_y);
    let lanes = i32x8::new(WINDOW_LANES);
    // The walk stays inside the bounding box widened by the narrow margin, where every value
    // fits `i32`.
    let mut row_edges: [i32x8; 3] = std::array::from_fn(|k| {
        let first =
            setup.start[k] + i64::from(x0) * i64::from(setup.step_x[k]) + i64::from(y0) * i64::from(setup.step_y[k]);
        i32x8::splat(first as i32) + lane_multiples(setup.step_x[k])
    });
    let row_step = setup.step_y.map(i32x8::splat);
    let lane_depths = f32x8::new(WINDOW_LANES.map(|k| k as f32)) * plane.dx.x;
    let width = rect.max_x - rect.min_x + 1;
    let windows = width.div_ceil(WINDOW as u32);
    // Lanes of the last window past the rect, with their sign bit set.
    let past_rect = lanes.simd_ge(i32x8::splat((width - (windows - 1) * WINDOW as u32) as i32));
    let infinite = i32x8::splat(f32::INFINITY.to_bits() as i32);
    // A window's depths where the lanes of `outside` have their sign bit clear, infinity on
    // the others.
    let depths = |outside: i32x8, depths: f32x8| depths + bytemuck::cast::<i32x8, f32x8>((outside >> 31) & infinite);
    let row_depths = |y: u32| f32x8::splat(plane.at(x0 as f32, (y - bounds.min_y) as f32).x) + lane_depths;
    let mut at = (rect.min_y - band.y0) as usize * band.stride + band.first + rect.min_x as usize;
    let mut window = |at: usize, depths: f32x8| {
        let texels: &mut [f32; WINDOW] = (&mut band.depth[at..at + WINDOW]).try_into().unwrap();
        // No value is NaN: the plain minimum is exact.
        *texels = depths.fast_min(f32x8::new(*texels)).to_array();
    };
    if windows == 1 {
        // Most of the map's triangles: one window a row, everything kept in registers, depths
        // stepped down the rows too (over a few rows, rounding stays far below the bias).
        // The lanes past the rect start, and stay, infinitely deep.
        let (mut depth, depth_step) = (depths(past_rect, row_depths(rect.min_y)), f32x8::splat(plane.dy.x));
        for _ in rect.min_y..=rect.max_y {
            window(at, depths(row_edges[0] | row_edges[1] | row_edges[2], depth));
            row_edges = std::array::from_fn(|k| row_edges[k] + row_step[k]);
            depth += depth_step;
            at += band.stride;
        }
        return;
    }
    let window_step = setup.step_x.map(|s| i32x8::splat(s * WINDOW as i32));
    let window_depth_step = f32x8::splat(plane.dx.x * WINDOW as f32);
    for y in rect.min_y..=rect.max_y {
        let (mut edges, mut row_depths) = (row_edges, row_depths(y));
        for last in (1..=windows).map(|window| window == windows) {
            let outside = edges[0] | edges[1] | edges[2] | if last { past_rect } else { i32x8::ZERO };
            window(at, depths(outside, row_depths));
            at += WINDOW;
            edges = std::array::from_fn(|k| edges[k] + window_step[k]);
            row_depths += window_depth_step;
        }
        row_edges = std::array::from_fn(|k| row_edges[k] + row_step[k]);
        at += band.stride - windows as usize * WINDOW;
    }
}

/// The depth-only pixel loop of the tile walk; `plane` starts at the first pixel of `bounds`
/// and holds the biased depth in its first lane.
fn fill_runs(walk: &Walk, rows: &mut RowMasks, bounds: PixelBounds, plane: &Plane, band: &mut DepthBand) {
    let lane_steps = plane.lane_steps(0);
    walk.covered_runs(rows, |py, run, lanes| {
        let z = plane.at((run - bounds.min_x) as f32, (py - bounds.min_y) as f32).x;
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
    use crate::setup::Viewport;
    use proptest::prelude::*;

    /// The side of the test map, in texels.
    const SIZE: u32 = 96;

    /// The first row and the rows of the test band: triangles reach past both of its ends.
    const BAND: (u32, u32) = (32, 40);

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
    /// as `narrow` says.
    fn draw(corners: [(i32, i32); 3], z: [f32; 3], narrow: bool) -> Option<Vec<f32>> {
        let vertices =
            [0, 1, 2].map(|k| ScreenVertex { code: 0, x: corners[k].0, y: corners[k].1, z: z[k], inv_w: 1.0 });
        let viewport = Viewport { width: SIZE, height: SIZE, cull_back_faces: false };
        let surface = Surface { tolerance: &[0.0; VARYINGS], flat_diffuse: 0.0 };
        let (setup, planes) =
            TriangleSetup::new::<BiasedDepth>(vertices.each_ref(), [&[0.0; VARYINGS]; 3], viewport, surface)?;
        if !setup.narrow {
            return None;
        }
        let (stride, mut depth) = empty_band();
        let mut band = DepthBand { y0: BAND.0, rows: BAND.1, width: SIZE, stride, first: 1, depth: &mut depth };
        fill_triangle(
            &TriangleSetup { narrow, ..setup },
            &planes[DEPTH / LANES],
            &mut [0; TILE_HEIGHT as usize],
            &mut band,
        );
        Some(depth)
    }

    proptest! {
        /// The windows of a narrow triangle draw the texels the tile walk draws (whose pixels
        /// the tile tests check against the edge functions' definition), with the same depths,
        /// and leave the borders alone.
        #[test]
        fn windows_draw_what_the_tile_walk_draws(
            corners in prop::array::uniform3((-4 * 256..100 * 256i32, 20 * 256..84 * 256i32)),
            z in prop::array::uniform3(0.0f32..1.0),
        ) {
            let Some(windows) = draw(corners, z, true) else { return Ok(()) };
            let walked = draw(corners, z, false).expect("the same setup");
            let (stride, empty) = empty_band();
            for (i, ((&w, &t), &e)) in windows.iter().zip(&walked).zip(&empty).enumerate() {
                let (row, column) = (i / stride, i % stride);
                prop_assert_eq!(w == e, t == e, "texel {} of row {}: {} against {}", column, row, w, t);
                prop_assert!(w == t || (w - t).abs() <= 1e-5, "texel {} of row {}: {} against {}", column, row, w, t);
                if !(1..=SIZE as usize).contains(&column) {
                    prop_assert_eq!(w, f32::INFINITY, "border texel {} of row {}", column, row);
                }
            }
        }
    }
}
