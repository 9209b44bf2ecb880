//! Reversible adaptive steps: the time-transformed stepping of Hairer and Söderlind for the
//! symmetric methods (LIEMID\[EA\], \[EAV\], \[EX\], \[FS\] and their compositions, Verlet, the
//! coupled orbit + attitude step of [`crate::rigid::satellite`]).
//!
//! A step density `ρ(y) > 0` (steps per unit time, up to the factor `1/ε`) is given by the
//! user or built in: `|y|^{−3/2}` for orbits ([`CentralDensity`], the orbit density of the
//! satellite), `|Ω|` for a rigid body ([`AngularSpeed`]), `(|Ω|² + |T|/I_min)^{1/2}` when
//! the torque sets the pace ([`TorqueRate`]). The step is `h_n = ε / z_{n+1/2}` with the
//! control variable `z ≈ ρ` advanced by the explicit symmetric recursion
//!
//! ```text
//! z_{1/2} = ρ(y_0) + (ε/2) G(y_0),   y_{n+1} = Φ_{ε / z_{n+1/2}}(y_n),
//! z_{n+3/2} = z_{n+1/2} + ε G(y_{n+1}),   G = d(log ρ)/dt along the flow,
//! ```
//!
//! the leapfrog discretisation of `dz/dτ = G` in the fictive time `τ` (`dt/dτ = 1/z`). With
//! `Φ` symmetric (`Φ_{−h} ∘ Φ_h = id`) the map `(y_n, z_{n−1/2}) → (y_{n+1}, z_{n+1/2})` is
//! symmetric, and when `ρ` is even and `G` odd under the negation of the momenta
//! (`ρ(Sy) = ρ(y)`, `G(Sy) = −G(y)`, true of every density here) it is time-reversible:
//! stepping forward, negating the momenta and stepping again returns to the negated start
//! up to round-off, amplified by the run's sensitivity ([`AdaptiveRun::reverse`]). An
//! order-`p` method keeps its order `p` in `ε` (the global error of any step sequence
//! `h_n = ε s_n` is `O(ε^p)`); a composition is applied whole inside each adaptive step.
//!
//! The run lands exactly on `t_end`: the step that would reach or pass it (to a relative
//! 1e-10) is shortened to end there, and the run is done; its length is reported as the
//! last step. The clock is summed with compensation (Kahan), so `t` carries no round-off
//! drift over millions of steps.
//!
//! ## Reference
//! E. Hairer, G. Söderlind, *Explicit, time reversible, adaptive step size control*, SIAM
//! J. Sci. Comput. 26(6) (2005) 1838–1851.

use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::linalg::Vec3;
use crate::rigid::rotation::{AnyRotationIntegrator, MethodCache, RotationIntegrator, RotationMethod};
use crate::rigid::{RigidBodySystem, RigidState};
use crate::vector::{MechanicalSystem, PhaseState, VectorIntegrator};

/// A symmetric one-step method bound to its system and to a step density: what
/// [`AdaptiveRun`] steps.
pub trait ReversibleStepper {
    /// The state stepped.
    type State: Clone;
    /// The method's name.
    fn name(&self) -> &'static str;
    /// The method's order (also its order in `ε`).
    fn order(&self) -> u32;
    /// The density's name.
    fn density_name(&self) -> &'static str;
    /// One step of the symmetric method, of length `h > 0`; on error the state is unchanged.
    ///
    /// # Errors
    /// The method's.
    fn step(&mut self, state: &mut Self::State, h: f64) -> Result<()>;
    /// The state's time.
    fn time(state: &Self::State) -> f64;
    /// Set the state's time.
    fn set_time(state: &mut Self::State, t: f64);
    /// Negate the momenta (the time reversal `S`).
    fn negate_momenta(state: &mut Self::State);
    /// The step density `ρ(y)` and `G(y) = d(log ρ)/dt` along the flow.
    fn density(&mut self, state: &Self::State) -> (f64, f64);
}

