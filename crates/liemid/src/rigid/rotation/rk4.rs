//! Classical Runge-Kutta 4 on (Π, unit quaternion): the baseline most users write by hand.

use super::{check_step, commit, RotationIntegrator};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};
use crate::rigid::{RigidBodySystem, RigidState};
use crate::so3::Quaternion;

/// Classical RK4 on `Π' = Π × W + T(R(q), t)`, `q' = ½ q ⊗ (0, W)`, `W = I⁻¹ Π`, with the
/// quaternion renormalised after each step (and at each stage before it is turned into
/// an attitude). Fourth order; conserves nothing exactly (energy and `π` drift). Four
/// torque evaluations per step.
///
/// The quaternion is kept between steps (keyed on the attitude it produced), so a run does
/// not convert the matrix back at every step.
#[derive(Clone, Debug, Default)]
pub struct RungeKutta4Quaternion {
    pub(super) last: Option<(Mat3, Quaternion)>,
}

impl RungeKutta4Quaternion {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

#[inline]
fn rates<S: RigidBodySystem + ?Sized>(system: &S, pi: Vec3, q: &Quaternion, t: f64) -> (Vec3, Quaternion) {
    let w = system.inertia().apply_inverse(pi);
    let r = q.normalized().to_matrix();
    let dpi = pi.cross(w) + system.torque(&r, t);
    let dq = q.mul(&Quaternion::new(0.0, 0.5 * w.x, 0.5 * w.y, 0.5 * w.z));
    (dpi, dq)
}

#[inline]
fn axpy(q: &Quaternion, dq: &Quaternion, s: f64) -> Quaternion {
    Quaternion::new(q.w + s * dq.w, q.x + s * dq.x, q.y + s * dq.y, q.z + s * dq.z)
}

impl RotationIntegrator for RungeKutta4Quaternion {
    fn name(&self) -> &'static str {
        "RK4"
    }
    fn order(&self) -> u32 {
        4
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let t = state.t;
        let q0 = match &self.last {
            Some((r, q)) if *r == state.rotation => *q,
            _ => Quaternion::from_matrix(&state.rotation),
        };
        let p0 = state.pi;
        let (k1p, k1q) = rates(system, p0, &q0, t);
        let (k2p, k2q) = rates(system, p0 + k1p * (0.5 * h), &axpy(&q0, &k1q, 0.5 * h), t + 0.5 * h);
        let (k3p, k3q) = rates(system, p0 + k2p * (0.5 * h), &axpy(&q0, &k2q, 0.5 * h), t + 0.5 * h);
        let (k4p, k4q) = rates(system, p0 + k3p * h, &axpy(&q0, &k3q, h), t + h);
        let pi = p0 + (k1p + (k2p + k3p) * 2.0 + k4p) * (h / 6.0);
        let sum = Quaternion::new(
            k1q.w + 2.0 * (k2q.w + k3q.w) + k4q.w,
            k1q.x + 2.0 * (k2q.x + k3q.x) + k4q.x,
            k1q.y + 2.0 * (k2q.y + k3q.y) + k4q.y,
            k1q.z + 2.0 * (k2q.z + k3q.z) + k4q.z,
        );
        let q = axpy(&q0, &sum, h / 6.0).normalized();
        let rotation = q.to_matrix();
        commit(self.name(), state, h, RigidState::new(t + h, pi, rotation))?;
        self.last = Some((rotation, q));
        Ok(())
    }
    fn reset(&mut self) {
        self.last = None;
    }
}

/// Runge-Kutta-Munthe-Kaas of order 4 on SO(3): classical RK4 in the exponential
/// coordinates of each step, `R = R_n exp(θ)`, `θ' = J_r(θ)⁻¹ Ω`, `Π' = Π × Ω + T`, then
/// `R_{n+1} = R_n exp(θ_{n+1})`. Fourth order, the attitude a rotation to round-off at
/// every stage (the Lie-group baseline users compare with, like MuJoCo's RK4 with the
/// exponential of the angular velocity per stage); conserves nothing exactly. Four torque
/// evaluations per step.
///
/// Reference: H. Munthe-Kaas, *High order Runge-Kutta methods on manifolds*, Appl. Numer.
/// Math. 29 (1999).
#[derive(Clone, Debug, Default)]
pub struct RungeKuttaMuntheKaas4;

impl RungeKuttaMuntheKaas4 {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self
    }
}

impl RotationIntegrator for RungeKuttaMuntheKaas4 {
    fn name(&self) -> &'static str {
        "RKMK4"
    }
    fn order(&self) -> u32 {
        4
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        check_step(h)?;
        let (t, r0, p0) = (state.t, state.rotation, state.pi);
        let inertia = system.inertia();
        let rates = |theta: Vec3, pi: Vec3, tt: f64| {
            let w = inertia.apply_inverse(pi);
            let r = crate::so3::rotate_right(&r0, theta);
            let dpi = pi.cross(w) + system.torque(&r, tt);
            (crate::so3::right_jacobian_inverse(theta) * w, dpi)
        };
        let (k1t, k1p) = rates(Vec3::ZERO, p0, t);
        let (k2t, k2p) = rates(k1t * (0.5 * h), p0 + k1p * (0.5 * h), t + 0.5 * h);
        let (k3t, k3p) = rates(k2t * (0.5 * h), p0 + k2p * (0.5 * h), t + 0.5 * h);
        let (k4t, k4p) = rates(k3t * h, p0 + k3p * h, t + h);
        let theta = (k1t + (k2t + k3t) * 2.0 + k4t) * (h / 6.0);
        let pi = p0 + (k1p + (k2p + k3p) * 2.0 + k4p) * (h / 6.0);
        commit(
            self.name(),
            state,
            h,
            RigidState::new(t + h, pi, crate::so3::rotate_right(&r0, theta)),
        )
    }
}
