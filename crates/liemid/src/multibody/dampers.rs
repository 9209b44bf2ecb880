//! Hinge, slide and ball dampers in the multibody step.
//!
//! A damper applies the generalized force `σ_k = −d_k q̇_k` along its coordinate gradient
//! `D_k` (`q̇_k = D_k v`): a hinge's or slide's coordinate, or the three components of a
//! ball's relative angular velocity (`−d (ω_child − ω_parent)`). The step splits it off
//! symmetrically: a forward-Euler half-kick by the dampers at the start (the start
//! velocities, `σ₀ = −d ∘ D(q) v`, added to the λ-kick), the conservative RATTLE/EA step,
//! and a backward-Euler half-kick at the end solved with the μ-kick,
//!
//! ```text
//!     Φ(h) = BE_D(h/2) ∘ RATTLE(h) ∘ FE_D(h/2),
//! ```
//!
//! every kick keeping the velocity constraints. Backward Euler is the adjoint of forward
//! Euler, so `Φ(h)` is symmetric (`Φ(−h) = Φ(h)⁻¹`) and second order, and the compositions
//! (`liemid4`…) keep their orders. A damper on a body of inertia `I` (parent held) turns
//! the joint rate by `(1 − x)/(1 + x)` per step, `x = h d/(2I)`: the trapezoidal rule,
//! A-stable, and under a constant load the rate settles at the exact creep rate.
//!
//! The drift moves at the start-kicked rate, `1 − x` times the start rate, which for
//! `x > 2` is larger than the rate itself and alternates in sign (a fast joint behind a
//! damper with `x` in the hundreds would turn its body by radians in one step). So a
//! damper row whose `x`, estimated from the row's own response `D M⁻¹ Dᵀ` (an upper
//! bound of the constrained one), exceeds 2 takes backward Euler at the start as well:
//! `σ₀` solved at the start configuration with the start forces in it, so that the rate
//! turns by `1/(1 + x)²` per step (L-stable, no ringing, the drift at `1/(1 + x)` of the
//! start rate) and the creep under a steady load is still exact. Such a row is then first
//! order, which is what an unresolved mode (`x > 2`) allows; models without one are not
//! touched.
//!
//! The implicit half-kicks are linear. At the end the velocities are
//! `v⁺(σ) = v⁺(0) + (h/2) P M⁻¹ Dᵀ σ` (`P` the projection of the velocity solve) and
//! `A = D P M⁻¹ Dᵀ` is symmetric positive semi-definite, so `σ = −d ∘ r(σ)`, `r(σ) = r₀ + (h/2) A σ`, is
//!
//! ```text
//!     (diag(1/d) + (h/2) A) σ = −r₀,
//! ```
//!
//! symmetric positive definite for `h > 0`, solved by conjugate gradients preconditioned
//! with `diag(d)` (eigenvalues of the preconditioned matrix in `[1, 1 + x]`), one solve
//! with the μ-kick's factorization per iteration (the response to the damping forces
//! alone), stopped when the residual is at 8 ulps of the rates; after `2 n + 8`
//! iterations for `n` damper rows a residual above `1e-10` of the rates is an error. The
//! start's is the same system over the stiff rows, projected with the start rows. A
//! composition's negative sub-steps make the matrix indefinite once `|h| d/(2I) ≥ 1`:
//! that is reported as a numerical error (anti-damping that strong has no stable step).
//! Dampers are not conservative: the step is then neither symplectic nor
//! energy-preserving.
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, II.3-II.5 (adjoint methods, splitting, composition); M. R. Hestenes,
//! E. Stiefel, J. Res. Nat. Bur. Standards 49 (1952) 409-436 (conjugate gradients).

use crate::error::{Error, Result};
use crate::linalg::Vec3;

use super::constraints::{add_impulse, apply, pose, Row};
use super::method::StepReport;
use super::model::JointKind;
use super::state::MultibodyState;
use super::system::MultibodySystem;
use super::workspace::{DamperScratch, Matrix, Workspace};