/// What an adaptive run did: the accuracy parameter and the steps it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveStats {
    /// The accuracy parameter `ε` (`h = ε / z`).
    pub eps: f64,
    /// Steps taken (the last, shortened one included).
    pub steps: u64,
    /// The smallest step, the last one excluded unless it is the only one.
    pub min_step: f64,
    /// The largest step, the last one excluded unless it is the only one.
    pub max_step: f64,
    /// The last step (shortened to land on `t_end`).
    pub last_step: f64,
}

/// A run of time-transformed steps from `t0` to `t_end` (see the [module](self) for the
/// recursion), advanced one step at a time.
#[derive(Clone, Debug)]
pub struct AdaptiveRun<P: ReversibleStepper> {
    /// The stepper (method, system, density).
    pub stepper: P,
    state: P::State,
    t0: f64,
    t_end: f64,
    eps: f64,
    /// +1 forward, −1 for a reversed run (the clock runs back).
    direction: f64,
    /// The control variable `z_{n+1/2}` of the next step.
    z: f64,
    /// A first step of given length (the reversed run's, which undoes the shortened one).
    forced: Option<f64>,
    /// Compensation of the clock's sum.
    clock_low: f64,
    stats: AdaptiveStats,
    done: bool,
}

fn control_error(t: f64, what: &'static str, value: f64, eps: f64) -> Error {
    Error::StepControl { t, what, value, eps }
}

impl<P: ReversibleStepper> AdaptiveRun<P> {
    /// A run of `stepper` from `initial` (at its time `t0`) to `t_end ≥ t0` with accuracy
    /// parameter `eps`: `z_{1/2} = ρ(y_0) + (ε/2) G(y_0)`.
    ///
    /// # Errors
    /// `eps` not finite and positive; `t_end` before `t0`; a density that is not finite and
    /// positive at the start.
    pub fn new(mut stepper: P, initial: P::State, t_end: f64, eps: f64) -> Result<Self> {
        if !(eps.is_finite() && eps > 0.0) {
            return Err(Error::InvalidParameter {
                name: "eps",
                value: eps,
                reason: "must be finite and positive",
            });
        }
        let t0 = P::time(&initial);
        if !(t0.is_finite() && t_end.is_finite()) || t_end < t0 {
            return Err(Error::EndBeforeStart { t0, t_end });
        }
        let (rho, g) = stepper.density(&initial);
        if !(rho.is_finite() && rho > 0.0) {
            return Err(control_error(t0, "rho", rho, eps));
        }
        let z = rho + 0.5 * eps * g;
        if !(z.is_finite() && z > 0.0) {
            return Err(control_error(t0, "z", z, eps));
        }
        Ok(AdaptiveRun {
            stepper,
            state: initial,
            t0,
            t_end,
            eps,
            direction: 1.0,
            z,
            forced: None,
            clock_low: 0.0,
            stats: AdaptiveStats {
                eps,
                steps: 0,
                min_step: f64::INFINITY,
                max_step: 0.0,
                last_step: 0.0,
            },
            done: t_end == t0,
        })
    }

    /// The current state.
    #[must_use]
    pub fn state(&self) -> &P::State {
        &self.state
    }

