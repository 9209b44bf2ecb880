//! The driver: integrate a rigid body from `t0` to `t_end` with a fixed step, observing the
//! state every `k` steps and tracking the extremes of the diagnostics.

use crate::error::{Error, Result};
use crate::linalg::Vec3;
use crate::rigid::rotation::RotationIntegrator;
use crate::rigid::{Diagnostics, RigidBodySystem, RigidState};

/// The most steps a run may take: step `k` ends at `t0 + k h` with `k` converted to `f64`,
/// which is exact up to `2^53`.
pub const MAX_STEPS: u64 = 1 << 53;

/// The number of steps of size `h` that cover `[t0, t_end]`: `(t_end − t0)/h` when that
/// is an integer to a relative `1e-9`, otherwise the next integer up (the last step is
/// then shorter).
///
/// # Errors
/// `h` not finite and positive; `t_end` before `t0`; and [`Error::StepTooSmall`] when the
/// run would take more than [`MAX_STEPS`] steps, or when `h` is below the resolution of the
/// time at the end of the interval (`|t| + h` rounds to `|t|`, so steps would share their
/// time stamps). A mistyped exponent (`1e-30` for `1e-3`) is refused before the first step
/// instead of running for ever.
pub fn step_count(t0: f64, t_end: f64, h: f64) -> Result<u64> {
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::InvalidStep { h });
    }
    if !(t0.is_finite() && t_end.is_finite()) || t_end < t0 {
        return Err(Error::EndBeforeStart { t0, t_end });
    }
    if t_end == t0 {
        return Ok(0);
    }
    let too_small = |reason: String| Err(Error::StepTooSmall { h, t0, t_end, reason });
    let t_max = t0.abs().max(t_end.abs());
    if t_max + h == t_max {
        return too_small(format!("t + h rounds to t at |t| = {}", crate::error::Num(t_max)));
    }
    let ratio = (t_end - t0) / h;
    if ratio > MAX_STEPS as f64 {
        return too_small(format!(
            "the run would take {ratio:.3e} steps, more than 2^53 = {MAX_STEPS:.3e}",
            MAX_STEPS = MAX_STEPS as f64
        ));
    }
    let nearest = ratio.round();
    let n = if (ratio - nearest).abs() <= 1e-9 * nearest.max(1.0) {
        nearest
    } else {
        ratio.ceil()
    };
    Ok(n as u64)
}

