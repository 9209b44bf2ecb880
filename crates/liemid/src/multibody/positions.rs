//! The position solve of the multibody step: the drift as a function of the multipliers
//! `λ` and the quasi-Newton iteration on `g(q⁺(λ)) = 0` (docs/theory/multibody.md §3).
//!
//! The drift with `λ`: `p½ = p + (h/2)(F + G_cᵀλ)`, `P = Π + (h/2)(T + G_θᵀλ)`,
//! `c⁺ = c + h M⁻¹ p½`, and EA's torque-free rotation, two midpoint solves (M) of step
//! `h/2`. Its exact Jacobian in `λ` is `(h²/2) G(q⁺) D G(q)ᵀ` with `D = M⁻¹ + O(h)` (the
//! drift's derivative in the impulse), so `(h²/2) G(q) M⁻¹ G(q)ᵀ` is a quasi-Newton matrix
//! with an `O(h)` relative error, as the end-row matrix `(h²/2) G(q⁺) M⁻¹ G(q)ᵀ` of docs/theory/multibody.md §3: the iteration
//! contracts by `O(h)` per step either way. It is the matrix that the previous step's
//! velocity solve factored (same configuration, same rows), so a step factors once. When a
//! correction reduces the residual by less than 4x (fast spin about an axis of small
//! inertia), the exact Jacobian at the current iterate is factored instead.
//!
//! The `O(h)` difference between the two matrices is mostly the rows turning with the
//! bodies over the step; the end-row matrix has only the drift's `D − M⁻¹` left. A correction
//! can therefore be refined toward the end-row system with the factored start matrix, by
//! products with `G(q⁺) M⁻¹ G(q)ᵀ` and solves, no drift
//! ([`Workspace::refine_correction`]); it is done when the contractions learned so
//! far say it saves position iterations (the double pendulum: yes, 3.43 → 1.25 iterations
//! per stage of liemid4 at h = 1e-2). Where the drift's own `D − M⁻¹` is not small (a
//! spinning body, a swinging chain at a long step) the correction is refined toward the
//! exact Jacobian `G(q⁺) D G(q)ᵀ` instead, with `D` from [`Workspace::drift_jacobian`]
//! in the products: the outer iteration is then Newton's (the spacecraft's liemid8 at
//! h = 1e-2: 5.42 → 2.01 iterations per stage, 165 → 136 µs per step; chain-10 at 1e-3:
//! 3.42 → 1.12, 18.8 → 16.6 µs). Each kind's contraction is learned and the one that
//! predicts the fewest iterations taken (the cheaper on a tie).
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, VII.1 (RATTLE, its simplified Newton iteration); P. Krysl, Int. J.
//! Numer. Meth. Engng 63 (2005) (LIEMID\[EA\]).

use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};
use crate::midpoint::newton_error;
use crate::midpoint::{self, NotConverged};
use crate::so3;
use crate::variational;

use super::constraints::{add_impulse, for_each_rate, pose, JointRows};
use super::method::{Drift, LimitState, StepReport, MAX_ITERATIONS};
use super::state::MultibodyState;
use super::system::MultibodySystem;
use super::workspace::{Matrix, Workspace};