    /// Whether the run has landed on `t_end`.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.done
    }

    /// The start and end times.
    #[must_use]
    pub fn span(&self) -> (f64, f64) {
        (self.t0, self.t_end)
    }

    /// The steps so far.
    #[must_use]
    pub fn stats(&self) -> AdaptiveStats {
        let mut s = self.stats;
        if s.steps == 1 {
            s.min_step = s.last_step;
            s.max_step = s.last_step;
        } else if s.steps == 0 {
            s.min_step = 0.0;
        }
        s
    }

    /// The control variable `z_{n+1/2}` of the next step (`h = ε / z`).
    #[must_use]
    pub fn control(&self) -> f64 {
        self.z
    }

    /// Take the next step; returns its length (0 once the run is done).
    ///
    /// # Errors
    /// The method's error (the state is then unchanged), a step control that lost
    /// positivity ([`Error::StepControl`]), or a step too small to move the clock.
    pub fn step(&mut self) -> Result<f64> {
        if self.done {
            return Ok(0.0);
        }
        let t = P::time(&self.state);
        let remaining = (self.t_end - t) * self.direction;
        let control = match self.forced.take() {
            Some(h) => h,
            None => self.eps / self.z,
        };
        if !(control.is_finite() && control > 0.0) {
            return Err(control_error(t, "h", control, self.eps));
        }
        let last = control >= remaining * (1.0 - 1e-10);
        let h = if last { remaining } else { control };
        // The clock: t + direction h, summed with compensation.
        let (t_next, low) = if last {
            (self.t_end, 0.0)
        } else {
            let y = self.direction * h - self.clock_low;
            let sum = t + y;
            (sum, (sum - t) - y)
        };
        if t_next == t {
            return Err(Error::StepTooSmall {
                h,
                t0: self.t0,
                t_end: self.t_end,
                reason: format!("t + h rounds to t at t = {}", crate::error::Num(t)),
            });
        }
        self.stepper.step(&mut self.state, h)?;
        P::set_time(&mut self.state, t_next);
        self.clock_low = low;
        let s = &mut self.stats;
        s.steps += 1;
        s.last_step = h;
        if last {
            self.done = true;
        } else {
            s.min_step = s.min_step.min(h);
            s.max_step = s.max_step.max(h);
            let (_, g) = self.stepper.density(&self.state);
            let z = self.z + self.eps * g;
            if !(z.is_finite() && z > 0.0) {
                return Err(control_error(t_next, "z", z, self.eps));
            }
            self.z = z;
        }
        Ok(h)
    }

    /// Step to `t_end`; returns the statistics.
    ///
    /// # Errors
    /// As [`AdaptiveRun::step`].
    pub fn run_to_end(&mut self) -> Result<AdaptiveStats> {
        while !self.done {
            self.step()?;
        }
        Ok(self.stats())
    }

    /// The time-reversed run of a finished run: the momenta negated, the control variable
    /// kept, and the clock running from `t_end` back to `t0`. Its first step is the
    /// shortened last step of this run and its `z` recursion retraces this run's, so for a
    /// symmetric method and an even density it returns to the start with negated momenta,
    /// to round-off times the sensitivity of the run. The system must be autonomous (the
    /// clock runs back while each step advances the negated motion by `+h`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when the run has not landed on `t_end`.
    pub fn reverse(self) -> Result<Self> {
        if !self.done {
            return Err(Error::InvalidParameter {
                name: "reverse",
                value: P::time(&self.state),
                reason: "the run has not reached t_end",
            });
        }
        let mut state = self.state;
        P::negate_momenta(&mut state);
        Ok(AdaptiveRun {
            stepper: self.stepper,
            state,
            t0: self.t_end,
            t_end: self.t0,
            eps: self.eps,
            direction: -self.direction,
            z: self.z,
            forced: (self.stats.steps > 0).then_some(self.stats.last_step),
            clock_low: 0.0,
            stats: AdaptiveStats {
                eps: self.eps,
                steps: 0,
                min_step: f64::INFINITY,
                max_step: 0.0,
                last_step: 0.0,
            },
            done: self.stats.steps == 0,
        })
    }
}

/// A step density for a rigid body about a fixed point: `ρ(Π, R, t)` and
/// `G = d(log ρ)/dt` along the flow, given the torque at the state.
pub trait RigidDensity {
    /// Short name, e.g. `omega`.
    fn name(&self) -> &'static str;
    /// `(ρ, G)` at `state`, where `torque = T(R, t)`; `system` gives the inertia and, if
    /// needed, further torque evaluations.
    fn evaluate<S: RigidBodySystem + ?Sized>(&self, system: &S, state: &RigidState, torque: Vec3) -> (f64, f64);
}

/// `Ω̇ = I⁻¹(Π × Ω + T)` and `Ω = I⁻¹ Π`.
fn angular_rate(inertia: &Inertia, pi: Vec3, torque: Vec3) -> (Vec3, Vec3) {
    let omega = inertia.apply_inverse(pi);
    (omega, inertia.apply_inverse(pi.cross(omega) + torque))
}

