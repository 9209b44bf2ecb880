//! [`Bodies::advance`]: many steps of the splitting integrator by a team of threads that
//! stays together for all of them, for interactions that offer [`TeamForces`].

use std::sync::Mutex;

use super::{kick_chunk, Bodies, Chunk, Configuration, Interaction, Motion, TeamForces, CHUNK};
use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
use crate::team::WorkShares;

/// The mutable state of all bodies as raw parts, for a team whose threads each take their
/// own chunks ([`Bodies::advance`]).
struct SharedBodies {
    n: usize,
    momentum: *mut Vec3,
    pi: *mut Vec3,
    position: *mut Vec3,
    rotation: *mut Mat3,
    force: *mut Vec3,
    torque: *mut Vec3,
}

// SAFETY: the threads of a team take disjoint chunks (each chunk of a phase is taken once,
// `WorkShares`), and read other chunks only between barriers that separate those reads
// from the writes (see `Bodies::team_steps`).
unsafe impl Send for SharedBodies {}
unsafe impl Sync for SharedBodies {}

impl SharedBodies {
    fn new(c: Chunk<'_>) -> Self {
        SharedBodies {
            n: c.momentum.len(),
            momentum: c.momentum.as_mut_ptr(),
            pi: c.pi.as_mut_ptr(),
            position: c.position.as_mut_ptr(),
            rotation: c.rotation.as_mut_ptr(),
            force: c.force.as_mut_ptr(),
            torque: c.torque.as_mut_ptr(),
        }
    }

    /// Chunk `k`'s state.
    ///
    /// # Safety
    /// No other reference to chunk `k`'s entries may live while the result does.
    #[allow(clippy::mut_from_ref)]
    unsafe fn chunk(&self, k: usize) -> (usize, Chunk<'_>) {
        let first = k * CHUNK;
        let len = CHUNK.min(self.n - first);
        // SAFETY: `first + len <= n`; exclusive by the caller's promise.
        unsafe {
            (
                first,
                Chunk {
                    momentum: std::slice::from_raw_parts_mut(self.momentum.add(first), len),
                    pi: std::slice::from_raw_parts_mut(self.pi.add(first), len),
                    position: std::slice::from_raw_parts_mut(self.position.add(first), len),
                    rotation: std::slice::from_raw_parts_mut(self.rotation.add(first), len),
                    force: std::slice::from_raw_parts_mut(self.force.add(first), len),
                    torque: std::slice::from_raw_parts_mut(self.torque.add(first), len),
                },
            )
        }
    }

    /// Every body's positions and attitudes.
    ///
    /// # Safety
    /// No body's position or attitude may be written while the result lives.
    unsafe fn configuration<'a>(&'a self, t: f64, mass: &'a [f64], free: &'a [bool]) -> Configuration<'a> {
        // SAFETY: `n` entries each; shared by the caller's promise.
        unsafe {
            Configuration {
                t,
                mass,
                free,
                position: std::slice::from_raw_parts(self.position, self.n),
                rotation: std::slice::from_raw_parts(self.rotation, self.n),
            }
        }
    }
}

/// How a team's run of steps ended.
enum TeamEnd {
    /// All steps taken.
    Done,
    /// A step's motion is done, but [`TeamForces::prepare`] found its evaluation stale.
    Stale,
    /// A body failed (the state is mid-step).
    Failed(Error),
}