/// The torque-free rotation of one body over `2 hh`: `Ψ₁` from (M) (EA's, [`Drift::Midpoint`])
/// or (V) (EAV's, [`Drift::Variational`]) with `(P, hh)`, `Π_a = exp(−Ψ₁) P`, `Ψ₂` from the
/// same equation with `(Π_a, hh)`; returns `exp(Ψ₁)`, `Π_a`, `exp(Ψ₂)`. With `guess`,
/// Newton starts from the last drift's `(Ψ₁, Ψ₂)` instead of the predictor. Inlined into the
/// drift's loop with the solver's own small error (the step's error is built only on
/// failure).
///
/// Reference: P. Krysl, Int. J. Numer. Meth. Engng 63 (2005) (LIEMID\[EA\]);
/// docs/theory/rigid.md §9 (the variational drift).
#[inline(always)]
fn drift_pair(
    drift: Drift,
    inertia: &Inertia,
    p: Vec3,
    hh: f64,
    guess: Option<(Vec3, Vec3)>,
) -> core::result::Result<(so3::Increment, Vec3, so3::Increment), NotConverged> {
    let solve = |p: Vec3, guess: Option<Vec3>| match (drift, guess) {
        (Drift::Midpoint, Some(g)) => midpoint::solve_increment_from(inertia, p, hh, g),
        (Drift::Midpoint, None) => midpoint::solve_increment(inertia, p, hh),
        (Drift::Variational, Some(g)) => variational::solve_increment_from(inertia, p, hh, g),
        (Drift::Variational, None) => variational::solve_increment(inertia, p, hh),
    };
    let (inc1, _) = solve(p, guess.map(|g| g.0))?;
    let pa = inc1.inverse_apply(p);
    let (inc2, _) = solve(pa, guess.map(|g| g.1))?;
    Ok((inc1, pa, inc2))
}

/// The larger of `acc` and `v`, NaN once either is (`f64::max` drops a NaN, and a NaN
/// residual must stop the solve, not pass for zero).
#[inline]
fn max_or_nan(acc: f64, v: f64) -> f64 {
    if v > acc || v.is_nan() {
        v
    } else {
        acc
    }
}

/// `dst += scale src` over the active rows of each joint (`scale` ±1: exact).
#[inline]
fn add_rows(rows: &[JointRows], scale: f64, src: &[[f64; 6]], dst: &mut [[f64; 6]]) {
    for ((jr, s), d) in rows.iter().zip(src).zip(dst) {
        for (d, s) in d[..jr.n].iter_mut().zip(&s[..jr.n]) {
            *d += scale * s;
        }
    }
}

/// Most passes of [`Workspace::refine_correction`] per position iteration.
const REFINE_PASSES: usize = 3;
/// Most passes toward the exact drift Jacobian (each gains `O(h |Ω|)`).
const EXACT_REFINE_PASSES: usize = 8;

/// The correction of a position iteration: the start matrix's, refined toward the end-row
/// `G(q⁺) M⁻¹ G(q)ᵀ`, or refined toward the exact Jacobian `G(q⁺) D G(q)ᵀ`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Refine {
    None,
    Spec,
    Exact,
}

impl Workspace {
    /// The drift with multipliers `self.lambda`: `p½`, `P`, then `c⁺`, `R⁺`, `Π'`. With
    /// `warm`, the midpoint solves start from the last drift's `Ψ₁`, `Ψ₂` (the same stage,
    /// `λ` changed by a quasi-Newton correction) instead of the predictor: one Newton
    /// iteration each instead of two on the spacecraft's hub.
    pub(super) fn drift(&mut self, sys: &MultibodySystem, state: &MultibodyState, h: f64, warm: bool) -> Result<()> {
        let hh = 0.5 * h;
        self.p_half.copy_from_slice(&self.pb);
        self.big_p.copy_from_slice(&self.pib);
        add_impulse(
            &sys.joints,
            &self.rows0,
            &self.lambda,
            hh,
            &mut self.p_half,
            &mut self.big_p,
        );
        if let Some(arm) = &sys.armature {
            return self.coupled_drift(arm, sys, state, h, warm);
        }
        for i in 0..sys.mass.len() {
            self.c_new[i] = state.c[i] + self.p_half[i] * (h / sys.mass[i]);
            let guess = warm.then_some((self.psi1[i], self.psi2[i]));
            let (inc1, pa, inc2) = match drift_pair(self.drift, &sys.inertia[i], self.big_p[i], hh, guess) {
                Ok(v) => v,
                Err(e) => {
                    let equation = match self.drift {
                        Drift::Midpoint => "midpoint equation (M)",
                        Drift::Variational => "variational equation (V)",
                    };
                    return Err(newton_error(self.method_name, equation, state.t, h, e));
                }
            };
            self.psi1[i] = inc1.psi();
            self.psi2[i] = inc2.psi();
            self.pi_a[i] = pa;
            self.r_new[i] = inc2.rotate(&inc1.rotate(&state.rotation[i]));
            self.pi_new[i] = inc2.inverse_apply(pa);
        }
        Ok(())
    }

