//! Handing a pass's parts (vertex runs, triangle runs, the image's bands, the shadow map's
//! strips) to the pool's threads, and keeping those threads awake from one pass to the next.
//!
//! A part takes as long as the triangles and pixels it holds, and those differ widely over a
//! frame (sky against near ground), while a frame looks much like the last one. So each part's
//! time is kept, and the next frame hands the parts out from one shared counter, those that took
//! longest first: the last parts a thread takes are short ones, and the threads finish close
//! together. Handing out from a counter rather than spawning a task per part also keeps the
//! executor from giving one thread a batch of parts while the other runs out of work.

use bevy_tasks::TaskPool;
use bevy_tasks::futures_lite::future::yield_now;
use std::cmp::Reverse;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The most parts a pass can have: an image of [`MAX_TARGET_SIZE`](crate::MAX_TARGET_SIZE) rows
/// in bands of [`TILE_HEIGHT`](crate::pipeline::TILE_HEIGHT).
pub(crate) const MAX_PARTS: usize = (crate::MAX_TARGET_SIZE / crate::pipeline::TILE_HEIGHT) as usize;

/// The order a pass's parts are handed out in, and how long each took last time; kept between
/// frames so that a frame of steady size does not allocate.
#[derive(Debug, Default)]
pub(crate) struct Schedule {
    order: Vec<usize>,
    times: Vec<Duration>,
}

impl Schedule {
    /// Calls `work(index, part)` for each of `parts` on the frame's `threads` (the calling
    /// thread included), the parts that took longest last time first, and returns what all the
    /// calls add up to with `add`, starting from `R::default()`.
    ///
    /// # Panics
    /// If there are more than [`MAX_PARTS`] parts.
    pub fn run<T: Send, R: Default + Send + 'static>(
        &mut self,
        threads: &FrameThreads,
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
        let totals = threads.on_each(|| {
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
        for (time, nanos) in times.iter_mut().zip(nanos) {
            *time = Duration::from_nanos(nanos.load(Ordering::Relaxed));
        }
        totals.into_iter().fold(R::default(), |mut sum, total| {
            add(&mut sum, total);
            sum
        })
    }
}

/// Keeps the pool's threads from going to sleep between a frame's passes (see
/// [`FrameThreads`]); kept by the renderer from frame to frame.
#[derive(Debug, Default)]
pub(crate) struct KeepAwake {
    signals: Arc<Signals>,
    /// Frames started.
    started: u64,
}

/// What the waiting tasks of [`FrameThreads`] watch.
#[derive(Debug, Default)]
struct Signals {
    /// The frame being drawn, counted from 1; 0 between frames.
    frame: AtomicU64,
    /// Passes handed to the threads so far.
    passes: AtomicU64,
}

/// How long a waiting task spins before it lets its thread look for other work anyway: so that
/// a pool shared with other work (or threads busy elsewhere when a pass starts) cannot leave a
/// pass's tasks waiting on a spinning thread for long.
const LONGEST_SPIN: Duration = Duration::from_micros(100);

impl KeepAwake {
    /// The threads of `pool` for one frame, kept awake until it is dropped.
    pub fn start<'a>(&mut self, pool: &'a TaskPool) -> FrameThreads<'a> {
        self.started += 1;
        let frame = self.started;
        self.signals.frame.store(frame, Ordering::Relaxed);
        for _ in 0..pool.thread_num() {
            let signals = Arc::clone(&self.signals);
            let mut seen = signals.passes.load(Ordering::Acquire);
            pool.spawn(async move {
                let mut spinning = Instant::now();
                while signals.frame.load(Ordering::Relaxed) == frame {
                    let passes = signals.passes.load(Ordering::Acquire);
                    if passes != seen || spinning.elapsed() > LONGEST_SPIN {
                        // Back in the pool's queue, behind the pass's tasks.
                        seen = passes;
                        yield_now().await;
                        spinning = Instant::now();
                    } else {
                        std::hint::spin_loop();
                    }
                }
            })
            .detach();
        }
        FrameThreads { pool, signals: Arc::clone(&self.signals) }
    }
}

/// A task pool's threads for the length of one frame.
///
/// A pool thread with nothing to run sleeps, and waking it takes tens of microseconds (20 to 36
/// here, far more on a loaded virtual machine, whose idle cores the host takes back), paid by
/// every pass, whose tasks the woken thread then joins late. So while a frame is drawn, each of
/// the pool's threads holds a task that waits for the next pass by spinning, then yields to the
/// pass's tasks ([`FrameThreads::on_each`] signals it); between frames the threads sleep. A
/// waiting task yields only when a pass starts (or after [`LONGEST_SPIN`]): a task yielding all
/// the time would keep the pool's queue, and its allocations, busy.
pub(crate) struct FrameThreads<'a> {
    pool: &'a TaskPool,
    signals: Arc<Signals>,
}

