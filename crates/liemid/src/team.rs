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

/// The items of a phase (chunks of bodies, partitions of pairs) shared out among a team's
/// parts at run time: each part takes the items of its own share ([`Part::range`]) from the
/// front, and when they are done takes the items still left in the other parts' shares,
/// from their backs. On a machine whose cores are taken away for milliseconds at a time (a
/// virtual machine's vCPUs: on the 2-core machine one of two threads waited 2-27 ms at a
/// step's barrier in a tenth of the steps of the fluid at 10⁵ bodies), the other part
/// finishes the phase instead of waiting; on a quiet machine each part takes its own share,
/// as with a fixed split. Each item is computed the same way whoever takes it, so the
/// results do not depend on who took what.
pub(crate) struct WorkShares {
    /// Per part, the untaken items of its share `lo..hi`, as `lo << 32 | hi`.
    shares: Vec<PaddedShare>,
}

/// One part's untaken items, on cache lines of their own (two parts taking items do not
/// make a line bounce between their cores).
#[repr(align(128))]
#[derive(Default)]
struct PaddedShare(std::sync::atomic::AtomicU64);

impl WorkShares {
    /// Shares for the parts of a team of `parts`, each part's share of `len` items given.
    pub(crate) fn full(parts: usize, len: usize) -> Self {
        let shares = WorkShares {
            shares: (0..parts.max(1)).map(|_| PaddedShare::default()).collect(),
        };
        let count = shares.shares.len();
        for index in 0..count {
            shares.reset(Part { index, count }, len);
        }
        shares
    }

    /// Give `part` its share of `len` items again (by the part itself, in a phase in which
    /// no part takes from these shares; the next barrier publishes it).
    pub(crate) fn reset(&self, part: Part, len: usize) {
        let r = part.range(len);
        assert!(len <= u32::MAX as usize && part.index < self.shares.len());
        self.shares[part.index].0.store(
            ((r.start as u64) << 32) | r.end as u64,
            std::sync::atomic::Ordering::Relaxed,
        );
    }

    /// The next item for `part`: the first untaken one of its own share, else the last
    /// untaken one of another part's share (the next parts first), else `None` (every item
    /// of the phase is taken).
    pub(crate) fn next(&self, part: Part) -> Option<usize> {
        let count = self.shares.len();
        let own = part.index % count;
        if let Some(i) = self.take(own, true) {
            return Some(i);
        }
        (1..count).find_map(|k| self.take((own + k) % count, false))
    }

    fn take(&self, share: usize, front: bool) -> Option<usize> {
        use std::sync::atomic::Ordering;
        let cell = &self.shares[share].0;
        let mut v = cell.load(Ordering::Relaxed);
        loop {
            let (lo, hi) = (v >> 32, v & u64::from(u32::MAX));
            if lo >= hi {
                return None;
            }
            let (taken, rest) = if front {
                (lo, ((lo + 1) << 32) | hi)
            } else {
                (hi - 1, (lo << 32) | (hi - 1))
            };
            match cell.compare_exchange_weak(v, rest, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => return Some(taken as usize),
                Err(now) => v = now,
            }
        }
    }
}

/// The number of parts [`run`] gives a team (`parallel` as passed to it).
pub(crate) fn parts(parallel: bool) -> usize {
    #[cfg(feature = "parallel")]
    if parallel {
        return rayon::current_num_threads().max(1);
    }
    let _ = parallel;
    1
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item is taken once, each part's own share first and in order; a part held up
    /// leaves its items to the others.
    #[test]
    fn work_shares_hand_out_every_item_once() {
        let (parts, len) = (3, 40);
        for held_up in [None, Some(1)] {
            let shares = WorkShares::full(parts, len);
            let taken: Vec<std::sync::Mutex<Vec<usize>>> = (0..parts).map(|_| Default::default()).collect();
            std::thread::scope(|scope| {
                for index in 0..parts {
                    let (shares, taken) = (&shares, &taken);
                    scope.spawn(move || {
                        let part = Part { index, count: parts };
                        if held_up == Some(index) {
                            std::thread::sleep(std::time::Duration::from_millis(200));
                        }
                        while let Some(i) = shares.next(part) {
                            taken[index].lock().unwrap().push(i);
                        }
                    });
                }
            });
            let taken: Vec<Vec<usize>> = taken.into_iter().map(|t| t.into_inner().unwrap()).collect();
            let mut all: Vec<usize> = taken.iter().flatten().copied().collect();
            all.sort_unstable();
            assert_eq!(all, (0..len).collect::<Vec<_>>(), "each item once");
            for (index, t) in taken.iter().enumerate() {
                let own = Part { index, count: parts }.range(len);
                let mine: Vec<usize> = t.iter().copied().filter(|i| own.contains(i)).collect();
                assert!(mine.windows(2).all(|w| w[0] < w[1]), "own share from the front");
            }
            if let Some(h) = held_up {
                // 200 ms is ages for 40 items: the others took all of its share.
                assert!(taken[h].is_empty(), "the held-up part took {:?}", taken[h]);
            }
        }
        // Given again, the shares hand out the items again.
        let shares = WorkShares::full(2, 5);
        let part = Part { index: 0, count: 2 };
        assert_eq!(
            std::iter::from_fn(|| shares.next(part)).collect::<Vec<_>>(),
            [0, 1, 4, 3, 2]
        );
        shares.reset(part, 5);
        assert_eq!(std::iter::from_fn(|| shares.next(part)).collect::<Vec<_>>(), [0, 1]);
    }
}