    /// The drift with hinge armature: `c⁺` as without, the rotations by two coupled solves
    /// over the tree (`Ψ₁` from `P`, `Π_a = exp(−Ψ₁) P`, `Ψ₂` from `Π_a`, each with `h/2`),
    /// each body's spatial momentum `R_i Π_i` kept (docs/theory/multibody.md §7).
    fn coupled_drift(
        &mut self,
        arm: &super::armature::Armature,
        sys: &MultibodySystem,
        state: &MultibodyState,
        h: f64,
        warm: bool,
    ) -> Result<()> {
        let hh = 0.5 * h;
        let nb = sys.mass.len();
        for i in 0..nb {
            self.c_new[i] = state.c[i] + self.p_half[i] * (h / sys.mass[i]);
        }
        let fail = |e| {
            let equation = match self.drift {
                Drift::Midpoint => "coupled midpoint equation (M) with armature",
                Drift::Variational => "coupled variational equation (V) with armature",
            };
            newton_error(self.method_name, equation, state.t, h, e)
        };
        // The two solves' factors from the last drift, kept while the iteration is warm
        // (the same stage, corrections small); invalid until both solves succeed again.
        let reuse = warm && self.arm_factored;
        self.arm_factored = false;
        let (dinv1, dinv2) = self.arm_dinv.split_at_mut(nb);
        super::armature::coupled_increments(
            arm,
            &sys.inertia,
            self.drift,
            &self.big_p,
            hh,
            warm,
            reuse,
            &mut self.psi1,
            dinv1,
            &mut self.arm_g,
        )
        .map_err(fail)?;
        for i in 0..nb {
            let inc1 = so3::Increment::new(self.psi1[i]);
            self.pi_a[i] = inc1.inverse_apply(self.big_p[i]);
            self.r_new[i] = inc1.rotate(&state.rotation[i]);
        }
        super::armature::coupled_increments(
            arm,
            &sys.inertia,
            self.drift,
            &self.pi_a,
            hh,
            warm,
            reuse,
            &mut self.psi2,
            dinv2,
            &mut self.arm_g,
        )
        .map_err(fail)?;
        self.arm_factored = true;
        for i in 0..nb {
            let inc2 = so3::Increment::new(self.psi2[i]);
            self.r_new[i] = inc2.rotate(&self.r_new[i]);
            self.pi_new[i] = inc2.inverse_apply(self.pi_a[i]);
        }
        Ok(())
    }

    /// Largest scaled `|g|` of `rows`.
    pub(super) fn residual(&self, sys: &MultibodySystem, rows: &[JointRows]) -> f64 {
        let mut r: f64 = 0.0;
        for jr in rows {
            for k in 0..jr.n {
                let v = jr.value[k].abs();
                r = max_or_nan(r, if jr.length[k] { v / sys.length } else { v });
            }
        }
        r
    }

