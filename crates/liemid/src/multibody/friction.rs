//! Joint dry friction (`frictionloss` f) in the multibody step: bounded rows.
//!
//! A friction row `k` is a joint coordinate's gradient `D_k` (`q̇_k = D_k v`) with a
//! generalized force `σ_k`, `|σ_k| ≤ f_k`. In each half-kick (the λ-kick at the start, the
//! μ-kick at the end) the force is chosen after all other forces of that half-kick (the
//! applied ones, the dampers') so that the joint rate after the kick, projected on the
//! joint constraints, is
//!
//! ```text
//!     r(σ) = r₀ + K σ,   K = (h/2) D P M⁻¹ Dᵀ   (P the projection of the velocity solve),
//!     r_k = 0 where |σ_k| < f_k (stick),   σ_k = −f_k sign(r_k) otherwise (slip),
//! ```
//!
//! a box-constrained linear complementarity problem: the impulse `(h/2) σ_k` of each kick
//! is bounded by `f_k h/2`. A joint sticks exactly when the other forces on it, over the
//! half-kick, are smaller than its friction; slipping, it feels `∓f_k` in each kick, so a
//! constant force beyond the friction accelerates it at exactly `(τ − f)/I` (kick-drift-
//! kick is exact under a constant force). `K` is symmetric positive definite for `h > 0`
//! (semi-definite in general; negative in a composition's negative sub-step, where the
//! same rule, stuck or `σ = −f sign r`, holds); the problem is solved by projected
//! Gauss–Seidel (each row's own solution, the others held) on the
//! dense `K` over the friction rows (one column per row, a projected response each), to
//! 8 ulps of the rates; a solve that does not converge in `50 n + 50` sweeps is an error.
//! This is the one-row case of contact (docs/theory/multibody.md §8): a contact's normal
//! and tangential rows are bounded rows of the same solve with bounds that depend on each
//! other. The friction force is solved after the dampers' with theirs held (one block
//! Gauss–Seidel pass between the two): exact when a joint has friction or damping, and
//! when a stuck joint's damper sees no rate.
//!
//! Reference: docs/theory/multibody.md §8; J. J. Moreau, "Unilateral contact and dry
//! friction in finite freedom dynamics", 1988; D. Stewart, J. Trinkle, IJNME 39 (1996).

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};

use super::constraints::{add_impulse, apply, pose, Row};
use super::method::StepReport;
use super::system::MultibodySystem;
use super::workspace::{FrictionScratch, Matrix, Workspace};