/// The observed order of accuracy: the least-squares slope of `log error` against
/// `log h`. `None` with fewer than two points, different lengths, or equal steps.
#[must_use]
pub fn observed_order(steps: &[f64], errors: &[f64]) -> Option<f64> {
    if steps.len() < 2 || steps.len() != errors.len() {
        return None;
    }
    let n = steps.len() as f64;
    let (mx, my) = (
        steps.iter().map(|h| h.ln()).sum::<f64>() / n,
        errors.iter().map(|e| e.ln()).sum::<f64>() / n,
    );
    let sxy: f64 = steps
        .iter()
        .zip(errors)
        .map(|(h, e)| (h.ln() - mx) * (e.ln() - my))
        .sum();
    let sxx: f64 = steps.iter().map(|h| (h.ln() - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// What a run did: the final state and the extremes of the diagnostics over every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSummary {
    /// The state at `t_end`.
    pub state: RigidState,
    /// Steps taken.
    pub steps: u64,
    /// Diagnostics of the initial state.
    pub initial: Diagnostics,
    /// Diagnostics of the final state.
    pub last: Diagnostics,
    /// Largest `|E − E₀| / |E₀|` over the run (absolute when `E₀ = 0`).
    pub max_energy_error: f64,
    /// Largest `|π_i − π_i(t0)|` over the run, for each spatial component.
    pub max_spatial_momentum_change: Vec3,
    /// Largest `||Π| − |Π₀||` over the run.
    pub max_body_momentum_norm_change: f64,
    /// Largest orthogonality defect `‖RᵀR − I‖_F` over the run.
    pub max_orthogonality_defect: f64,
}

/// A fixed-step run from `t0` to `t_end` that can be advanced one step at a time, stopped
/// and continued: everything that decides the next step is in its public fields, so a run
/// rebuilt from them (a checkpoint) continues bit for bit as if it had not stopped.
///
/// Step `k` ends at `t0 + k h` exactly as computed in floating point (the time is reset
/// after each step so that it does not accumulate round-off), and the last step lands on
/// `t_end`. The diagnostics are evaluated after every step and their extremes kept in
/// [`Run::progress`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t_end: f64,
    /// Nominal step.
    pub h: f64,
    /// Steps of the whole run, [`step_count`]`(t0, t_end, h)`.
    pub total_steps: u64,
    /// The run so far: the current state, the steps taken and the extremes of the
    /// diagnostics.
    pub progress: RunSummary,
}

impl Run {
    /// A run of `system` from `initial` (at `initial.t`) to `t_end` with step `h`.
    ///
    /// # Errors
    /// Invalid `h`, `t_end` before `t0`, a step too small for the interval, a non-finite
    /// initial state or an attitude that is not a rotation ([`RigidState::check_valid`]).
    pub fn new<S: RigidBodySystem + ?Sized>(system: &S, initial: RigidState, t_end: f64, h: f64) -> Result<Run> {
        initial.check_valid()?;
        let total_steps = step_count(initial.t, t_end, h)?;
        let first = Diagnostics::of(system, &initial);
        Ok(Run {
            t0: initial.t,
            t_end,
            h,
            total_steps,
            progress: RunSummary {
                state: initial,
                steps: 0,
                initial: first,
                last: first,
                max_energy_error: 0.0,
                max_spatial_momentum_change: Vec3::ZERO,
                max_body_momentum_norm_change: 0.0,
                max_orthogonality_defect: first.orthogonality_defect,
            },
        })
    }

    /// Whether the run has reached `t_end`.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.progress.steps >= self.total_steps
    }

    /// The current state.
    #[must_use]
    pub fn state(&self) -> &RigidState {
        &self.progress.state
    }

    /// The size of the next step: `h`, or the shorter last step that lands on `t_end`.
    #[must_use]
    pub fn next_step_size(&self) -> f64 {
        if self.progress.steps + 1 >= self.total_steps {
            self.t_end - self.progress.state.t
        } else {
            self.h
        }
    }

    /// Take the next step and update the diagnostics; returns the new state's diagnostics.
    /// Does nothing (and returns the last diagnostics) once the run is done.
    ///
    /// # Errors
    /// The method's error (Newton not converging, a non-finite result), with its time and
    /// step; the run is then unchanged.
    pub fn step<M, S>(&mut self, method: &mut M, system: &S) -> Result<Diagnostics>
    where
        M: RotationIntegrator,
        S: RigidBodySystem + ?Sized,
    {
        if self.is_done() {
            return Ok(self.progress.last);
        }
        let k = self.progress.steps + 1;
        let last_step = k == self.total_steps;
        let target = if last_step {
            self.t_end
        } else {
            self.t0 + k as f64 * self.h
        };
        let dt = if last_step {
            target - self.progress.state.t
        } else {
            self.h
        };
        let mut state = self.progress.state;
        method.step(system, &mut state, dt)?;
        state.t = target;
        let d = Diagnostics::of(system, &state);
        let p = &mut self.progress;
        let e0 = p.initial.energy;
        let de = (d.energy - e0).abs();
        p.max_energy_error = p.max_energy_error.max(if e0 != 0.0 { de / e0.abs() } else { de });
        let dm = d.spatial_momentum - p.initial.spatial_momentum;
        let m = p.max_spatial_momentum_change;
        p.max_spatial_momentum_change = Vec3::new(m.x.max(dm.x.abs()), m.y.max(dm.y.abs()), m.z.max(dm.z.abs()));
        p.max_body_momentum_norm_change = p
            .max_body_momentum_norm_change
            .max((d.body_momentum_norm - p.initial.body_momentum_norm).abs());
        p.max_orthogonality_defect = p.max_orthogonality_defect.max(d.orthogonality_defect);
        p.state = state;
        p.last = d;
        p.steps = k;
        Ok(d)
    }

    /// The summary of the run so far.
    #[must_use]
    pub fn summary(&self) -> RunSummary {
        self.progress
    }
}