    /// The exact Jacobian `D = ∂θ⁺/∂P` of the drift's rotation (body-frame increment of
    /// `R⁺` per start impulse `δP`), from the last drift: with `J_k` the Jacobians of the
    /// drift's equation and `K(Ψ)` the derivative of its right-hand side in `P`
    /// (`exp(−Ψ/2)` for (M), `Jr(Ψ)` for (V)), `A₁ = J₁⁻¹ K(Ψ₁) h/2`,
    /// `B = exp(−Ψ₁)(1 + hat(P) Jr(−Ψ₁) A₁)`, `A₂ = J₂⁻¹ K(Ψ₂) (h/2) B`,
    /// `D = exp(−Ψ₂) Jr(Ψ₁) A₁ + Jr(Ψ₂) A₂`; stored as the effective inertia `h D⁻¹`
    /// (`= I` to leading order in `h`).
    pub(super) fn drift_jacobian(&mut self, sys: &MultibodySystem, h: f64) {
        let hh = 0.5 * h;
        for i in 0..sys.mass.len() {
            let (psi1, psi2) = (self.psi1[i], self.psi2[i]);
            let inertia = &sys.inertia[i];
            let (j1, j2, k1, k2) = match self.drift {
                Drift::Midpoint => (
                    midpoint::jacobian(inertia, self.big_p[i], hh, psi1),
                    midpoint::jacobian(inertia, self.pi_a[i], hh, psi2),
                    so3::exp(-psi1 * 0.5),
                    so3::exp(-psi2 * 0.5),
                ),
                Drift::Variational => (
                    variational::jacobian(inertia, self.big_p[i], hh, psi1),
                    variational::jacobian(inertia, self.pi_a[i], hh, psi2),
                    so3::right_jacobian(psi1),
                    so3::right_jacobian(psi2),
                ),
            };
            let (Some(j1i), Some(j2i)) = (j1.inverse(), j2.inverse()) else {
                self.effective[i] = sys.inertia_matrix[i];
                self.drift_rate[i] = sys.inertia_matrix[i].inverse().unwrap_or(Mat3::IDENTITY);
                continue;
            };
            let a1 = j1i * k1 * hh;
            let e1 = so3::exp(-psi1);
            let b = e1 + e1 * so3::hat(self.big_p[i]) * so3::right_jacobian(-psi1) * a1;
            let a2 = j2i * k2 * b * hh;
            let d = so3::exp(-psi2) * so3::right_jacobian(psi1) * a1 + so3::right_jacobian(psi2) * a2;
            if let Some(d_inverse) = d.inverse() {
                self.effective[i] = d_inverse * h;
                self.drift_rate[i] = d * (1.0 / h);
            } else {
                self.effective[i] = sys.inertia_matrix[i];
                self.drift_rate[i] = sys.inertia_matrix[i].inverse().unwrap_or(Mat3::IDENTITY);
            }
        }
    }