impl Workspace {
    /// The start half-kick's friction at the state `(c, R)` with momenta `p`, `Π`: adds
    /// `Dᵀσ` to `damp_f`, `damp_t` (which hold the dampers' start forces, or zero), so
    /// that the λ-kick's joint rates stick or slip (module docs). `hh = h/2`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn start_friction(
        &mut self,
        sys: &MultibodySystem,
        (c, r): (&[Vec3], &[Mat3]),
        (p, pi): (&[Vec3], &[Vec3]),
        t: f64,
        hh: f64,
        report: &mut StepReport,
    ) -> Result<()> {
        let any_rows = self.rows0.iter().any(|r| r.n > 0);
        if any_rows && !self.factor_rows0 {
            self.factor(sys, Matrix::Start)?;
            report.factorizations += 1;
        }
        let mut s = core::mem::take(&mut self.friction);
        for i in 0..sys.mass.len() {
            s.linear[i] = p[i] + (self.force[i] + self.damp_f[i]) * hh;
            s.angular[i] = pi[i] + (self.torque[i] + self.damp_t[i]) * hh;
        }
        let result = self.solve_friction(sys, &mut s, (c, r), t, hh, any_rows, true);
        self.friction = s;
        result
    }

    /// The end half-kick's friction with the μ-kick: at the end configuration, after the
    /// forces `force1` and the end dampers in `damp_f`, `damp_t` (to which it adds `Dᵀσ`).
    pub(super) fn end_friction(&mut self, sys: &MultibodySystem, t: f64, hh: f64, any_rows: bool) -> Result<()> {
        let mut s = core::mem::take(&mut self.friction);
        for i in 0..sys.mass.len() {
            s.linear[i] = self.p_half[i] + (self.force1[i] + self.damp_f[i]) * hh;
            s.angular[i] = self.pi_new[i] + (self.torque1[i] + self.damp_t[i]) * hh;
        }
        let c = core::mem::take(&mut self.c_new);
        let r = core::mem::take(&mut self.r_new);
        let result = self.solve_friction(sys, &mut s, (&c, &r), t, hh, any_rows, false);
        self.c_new = c;
        self.r_new = r;
        self.friction = s;
        result
    }

    /// The bounded rows' problem (module docs) from the momenta in `s.linear`,
    /// `s.angular`, by projected Gauss–Seidel; the forces added to `damp_f`, `damp_t`.
    #[allow(clippy::too_many_arguments)]
    fn solve_friction(
        &mut self,
        sys: &MultibodySystem,
        s: &mut FrictionScratch,
        (c, r): (&[Vec3], &[Mat3]),
        t: f64,
        hh: f64,
        any_rows: bool,
        start: bool,
    ) -> Result<()> {
        let n = s.joints.len();
        for (m, &k) in s.joints.iter().enumerate() {
            let g = &sys.joints[k];
            let (pi, pj) = pose(g, c, r);
            s.grad[m] = g.coordinate(pi, pj).map(|(_, row)| row);
        }
        // r₀: the rates after the kick without friction.
        self.project(sys, &mut s.linear, &mut s.angular, hh, any_rows, start);
        self.friction_rates(sys, &s.grad, &s.joints, &mut s.rates0);
        // K, column by column: the rates after a half-kick by a unit force on one row.
        for col in 0..n {
            s.linear.iter_mut().for_each(|v| *v = Vec3::ZERO);
            s.angular.iter_mut().for_each(|v| *v = Vec3::ZERO);
            if let Some(row) = &s.grad[col] {
                apply(&sys.joints[s.joints[col]], row, hh, &mut s.linear, &mut s.angular);
            }
            self.project(sys, &mut s.linear, &mut s.angular, hh, any_rows, start);
            self.friction_rates(sys, &s.grad, &s.joints, &mut s.rates);
            s.k[col * n..(col + 1) * n].copy_from_slice(&s.rates);
        }
        // Projected Gauss–Seidel on r = r₀ + K σ, |σ_k| ≤ f_k.
        let scale = s.rates0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        s.sigma.iter_mut().for_each(|x| *x = 0.0);
        s.rates.copy_from_slice(&s.rates0);
        if scale > 0.0 {
            let tol = 8.0 * f64::EPSILON * scale;
            let mut sweeps = 0;
            loop {
                let mut worst: f64 = 0.0;
                for m in 0..n {
                    let kmm = s.k[m * n + m];
                    if kmm == 0.0 {
                        continue;
                    }
                    // Row m alone, the others held: r_m(σ) = ρ + K_mm σ; stuck if the root
                    // is within the bound, else σ = −f sign ρ (the same as the clamp of the
                    // root when K_mm > 0; also right in a negative sub-step, K_mm < 0).
                    let rho = s.rates[m] - kmm * s.sigma[m];
                    let root = -rho / kmm;
                    let next = if root.abs() <= s.bound[m] {
                        root
                    } else {
                        -s.bound[m] * rho.signum()
                    };
                    let d = next - s.sigma[m];
                    if d != 0.0 {
                        s.sigma[m] = next;
                        for (i, ri) in s.rates.iter_mut().enumerate() {
                            *ri += s.k[m * n + i] * d;
                        }
                    }
                }
                for m in 0..n {
                    // The rate of a stuck row is 0; of a slipping one, against its force.
                    let stuck = s.sigma[m].abs() < s.bound[m];
                    let violation = if stuck {
                        s.rates[m].abs()
                    } else {
                        (s.rates[m] * s.sigma[m].signum()).max(0.0)
                    };
                    worst = worst.max(violation);
                }
                sweeps += 1;
                if worst <= tol {
                    break;
                }
                if sweeps >= 50 * n + 50 {
                    if worst <= 1e-10 * scale {
                        break;
                    }
                    return Err(Error::NewtonDidNotConverge {
                        method: self.method_name,
                        equation: "the joint friction rows (projected Gauss-Seidel)",
                        t,
                        h: 2.0 * hh,
                        residual: worst / scale,
                        iterations: u32::try_from(sweeps).unwrap_or(u32::MAX),
                    });
                }
            }
        }
        for (m, row) in s.grad.iter().enumerate() {
            if let Some(row) = row {
                apply(
                    &sys.joints[s.joints[m]],
                    row,
                    s.sigma[m],
                    &mut self.damp_f,
                    &mut self.damp_t,
                );
            }
        }
        Ok(())
    }

    /// The velocities of the momenta `lin`, `ang` projected on `G v = 0` (the start rows or
    /// the end rows, factored) into `vel`, `omega` (the momenta are changed).
    pub(super) fn project(
        &mut self,
        sys: &MultibodySystem,
        lin: &mut [Vec3],
        ang: &mut [Vec3],
        hh: f64,
        any_rows: bool,
        start: bool,
    ) {
        self.velocities(sys, lin, ang);
        if any_rows {
            self.rates_rhs(sys, start, -1.0 / hh);
            self.timed_solve(sys);
            let rows = if start { &self.rows0 } else { &self.rows1 };
            add_impulse(&sys.joints, rows, &self.delta, hh, lin, ang);
            self.velocities(sys, lin, ang);
        }
    }

    /// The velocities (in `vel`, `omega`) of the momenta `lin`, `ang` projected on the
    /// start rows, factored (the response of a unit impulse, for the step check).
    pub(super) fn project_response(
        &mut self,
        sys: &MultibodySystem,
        lin: &mut [Vec3],
        ang: &mut [Vec3],
        any_rows: bool,
    ) {
        self.project(sys, lin, ang, 1.0, any_rows, true);
    }

    /// The friction rows' rates at the velocities in `vel`, `omega`.
    fn friction_rates(&self, sys: &MultibodySystem, grad: &[Option<Row>], joints: &[usize], rates: &mut [f64]) {
        for ((out, row), &k) in rates.iter_mut().zip(grad).zip(joints) {
            *out = row.as_ref().map_or(0.0, |row| {
                let g = &sys.joints[k];
                let (vi, wi) = g
                    .parent
                    .map_or((Vec3::ZERO, Vec3::ZERO), |p| (self.vel[p], self.omega[p]));
                row.rate(vi, wi, self.vel[g.child], self.omega[g.child])
            });
        }
    }
}
