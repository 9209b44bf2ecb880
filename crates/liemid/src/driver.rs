//! The driver: integrate a rigid body from `t0` to `t_end` with a fixed step, observing the
//! state every `k` steps and tracking the extremes of the diagnostics.

use crate::error::{Error, Result};
use crate::linalg::Vec3;
use crate::rigid::{Diagnostics, RigidBodySystem, RigidState};
use crate::rotation::RotationIntegrator;

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
        return too_small(format!("t + h rounds to t at |t| = {t_max}"));
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
}
