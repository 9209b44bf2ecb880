//! The fixed-step driver of the multibody step: the time loop every front end runs (the
//! last step lands on `t_end`), the extremes of the run, and an observer per step.
//!
//! Reference: docs/theory/multibody.md §5; `crate::rigid::driver::integrate` (the same
//! time stepping).

use crate::error::{Error, Result};

use super::method::StepReport;
use super::rattle::Rattle;
use super::state::MultibodyState;
use super::system::MultibodySystem;

/// What a run did: steps and the extremes over every step.
///
/// Reference: docs/theory/multibody.md §5.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MultibodyRun {
    /// Steps taken.
    pub steps: u64,
    /// Largest relative position violation over the steps.
    pub max_position_violation: f64,
    /// Largest relative velocity violation over the steps.
    pub max_velocity_violation: f64,
    /// Largest iteration count of one step.
    pub max_iterations: u32,
    /// Total position iterations.
    pub total_iterations: u64,
    /// Largest `|E − E₀| / |E₀|` (absolute when `E₀ = 0`).
    pub max_energy_error: f64,
}

impl Rattle {
    /// Integrate from `state.t` to `t_end` with step `h` (the last step lands on `t_end`),
    /// calling `observer(k, state, report)` after every step; returns the extremes.
    ///
    /// # Errors
    /// The step's errors, [`crate::rigid::driver::step_count`]'s, and
    /// [`Error::ObserverFailed`] when the observer returns an error.
    ///
    /// Reference: `crate::rigid::driver::integrate` (the same time stepping).
    pub fn integrate<O>(
        &mut self,
        system: &MultibodySystem,
        state: &mut MultibodyState,
        t_end: f64,
        h: f64,
        mut observer: O,
    ) -> Result<MultibodyRun>
    where
        O: FnMut(u64, &MultibodyState, &StepReport) -> core::result::Result<(), String>,
    {
        let t0 = state.t;
        let n = crate::rigid::driver::step_count(t0, t_end, h)?;
        let e0 = system.energy(state);
        let mut run = MultibodyRun::default();
        for k in 1..=n {
            let t_next = if k == n { t_end } else { t0 + k as f64 * h };
            let report = self.step(system, state, t_next - state.t)?;
            self.work.set_time(state, t_next);
            run.steps = k;
            run.max_position_violation = run.max_position_violation.max(report.position_violation);
            run.max_velocity_violation = run.max_velocity_violation.max(report.velocity_violation);
            run.max_iterations = run.max_iterations.max(report.iterations);
            run.total_iterations += u64::from(report.iterations);
            let de = (system.energy(state) - e0).abs();
            run.max_energy_error = run.max_energy_error.max(if e0 != 0.0 { de / e0.abs() } else { de });
            observer(k, state, &report).map_err(|reason| Error::ObserverFailed { t: state.t, reason })?;
        }
        Ok(run)
    }
}

/// A system and its integrator together: what the front ends (the `liemid multibody`
/// command, the Python package) and most tests step. The model stays apart from the
/// working memory ([`MultibodySystem`], [`Rattle`]); this only pairs them so that a call
/// cannot hand an integrator the wrong system.
///
/// Reference: docs/theory/multibody.md §3.
#[derive(Debug)]
pub struct Simulation {
    /// The model data, read by every step.
    pub system: MultibodySystem,
    /// The method and its working memory.
    pub integrator: Rattle,
}

impl Simulation {
    /// The system of `model` and its integrator by `method`.
    ///
    /// # Errors
    /// [`MultibodySystem::new`]'s errors.
    pub fn new(model: &super::Model, method: super::MultibodyMethod) -> Result<Self> {
        let system = MultibodySystem::new(model)?;
        let integrator = Rattle::new(&system, method);
        Ok(Simulation { system, integrator })
    }

    /// One step ([`Rattle::step`]).
    ///
    /// # Errors
    /// [`Rattle::step`]'s errors.
    pub fn step(&mut self, state: &mut MultibodyState, h: f64) -> Result<StepReport> {
        self.integrator.step(&self.system, state, h)
    }

    /// Integrate to `t_end` ([`Rattle::integrate`]).
    ///
    /// # Errors
    /// [`Rattle::integrate`]'s errors.
    pub fn integrate<O>(&mut self, state: &mut MultibodyState, t_end: f64, h: f64, observer: O) -> Result<MultibodyRun>
    where
        O: FnMut(u64, &MultibodyState, &StepReport) -> core::result::Result<(), String>,
    {
        self.integrator.integrate(&self.system, state, t_end, h, observer)
    }

    /// The constraint violations of `state` with the integrator's active limits
    /// ([`Rattle::constraint_violation`]).
    #[must_use]
    pub fn constraint_violation(&self, state: &MultibodyState) -> (f64, f64) {
        self.integrator.constraint_violation(&self.system, state)
    }

    /// [`Rattle::project_velocities`] on this system.
    ///
    /// # Errors
    /// [`Rattle::project_velocities`]'s errors.
    pub fn project_velocities(&mut self, state: &mut MultibodyState) -> Result<f64> {
        self.integrator.project_velocities(&self.system, state)
    }

    /// [`Rattle::project_positions`] on this system.
    ///
    /// # Errors
    /// [`Rattle::project_positions`]'s errors.
    pub fn project_positions(&mut self, state: &mut MultibodyState) -> Result<f64> {
        self.integrator.project_positions(&self.system, state)
    }

    /// [`Rattle::initial_state_on_loops`] on this system (`model` the one it was built
    /// from).
    ///
    /// # Errors
    /// [`Rattle::initial_state_on_loops`]'s errors.
    pub fn initial_state_on_loops(&mut self, model: &super::Model) -> Result<(MultibodyState, f64, f64)> {
        self.integrator.initial_state_on_loops(&self.system, model)
    }
}
