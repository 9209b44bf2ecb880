//! Ctrl-C in a long run. The bindings' loops run in Rust, most of them with the GIL
//! released, where Python cannot deliver a `KeyboardInterrupt`: its C handler only notes
//! the signal. [`Interrupt`] looks now and then whether one is pending (every few steps,
//! at most every [`INTERVAL`] of wall time) and returns the exception its Python handler
//! raised, which the run raises instead of a result. [`watched`] does the same for work
//! that runs on other threads (an ensemble on a thread pool, a study): the calling thread
//! looks while the work runs and asks it to stop.
//!
//! Signals are handled on the main thread only (`PyErr_CheckSignals` does nothing on
//! another), so the looking is always done on the thread that called the binding.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use pyo3::prelude::*;

/// Steps between two readings of the clock, for steps of a fraction of a microsecond (a
/// rigid body's): 1024 steps take about 0.2 ms there.
pub(crate) const STEPS: u64 = 1024;

/// The least wall time between two looks at the pending signals (each takes the GIL).
pub(crate) const INTERVAL: Duration = Duration::from_millis(50);

/// A counter of steps that looks for a pending signal every `every` steps, at most every
/// [`INTERVAL`].
pub(crate) struct Interrupt {
    every: u64,
    count: u64,
    last: Instant,
}

impl Interrupt {
    /// A look every [`STEPS`] steps.
    pub(crate) fn new() -> Self {
        Self::every(STEPS)
    }

    /// A look every `every` steps (at least 1): fewer for costly steps, 1 after a chunk
    /// of many steps.
    pub(crate) fn every(every: u64) -> Self {
        Interrupt {
            every: every.max(1),
            count: 0,
            last: Instant::now(),
        }
    }

    /// A look every [`STEPS`] / `work` steps, for steps that each cost about `work`
    /// rigid-body steps (a model of `work` bodies).
    pub(crate) fn for_work(work: usize) -> Self {
        Self::every(STEPS / (work.max(1) as u64))
    }

    /// Count one step.
    ///
    /// # Errors
    /// The exception of a pending signal (`KeyboardInterrupt` for Ctrl-C).
    #[inline]
    pub(crate) fn step(&mut self) -> PyResult<()> {
        self.count += 1;
        if self.count < self.every {
            return Ok(());
        }
        self.count = 0;
        self.look()
    }

    #[cold]
    fn look(&mut self) -> PyResult<()> {
        let now = Instant::now();
        if now.duration_since(self.last) < INTERVAL {
            return Ok(());
        }
        self.last = now;
        pending()
    }
}

/// The exception of a pending signal, taking the GIL for a moment (it may be held).
fn pending() -> PyResult<()> {
    Python::attach(|py| py.check_signals())
}

/// Run `work` on a helper thread with the GIL released while this thread looks for a
/// pending signal every [`INTERVAL`]; on one, the flag handed to `work` is set, and once
/// `work` has returned (it should soon: it reads the flag between runs or every few
/// steps) the signal's exception is returned instead of its result.
///
/// # Errors
/// The exception of a signal that arrived during the work.
pub(crate) fn watched<R, W>(py: Python<'_>, work: W) -> PyResult<R>
where
    R: Send,
    W: FnOnce(&AtomicBool) -> R + Send,
{
    let stop = AtomicBool::new(false);
    let (result, raised) = py.detach(|| {
        std::thread::scope(|scope| {
            let caller = std::thread::current();
            let stop = &stop;
            let handle = scope.spawn(move || {
                let r = work(stop);
                caller.unpark();
                r
            });
            let mut raised = None;
            while !handle.is_finished() {
                std::thread::park_timeout(INTERVAL);
                if raised.is_none() && !handle.is_finished() {
                    if let Err(e) = pending() {
                        stop.store(true, Ordering::Relaxed);
                        raised = Some(e);
                    }
                }
            }
            (handle.join(), raised)
        })
    });
    let result = result.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
    match raised {
        Some(e) => Err(e),
        None => Ok(result),
    }
}
