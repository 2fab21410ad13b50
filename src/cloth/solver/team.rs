//! A persistent parallel region: a few threads that run one closure
//! together and meet at barriers (Box2D v3's solver does the same).
//!
//! The adjust phase is a long chain of short colour batches: a 64 × 64
//! sheet projects about 40 batches of a few thousand constraints per sweep.
//! Handing each batch to a thread pool costs about as much as the batch
//! itself, so instead every thread of a [`Crew`] walks the whole chain at
//! once, claims blocks of each batch as it comes free ([`Crew::claim`]; a
//! fixed slice, [`Crew::share`], left one thread waiting for the other
//! where the cloth's far part turns more; thread 0 claims from the front,
//! the others from the back, so each keeps to its part of the cloth) and
//! waits at a [`Crew::barrier`] before the next. The constraints of a
//! colour share no free particle and each one's result does not depend on
//! the thread that projects it, so the result does not depend on the number
//! of threads or the split.
//!
//! The threads come from one private pool, created on first use, with a
//! thread per core. Only one region runs on it at a time (two regions
//! interleaved on the same threads could each wait at a barrier for a thread
//! the other holds): a solver stepping while another one's region runs (as
//! in `weft sweep --jobs`) waits for it. The crew's size follows rayon's
//! thread count where the solver is called (`RAYON_NUM_THREADS`, or a pool's
//! `install`), capped by the private pool.
//!
//! ```ignore
//! team::run(2, |crew| {
//!     for batch in &batches {
//!         while let Some(block) = crew.claim(batch.len(), 64) {
//!             for k in block { /* project batch[k] */ }
//!         }
//!         crew.barrier();
//!     }
//! });
//! ```

use std::ops::Range;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, OnceLock};

/// One thread's place in a parallel region.
pub(crate) struct Crew<'a> {
    index: usize,
    size: usize,
    barrier: &'a Barrier,
}

impl Crew<'_> {
    /// This thread's index, `0..size`; thread 0 is the one that times.
    pub(crate) fn index(&self) -> usize {
        self.index
    }

    /// This thread's share of `len` items: contiguous, in order, and fixed
    /// by `len` and the crew's size alone.
    #[inline]
    pub(crate) fn share(&self, len: usize) -> Range<usize> {
        share(len, self.index, self.size)
    }

    /// How many threads the crew has.
    pub(crate) fn size(&self) -> usize {
        self.size
    }

    /// The next block of up to `block` items of a batch of `len` items that
    /// no thread of the crew has taken yet, or `None` when all are taken.
    /// Threads take blocks as they come free, so one that meets cheap items
    /// does not wait at the next barrier for one that meets dear ones. Which
    /// thread handles an item must not change its result (true of a colour
    /// batch); every thread of the crew calls this until `None`, for one
    /// batch between two barriers.
    ///
    /// Thread 0 takes blocks from the front of the batch and the others
    /// from the back, until they meet: a colour batch is laid out in grid
    /// order, so each thread keeps to its own part of the cloth from one
    /// batch to the next (its particles stay in its core's cache) while the
    /// meeting point moves to balance the work.
    #[inline]
    pub(crate) fn claim(&self, len: usize, block: usize) -> Option<Range<usize>> {
        debug_assert!(len as u64 <= FRONT, "a batch of at most 2^32 - 1 items");
        let cursor = self.barrier.cursor();
        let mut taken = cursor.load(Ordering::Relaxed);
        loop {
            let (front, back) = ((taken & FRONT) as usize, (taken >> 32) as usize);
            let left = len.saturating_sub(front + back);
            if left == 0 {
                return None;
            }
            let size = block.max(1).min(left);
            let (range, more) = if self.index == 0 {
                (front..front + size, size as u64)
            } else {
                (len - back - size..len - back, (size as u64) << 32)
            };
            match cursor.compare_exchange_weak(
                taken,
                taken + more,
                Ordering::Relaxed,
                Ordering::Relaxed,
            ) {
                Ok(_) => return Some(range),
                Err(now) => taken = now,
            }
        }
    }

    /// Waits until every thread of the crew has arrived. Everything written
    /// before it is visible to every thread after it. (A crew of one passes
    /// at once, but still opens the next phase for [`Crew::claim`].)
    #[inline]
    pub(crate) fn barrier(&self) {
        self.barrier.wait(self.size);
    }
}

