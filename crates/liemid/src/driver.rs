//! The driver: integrate a rigid body from `t0` to `t_end` with a fixed step, observing the
//! state every `k` steps and tracking the extremes of the diagnostics.

use crate::error::{Error, Result};
use crate::linalg::Vec3;
use crate::rigid::{Diagnostics, RigidBodySystem, RigidState};
use crate::rotation::RotationIntegrator;

/// The number of steps of size `h` that cover `[t0, t_end]`: `(t_end − t0)/h` when that
/// is an integer to a relative `1e-9`, otherwise the next integer up (the last step is
/// then shorter).
pub fn step_count(t0: f64, t_end: f64, h: f64) -> Result<u64> {
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::InvalidStep { h });
    }
    if !(t0.is_finite() && t_end.is_finite()) || t_end < t0 {
        return Err(Error::EndBeforeStart { t0, t_end });
    }
    let ratio = (t_end - t0) / h;
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

/// Tracks the extremes of the diagnostics along a run.
#[derive(Clone, Copy, Debug)]
struct Extremes {
    initial: Diagnostics,
    energy: f64,
    momentum: Vec3,
    norm: f64,
    defect: f64,
}

impl Extremes {
    fn new(initial: Diagnostics) -> Self {
        Extremes {
            initial,
            energy: 0.0,
            momentum: Vec3::ZERO,
            norm: 0.0,
            defect: initial.orthogonality_defect,
        }
    }

    fn update(&mut self, d: &Diagnostics) {
        let e0 = self.initial.energy;
        let de = (d.energy - e0).abs();
        self.energy = self.energy.max(if e0 != 0.0 { de / e0.abs() } else { de });
        let dm = d.spatial_momentum - self.initial.spatial_momentum;
        self.momentum = Vec3::new(
            self.momentum.x.max(dm.x.abs()),
            self.momentum.y.max(dm.y.abs()),
            self.momentum.z.max(dm.z.abs()),
        );
        self.norm = self
            .norm
            .max((d.body_momentum_norm - self.initial.body_momentum_norm).abs());
        self.defect = self.defect.max(d.orthogonality_defect);
    }
}

/// Integrate `system` from `initial` (at `initial.t`) to `t_end` with step `h`.
///
/// The observer sees step 0, every `every`-th step and the final step (so a run of `n`
/// steps with `every` dividing `n` makes `n/every + 1` calls), with the state and its
/// diagnostics; returning `Err(message)` stops the run with [`Error::ObserverFailed`].
/// Step `k` ends at `t0 + k h` exactly as computed in floating point, and the last step
/// lands on `t_end`. The diagnostics are evaluated after every step.
///
/// # Errors
/// Invalid `h`, `t_end` before `t0`, `every = 0`, a non-finite initial state, or the first
/// failing step (Newton not converging, a non-finite result), with its time and step.
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
    initial.check_finite()?;
    let t0 = initial.t;
    let steps = step_count(t0, t_end, h)?;
    let first = Diagnostics::of(system, &initial);
    let mut extremes = Extremes::new(first);
    let mut state = initial;
    let mut last = first;
    let fail = |t: f64, reason: String| Error::ObserverFailed { t, reason };
    observer(0, &state, &first).map_err(|r| fail(t0, r))?;
    for k in 1..=steps {
        let target = if k == steps { t_end } else { t0 + k as f64 * h };
        // The nominal step, except for the last one, which lands on t_end; the time is then
        // reset to t0 + k h so that it does not accumulate round-off.
        let dt = if k == steps { target - state.t } else { h };
        method.step(system, &mut state, dt)?;
        state.t = target;
        last = Diagnostics::of(system, &state);
        extremes.update(&last);
        if k % every == 0 || k == steps {
            observer(k, &state, &last).map_err(|r| fail(state.t, r))?;
        }
    }
    Ok(RunSummary {
        state,
        steps,
        initial: first,
        last,
        max_energy_error: extremes.energy,
        max_spatial_momentum_change: extremes.momentum,
        max_body_momentum_norm_change: extremes.norm,
        max_orthogonality_defect: extremes.defect,
    })
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
    state.check_finite()?;
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
    }
}
