//! The midpoint Lie family: explicit LIEMID\[E1\], LIEMID\[E2\], their alternating composition
//! LIEMID\[EA\], and the implicit LIEMID\[I\].
//!
//! All four advance the attitude by `R_{n+1} = R_n exp(Ψ)` with `Ψ` from the midpoint
//! equation `(1/h) I Ψ = exp(−Ψ/2) P` (see [`crate::midpoint`]); they differ in where the
//! torque impulse is applied.
//!
//! ## Reference
//! P. Krysl, *Explicit momentum-conserving integrator for dynamics of rigid bodies
//! approximating the midpoint Lie algorithm*, Int. J. Numer. Meth. Engng 63 (2005).

use super::{check_step, commit, newton_error, RotationIntegrator, TorqueCache};
use crate::error::Result;
use crate::linalg::Vec3;
use crate::midpoint;
use crate::rigid::{RigidBodySystem, RigidState};
use crate::so3;

/// The step of the alternating family, `E1_{h/2} ∘ E2_{h/2}` around a torque-free half step
/// (`$solve`: the solve of (M) for EA, of (V) for EAV): the half impulse from the cached
/// start torque, two half steps of the drift, the end torque (cached for the next step's
/// start) and the second half impulse. A macro, not a generic function: passed as a closure,
/// the solver was not inlined the same way and EA's step cost 210 instead of 140 µs per
/// 1000 steps of the fast top (`benches/step.rs`).
macro_rules! alternating_step {
    ($self:ident, $system:ident, $state:ident, $h:ident, $solve:path, $equation:literal) => {{
        check_step($h)?;
        let t = $state.t;
        let hh = 0.5 * $h;
        let inertia = $system.inertia();
        let method = $self.name();
        let rotate = |p: Vec3| -> Result<so3::Increment> {
            let (increment, _) = $solve(inertia, p, hh).map_err(|e| newton_error(method, $equation, t, $h, e))?;
            Ok(increment)
        };
        let torque0 = $self.cache.torque($system, &$state.rotation, t);
        let p = Vec3::load_split(&$state.pi) + torque0 * hh;
        let inc1 = rotate(p)?;
        let pi_half = inc1.inverse_apply(p);
        let inc2 = rotate(pi_half)?;
        let rotation = inc2.rotate(&inc1.rotate(&$state.rotation));
        let t1 = t + $h;
        let torque1 = $system.torque(&rotation, t1);
        let next = RigidState::new(t1, inc2.inverse_apply(pi_half) + torque1 * hh, rotation);
        commit(method, $state, $h, next)?;
        $self.cache.store($system, &rotation, t1, torque1);
        Ok(())
    }};
}
pub(super) use alternating_step;

/// Solve (M) for `(P, h)` and return the increment `exp(Ψ)`; errors name the step
/// `(t, step)` that was being taken.
#[inline(always)]
fn midpoint_rotation(
    method: &'static str,
    inertia: &crate::inertia::Inertia,
    p: Vec3,
    h: f64,
    (t, step): (f64, f64),
) -> Result<so3::Increment> {
    let (increment, _) = midpoint::solve_increment(inertia, p, h)
        .map_err(|e| newton_error(method, "midpoint equation (M)", t, step, e))?;
    Ok(increment)
}

/// LIEMID\[E2\]: explicit midpoint Lie with the torque impulse at the start of the step
/// (the SO(3) analogue of symplectic Euler).
///
/// ```text
/// P = Π_n + h T(R_n, t_n);  solve (1/h) I Ψ = exp(−Ψ/2) P;
/// Π_{n+1} = exp(−Ψ) P;      R_{n+1} = R_n exp(Ψ)
/// ```
///
/// First order. Keeps `|Π|` and `π` exactly torque-free, and the spatial
/// momentum component along any axis about which the spatial torque vanishes (the
/// vertical for a heavy top). One torque evaluation per step.
#[derive(Clone, Debug, Default)]
pub struct LieMidpointE2 {
    pub(super) cache: TorqueCache,
}

impl LieMidpointE2 {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

impl RotationIntegrator for LieMidpointE2 {
    fn name(&self) -> &'static str {
        "LIEMID[E2]"
    }
    fn order(&self) -> u32 {
        1
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let t = state.t;
        let torque = self.cache.torque(system, &state.rotation, t);
        let p = Vec3::load_split(&state.pi) + torque * h;
        let inc = midpoint_rotation(self.name(), system.inertia(), p, h, (t, h))?;
        let next = RigidState::new(t + h, inc.inverse_apply(p), inc.rotate(&state.rotation));
        commit(self.name(), state, h, next)
    }
    fn reset(&mut self) {
        self.cache.clear();
    }
}