impl Bodies {
    /// `steps` steps of [`Bodies::step`] with step `h`: the same bits, with less
    /// synchronisation. When the interaction offers [`TeamForces`]
    /// ([`Interaction::team_forces`]), the threads of the pool stay together for all the
    /// steps as a team, moving and evaluating chunks of bodies and partitions of pairs (each
    /// thread its own share first, then what is left of the others': a thread the machine
    /// holds up does not hold up the step), with two spin barriers per step (after the
    /// motion, after the pair pass) instead of four hand-offs through the pool. A step
    /// whose evaluation went stale (a neighbour list to rebuild) is brought up to date
    /// within the team ([`TeamForces::refresh`], by one thread while the others take
    /// the parallel work it hands out); if the interaction cannot, [`Interaction::compute`]
    /// completes the step and the team is formed again. Otherwise it takes ordinary steps.
    ///
    /// # Errors
    /// As [`Bodies::step`]; the system is then left mid-step.
    pub fn advance<I: Interaction + ?Sized>(&mut self, interaction: &I, h: f64, steps: u64) -> Result<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        let mut done = 0;
        while done < steps {
            if !self.forces_valid {
                self.evaluate(interaction);
            }
            let mut outcome = None;
            let (n, remaining) = (self.len(), steps - done);
            interaction.team_forces(n, &mut |team| outcome = Some(self.team_steps(team, h, remaining)));
            let Some((completed, end)) = outcome else {
                self.step(interaction, h)?;
                done += 1;
                continue;
            };
            done += completed;
            match end {
                TeamEnd::Done => {}
                TeamEnd::Stale => {
                    // As `step` ends: the time, the forces, the end impulse.
                    self.t += h;
                    self.evaluate(interaction);
                    self.kick(h);
                    done += 1;
                }
                TeamEnd::Failed(e) => {
                    self.forces_valid = false;
                    return Err(e);
                }
            }
        }
        Ok(())
    }

    /// Up to `steps` steps by a team (see [`Bodies::advance`]); the steps completed and how
    /// the team ended. The forces are valid at the start and, after [`TeamEnd::Done`], at
    /// the end.
    fn team_steps(&mut self, team: &dyn TeamForces, h: f64, steps: u64) -> (u64, TeamEnd) {
        use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
        let n = self.len();
        let chunks = n.div_ceil(CHUNK);
        let failure: Mutex<Option<(usize, Error)>> = Mutex::new(None);
        let (stale, failed, completed) = (AtomicBool::new(false), AtomicBool::new(false), AtomicU64::new(0));
        let refreshed = AtomicBool::new(false);
        let (motion, all) = self.split(h);
        let (free, mass) = (motion.free, motion.mass);
        let shared = SharedBodies::new(all);
        let items = team.pair_items();
        let parallel = chunks >= 2;
        let parts = crate::team::parts(parallel);
        // Chunks of bodies (the end of one step and the motion of the next, chunk by chunk)
        // and partitions of pairs, taken at run time (`WorkShares`); each share is given
        // again in the phase before the one that takes from it, which no part takes from.
        let (chunk_shares, pair_shares) = (WorkShares::full(parts, chunks), WorkShares::full(parts, items));
        // The motion of chunk `k` from `motion.t` (its start impulse, drift and rotation) and
        // its bodies' places for the evaluation at the step's end; whether they are within
        // the list's skin.
        let move_and_prepare = |motion: &Motion<'_>, k: usize| -> bool {
            // SAFETY: chunk `k` is taken by one part per phase; no other part touches it.
            let (first, mut c) = unsafe { shared.chunk(k) };
            if !motion.move_chunk(first, &mut c, &failure) {
                failed.store(true, Ordering::Relaxed);
            }
            let len = c.momentum.len();
            let run = Configuration {
                t: motion.t + h,
                mass: &mass[first..first + len],
                free: &free[first..first + len],
                position: c.position,
                rotation: c.rotation,
            };
            // SAFETY: the calling order of `TeamForces`.
            unsafe { team.prepare(first, run) }
        };
        // The forces of chunk `k` at `t_end` and its end impulse.
        let finish = |t_end: f64, k: usize| {
            // SAFETY: chunk `k` is taken by one part in this phase; other parts read none
            // of it now.
            let (first, c) = unsafe { shared.chunk(k) };
            let len = c.momentum.len();
            let (free, mass) = (&free[first..first + len], &mass[first..first + len]);
            let run = Configuration {
                t: t_end,
                mass,
                free,
                position: c.position,
                rotation: c.rotation,
            };
            // SAFETY: the calling order of `TeamForces`.
            unsafe { team.forces(first, run, c.force, c.torque) };
            kick_chunk(free, c.momentum, c.pi, c.force, c.torque, 0.5 * h);
        };
        crate::team::run(parallel, |part, barrier| {
            let mut motion = motion;
            // The first step's motion.
            let mut fresh = true;
            while let Some(k) = chunk_shares.next(part) {
                fresh &= move_and_prepare(&motion, k);
            }
            for step in 0..steps {
                let t_end = motion.t + h;
                if !fresh {
                    stale.store(true, Ordering::Relaxed);
                }
                barrier.wait();
                // Read by every part before the one that refreshes resets it.
                let was_stale = stale.load(Ordering::Relaxed);
                if failed.load(Ordering::Relaxed) {
                    if part.index() == 0 {
                        completed.store(step, Ordering::Relaxed);
                    }
                    return;
                }
                // SAFETY: nobody writes positions or attitudes until the next barrier.
                let config = unsafe { shared.configuration(t_end, mass, free) };
                if was_stale {
                    // Brought up to date by one part (the others help with the pool's
                    // parallel work while they wait), or the team stops.
                    if part.index() == 0 {
                        // SAFETY: the calling order of `TeamForces`.
                        refreshed.store(unsafe { team.refresh(config) }, Ordering::Relaxed);
                    }
                    barrier.wait_helping();
                    if !refreshed.load(Ordering::Relaxed) {
                        if part.index() == 0 {
                            completed.store(step, Ordering::Relaxed);
                        }
                        return;
                    }
                    if part.index() == 0 {
                        // Every part has read it; none sets it again before the next barrier.
                        stale.store(false, Ordering::Relaxed);
                    }
                }
                chunk_shares.reset(part, chunks);
                while let Some(p) = pair_shares.next(part) {
                    // SAFETY: the calling order of `TeamForces`; partition `p` is this part's.
                    unsafe { team.pairs(p..p + 1, config) };
                }
                barrier.wait();
                pair_shares.reset(part, items);
                // The step's end impulse, chunk by chunk, and the next step's motion of the
                // chunk (whose forces no other part reads: they read their own bodies'
                // sums and places).
                let next = step + 1 < steps;
                motion.t = t_end;
                fresh = true;
                while let Some(k) = chunk_shares.next(part) {
                    finish(t_end, k);
                    if next {
                        fresh &= move_and_prepare(&motion, k);
                    }
                }
            }
            if part.index() == 0 {
                completed.store(steps, Ordering::Relaxed);
            }
        });
        let completed = completed.load(Ordering::Relaxed);
        for _ in 0..completed {
            self.t += h;
        }
        let end = if let Some((_, e)) = failure.into_inner().expect("not poisoned") {
            TeamEnd::Failed(e)
        } else if stale.load(Ordering::Relaxed) {
            TeamEnd::Stale
        } else {
            TeamEnd::Done
        };
        (completed, end)
    }
}