impl FrameThreads<'_> {
    /// The pool's threads, not counting the calling one.
    pub fn pool_threads(&self) -> usize {
        self.pool.thread_num()
    }

    /// Runs `taker` once on each of the pool's threads and once on the calling thread, at
    /// once, and returns what each returned: a pass whose `taker` takes its parts from a
    /// shared counter until none is left.
    ///
    /// The calling thread runs only its own taker (it does not pick up the pool's tasks, nor
    /// their waiting ones).
    pub fn on_each<R: Send + 'static>(&self, taker: impl Fn() -> R + Sync) -> Vec<R> {
        let taker = &taker;
        self.pool.scope_with_executor(false, None, |scope| {
            for _ in 0..self.pool.thread_num() {
                scope.spawn(async move { taker() });
            }
            // Once the pool's takers are queued, the waiting tasks yield to them.
            self.signals.passes.fetch_add(1, Ordering::Release);
            scope.spawn_on_scope(async move { taker() });
        })
    }
}

impl Drop for FrameThreads<'_> {
    fn drop(&mut self) {
        self.signals.frame.store(0, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy_tasks::TaskPoolBuilder;

    #[test]
    fn every_part_is_worked_once_and_the_longest_last_time_go_first() {
        let pool = TaskPoolBuilder::new().num_threads(2).build();
        let threads = KeepAwake::default().start(&pool);
        let mut schedule = Schedule::default();
        // Each part records its index and value; part 3 takes at least two milliseconds.
        let work = |index: usize, value: u32| {
            if index == 3 {
                std::thread::sleep(Duration::from_millis(2));
            }
            vec![(index, value)]
        };
        let add = |total: &mut Vec<(usize, u32)>, more: Vec<(usize, u32)>| total.extend(more);
        let mut done = schedule.run(&threads, (0..6).map(|k| k * 10), work, add);
        done.sort_unstable();
        assert_eq!(done, (0..6).map(|k| (k, k as u32 * 10)).collect::<Vec<_>>());
        assert_eq!(schedule.order, [0, 1, 2, 3, 4, 5], "no times yet: in order");
        assert!(schedule.times[3] >= Duration::from_millis(2), "{:?}", schedule.times);

        schedule.times = [3, 1, 4, 1, 5, 9].map(Duration::from_millis).to_vec();
        let done = schedule.run(&threads, 0..6u32, work, add);
        assert_eq!(done.len(), 6);
        assert_eq!(schedule.order, [5, 4, 2, 0, 1, 3], "longest first, ties in order");
    }

    /// Whether the tasks holding `keep`'s signals (besides `keep` and `held` frames) end within
    /// `wait`.
    fn tasks_end(keep: &KeepAwake, held: usize, wait: Duration) -> bool {
        let started = Instant::now();
        while Arc::strong_count(&keep.signals) > 1 + held {
            if started.elapsed() > wait {
                return false;
            }
            std::thread::yield_now();
        }
        true
    }

    #[test]
    fn each_thread_takes_one_taker_and_the_waiting_tasks_last_as_long_as_their_frame() {
        let pool = TaskPoolBuilder::new().num_threads(1).build();
        let mut keep = KeepAwake::default();
        let threads = keep.start(&pool);
        // A pass runs one taker on the pool's thread and one on the calling thread, however
        // many passes follow one another.
        for _ in 0..200 {
            let ran_on = threads.on_each(|| std::thread::current().id());
            assert_eq!(ran_on.len(), 2);
            assert_ne!(ran_on[0], ran_on[1]);
            assert!(ran_on.contains(&std::thread::current().id()));
        }
        let (short, long) = (Duration::from_millis(100), Duration::from_secs(10));
        assert!(!tasks_end(&keep, 1, short), "the waiting task ended during its frame");
        drop(threads);
        assert!(tasks_end(&keep, 0, long), "the waiting task outlived its frame");
        // A new frame's waiting task does not keep the last one's alive, nor does a pool
        // without threads get one.
        let first = keep.start(&pool);
        let second = keep.start(&pool);
        assert!(tasks_end(&keep, 3, long), "the first frame's waiting task outlived it");
        drop((first, second));
        assert!(tasks_end(&keep, 0, long));
        let alone = TaskPoolBuilder::new().num_threads(0).build();
        let threads = keep.start(&alone);
        assert_eq!(Arc::strong_count(&keep.signals), 2, "only the frame holds the signals");
        assert_eq!(threads.on_each(|| 7), [7], "the calling thread alone");
    }

    #[test]
    fn passes_finish_when_the_pool_has_more_threads_than_work() {
        // Three pool threads, each waiting task spinning, and passes whose takers find nothing
        // left to take at once: every pass still ends.
        let pool = TaskPoolBuilder::new().num_threads(3).build();
        let threads = KeepAwake::default().start(&pool);
        let next = AtomicUsize::new(0);
        for pass in 0..100 {
            let taken = threads.on_each(|| usize::from(next.fetch_add(1, Ordering::Relaxed) == pass * 4));
            assert_eq!(taken.len(), 4);
            assert_eq!(taken.iter().sum::<usize>(), 1);
        }
    }
}
