//! Handing a pass's parts (the image's bands, the shadow map's strips) to the pool's threads.
//!
//! A part takes as long as the triangles and pixels it holds, and those differ widely over a
//! frame (sky against near ground), while a frame looks much like the last one. So each part's
//! time is kept, and the next frame hands the parts out from one shared counter, those that took
//! longest first: the last parts a thread takes are short ones, and the threads finish close
//! together. Handing out from a counter rather than spawning a task per part also keeps the
//! executor from giving one thread a batch of parts while the other runs out of work.

use crate::screen::{MAX_TARGET_SIZE, TILE_HEIGHT};

use bevy_tasks::TaskPool;
use std::cmp::Reverse;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The most parts a pass can have: an image of [`MAX_TARGET_SIZE`](crate::MAX_TARGET_SIZE) rows
/// in bands of [`TILE_HEIGHT`](crate::screen::TILE_HEIGHT).
pub(crate) const MAX_PARTS: usize = (MAX_TARGET_SIZE / TILE_HEIGHT) as usize;

/// The order a pass's parts are handed out in, and how long each took last time; kept between
/// frames so that a frame of steady size does not allocate.
#[derive(Debug, Default)]
pub(crate) struct Schedule {
    order: Vec<usize>,
    times: Vec<Duration>,
}

impl Schedule {
    /// Calls `work(index, part)` for each of `parts` on the threads of `pool` (the calling
    /// thread included), the parts that took longest last time first, and returns what all the
    /// calls add up to with `add`, starting from `R::default()`.
    ///
    /// # Panics
    /// If there are more than [`MAX_PARTS`] parts.
    pub fn run<T: Send, R: Default + Send + 'static>(
        &mut self,
        pool: &TaskPool,
        parts: impl Iterator<Item = T>,
        work: impl Fn(usize, T) -> R + Sync,
        add: impl Fn(&mut R, R) + Sync,
    ) -> R {
        let slots: [Mutex<Option<T>>; MAX_PARTS] = std::array::from_fn(|_| Mutex::new(None));
        let mut count = 0;
        for part in parts {
            *slots.get(count).expect("at most MAX_PARTS parts").lock().expect("an unused slot") = Some(part);
            count += 1;
        }
        self.times.resize(count, Duration::ZERO);
        self.order.clear();
        self.order.extend(0..count);
        let times = &mut self.times;
        self.order.sort_unstable_by_key(|&part| (Reverse(times[part]), part));
        let nanos: [AtomicU64; MAX_PARTS] = std::array::from_fn(|_| AtomicU64::new(0));
        let next = AtomicUsize::new(0);
        let (order, slots, nanos, next, work, add) = (&self.order, &slots, &nanos, &next, &work, &add);
        let totals = pool.scope(|scope| {
            // One taker per thread: the pool's and the calling one.
            for _ in 0..=pool.thread_num() {
                scope.spawn(async move {
                    let mut total = R::default();
                    while let Some(&index) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let part = slots[index].lock().expect("a part's slot").take().expect("each part is taken once");
                        let started = Instant::now();
                        add(&mut total, work(index, part));
                        let elapsed = started.elapsed().as_nanos().try_into().unwrap_or(u64::MAX);
                        nanos[index].store(elapsed, Ordering::Relaxed);
                    }
                    total
                });
            }
        });
        for (time, nanos) in times.iter_mut().zip(nanos) {
            *time = Duration::from_nanos(nanos.load(Ordering::Relaxed));
        }
        totals.into_iter().fold(R::default(), |mut sum, total| {
            add(&mut sum, total);
            sum
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy_tasks::TaskPoolBuilder;

    #[test]
    fn every_part_is_worked_once_and_the_longest_last_time_go_first() {
        let pool = TaskPoolBuilder::new().num_threads(2).build();
        let mut schedule = Schedule::default();
        // Each part records its index and value; part 3 takes at least two milliseconds.
        let work = |index: usize, value: u32| {
            if index == 3 {
                std::thread::sleep(Duration::from_millis(2));
            }
            vec![(index, value)]
        };
        let add = |total: &mut Vec<(usize, u32)>, more: Vec<(usize, u32)>| total.extend(more);
        let mut done = schedule.run(&pool, (0..6).map(|k| k * 10), work, add);
        done.sort_unstable();
        assert_eq!(done, (0..6).map(|k| (k, k as u32 * 10)).collect::<Vec<_>>());
        assert_eq!(schedule.order, [0, 1, 2, 3, 4, 5], "no times yet: in order");
        assert!(schedule.times[3] >= Duration::from_millis(2), "{:?}", schedule.times);

        schedule.times = [3, 1, 4, 1, 5, 9].map(Duration::from_millis).to_vec();
        let done = schedule.run(&pool, 0..6u32, work, add);
        assert_eq!(done.len(), 6);
        assert_eq!(schedule.order, [5, 4, 2, 0, 1, 3], "longest first, ties in order");
    }
}
