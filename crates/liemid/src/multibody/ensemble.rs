//! Many independent copies of a jointed system stepped together on threads: one
//! [`MultibodySystem`] shared by all, each copy its own [`Rattle`] and [`MultibodyState`], the copies are shared out in fixed
//! contiguous parts (one per thread), and each copy's steps are computed the same way
//! whichever thread takes it, so the states are bitwise identical for any thread count.
//! For parameter sweeps and ensembles of initial conditions (a thousand 10-link chains).
//!
//! Reference: as [`Rattle::step`] (RATTLE with EA's rotation; E. Hairer, C.
//! Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006, VII.1).

use super::{Model, MultibodyMethod, MultibodyState, MultibodySystem, Rattle};
use crate::error::{Error, Result};

/// Copies of jointed systems advanced together.
pub struct MultibodyEnsemble {
    system: MultibodySystem,
    integrators: Vec<Rattle>,
    states: Vec<MultibodyState>,
}

impl MultibodyEnsemble {
    /// `copies` of `model`, each started by `start(copy, &mut state)` from the model's
    /// initial state (e.g. a perturbed joint velocity); the velocities the starts leave are
    /// projected onto the joints' constraints.
    ///
    /// # Errors
    /// The model's errors ([`MultibodySystem::new`], [`Model::initial_state`]);
    /// [`Error::InvalidParameter`] for zero copies.
    pub fn new(
        model: &Model,
        method: MultibodyMethod,
        copies: usize,
        mut start: impl FnMut(usize, &mut MultibodyState),
    ) -> Result<Self> {
        if copies == 0 {
            return Err(Error::InvalidParameter {
                name: "copies",
                value: 0.0,
                reason: "an ensemble needs at least one copy",
            });
        }
        let initial = model.initial_state()?;
        let system = MultibodySystem::new(model)?;
        let mut integrators = Vec::with_capacity(copies);
        let mut states = Vec::with_capacity(copies);
        for k in 0..copies {
            let mut integrator = Rattle::new(&system, method);
            let mut state = initial.clone();
            start(k, &mut state);
            integrator.project_velocities(&system, &mut state)?;
            integrators.push(integrator);
            states.push(state);
        }
        Ok(MultibodyEnsemble {
            system,
            integrators,
            states,
        })
    }

    /// The copies' states.
    #[must_use]
    pub fn states(&self) -> &[MultibodyState] {
        &self.states
    }

    /// The system every copy steps (energy, momenta, joint readouts of a state).
    #[must_use]
    pub fn system(&self) -> &MultibodySystem {
        &self.system
    }

    /// Number of copies.
    #[must_use]
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Whether there are no copies (never, once built).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// Bodies over all copies.
    #[must_use]
    pub fn bodies(&self) -> usize {
        self.states.iter().map(MultibodyState::len).sum()
    }

    /// Advance every copy by `steps` steps of `h` on `threads` threads (at least 1). The
    /// result does not depend on `threads`. Allocates only the threads' handles per call.
    ///
    /// # Errors
    /// The first failing copy's step error (by copy index); the copies then stand where
    /// their own runs stopped.
    pub fn advance(&mut self, h: f64, steps: u64, threads: usize) -> Result<()> {
        let threads = threads.clamp(1, self.states.len());
        let len = self.states.len();
        let system = &self.system;
        let run = |integrators: &mut [Rattle], states: &mut [MultibodyState]| -> Result<()> {
            for (integrator, state) in integrators.iter_mut().zip(states.iter_mut()) {
                for _ in 0..steps {
                    integrator.step(system, state, h)?;
                }
            }
            Ok(())
        };
        if threads == 1 {
            return run(&mut self.integrators, &mut self.states);
        }
        let results: Vec<Result<()>> = std::thread::scope(|scope| {
            let mut integrators: &mut [Rattle] = &mut self.integrators;
            let mut states: &mut [MultibodyState] = &mut self.states;
            let mut handles = Vec::with_capacity(threads);
            let mut taken = 0;
            for part in 0..threads {
                let end = (part + 1) * len / threads;
                let (int_part, int_rest) = std::mem::take(&mut integrators).split_at_mut(end - taken);
                let (st_part, st_rest) = std::mem::take(&mut states).split_at_mut(end - taken);
                integrators = int_rest;
                states = st_rest;
                taken = end;
                handles.push(scope.spawn(move || run(int_part, st_part)));
            }
            handles
                .into_iter()
                .map(|h| {
                    h.join().unwrap_or(Err(Error::InvalidParameter {
                        name: "threads",
                        value: threads as f64,
                        reason: "a worker thread panicked",
                    }))
                })
                .collect()
        });
        results.into_iter().collect()
    }
}
