//! Sorting triangles into horizontal strips of a target, for passes that then set each strip's
//! triangles up and draw them at once.
//!
//! Sorting reads only the projected vertices: it drops triangles wholly outside the view
//! volume or between two rows of pixel centres, and lists each other triangle, as its three
//! vertex indices, in every strip its pixel rows reach. Runs of triangles are sorted in
//! parallel, and a strip reads the runs in order, so it sees its triangles in draw order.
//! Keeping indices instead of set-up triangles keeps the data between the two stages small: a
//! strip sets its triangles up right before drawing them, while they are in the core's cache.

use crate::clip::outside;
use crate::frame::{Instance, Span, View, instance_runs, runs, triangle_count};
use crate::screen::{pixel_span, range_of};
use bevy_tasks::TaskPool;
use std::ops::Range;

/// The vertex indices of one triangle, in the frame's global numbering.
pub(crate) type Corners = [u32; 3];

/// Contiguous runs of triangles sorted in parallel, per worker thread.
const RUNS_PER_THREAD: usize = 4;

/// The triangles reaching each strip, kept between frames so that a scene of steady size does
/// not allocate.
#[derive(Debug, Default)]
pub(crate) struct Sorted {
    /// Per run of triangles, per strip, the triangles reaching the strip, in order.
    runs: Vec<Vec<Vec<Corners>>>,
}

impl Sorted {
    /// Sorts every triangle of `instances` (whose vertex and triangle numbering `spans` give)
    /// into strips of `ROWS` rows of `first`'s view and, when there is a `second`, into strips
    /// of `SECOND_ROWS` rows of its view, spreading the work over `pool`: one pass over the
    /// triangles, and one wait for the pool's threads, serves both (the image and the shadow
    /// map).
    ///
    /// The rows are constants so that finding a row's strip is a shift, not a division per
    /// triangle.
    pub fn sort_for<const ROWS: u32, const SECOND_ROWS: u32>(
        pool: &TaskPool,
        spans: &[Span],
        instances: &[Instance],
        (first, first_view): (&mut Self, View),
        second: Option<(&mut Self, View)>,
    ) {
        let parts = pool.thread_num().max(1) * RUNS_PER_THREAD;
        first.prepare(parts, first_view.viewport.height.div_ceil(ROWS) as usize);
        pool.scope(|scope| {
            let ranges = runs(triangle_count(spans, instances), parts).zip(first.runs.iter_mut());
            // Without a second view, a loop of its own: testing for one at every triangle made
            // unshadowed frames about 1% slower.
            match second {
                None => {
                    for (range, sorted) in ranges {
                        scope.spawn(async move {
                            each_triangle(spans, instances, range, |corners| sort::<ROWS>(corners, first_view, sorted));
                        });
                    }
                }
                Some((second, second_view)) => {
                    second.prepare(parts, second_view.viewport.height.div_ceil(SECOND_ROWS) as usize);
                    for ((range, sorted), second_sorted) in ranges.zip(second.runs.iter_mut()) {
                        scope.spawn(async move {
                            each_triangle(spans, instances, range, |corners| {
                                sort::<ROWS>(corners, first_view, sorted);
                                sort::<SECOND_ROWS>(corners, second_view, second_sorted);
                            });
                        });
                    }
                }
            }
        });
    }

    /// Makes room for `parts` runs of `strips` empty strips each, keeping what was allocated.
    fn prepare(&mut self, parts: usize, strips: usize) {
        self.runs.resize_with(parts, Vec::new);
        for run in &mut self.runs {
            run.resize_with(strips, Vec::new);
            run.iter_mut().for_each(Vec::clear);
        }
    }

    /// The triangles reaching strip `index`, in draw order.
    pub fn strip(&self, index: usize) -> impl Iterator<Item = &Corners> {
        self.runs.iter().flat_map(move |run| &run[index])
    }
}

/// Calls `visit` with the corners (global vertex indices) of each of the global triangles
/// `range` of `instances`, in order.
#[inline(always)]
fn each_triangle(spans: &[Span], instances: &[Instance], range: Range<usize>, mut visit: impl FnMut(Corners)) {
    for run in instance_runs(spans, instances, range) {
        for triangle in &run.instance.mesh.triangles[run.triangles] {
            visit(triangle.map(|i| (run.span.first_vertex + i as usize) as u32));
        }
    }
}

/// Adds the triangle `corners` to the strips of `ROWS` rows its pixel rows reach. A triangle
/// that needs clipping goes to every strip, which clips it again.
fn sort<const ROWS: u32>(corners: Corners, view: View, sorted: &mut [Vec<Corners>]) {
    let [a, b, c] = corners.map(|i| &view.vertices[i as usize]);
    if a.code & b.code & c.code & outside::VIEW != 0 {
        return;
    }
    let strips = if (a.code | b.code | c.code) & outside::CLIPPED != 0 {
        0..sorted.len()
    } else {
        // Columns are left to the setup, which drops a triangle covering none.
        let Some((first, last)) = pixel_span(range_of([a, b, c].map(|v| i64::from(v.y))), view.viewport.height) else {
            return;
        };
        (first / ROWS) as usize..(last / ROWS) as usize + 1
    };
    for strip in &mut sorted[strips] {
        strip.push(corners);
    }
}
