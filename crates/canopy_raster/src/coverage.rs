//! Coverage: a triangle's walk over the pixels of a tile, row by row, with its exact edge
//! functions, [`MASK_PIXELS`] pixels at a time, handing runs of [`LANES`] covered pixels to
//! the pass that draws them. The colour pass and the shadow map's depth pass share it.

use crate::lanes::{LANES, MASK_PIXELS};
use crate::screen::{PixelBounds, TILE_HEIGHT, TILE_WIDTH};
use crate::setup::Edges;
use std::ops::{Add, Mul};
use wide::{f32x4, i32x4, i32x8, u32x4};

/// The coverage bits of one run.
const RUN_MASK: u64 = (1 << LANES) - 1;

/// Which pixels of each row of a walk are covered: bit `k` of word `r` for pixel `k` of the
/// walk's row `r`. Kept by the band and reused by every walk, so that it is not cleared for each.
pub(crate) type RowMasks = [u64; TILE_HEIGHT as usize];

/// A triangle's walk over the pixels of one tile.
pub(crate) struct Walk {
    /// The pixels to visit: the triangle's bounds within the tile.
    rect: PixelBounds,
    /// Edge functions at the centre of the rect's first pixel, top-left bias included.
    start: [i64; 3],
    step_x: [i32; 3],
    step_y: [i32; 3],
    /// Whether the edge functions fit `i32` (see [`Edges::narrow`]).
    narrow: bool,
}

impl Walk {
    /// The walk of a triangle's `edges` over `tile`; `None` when its bounds miss the tile.
    #[inline(always)]
    pub(crate) fn new(edges: &Edges, tile: PixelBounds) -> Option<Self> {
        let bounds = edges.bounds;
        let rect = PixelBounds {
            min_x: bounds.min_x.max(tile.min_x),
            max_x: bounds.max_x.min(tile.max_x),
            min_y: bounds.min_y.max(tile.min_y),
            max_y: bounds.max_y.min(tile.max_y),
        };
        if rect.min_x > rect.max_x || rect.min_y > rect.max_y {
            return None;
        }
        let (dx, dy) = (i64::from(rect.min_x - bounds.min_x), i64::from(rect.min_y - bounds.min_y));
        let start =
            std::array::from_fn(|k| edges.start[k] + dx * i64::from(edges.step_x[k]) + dy * i64::from(edges.step_y[k]));
        Some(Self { rect, start, step_x: edges.step_x, step_y: edges.step_y, narrow: edges.narrow })
    }

    /// Walks each row's covered span in runs of up to [`LANES`] pixels, calling
    /// `visit(y, x, lanes)` for each: `x` is the run's first pixel and bit `k` of `lanes` is
    /// set when pixel `x + k` is covered. Returns the pixels covered.
    #[inline(always)]
    pub(crate) fn covered_runs(&self, rows: &mut RowMasks, visit: impl FnMut(u32, u32, u32)) -> u64 {
        self.visit_runs(rows, &mut EachRun { visit, y: 0, x: 0 })
    }

    /// Walks each row's covered span as [`Walk::covered_runs`] does, telling `visitor` where
    /// each row's runs start and then each run's covered pixels. Returns the pixels covered.
    #[inline(always)]
    pub(crate) fn visit_runs(&self, rows: &mut RowMasks, visitor: &mut impl RunVisitor) -> u64 {
        let width = self.rect.max_x - self.rect.min_x + 1;
        if self.narrow && width <= MASK_PIXELS {
            // Most walks: a row's pixels fit one mask, found and visited at once.
            let steps = i32::mask_steps(self.step_x);
            let valid = u32::MAX >> (u32::BITS - width);
            let mut edges = self.start.map(|e| e as i32);
            let mut fragments = 0;
            // Pixel coordinates are far below `u32::MAX`: the exclusive range, cheaper to step
            // than an inclusive one, reaches the last row.
            for y in self.rect.min_y..self.rect.max_y + 1 {
                let coverage = i32::coverage(edges, &steps) & valid;
                edges = add(edges, self.step_y);
                fragments += self.visit_row(y, coverage.into(), visitor);
            }
            return fragments;
        }
        if self.narrow {
            // The start fits too: it is one of the values the walk computes.
            self.coverage(self.start.map(|e| e as i32), self.step_x, self.step_y, rows);
        } else {
            self.coverage(self.start, self.step_x.map(i64::from), self.step_y.map(i64::from), rows);
        }
        let rows = (self.rect.min_y..self.rect.max_y + 1).zip(rows.iter());
        rows.map(|(y, &coverage)| self.visit_row(y, coverage, visitor)).sum()
    }