/// Integrate `system` from `initial` (at `initial.t`) to `t_end` with step `h`.
///
/// The observer sees step 0, every `every`-th step and the final step (so a run of `n`
/// steps with `every` dividing `n` makes `n/every + 1` calls), with the state and its
/// diagnostics; returning `Err(message)` stops the run with [`Error::ObserverFailed`].
/// Step `k` ends at `t0 + k h` exactly as computed in floating point, and the last step
/// lands on `t_end`. The diagnostics are evaluated after every step. A [`Run`] does the
/// same one step at a time.
///
/// # Errors
/// Invalid `h`, `t_end` before `t0`, `every = 0`, a non-finite initial state, an initial
/// attitude that is not a rotation ([`RigidState::check_valid`]), or the first failing
/// step (Newton not converging, a non-finite result), with its time and step.
pub fn integrate<M, S, O>(
    method: &mut M,
    system: &S,
    initial: RigidState,
    t_end: f64,
    h: f64,
    every: u64,
    mut observer: O,
) -> Result<RunSummary>
where
    M: RotationIntegrator,
    S: RigidBodySystem + ?Sized,
    O: FnMut(u64, &RigidState, &Diagnostics) -> core::result::Result<(), String>,
{
    if every == 0 {
        return Err(Error::InvalidObserverInterval);
    }
    let mut run = Run::new(system, initial, t_end, h)?;
    let fail = |t: f64, reason: String| Error::ObserverFailed { t, reason };
    observer(0, &run.progress.state, &run.progress.initial).map_err(|r| fail(run.t0, r))?;
    while !run.is_done() {
        let d = run.step(method, system)?;
        let k = run.progress.steps;
        if k % every == 0 || k == run.total_steps {
            observer(k, &run.progress.state, &d).map_err(|r| fail(run.progress.state.t, r))?;
        }
    }
    Ok(run.summary())
}

/// Step from `state` to `t_end` with step `h` and nothing else: no diagnostics, no
/// observer; the fastest way to advance a state. The last step lands on `t_end`. Returns
/// the number of steps.
///
/// # Errors
/// As [`integrate`]; on error `state` holds the last good state.
pub fn advance<M, S>(method: &mut M, system: &S, state: &mut RigidState, t_end: f64, h: f64) -> Result<u64>
where
    M: RotationIntegrator,
    S: RigidBodySystem + ?Sized,
{
    state.check_valid()?;
    let t0 = state.t;
    let steps = step_count(t0, t_end, h)?;
    for k in 1..=steps {
        let target = if k == steps { t_end } else { t0 + k as f64 * h };
        let dt = if k == steps { target - state.t } else { h };
        method.step(system, state, dt)?;
        state.t = target;
    }
    Ok(steps)
}

