//! SW: the Simo-Wong energy-momentum rule.
//!
//! ## Reference
//! J. C. Simo, K. K. Wong, *Unconditionally stable algorithms for rigid body dynamics that
//! exactly preserve energy and momentum*, Int. J. Numer. Meth. Engng 31 (1991).

use super::{check_step, commit, newton_error, RotationIntegrator};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};
use crate::midpoint::{NewtonStop, NotConverged, MAX_INCREMENT_ANGLE, MAX_ITERATIONS};
use crate::rigid::{RigidBodySystem, RigidState};
use crate::so3;

/// SW (Simo and Wong 1991):
///
/// ```text
/// Θ = (h/2)(W_n + W_{n+1}),  R_{n+1} = R_n exp(Θ)
/// Π_{n+1} = exp(−Θ) Π_n + h exp(−Θ/2) T(R_n exp(Θ/2), t_n + h/2)
/// ```
///
/// Second order. Torque-free it keeps the energy and `π` exactly. Solved by Newton on `Θ`
/// with the exact Jacobian of the free part,
/// `I − (h/2) I⁻¹ [exp(−Θ) hat(Π_n) Jr(−Θ) + (h/2) exp(−Θ/2) hat(T_a) Jr(−Θ/2)]`, and the
/// midpoint torque frozen per iteration.
#[derive(Clone, Debug, Default)]
pub struct SimoWong;

impl SimoWong {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self
    }
}

/// `Π_{n+1}(Θ)` and the pieces of its Jacobian.
#[inline]
fn end_momentum<S: RigidBodySystem + ?Sized>(
    system: &S,
    r0: &Mat3,
    pi0: Vec3,
    theta: Vec3,
    tm: f64,
    h: f64,
) -> (Vec3, Vec3, Mat3, Mat3) {
    let half = so3::exp(theta * 0.5);
    let full = half * half;
    let torque = system.torque(&(*r0 * half), tm);
    let pi1 = full.tr_mul_vec(pi0) + half.tr_mul_vec(torque) * h;
    (pi1, torque, full, half)
}

impl RotationIntegrator for SimoWong {
    fn name(&self) -> &'static str {
        "SW"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let t = state.t;
        let tm = t + 0.5 * h;
        let inertia = system.inertia();
        let (pi0, r0) = (state.pi, state.rotation);
        let w0 = inertia.apply_inverse(pi0);
        let mut theta = w0 * h;
        let mut stop = NewtonStop::new();
        let mut converged = false;
        let mut residual = 0.0;
        for _ in 0..MAX_ITERATIONS {
            let (pi1, torque, full, half) = end_momentum(system, &r0, pi0, theta, tm, h);
            let g = theta - (w0 + inertia.apply_inverse(pi1)) * (0.5 * h);
            residual = g.norm();
            let dpi = full.transpose() * so3::hat(pi0) * so3::right_jacobian(-theta)
                + half.transpose() * so3::hat(torque) * so3::right_jacobian(-theta * 0.5) * (0.5 * h);
            let j = Mat3::IDENTITY - *inertia.inverse() * dpi * (0.5 * h);
            let Some(delta) = j.solve(g) else { break };
            theta -= delta;
            if !theta.is_finite() {
                break;
            }
            if stop.done(delta.norm(), theta.norm()) {
                converged = true;
                break;
            }
        }
        if !converged {
            let scale = (w0 * h).norm() + f64::MIN_POSITIVE;
            let e = NotConverged::Iterations {
                residual: residual / scale,
                iterations: MAX_ITERATIONS,
            };
            return Err(newton_error(self.name(), "energy-momentum equation", t, h, e));
        }
        let angle = theta.norm();
        if angle > MAX_INCREMENT_ANGLE {
            let e = NotConverged::IncrementTooLarge { angle };
            return Err(newton_error(self.name(), "energy-momentum equation", t, h, e));
        }
        let (pi1, _, full, _) = end_momentum(system, &r0, pi0, theta, tm, h);
        let next = RigidState::new(t + h, pi1, r0 * full);
        commit(self.name(), state, h, next)
    }
}