/// Item range of thread `index` of `size` over `len` items.
#[inline]
fn share(len: usize, index: usize, size: usize) -> Range<usize> {
    (len * index / size)..(len * (index + 1) / size)
}

/// Runs `work` on a crew of up to `threads` threads and returns what each
/// thread returned, in crew order.
pub(crate) fn run<T: Send>(threads: usize, work: impl Fn(&Crew) -> T + Sync) -> Vec<T> {
    let solo = |work: &dyn Fn(&Crew) -> T| {
        let barrier = Barrier::default();
        vec![work(&Crew {
            index: 0,
            size: 1,
            barrier: &barrier,
        })]
    };
    if threads <= 1 {
        return solo(&work);
    }
    let pool = pool();
    // A region that panicked poisons the lock but leaves nothing inconsistent.
    let _one_at_a_time = BUSY.lock().unwrap_or_else(|e| e.into_inner());
    let size = threads.min(pool.current_num_threads());
    let barrier = Barrier::default();
    pool.broadcast(|ctx| {
        (ctx.index() < size).then(|| {
            work(&Crew {
                index: ctx.index(),
                size,
                barrier: &barrier,
            })
        })
    })
    .into_iter()
    .flatten()
    .collect()
}

/// Runs `work` over `0..len` in blocks of `block` items on a crew of up
/// to `threads` threads, and returns each block's result in block order.
/// The blocks are handed out as threads come free (a share fixed in
/// advance leaves one thread idle while the other finishes a busy part),
/// and a block's result depends on its items alone, so what is returned
/// does not depend on which thread took which block.
pub(crate) fn run_blocks<T: Send>(
    threads: usize,
    len: usize,
    block: usize,
    work: impl Fn(Range<usize>) -> T + Sync,
) -> Vec<T> {
    let block = block.max(1);
    let next = AtomicUsize::new(0);
    let mut done: Vec<(usize, T)> = run(threads, |_| {
        let mut done = Vec::new();
        loop {
            let b = next.fetch_add(1, Ordering::Relaxed);
            let start = b.saturating_mul(block);
            if start >= len {
                return done;
            }
            done.push((b, work(start..len.min(start + block))));
        }
    })
    .into_iter()
    .flatten()
    .collect();
    done.sort_unstable_by_key(|&(b, _)| b);
    done.into_iter().map(|(_, t)| t).collect()
}

/// How many threads a region may use where it is called from.
pub(crate) fn available() -> usize {
    rayon::current_num_threads().min(pool().current_num_threads())
}

/// Held while a region runs on the pool.
static BUSY: Mutex<()> = Mutex::new(());

fn pool() -> &'static rayon::ThreadPool {
    static POOL: OnceLock<rayon::ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("weft-solver-{i}"))
            .build()
            .expect("the solver's thread pool")
    })
}

/// A reusable barrier: spins briefly (a batch takes microseconds), then
/// sleeps until the last thread arrives. A thread of the crew that is not
/// running (the machine is shared: the telemetry's writer threads, another
/// program) can keep the others waiting for a whole time slice; sleeping
/// gives their cores to it instead of burning them.
///
/// It also keeps the cursors of [`Crew::claim`], one for the phases between
/// barriers of even generation and one for odd: the thread that completes a
/// barrier zeroes the cursor of the phase it opens, last used two phases
/// ago by threads that have all arrived since.
#[derive(Default)]
struct Barrier {
    arrived: AtomicUsize,
    generation: AtomicUsize,
    /// Items taken from the front of the batch (low 32 bits) and from its
    /// back (high 32 bits).
    cursors: [AtomicU64; 2],
    /// Threads asleep or about to be, and where they sleep.
    sleepers: AtomicUsize,
    bed: Mutex<()>,
    wake: Condvar,
}

/// The bits of a claim cursor that count the items taken from the front.
const FRONT: u64 = u32::MAX as u64;

impl Barrier {
    /// The claim cursor of the current phase (the generation cannot change
    /// while a thread of the crew is between two barriers).
    #[inline]
    fn cursor(&self) -> &AtomicU64 {
        &self.cursors[self.generation.load(Ordering::Acquire) % 2]
    }