/// Scratch of the damper half-kicks, three rows per joint (`None`/zero where there is no
/// damper row).
impl DamperScratch {
    /// The damper rows at poses `(c, R)`, three slots per joint (row `3k + m`): a hinge's or
    /// slide's coordinate gradient in slot 0, a ball's relative angular velocity along the
    /// world axes `e_m` in slots 0-2 (`e_m·(R_j Ω_j − R_i Ω_i)`: `∂/∂Ω_i = −R_iᵀ e_m`,
    /// `∂/∂Ω_j = R_jᵀ e_m`; isotropic, so the force is `−d (ω_j − ω_i)` in any axes).
    fn gradients(&mut self, sys: &MultibodySystem, c: &[Vec3], r: &[crate::linalg::Mat3]) {
        for (k, g) in sys.joints.iter().enumerate() {
            let d = sys.params[k].damping;
            for m in 0..3 {
                self.damping[3 * k + m] = d;
                self.grad[3 * k + m] = None;
            }
            if d == 0.0 {
                continue;
            }
            let (pi, pj) = pose(g, c, r);
            if g.kind == JointKind::Ball {
                for m in 0..3 {
                    let mut e = [0.0; 3];
                    e[m] = 1.0;
                    let e = Vec3::from_array(e);
                    self.grad[3 * k + m] = Some(Row {
                        ci: Vec3::ZERO,
                        ti: -(pi.1.transpose() * e),
                        cj: Vec3::ZERO,
                        tj: pj.1.transpose() * e,
                    });
                }
            } else {
                self.grad[3 * k] = g.coordinate(pi, pj).map(|(_, row)| row);
            }
        }
    }
}

impl Workspace {
    /// The start half-kick: the damping forces at the state's velocities (`FE_D(h/2)`) into
    /// `damp_f`, `damp_t`, for the λ-kick to add; a stiff damper row (`x > 2`) instead
    /// backward Euler, solved at the start configuration (module docs). `t` and `hh = h/2`
    /// are the step's.
    pub(super) fn start_dampers(
        &mut self,
        sys: &MultibodySystem,
        state: &MultibodyState,
        t: f64,
        hh: f64,
        report: &mut StepReport,
    ) -> Result<()> {
        let mut s = core::mem::take(&mut self.dampers);
        let result = self.start_dampers_in(sys, &mut s, state, t, hh, report);
        self.dampers = s;
        result
    }

    fn start_dampers_in(
        &mut self,
        sys: &MultibodySystem,
        s: &mut DamperScratch,
        state: &MultibodyState,
        t: f64,
        hh: f64,
        report: &mut StepReport,
    ) -> Result<()> {
        s.gradients(sys, &state.c, &state.rotation);
        self.velocities(sys, &state.p, &state.pi);
        self.rates_into(sys, &s.grad, &mut s.rates0);
        let mut stiff = 0;
        for r in 0..s.sigma.len() {
            s.active[r] = false;
            s.sigma[r] = 0.0;
            let Some(row) = s.grad[r] else { continue };
            // x = (h/2) d D M⁻¹ Dᵀ: the row's own response bounds the constrained one above.
            // Up to x = 2 the trapezoidal drift's factor 1 − x stays within [−1, 1].
            let g = &sys.joints[r / 3];
            let own = |i: Option<usize>, c: Vec3, w: Vec3| {
                i.map_or(0.0, |i| {
                    c.norm_squared() / sys.mass[i]
                        + match &sys.armature {
                            None => w.dot(sys.inertia[i].apply_inverse(w)),
                            // The diagonal block of 𝕁 (a heuristic's scale).
                            Some(a) => a.own_response(i, w),
                        }
                })
            };
            let x = hh * s.damping[r] * (own(g.parent, row.ci, row.ti) + own(Some(g.child), row.cj, row.tj));
            if x > 2.0 {
                s.active[r] = true;
                stiff += 1;
            } else {
                s.sigma[r] = -s.damping[r] * s.rates0[r];
            }
        }
        if stiff > 0 {
            // The stiff rows' rates after the start half-kick by the forces and the explicit
            // rows, projected on G(q) v = 0: the force in the implicit solve makes the
            // creep under a steady load exact (σ = −F at rest), as the trapezoidal rule's.
            let any_rows = self.rows0.iter().any(|r| r.n > 0);
            if any_rows && !self.factor_rows0 {
                self.factor(sys, Matrix::Start)?;
                report.factorizations += 1;
            }
            self.set_dampers(sys, &s.grad, Some(&s.sigma));
            for i in 0..sys.mass.len() {
                s.linear[i] = state.p[i] + (self.force[i] + self.damp_f[i]) * hh;
                s.angular[i] = state.pi[i] + (self.torque[i] + self.damp_t[i]) * hh;
            }
            self.project_momenta(sys, s, hh, any_rows, true);
            self.rates_into(sys, &s.grad, &mut s.rates0);
            self.solve_dampers(sys, s, t, hh, any_rows, true)?;
        }
        self.set_dampers(sys, &s.grad, Some(&s.sigma));
        Ok(())
    }