    /// Visits the runs of row `y`, whose covered pixels are the set bits of `coverage` (bit
    /// `k` for the rect's pixel `k`), as [`Walk::visit_runs`] does; returns how many pixels
    /// are covered.
    #[inline(always)]
    fn visit_row(&self, y: u32, coverage: u64, visitor: &mut impl RunVisitor) -> u64 {
        if coverage == 0 {
            return 0;
        }
        let first = coverage.trailing_zeros();
        let covered = u64::from(u64::BITS - coverage.leading_zeros() - first);
        visitor.row(y, self.rect.min_x + first);
        let mut rest = coverage >> first;
        while rest != 0 {
            visitor.run((rest & RUN_MASK) as u32);
            rest >>= LANES;
        }
        covered
    }

    /// Writes which pixels of the rect the triangle covers into the first rows of `rows`, with
    /// edge functions
    /// stepped in `E`: one bit per pixel (at most [`TILE_WIDTH`] of them) and a word per row
    /// (at most [`TILE_HEIGHT`]), found [`MASK_PIXELS`] pixels at a time without a branch per
    /// pixel.
    ///
    /// The triangle is convex, so each row's covered pixels run from its lowest set bit to its
    /// highest.
    #[inline(always)]
    fn coverage<E: EdgeValue>(&self, start: [E; 3], step_x: [E; 3], step_y: [E; 3], rows: &mut RowMasks) {
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

/// What a [`Walk`] hands its covered pixels to, row by row.
pub(crate) trait RunVisitor {
    /// The runs that follow, up to the next call, are in row `y`: the first starts at pixel
    /// `x`, each of the others [`LANES`] pixels after the one before.
    fn row(&mut self, y: u32, x: u32);
    /// The next run: bit `k` of `lanes` is set when its pixel `k` is covered.
    fn run(&mut self, lanes: u32);
}

/// A [`RunVisitor`] calling `visit(y, x, lanes)` with each run's row and first pixel.
struct EachRun<F> {
    visit: F,
    y: u32,
    x: u32,
}

impl<F: FnMut(u32, u32, u32)> RunVisitor for EachRun<F> {
    #[inline(always)]
    fn row(&mut self, y: u32, x: u32) {
        (self.y, self.x) = (y, x);
    }

    #[inline(always)]
    fn run(&mut self, lanes: u32) {
        (self.visit)(self.y, self.x, lanes);
        self.x += LANES as u32;
    }
}

/// An integer type edge functions are stepped in: `i32` for the triangles whose values fit
/// (see [`Edges::narrow`]), eight pixels to a SIMD coverage mask; `i64` for the rest.
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
        step_x.map(lane_multiples)
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

/// `k` times `step` in lane `k` of eight: an edge function's offsets from a group's first
/// pixel to each of its pixels.
#[inline(always)]
pub(crate) fn lane_multiples(step: i32) -> i32x8 {
    // Sums rather than products: SSE2 has no 32-bit lane multiplication.
    let first = i32x4::new([0, step, step + step, step + step + step]);
    bytemuck::cast([first, first + i32x4::splat(step << 2)])
}

/// Edge functions advanced by one step.
#[inline(always)]
fn add<E: EdgeValue>(edges: [E; 3], by: [E; 3]) -> [E; 3] {
    [edges[0] + by[0], edges[1] + by[1], edges[2] + by[2]]
}

/// The lane mask with lane `k` set when bit `k` of `lanes` is.
#[inline(always)]
pub(crate) fn covered(lanes: u32) -> f32x4 {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::screen::{SUBPIXEL_STEPS, TILE_WIDTH, edge, tile_rect};
    use crate::setup::{Viewport, is_top_left};
    use proptest::prelude::*;

    const TILE: PixelBounds = PixelBounds { min_x: 64, max_x: 127, min_y: 32, max_y: 63 };

    /// The edges of the triangle with corners at whole sub-pixel positions, if it covers a
    /// pixel centre.
    fn edges(corners: [(i32, i32); 3]) -> Option<Edges> {
        Edges::of_corners(corners, Viewport { width: 4096, height: 4096, cull_back_faces: false })
    }

    /// Whether the pixel centre `(x, y)` is inside the triangle `corners` under the top-left
    /// rule, straight from the definition.
    fn inside(corners: [(i32, i32); 3], (x, y): (u32, u32)) -> bool {
        let [a, b, c] = corners.map(|(x, y)| (i64::from(x), i64::from(y)));
        let [a, b, c] = if edge(a, b, c) < 0 { [a, c, b] } else { [a, b, c] };
        let centre =
            (i64::from(x) * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2, i64::from(y) * SUBPIXEL_STEPS + SUBPIXEL_STEPS / 2);
        [(b, c), (c, a), (a, b)].into_iter().all(|(from, to)| {
            let e = edge(from, to, centre);
            e > 0 || (e == 0 && is_top_left(from, to))
        })
    }

    /// Every run a walk visits: row, first pixel and coverage bits.
    fn runs(walk: &Walk) -> Vec<(u32, u32, u32)> {
        let mut runs = Vec::new();
        walk.covered_runs(&mut [0; TILE_HEIGHT as usize], |y, x, lanes| runs.push((y, x, lanes)));
        runs
    }

    proptest! {
        /// The `i32` walk visits exactly the pixels of the `i64` one.
        #[test]
        fn narrow_walks_match_wide_ones(
            corners in prop::array::uniform3((40 * 256..150 * 256i32, 20 * 256..80 * 256i32)),
        ) {
            let Some(narrow) = edges(corners).and_then(|edges| Walk::new(&edges, TILE)) else { return Ok(()) };
            prop_assume!(narrow.narrow);
            let wide = Walk { narrow: false, ..narrow };
            prop_assert_eq!(runs(&Walk { ..narrow }), runs(&wide));
        }

        /// Over the tiles a triangle's bounds meet, its walks visit exactly the pixels inside
        /// it, each once.
        #[test]
        fn walks_cover_exactly_the_inside_pixels(
            corners in prop::array::uniform3((-20 * 256..300 * 256i32, -20 * 256..150 * 256i32)),
        ) {
            let Some(edges) = edges(corners) else { return Ok(()) };
            let mut visited = Vec::new();
            for ty in 0..=150 / TILE_HEIGHT {
                for tx in 0..=300 / TILE_WIDTH {
                    let Some(walk) = Walk::new(&edges, tile_rect(tx, ty * TILE_HEIGHT, 4096, TILE_HEIGHT)) else { continue };
                    for (y, x, lanes) in runs(&walk) {
                        visited.extend((0..LANES as u32).filter(|k| lanes & 1 << k != 0).map(|k| (x + k, y)));
                    }
                }
            }
            visited.sort_unstable_by_key(|&(x, y)| (y, x));
            let bounds = edges.bounds;
            let expected: Vec<(u32, u32)> = (bounds.min_y..=bounds.max_y)
                .flat_map(|y| (bounds.min_x..=bounds.max_x).map(move |x| (x, y)))
                .filter(|&pixel| inside(corners, pixel))
                .collect();
            prop_assert_eq!(visited, expected);
        }
    }
}
