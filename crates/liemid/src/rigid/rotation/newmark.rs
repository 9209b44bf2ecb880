//! NMB: the Krysl-Endres explicit Newmark algorithm for rotations.
//!
//! ## Reference
//! P. Krysl, L. Endres, *Explicit Newmark/Verlet algorithm for time integration of the
//! rotational dynamics of rigid bodies*, Int. J. Numer. Meth. Engng 62 (2005).

use super::{check_step, commit, newton_error, RotationIntegrator, TorqueCache};
use crate::error::Result;
use crate::linalg::Mat3;
use crate::midpoint::{NewtonStop, NotConverged, MAX_ITERATIONS};
use crate::rigid::{RigidBodySystem, RigidState};
use crate::so3;

/// NMB (Krysl and Endres 2005), explicit Newmark with `γ = 1/2`, `β = 0` for rotations.
/// With the body angular acceleration `A = I⁻¹(T − W × I W)`:
///
/// ```text
/// R_{n+1} = R_n exp(h W_n + (h²/2) A_n)
/// solve for W_{n+1}:  I A_{n+1} + W_{n+1} × I W_{n+1} = T(R_{n+1}, t_{n+1}),
///                     W_{n+1} = W_n + (h/2)(A_n + A_{n+1})
/// ```
///
/// Second order, symmetric, explicit in the torque (one evaluation per step, the end
/// torque is cached), but it does not keep `π` exactly. The velocity equation is solved
/// by Newton with the Jacobian `I + (h/2)(hat(W) I − hat(I W))`.
#[derive(Clone, Debug, Default)]
pub struct KryslEndresNewmark {
    pub(super) cache: TorqueCache,
}

impl KryslEndresNewmark {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

impl RotationIntegrator for KryslEndresNewmark {
    fn name(&self) -> &'static str {
        "NMB"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let (t, t1) = (state.t, state.t + h);
        let inertia = system.inertia();
        let w0 = inertia.apply_inverse(state.pi);
        let torque0 = self.cache.torque(system, &state.rotation, t);
        let a0 = inertia.apply_inverse(torque0 - w0.cross(state.pi));
        let rotation = state.rotation * so3::exp(w0 * h + a0 * (0.5 * h * h));
        let torque1 = system.torque(&rotation, t1);
        // F(W) = I (W − W_n) − (h/2) I A_n + (h/2)(W × I W − T_{n+1}) = 0.
        let base = state.pi + inertia.apply(a0) * (0.5 * h) + torque1 * (0.5 * h);
        let mut w = w0 + a0 * h;
        let mut stop = NewtonStop::new();
        let mut converged = false;
        let mut residual = 0.0;
        for _ in 0..MAX_ITERATIONS {
            let iw = inertia.apply(w);
            let f = iw + w.cross(iw) * (0.5 * h) - base;
            residual = f.norm();
            let j: Mat3 = *inertia.matrix() + (so3::hat(w) * *inertia.matrix() - so3::hat(iw)) * (0.5 * h);
            let Some(delta) = j.solve(f) else { break };
            w -= delta;
            if !w.is_finite() {
                break;
            }
            if stop.done(delta.norm(), w.norm()) {
                converged = true;
                break;
            }
        }
        if !converged {
            let scale = base.norm() + f64::MIN_POSITIVE;
            let e = NotConverged::Iterations {
                residual: residual / scale,
                iterations: MAX_ITERATIONS,
            };
            return Err(newton_error(self.name(), "velocity equation", t, h, e));
        }
        let next = RigidState::new(t1, inertia.apply(w), rotation);
        commit(self.name(), state, h, next)?;
        self.cache.store(system, &rotation, t1, torque1);
        Ok(())
    }
    fn reset(&mut self) {
        self.cache.clear();
    }
}