/// The density `ρ = |Ω|`: a step turns the body by about `ε` radians. `G = Ω·Ω̇ / |Ω|²`
/// with `Ω̇ = I⁻¹(Π × Ω + T)`; even/odd under `Π → −Π` as required. A body at rest has no
/// density (an error at the start).
///
/// Reference: E. Hairer, G. Söderlind, SIAM J. Sci. Comput. 26(6) (2005).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AngularSpeed;

impl RigidDensity for AngularSpeed {
    fn name(&self) -> &'static str {
        "omega"
    }
    fn evaluate<S: RigidBodySystem + ?Sized>(&self, system: &S, state: &RigidState, torque: Vec3) -> (f64, f64) {
        let (omega, rate) = angular_rate(system.inertia(), state.pi, torque);
        let w2 = omega.norm_squared();
        (w2.sqrt(), omega.dot(rate) / w2)
    }
}

/// The density `ρ = (|Ω|² + |T| / I_min)^{1/2}`: the spin rate, or the rate the torque
/// sets (`|T|/I_min` is the square of a libration frequency) where that is faster. `G` needs
/// `dT/dt` along the flow, taken by a central difference over the body's own turn,
/// `(T(R exp(δΩ), t + δ) − T(R exp(−δΩ), t − δ)) / 2δ` with `δ |Ω| = 10⁻⁵` (odd under
/// `Π → −Π`, so the step stays reversible): two more torque evaluations per step.
///
/// Reference: E. Hairer, G. Söderlind, SIAM J. Sci. Comput. 26(6) (2005).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TorqueRate;

impl RigidDensity for TorqueRate {
    fn name(&self) -> &'static str {
        "torque"
    }
    fn evaluate<S: RigidBodySystem + ?Sized>(&self, system: &S, state: &RigidState, torque: Vec3) -> (f64, f64) {
        let inertia = system.inertia();
        let (omega, rate) = angular_rate(inertia, state.pi, torque);
        let scale = inertia.inverse_norm_bound();
        let tn = torque.norm();
        let w = omega.norm();
        let torque_rate = if w > 0.0 && tn > 0.0 {
            let d = 1e-5 / w;
            let plus = system.torque(&(state.rotation * crate::so3::exp(omega * d)), state.t + d);
            let minus = system.torque(&(state.rotation * crate::so3::exp(omega * -d)), state.t - d);
            torque.dot(plus - minus) / (2.0 * d * tn)
        } else {
            0.0
        };
        let rho2 = omega.norm_squared() + scale * tn;
        (
            rho2.sqrt(),
            (2.0 * omega.dot(rate) + scale * torque_rate) / (2.0 * rho2),
        )
    }
}

/// A rigid body's symmetric method with a density, for [`AdaptiveRun`]. The density's
/// torque comes from the method's cache (the end torque of the last step), so `ρ = |Ω|`
/// costs no torque evaluation.
#[derive(Clone, Debug)]
pub struct RigidAdaptive<'a, S: ?Sized, D> {
    system: &'a S,
    method: AnyRotationIntegrator,
    density: D,
}

impl<'a, S: RigidBodySystem + ?Sized, D: RigidDensity> RigidAdaptive<'a, S, D> {
    /// `method` (symmetric: [`RotationMethod::check_reversible`]) on `system` with `density`.
    ///
    /// # Errors
    /// [`Error::NotReversible`] for a method that is not symmetric.
    pub fn new(system: &'a S, method: RotationMethod, density: D) -> Result<Self> {
        method.check_reversible()?;
        Ok(RigidAdaptive {
            system,
            method: method.integrator(),
            density,
        })
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> &AnyRotationIntegrator {
        &self.method
    }
}

impl<S: RigidBodySystem + ?Sized, D: RigidDensity> ReversibleStepper for RigidAdaptive<'_, S, D> {
    type State = RigidState;
    fn name(&self) -> &'static str {
        self.method.name()
    }
    fn order(&self) -> u32 {
        self.method.order()
    }
    fn density_name(&self) -> &'static str {
        self.density.name()
    }
    fn step(&mut self, state: &mut RigidState, h: f64) -> Result<()> {
        self.method.step(self.system, state, h)
    }
    fn time(state: &RigidState) -> f64 {
        state.t
    }
    fn set_time(state: &mut RigidState, t: f64) {
        state.t = t;
    }
    fn negate_momenta(state: &mut RigidState) {
        state.pi = -state.pi;
    }
    fn density(&mut self, state: &RigidState) -> (f64, f64) {
        let torque = match self.method.cache() {
            MethodCache::Torque { t, rotation, torque }
                if rotation.bitwise_eq(&state.rotation)
                    && (t == state.t || (t - state.t).abs() <= 1e-12 * t.abs().max(state.t.abs())) =>
            {
                torque
            }
            _ => self.system.torque(&state.rotation, state.t),
        };
        self.density.evaluate(self.system, state, torque)
    }
}