    /// The quasi-Newton iteration for λ.
    pub(super) fn solve_positions(
        &mut self,
        sys: &MultibodySystem,
        state: &MultibodyState,
        h: f64,
        report: &mut StepReport,
    ) -> Result<()> {
        let any_rows = self.rows0.iter().any(|r| r.n > 0);
        let mut prev = f64::INFINITY;
        let mut factored = false;
        // Whether the factored matrix is the start one `G(q) M⁻¹ G(q)ᵀ` (not the exact).
        let mut start_matrix = false;
        // With armature the drift's Jacobian is not block diagonal: the plain quasi-Newton
        // iteration only (no refinement, no exact matrix).
        let refine = !self.solver.has_loops() && sys.armature.is_none();
        // Whether the last correction was refined (`None`: no correction yet).
        let mut refined: Option<Refine> = None;
        let mut it = 0;
        loop {
            // Warm midpoint starts once the corrections are small (a long step's first
            // corrections can move Ψ farther than the predictor's error).
            self.drift(sys, state, h, prev <= 1e-6)?;
            self.end_rows(sys);
            if !any_rows {
                return Ok(());
            }
            let r = self.residual(sys, &self.rows1);
            let extent = self.c_new.iter().fold(0.0f64, |m, c| m.max(c.max_abs()));
            let floor = 16.0 * f64::EPSILON * (1.0 + extent / sys.length);
            if let Some(was) = refined {
                // Learn the contraction of each kind of correction (log-average).
                let rho = (r / prev).clamp(1e-12, 1.0).ln();
                let est = match was {
                    Refine::Exact => &mut self.rho_exact,
                    Refine::Spec => &mut self.rho_refined,
                    Refine::None => &mut self.rho_plain,
                };
                *est = 0.75 * *est + 0.25 * rho;
            }
            if r <= floor || (r <= 1e-12 && r > 0.5 * prev) {
                report.position_violation = report.position_violation.max(r);
                return Ok(());
            }
            if it >= MAX_ITERATIONS || !r.is_finite() {
                return Err(Error::NewtonDidNotConverge {
                    method: self.method_name,
                    equation: "position constraints g(q+(lambda)) = 0",
                    t: state.t,
                    h,
                    residual: r,
                    iterations: it,
                });
            }
            if !factored {
                // First `G(q) M⁻¹ G(q)ᵀ`, usually factored already by the previous velocity
                // solve; when that converges slowly (fast spin about an axis of small
                // inertia), the exact drift Jacobian at the current iterate.
                if !self.factor_rows0 {
                    self.factor(sys, Matrix::Start)?;
                    report.factorizations += 1;
                }
                factored = true;
                start_matrix = true;
            } else if r > 0.25 * prev && sys.armature.is_none() {
                self.drift_jacobian(sys, h);
                self.factor(sys, Matrix::Exact)?;
                report.factorizations += 1;
                start_matrix = false;
            }
            let s = -2.0 / (h * h);
            for (k, jr) in self.rows1.iter().enumerate() {
                for r in 0..jr.n {
                    self.rhs[k][r] = jr.value[r] * s;
                }
            }
            self.timed_solve(sys);
            // Refine when, by the learned contractions, it saves position iterations.
            let need = (floor / r).ln();
            let iterations = |rho: f64| (need / rho.min(-1e-3)).ceil();
            let choice = if !(refine && start_matrix) {
                Refine::None
            } else {
                let (plain, spec, exact) = (
                    iterations(self.rho_plain),
                    iterations(self.rho_refined),
                    iterations(self.rho_exact),
                );
                if exact < spec.min(plain) {
                    Refine::Exact
                } else if spec < plain {
                    Refine::Spec
                } else {
                    Refine::None
                }
            };
            match choice {
                Refine::None => {}
                Refine::Spec => self.refine_correction(sys, h, floor, false),
                Refine::Exact => {
                    self.drift_jacobian(sys, h);
                    self.refine_correction(sys, h, floor, true);
                }
            }
            // Only corrections with the start matrix teach the estimates (after the exact
            // matrix is factored the contraction is Newton's, of no kind above).
            refined = start_matrix.then_some(choice);
            add_rows(&self.rows1, 1.0, &self.delta, &mut self.lambda);
            prev = r;
            it += 1;
            report.iterations += 1;
        }
    }

