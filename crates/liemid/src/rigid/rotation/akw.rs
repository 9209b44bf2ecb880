//! AKW: the implicit midpoint Lie-Poisson rule with a Cayley attitude update.
//!
//! ## Reference
//! M. Austin, P. S. Krishnaprasad, L.-S. Wang, *Almost Poisson integration of rigid body
//! systems*, J. Comput. Phys. 107 (1993).

use super::{check_step, commit, newton_error, RotationIntegrator, TorqueCache};
use crate::error::Result;
use crate::midpoint::{NewtonStop, NotConverged, MAX_ITERATIONS};
use crate::rigid::{RigidBodySystem, RigidState};
use crate::so3;

/// AKW (Austin, Krishnaprasad and Wang 1993):
///
/// ```text
/// Π_m = (Π_n + Π_{n+1})/2,  W_m = I⁻¹ Π_m
/// Π_{n+1} = Π_n + h Π_m × W_m + (h/2)(T_n + T_{n+1})
/// R_{n+1} = R_n cay(h W_m),  T_{n+1} = T(R_{n+1}, t_{n+1})
/// ```
///
/// Second order. Torque-free it keeps the energy and `|Π|` exactly. Solved by Newton on
/// `Π_{n+1}` with the exact Jacobian `I − (h/2)(hat(Π_m) I⁻¹ − hat(W_m))` of the
/// Lie-Poisson part and the end torque frozen per iteration (one torque evaluation per
/// iteration). At high spin rates the Cayley map's phase error dominates its attitude error.
#[derive(Clone, Debug, Default)]
pub struct AustinKrishnaprasadWang {
    pub(super) cache: TorqueCache,
}

impl AustinKrishnaprasadWang {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

impl RotationIntegrator for AustinKrishnaprasadWang {
    fn name(&self) -> &'static str {
        "AKW"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let (t, t1) = (state.t, state.t + h);
        let inertia = system.inertia();
        let (pi0, r0) = (state.pi, state.rotation);
        let torque0 = self.cache.torque(system, &r0, t);
        let w0 = inertia.apply_inverse(pi0);
        // Explicit Euler guess.
        let mut x = pi0 + (pi0.cross(w0) + torque0) * h;
        let mut stop = NewtonStop::new();
        let mut converged = false;
        let mut residual = 0.0;
        for _ in 0..MAX_ITERATIONS {
            let pm = (pi0 + x) * 0.5;
            let wm = inertia.apply_inverse(pm);
            let torque1 = system.torque(&(r0 * so3::cayley(wm * h)), t1);
            let f = x - pi0 - pm.cross(wm) * h - (torque0 + torque1) * (0.5 * h);
            residual = f.norm();
            let j = crate::linalg::Mat3::IDENTITY - (so3::hat(pm) * *inertia.inverse() - so3::hat(wm)) * (0.5 * h);
            let Some(delta) = j.solve(f) else { break };
            x -= delta;
            if !x.is_finite() {
                break;
            }
            if stop.done(delta.norm(), x.norm()) {
                converged = true;
                break;
            }
        }
        if !converged {
            let scale = pi0.norm() + (torque0 * h).norm() + f64::MIN_POSITIVE;
            let e = NotConverged::Iterations {
                residual: residual / scale,
                iterations: MAX_ITERATIONS,
            };
            return Err(newton_error(self.name(), "Lie-Poisson midpoint equation", t, h, e));
        }
        let wm = inertia.apply_inverse((pi0 + x) * 0.5);
        let rotation = r0 * so3::cayley(wm * h);
        let next = RigidState::new(t1, x, rotation);
        commit(self.name(), state, h, next)?;
        // The converged end torque, for the next step's start.
        self.cache.store(system, &rotation, t1, system.torque(&rotation, t1));
        Ok(())
    }
    fn reset(&mut self) {
        self.cache.clear();
    }
}
