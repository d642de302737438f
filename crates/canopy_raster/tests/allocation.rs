//! Steady-state frames allocate nothing of the renderer's own: what the task pool allocates to
//! run its tasks is all there is, the same for a small and a large scene.

use bevy_tasks::TaskPoolBuilder;
use canopy_raster::benchmark_scene::{self as standard, CAMERAS};
use canopy_raster::{Framebuffer, Instance, RenderSettings, Renderer};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting allocations and bytes.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static BYTES: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded unchanged to the system allocator; the counters are atomics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        BYTES.fetch_add(layout.size(), Ordering::Relaxed);
        // SAFETY: the caller's contract for `alloc` is passed on as is.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Allocations and bytes of a steady-state frame of `instances` (the least over a few frames:
/// the task pool's own bookkeeping varies a little with timing).
fn steady_frame(instances: &[Instance], shadows: bool) -> (usize, usize) {
    let pool = TaskPoolBuilder::new().num_threads(2).build();
    let mut renderer = Renderer::default();
    let mut target = Framebuffer::new(320, 180);
    let frame = standard::frame(&CAMERAS[0], instances, RenderSettings { shadows, ..RenderSettings::default() });
    for _ in 0..3 {
        renderer.render(&mut target, &pool, &frame);
    }
    (0..5)
        .map(|_| {
            let (count, bytes) = (ALLOCATIONS.load(Ordering::SeqCst), BYTES.load(Ordering::SeqCst));
            renderer.render(&mut target, &pool, &frame);
            (ALLOCATIONS.load(Ordering::SeqCst) - count, BYTES.load(Ordering::SeqCst) - bytes)
        })
        .fold((usize::MAX, usize::MAX), |(c, b), (count, bytes)| (c.min(count), b.min(bytes)))
}

#[test]
fn steady_frames_allocate_only_for_the_task_pool() {
    let small = vec![standard::instance()];
    // Eight grids: eight times the vertices, triangles, bins and clipped triangles.
    let large: Vec<Instance> = (0..8).map(|_| standard::instance()).collect();
    for shadows in [false, true] {
        let (small_count, small_bytes) = steady_frame(&small, shadows);
        let (large_count, large_bytes) = steady_frame(&large, shadows);
        // Task bookkeeping only: about as many allocations and bytes for both scenes. One
        // allocation per triangle would be thousands more; a buffer sized by the large scene's
        // 258,064 triangles would be over 64 KiB more even at one byte per triangle.
        assert!(large_count <= small_count + 16, "shadows {shadows}: {small_count} vs {large_count} allocations");
        assert!(large_bytes <= small_bytes + 64 * 1024, "shadows {shadows}: {small_bytes} vs {large_bytes} bytes");
    }
}