/// A step density for a [`MechanicalSystem`]: `(ρ, G)` at a state.
pub trait VectorDensity<S: ?Sized> {
    /// Short name.
    fn name(&self) -> &'static str;
    /// `(ρ, G = d(log ρ)/dt)` at `state`.
    fn evaluate(&mut self, system: &S, state: &PhaseState) -> (f64, f64);
}

/// The orbit density `ρ = |u|^{−3/2}` (Kepler's third law: the local orbital rate for
/// `μ = 1`), `G = −(3/2) u·u̇ / |u|²` with `u̇ = M⁻¹ p`. Scratch sized once.
///
/// Reference: E. Hairer, G. Söderlind, SIAM J. Sci. Comput. 26(6) (2005), section 5.
#[derive(Clone, Debug, Default)]
pub struct CentralDensity {
    velocity: Vec<f64>,
}

impl<S: MechanicalSystem + ?Sized> VectorDensity<S> for CentralDensity {
    fn name(&self) -> &'static str {
        "orbit"
    }
    fn evaluate(&mut self, system: &S, state: &PhaseState) -> (f64, f64) {
        if self.velocity.len() != state.p.len() {
            self.velocity = vec![0.0; state.p.len()];
        }
        self.velocity.copy_from_slice(&state.p);
        system.mass().solve_in_place(&mut self.velocity);
        let r2: f64 = state.u.iter().map(|x| x * x).sum();
        let rv: f64 = state.u.iter().zip(&self.velocity).map(|(x, v)| x * v).sum();
        (r2.powf(-0.75), -1.5 * rv / r2)
    }
}

/// A vector-space symmetric method (Verlet or a composition of it) with a density, for
/// [`AdaptiveRun`].
#[derive(Clone, Debug)]
pub struct VectorAdaptive<'a, S: ?Sized, M, D> {
    system: &'a S,
    method: M,
    density: D,
}

impl<'a, S: MechanicalSystem + ?Sized, M: VectorIntegrator, D: VectorDensity<S>> VectorAdaptive<'a, S, M, D> {
    /// `method` on `system` with `density`. The method must be symmetric (Verlet or a
    /// symmetric composition of it): the caller's guarantee, since [`VectorIntegrator`]
    /// does not say.
    pub fn new(system: &'a S, method: M, density: D) -> Self {
        VectorAdaptive {
            system,
            method,
            density,
        }
    }
}

impl<S: MechanicalSystem + ?Sized, M: VectorIntegrator, D: VectorDensity<S>> ReversibleStepper
    for VectorAdaptive<'_, S, M, D>
{
    type State = PhaseState;
    fn name(&self) -> &'static str {
        self.method.name()
    }
    fn order(&self) -> u32 {
        self.method.order()
    }
    fn density_name(&self) -> &'static str {
        self.density.name()
    }
    fn step(&mut self, state: &mut PhaseState, h: f64) -> Result<()> {
        self.method.step(self.system, state, h)
    }
    fn time(state: &PhaseState) -> f64 {
        state.t
    }
    fn set_time(state: &mut PhaseState, t: f64) {
        state.t = t;
    }
    fn negate_momenta(state: &mut PhaseState) {
        state.p.iter_mut().for_each(|p| *p = -*p);
    }
    fn density(&mut self, state: &PhaseState) -> (f64, f64) {
        self.density.evaluate(self.system, state)
    }
}