    /// The end half-kick `BE_D(h/2)` solved with the μ-kick (module docs), `hh = h/2`, in
    /// the step from `t`.
    /// Leaves `damp_f`, `damp_t` at the solved damping and `delta` at its μ.
    pub(super) fn end_dampers(
        &mut self,
        sys: &MultibodySystem,
        t: f64,
        hh: f64,
        any_rows: bool,
        report: &mut StepReport,
    ) -> Result<()> {
        let mut s = core::mem::take(&mut self.dampers);
        let result = self.end_dampers_in(sys, &mut s, t, hh, any_rows, report);
        self.dampers = s;
        result
    }

    fn end_dampers_in(
        &mut self,
        sys: &MultibodySystem,
        s: &mut DamperScratch,
        t: f64,
        hh: f64,
        any_rows: bool,
        report: &mut StepReport,
    ) -> Result<()> {
        s.gradients(sys, &self.c_new, &self.r_new);
        // r₀: the rates without end damping; this pass also settles the active limits.
        self.set_dampers(sys, &s.grad, None);
        self.velocity_pass(sys, hh, any_rows, report)?;
        self.end_velocities(sys, hh);
        self.rates_into(sys, &s.grad, &mut s.rates0);
        for r in 0..s.sigma.len() {
            s.active[r] = s.grad[r].is_some();
            s.sigma[r] = 0.0;
        }
        self.solve_dampers(sys, s, t, hh, any_rows, false)?;
        // The μ-kick at the solved damping.
        self.set_dampers(sys, &s.grad, Some(&s.sigma));
        self.velocity_pass(sys, hh, any_rows, report)
    }

    /// Backward Euler for the active damper rows: `(diag(1/d) + (h/2) A) σ = −r₀` on them by
    /// preconditioned conjugate gradients (module docs), the other rows' forces held; `A`
    /// projected on the start rows (`start`) or the end rows, whose factorization is current.
    fn solve_dampers(
        &mut self,
        sys: &MultibodySystem,
        s: &mut DamperScratch,
        t: f64,
        hh: f64,
        any_rows: bool,
        start: bool,
    ) -> Result<()> {
        let n = s.sigma.len();
        let mut count = 0;
        let mut scale: f64 = 0.0;
        for r in 0..n {
            if s.active[r] {
                count += 1;
                scale = scale.max(s.rates0[r].abs());
            }
        }
        if scale == 0.0 {
            return Ok(());
        }
        let tol = 8.0 * f64::EPSILON * scale;
        // The residual b − Kσ at σ = 0 and the preconditioned direction d ∘ residual.
        let mut rz = 0.0;
        for r in 0..n {
            (s.residual[r], s.direction[r]) = if s.active[r] {
                (-s.rates0[r], -s.damping[r] * s.rates0[r])
            } else {
                (0.0, 0.0)
            };
            rz += s.residual[r] * s.direction[r];
        }
        let mut worst = scale;
        let mut iterations = 0;
        while worst > tol {
            if rz == 0.0 {
                break;
            }
            if iterations == 2 * count + 8 {
                // Round-off keeps the residual above 8 ulps of the rates: accept it when the
                // damping force is still right to 1e-10 of the rates, else say so.
                if worst <= 1e-10 * scale {
                    break;
                }
                return Err(Error::NewtonDidNotConverge {
                    method: self.method_name,
                    equation: "the dampers' implicit half-kick (conjugate gradients)",
                    t,
                    h: 2.0 * hh,
                    residual: worst / scale,
                    iterations: u32::try_from(iterations).unwrap_or(u32::MAX),
                });
            }
            iterations += 1;
            // K p = p / d + (h/2) A p.
            self.damper_response(sys, s, hh, any_rows, start);
            let mut pkp = 0.0;
            for r in 0..n {
                if s.active[r] {
                    s.image[r] += s.direction[r] / s.damping[r];
                    pkp += s.direction[r] * s.image[r];
                }
            }
            if pkp.is_nan() || pkp <= 0.0 {
                return Err(Error::NewtonDidNotConverge {
                    method: self.method_name,
                    equation:
                        "the dampers' implicit half-kick (indefinite: a negative sub-step with |h| d / (2 I) >= 1)",
                    t,
                    h: 2.0 * hh,
                    residual: rz.abs().sqrt(),
                    iterations: 0,
                });
            }
            let alpha = rz / pkp;
            worst = 0.0;
            let mut rz_next = 0.0;
            for r in 0..n {
                if s.active[r] {
                    s.sigma[r] += alpha * s.direction[r];
                    s.residual[r] -= alpha * s.image[r];
                    worst = worst.max(s.residual[r].abs());
                    rz_next += s.damping[r] * s.residual[r] * s.residual[r];
                }
            }
            let beta = rz_next / rz;
            rz = rz_next;
            for r in 0..n {
                if s.active[r] {
                    s.direction[r] = s.damping[r] * s.residual[r] + beta * s.direction[r];
                }
            }
        }
        Ok(())
    }