    fn wait(&self, size: usize) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == size {
            self.arrived.store(0, Ordering::Relaxed);
            self.cursors[(generation + 1) % 2].store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::SeqCst);
            // A sleeper counts itself before it last looks at the
            // generation, and this looks at the count after moving the
            // generation on (both sequentially consistent): either it saw
            // the new generation, or it is counted here and woken.
            if self.sleepers.load(Ordering::SeqCst) > 0 {
                let _bed = self.bed.lock().unwrap_or_else(|e| e.into_inner());
                self.wake.notify_all();
            }
            return;
        }
        for _ in 0..SPINS {
            if self.generation.load(Ordering::Acquire) != generation {
                return;
            }
            std::hint::spin_loop();
        }
        self.sleepers.fetch_add(1, Ordering::SeqCst);
        let mut bed = self.bed.lock().unwrap_or_else(|e| e.into_inner());
        while self.generation.load(Ordering::SeqCst) == generation {
            bed = self.wake.wait(bed).unwrap_or_else(|e| e.into_inner());
        }
        drop(bed);
        self.sleepers.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Spins before a waiting thread sleeps: a few microseconds, longer than
/// most waits at a barrier between colour batches. (Measured on the 64 × 64
/// bench sheet with full telemetry to a file: 1000 spins left the step
/// 6.6 ms off and 11.6 ms at full, 4000 spins 12.3, 16 000 spins 13.3; 100
/// spins slowed the step with telemetry off.)
const SPINS: u32 = 1000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_come_back_in_order_whatever_thread_took_them() {
        for threads in [1, 2, 3] {
            let blocks = run_blocks(threads, 103, 10, |r| r.collect::<Vec<_>>());
            assert_eq!(blocks.len(), 11);
            assert_eq!(blocks.concat(), (0..103).collect::<Vec<_>>());
        }
        assert!(run_blocks(2, 0, 10, |r| r.len()).is_empty());
    }

    #[test]
    fn shares_cover_every_item_once_in_order() {
        for len in [0, 1, 2, 7, 100, 1023] {
            for size in 1..=4 {
                let ranges: Vec<_> = (0..size).map(|i| share(len, i, size)).collect();
                assert_eq!(ranges[0].start, 0);
                assert_eq!(ranges[size - 1].end, len);
                for w in ranges.windows(2) {
                    assert_eq!(w[0].end, w[1].start);
                }
            }
        }
    }

    #[test]
    fn claims_hand_out_each_item_of_each_batch_once() {
        let lens = [37usize, 0, 8, 100, 3];
        for threads in [1, 2, 3] {
            let taken = run(threads, |crew| {
                let mut taken = Vec::new();
                for (batch, &len) in lens.iter().enumerate() {
                    while let Some(r) = crew.claim(len, 8) {
                        taken.extend(r.map(|k| (batch, k)));
                    }
                    crew.barrier();
                }
                taken
            });
            let mut all = taken.concat();
            all.sort_unstable();
            let expected: Vec<_> = lens
                .iter()
                .enumerate()
                .flat_map(|(b, &len)| (0..len).map(move |k| (b, k)))
                .collect();
            assert_eq!(all, expected, "{threads} threads");
        }
    }

    /// Runs `phases` phases on two threads, each adding one to a counter
    /// before a barrier and reading it after (thread 0 first waits `late`),
    /// and checks every thread read every thread's additions, no more.
    fn check_phases(phases: u64, late: std::time::Duration) {
        use std::sync::atomic::AtomicU64;
        let counter = AtomicU64::new(0);
        let seen = run(2, |crew| {
            let mut seen = Vec::new();
            for _ in 0..phases {
                if crew.index() == 0 {
                    std::thread::sleep(late);
                }
                counter.fetch_add(1, Ordering::Relaxed);
                crew.barrier();
                seen.push(counter.load(Ordering::Relaxed));
                crew.barrier();
            }
            seen
        });
        let size = seen.len() as u64;
        assert_eq!(size, available().min(2) as u64);
        for s in &seen {
            assert_eq!(s, &(1..=phases).map(|p| p * size).collect::<Vec<_>>());
        }
    }

    #[test]
    fn a_barrier_orders_phases() {
        check_phases(100, std::time::Duration::ZERO);
    }

    #[test]
    fn a_barrier_wakes_threads_that_fell_asleep_waiting() {
        // Thread 0 comes late: the others outlast their spins and sleep.
        check_phases(5, std::time::Duration::from_millis(5));
    }
}