/// LIEMID\[E1\]: explicit midpoint Lie with the torque impulse at the end of the step, the
/// adjoint of [`LieMidpointE2`] (`E1_h = (E2_{−h})⁻¹`).
///
/// ```text
/// solve (1/h) I Ψ = exp(−Ψ/2) Π_n;   R_{n+1} = R_n exp(Ψ);
/// Π_{n+1} = exp(−Ψ) Π_n + h T(R_{n+1}, t_{n+1})
/// ```
///
/// The end impulse acts in the end configuration, so it is added after the rotation of the
/// momentum (the paper prints `exp(−Ψ)(Π_n + h T_{n+1})`, which is first order too but
/// neither the adjoint of E2 nor momentum conserving). First order, same
/// invariants as E2. One torque evaluation per step (at the end).
#[derive(Clone, Debug, Default)]
pub struct LieMidpointE1;

impl LieMidpointE1 {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self
    }
}

impl RotationIntegrator for LieMidpointE1 {
    fn name(&self) -> &'static str {
        "LIEMID[E1]"
    }
    fn order(&self) -> u32 {
        1
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let t = state.t;
        let pi = Vec3::load_split(&state.pi);
        let inc = midpoint_rotation(self.name(), system.inertia(), pi, h, (t, h))?;
        let rotation = inc.rotate(&state.rotation);
        let t1 = t + h;
        let torque = system.torque(&rotation, t1);
        let next = RigidState::new(t1, inc.inverse_apply(pi) + torque * h, rotation);
        commit(self.name(), state, h, next)
    }
}

/// LIEMID\[EA\]: the alternating composition `E1_{h/2} ∘ E2_{h/2}`.
///
/// ```text
/// P = Π_n + (h/2) T_n;            solve (M) with (P, h/2) → Ψ₁;
/// R½ = R_n exp(Ψ₁);               Π½ = exp(−Ψ₁) P;
/// solve (M) with (Π½, h/2) → Ψ₂;  R_{n+1} = R½ exp(Ψ₂);
/// Π_{n+1} = exp(−Ψ₂) Π½ + (h/2) T(R_{n+1}, t_{n+1})
/// ```
///
/// Second order and time-reversible (`EA_{−h} ∘ EA_h = id`), but not symplectic: the
/// torque-free map of (M) has a Lie–Poisson defect of `O(h³)` per step, measured by
/// `tests/rigid/lie_poisson.rs` (the source paper calls it symplectic; LIEMID\[EAV\] is
/// the Lie–Poisson variant, docs/theory/rigid.md §9). Keeps `|Π|` and
/// `π` exactly torque-free and `π · ĝ` for a heavy top; the energy error stays bounded.
/// The end torque is the next step's start torque, so a run costs one torque evaluation
/// per step.
#[derive(Clone, Debug, Default)]
pub struct LieMidpointAlternating {
    pub(super) cache: TorqueCache,
}

impl LieMidpointAlternating {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

impl RotationIntegrator for LieMidpointAlternating {
    fn name(&self) -> &'static str {
        "LIEMID[EA]"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        alternating_step!(
            self,
            system,
            state,
            h,
            midpoint::solve_increment,
            "midpoint equation (M)"
        )
    }
    fn reset(&mut self) {
        self.cache.clear();
    }
}

/// LIEMID\[I\]: the implicit midpoint Lie rule, torque at the midpoint configuration
/// `R_a = R_n exp(Ψ/2)`, `T_a = T(R_a, t_n + h/2)`:
///
/// ```text
/// I Ψ / h = exp(−Ψ/2) Π_n + (h/2) T_a
/// Π_{n+1} = exp(−Ψ) Π_n + h exp(−Ψ/2) T_a;   R_{n+1} = R_n exp(Ψ)
/// ```
///
/// Second order and symmetric; the spatial impulse `h R_a T_a` keeps the same momentum
/// components as EA. Solved by Newton with the exact Jacobian of the midpoint part and the
/// torque frozen per iteration, which converges linearly at a rate `O(h² ∂T/∂R / I)`; each
/// iteration costs one torque evaluation.
#[derive(Clone, Debug, Default)]
pub struct LieMidpointImplicit;

impl LieMidpointImplicit {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self
    }
}

impl RotationIntegrator for LieMidpointImplicit {
    fn name(&self) -> &'static str {
        "LIEMID[I]"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let t = state.t;
        let tm = t + 0.5 * h;
        let r0 = state.rotation;
        let inertia = system.inertia();
        let impulse = |psi: Vec3| system.torque(&(r0 * so3::exp(psi * 0.5)), tm) * (0.5 * h * h);
        let guess = inertia.apply_inverse(state.pi) * h;
        let (psi, _) = midpoint::solve_with(inertia, state.pi, h, guess, impulse)
            .map_err(|e| newton_error(self.name(), "implicit midpoint equation", t, h, e))?;
        let half = so3::exp(psi * 0.5);
        let torque = system.torque(&(r0 * half), tm);
        let q = half * half;
        let next = RigidState::new(t + h, q.tr_mul_vec(state.pi) + half.tr_mul_vec(torque) * h, r0 * q);
        commit(self.name(), state, h, next)
    }
}