    /// `(h/2) A p` into `s.image`: the damper rows' rates after a half-kick by the damping
    /// forces `Dᵀ p` (`p = s.direction`) alone, projected on `G v = 0` with the current
    /// factorization, of the start rows (`start`) or the end rows (linear: no other
    /// momentum enters, so nothing cancels).
    fn damper_response(&mut self, sys: &MultibodySystem, s: &mut DamperScratch, hh: f64, any_rows: bool, start: bool) {
        self.set_dampers(sys, &s.grad, Some(&s.direction));
        for i in 0..sys.mass.len() {
            s.linear[i] = self.damp_f[i] * hh;
            s.angular[i] = self.damp_t[i] * hh;
        }
        self.project_momenta(sys, s, hh, any_rows, start);
        self.rates_into(sys, &s.grad, &mut s.image);
    }

    /// The velocities of the momenta `s.linear`, `s.angular` projected on `G v = 0` (the
    /// start rows or the end rows, factored), in `vel`, `omega` (the momenta are changed).
    fn project_momenta(&mut self, sys: &MultibodySystem, s: &mut DamperScratch, hh: f64, any_rows: bool, start: bool) {
        self.velocities(sys, &s.linear, &s.angular);
        if any_rows {
            self.rates_rhs(sys, start, -1.0 / hh);
            self.timed_solve(sys);
            let rows = if start { &self.rows0 } else { &self.rows1 };
            add_impulse(&sys.joints, rows, &self.delta, hh, &mut s.linear, &mut s.angular);
            self.velocities(sys, &s.linear, &s.angular);
        }
    }

    /// The damping forces `Dᵀ σ` into `damp_f`, `damp_t` (`None`: zero).
    fn set_dampers(&mut self, sys: &MultibodySystem, grad: &[Option<Row>], sigma: Option<&[f64]>) {
        self.damp_f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        self.damp_t.iter_mut().for_each(|v| *v = Vec3::ZERO);
        let Some(sigma) = sigma else { return };
        for (r, row) in grad.iter().enumerate() {
            if let Some(row) = row {
                apply(&sys.joints[r / 3], row, sigma[r], &mut self.damp_f, &mut self.damp_t);
            }
        }
    }

    /// The damper rows' rates `D_r v` at the velocities in `vel`, `omega`.
    fn rates_into(&self, sys: &MultibodySystem, grad: &[Option<Row>], rates: &mut [f64]) {
        for (r, row) in grad.iter().enumerate() {
            rates[r] = match row {
                Some(row) => {
                    let g = &sys.joints[r / 3];
                    let (vi, wi) = g
                        .parent
                        .map_or((Vec3::ZERO, Vec3::ZERO), |p| (self.vel[p], self.omega[p]));
                    row.rate(vi, wi, self.vel[g.child], self.omega[g.child])
                }
                None => 0.0,
            };
        }
    }
}