/// [`integrate`] without an observer.
pub fn integrate_to<M, S>(method: &mut M, system: &S, initial: RigidState, t_end: f64, h: f64) -> Result<RunSummary>
where
    M: RotationIntegrator,
    S: RigidBodySystem + ?Sized,
{
    integrate(method, system, initial, t_end, h, u64::MAX, |_, _, _| Ok(()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_count_rounds_sensibly() {
        assert_eq!(step_count(0.0, 0.8, 1e-4).unwrap(), 8000);
        assert_eq!(step_count(0.0, 0.8, 2e-3 / 16.0).unwrap(), 6400);
        assert_eq!(step_count(0.0, 1.0, 0.3).unwrap(), 4);
        assert_eq!(step_count(1.0, 1.0, 0.3).unwrap(), 0);
        assert!(matches!(step_count(0.0, 1.0, 0.0), Err(Error::InvalidStep { .. })));
        assert!(matches!(step_count(0.0, 1.0, f64::NAN), Err(Error::InvalidStep { .. })));
        assert!(matches!(step_count(1.0, 0.0, 0.1), Err(Error::EndBeforeStart { .. })));
        // A mistyped exponent: a step that does not move the clock (it would run for ever).
        assert!(matches!(step_count(0.0, 0.8, 1e-30), Err(Error::StepTooSmall { .. })));
        assert!(matches!(step_count(0.0, 1e12, 1e-5), Err(Error::StepTooSmall { .. })));
        assert!(matches!(
            step_count(1e6, 1e6 + 1.0, 1e-12),
            Err(Error::StepTooSmall { .. })
        ));
        let msg = step_count(0.0, 0.8, 1e-30).unwrap_err().to_string();
        assert!(
            msg.contains("h = 1e-30") && msg.contains("rounds to t at |t| = 0.8"),
            "{msg}"
        );
        // Steps that move the clock but are more than the counter keeps exact: 1.98 × 2^53.
        let ulp = f64::EPSILON / 2.0;
        let msg = step_count(-0.99, 0.99, ulp).unwrap_err().to_string();
        assert!(msg.contains("1.783e16 steps, more than 2^53"), "{msg}");
        // Up to the limits, runs are accepted.
        assert_eq!(step_count(-0.5, 0.5, ulp).unwrap(), MAX_STEPS);
        assert_eq!(step_count(0.0, 1.0, f64::EPSILON).unwrap(), MAX_STEPS / 2);
        assert_eq!(step_count(1.0, 1.0, 1e-300).unwrap(), 0);
    }

    #[test]
    fn refuses_an_attitude_that_is_not_a_rotation() {
        // Issue 14, item 7: diag(2, 1, 1) used to run and only report a defect of 3.
        let top = crate::rigid::problems::fast_top();
        let mut ea = crate::LieMidpointAlternating::new();
        let bad = RigidState::new(
            0.0,
            top.initial.pi,
            crate::Mat3::from_diagonal(Vec3::new(2.0, 1.0, 1.0)),
        );
        let e = integrate_to(&mut ea, &top.system, bad, 0.01, 1e-4).unwrap_err();
        assert!(matches!(e, Error::NotARotation { .. }), "{e}");
        assert!(e.to_string().contains("defect |R^T R - I| = 3.000e0"), "{e}");
        let mut state = bad;
        assert!(advance(&mut ea, &top.system, &mut state, 0.01, 1e-4).is_err());
        // A reflection is refused too.
        let mirror = RigidState::new(
            0.0,
            top.initial.pi,
            crate::Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0)),
        );
        assert!(matches!(
            Run::new(&top.system, mirror, 0.01, 1e-4),
            Err(Error::NotARotation { .. })
        ));
        // Round-off-level defects are accepted.
        let r = crate::so3::exp(Vec3::new(0.3, 0.2, 0.1)) * (1.0 + 1e-9);
        assert!(Run::new(&top.system, RigidState::new(0.0, top.initial.pi, r), 0.01, 1e-4).is_ok());
    }

    #[test]
    fn a_run_rebuilt_from_its_fields_continues_bit_for_bit() {
        let top = crate::rigid::problems::fast_top();
        let method = crate::RotationMethod::RungeKutta4;
        let whole = integrate_to(&mut method.integrator(), &top.system, top.initial, 0.05, 3e-4).unwrap();
        let mut first = method.integrator();
        let mut run = Run::new(&top.system, top.initial, 0.05, 3e-4).unwrap();
        assert_eq!(run.total_steps, 167);
        for _ in 0..100 {
            run.step(&mut first, &top.system).unwrap();
        }
        // A copy of the fields and of the method's cache, as a checkpoint holds them.
        let mut copy = run;
        let mut second = method.integrator();
        second.restore_cache(&top.system, first.cache()).unwrap();
        while !copy.is_done() {
            copy.step(&mut second, &top.system).unwrap();
        }
        assert_eq!(copy.summary(), whole);
        assert_eq!(copy.state().t, 0.05);
    }
}