    /// Refine the correction `δ = B⁻¹ b` of the start matrix `B = G(q) M⁻¹ G(q)ᵀ` toward the
    /// solution of the end-row quasi-Newton system `A δ = b`, `A = G(q⁺) M⁻¹ G(q)ᵀ`
    /// (docs/theory/multibody.md §3, `q⁺` the current iterate), by the inner iteration
    /// `δ ← δ + B⁻¹ (b − A δ)`: a product with `A` (the impulse `G(q)ᵀ δ`, `M⁻¹`, the
    /// rates of the rows at `q⁺`) and a solve with the factored `B` each, no drift. `B`
    /// differs from `A` by `O(h)` (the rows turn with the bodies over the step), so each pass
    /// gains that factor; `A` differs from the exact Jacobian `G(q⁺) D G(q)ᵀ` only by the
    /// drift's `D − M⁻¹`, which is small unless a body spins fast. Stops when the linear
    /// residual `(h²/2)|b − A δ|` is below the floor of the position solve, or after
    /// [`REFINE_PASSES`] passes. Only the path to the root changes: the iteration still
    /// stops on the residual of `g(q⁺(λ))` itself. The position solve refines when the
    /// contractions it has seen (log-averages of `r_{k+1}/r_k` with and without refinement,
    /// starting at `1e-6` and `1e-2`) predict fewer iterations to the floor. Measured on the
    /// double pendulum, liemid4 at h = 1e-2: 3.43 → 1.25 position iterations (drifts) per
    /// stage, 4.34 → 3.52 µs per stage (`examples/profile_multibody.rs`).
    ///
    /// Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd
    /// ed., Springer 2006, VII.1 (the simplified Newton iteration of RATTLE).
    ///
    /// With `exact`, `A` is the exact Jacobian `G(q⁺) D G(q)ᵀ` (the drift's rotation per
    /// impulse `D`, [`Workspace::drift_jacobian`], in place of `I⁻¹`): the passes
    /// then converge to Newton's correction, gaining `O(h |Ω|)` each, up to
    /// `EXACT_REFINE_PASSES`.
    fn refine_correction(&mut self, sys: &MultibodySystem, h: f64, floor: f64, exact: bool) {
        let g_scale = 0.5 * h * h;
        let mut last = f64::INFINITY;
        for _ in 0..if exact { EXACT_REFINE_PASSES } else { REFINE_PASSES } {
            self.vel.iter_mut().for_each(|v| *v = Vec3::ZERO);
            self.omega.iter_mut().for_each(|v| *v = Vec3::ZERO);
            add_impulse(
                &sys.joints,
                &self.rows0,
                &self.delta,
                1.0,
                &mut self.vel,
                &mut self.omega,
            );
            for i in 0..sys.mass.len() {
                self.vel[i] = self.vel[i] * (1.0 / sys.mass[i]);
                self.omega[i] = if exact {
                    self.drift_rate[i] * self.omega[i]
                } else {
                    sys.inertia[i].apply_inverse(self.omega[i])
                };
            }
            let mut worst: f64 = 0.0;
            let (rhs, inner_rhs, length) = (&self.rhs, &mut self.inner_rhs, sys.length);
            for_each_rate(&sys.joints, &self.rows1, &self.vel, &self.omega, |k, r, rate| {
                let res = rhs[k][r] - rate;
                inner_rhs[k][r] = res;
                let v = (res * g_scale).abs();
                worst = max_or_nan(worst, if self.rows1[k].length[r] { v / length } else { v });
            });
            if worst <= floor {
                return;
            }
            if worst > last {
                // The passes diverge (a step too long for the spin): take back the last.
                add_rows(&self.rows1, -1.0, &self.inner_delta, &mut self.delta);
                return;
            }
            last = worst;
            let start = self.profiling.then(std::time::Instant::now);
            self.solver.solve(&sys.pairs, &self.inner_rhs, &mut self.inner_delta);
            if let Some(start) = start {
                self.solver_time += start.elapsed();
            }
            add_rows(&self.rows1, 1.0, &self.inner_delta, &mut self.delta);
        }
    }

    /// Switch limits on where the end coordinate crossed a bound, off where the multiplier
    /// pulls. Returns whether anything changed.
    pub(super) fn update_limits_after_positions(&mut self, sys: &MultibodySystem) -> bool {
        let mut changed = false;
        for k in 0..sys.joints.len() {
            let Some((lo, hi)) = sys.params[k].range else { continue };
            let base = sys.joints[k].kind.rows();
            match self.limit[k] {
                LimitState::Inactive => {
                    let g = &sys.joints[k];
                    let (pi, pj) = pose(g, &self.c_new, &self.r_new);
                    if let Some((q, _)) = g.coordinate(pi, pj) {
                        if q < lo || q > hi {
                            self.limit[k] = if q < lo { LimitState::Lower } else { LimitState::Upper };
                            self.lambda[k][base] = 0.0;
                            changed = true;
                        }
                    }
                }
                LimitState::Lower | LimitState::Upper => {
                    let l = self.lambda[k][base];
                    let pulls = if self.limit[k] == LimitState::Lower {
                        l < 0.0
                    } else {
                        l > 0.0
                    };
                    if pulls {
                        self.limit[k] = LimitState::Inactive;
                        self.lambda[k][base] = 0.0;
                        changed = true;
                    }
                }
            }
        }
        changed
    }
}
