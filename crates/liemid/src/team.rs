//! A team of threads that stays together over many parallel phases, separated by spin
//! barriers: for work that is split in fixed parts and whose phases take tens of
//! microseconds, less than a sleeping thread of a pool needs to wake (on the 2-core
//! machine, with four hand-offs through rayon a step, the dipolar fluid's two-thread step
//! took half the one-thread step plus about 170 µs; a spin barrier takes 1-10 µs). Used by
//! the spin splitting's sweeps and by [`crate::many::Bodies::advance`].
//!
//! Each part's share is fixed by the part count and each element is computed the same way
//! whoever computes it, so the results of a team do not depend on its size.

/// A worker's share of a sweep: part `index` of `count`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Part {
    index: usize,
    count: usize,
}

impl Part {
    /// Which part this is (0 to the part count − 1).
    #[inline]
    pub(crate) fn index(&self) -> usize {
        self.index
    }

    /// The contiguous share of `len` items of this part (fixed by the part count alone).
    #[inline]
    pub(crate) fn range(&self, len: usize) -> std::ops::Range<usize> {
        (self.index * len / self.count)..((self.index + 1) * len / self.count)
    }
}

/// A barrier that spins (then yields) instead of sleeping: the sweeps it separates take
/// tens of microseconds, less than a sleeping thread needs to wake.
pub(crate) struct SpinBarrier {
    threads: usize,
    arrived: std::sync::atomic::AtomicUsize,
    generation: std::sync::atomic::AtomicUsize,
}

impl SpinBarrier {
    fn new(threads: usize) -> Self {
        SpinBarrier {
            threads,
            arrived: std::sync::atomic::AtomicUsize::new(0),
            generation: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    /// Wait until every thread has arrived; what each wrote before is visible to all after.
    pub(crate) fn wait(&self) {
        self.wait_and(false);
    }

    /// [`SpinBarrier::wait`], taking the pool's pending parallel work while waiting: for a
    /// phase in which one thread runs parallel iterators of the pool that the others would
    /// otherwise leave to it alone.
    pub(crate) fn wait_helping(&self) {
        self.wait_and(true);
    }

    fn wait_and(&self, help: bool) {
        use std::sync::atomic::Ordering;
        if self.threads == 1 {
            return;
        }
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.threads {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
        } else {
            let mut spins = 0u32;
            while self.generation.load(Ordering::Acquire) == generation {
                #[cfg(feature = "parallel")]
                if help && rayon::yield_now() == Some(rayon::Yield::Executed) {
                    continue;
                }
                #[cfg(not(feature = "parallel"))]
                let _ = help;
                if spins < 4096 {
                    std::hint::spin_loop();
                    spins += 1;
                } else {
                    std::thread::yield_now();
                }
            }
        }
    }
}

/// Run `work` once on every thread of the current pool (one thread when `parallel` is
/// `false` or without the `parallel` feature), each with its [`Part`] and a shared barrier
/// for the phases it separates.
pub(crate) fn run(parallel: bool, work: impl Fn(Part, &SpinBarrier) + Sync) {
    #[cfg(feature = "parallel")]
    {
        let threads = rayon::current_num_threads();
        if threads > 1 && parallel {
            let barrier = SpinBarrier::new(threads);
            rayon::broadcast(|ctx| {
                work(
                    Part {
                        index: ctx.index(),
                        count: ctx.num_threads(),
                    },
                    &barrier,
                )
            });
            return;
        }
    }
    let _ = parallel;
    work(Part { index: 0, count: 1 }, &SpinBarrier::new(1));
}
