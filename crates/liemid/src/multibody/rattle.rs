//! The multibody step: RATTLE with the rotation of LIEMID\[EA\] (docs/theory/multibody.md §3).
//!
//! ```text
//! 1. λ-kick  p½ = p + (h/2)(F(q) + G_c(q)ᵀλ),   P = Π + (h/2)(T(q) + G_θ(q)ᵀλ)
//! 2. drift   c⁺ = c + h M⁻¹ p½;  (P, h/2) → Ψ₁, R_a = R exp(Ψ₁), Π_a = exp(−Ψ₁) P;
//!            (Π_a, h/2) → Ψ₂, R⁺ = R_a exp(Ψ₂), Π' = exp(−Ψ₂) Π_a;   g(c⁺, R⁺) = 0 fixes λ
//! 3. μ-kick  p⁺ = p½ + (h/2)(F(q⁺) + G_c(q⁺)ᵀμ),  Π⁺ = Π' + (h/2)(T(q⁺) + G_θ(q⁺)ᵀμ),
//!            G(q⁺)(v⁺, Ω⁺) = 0 fixes μ
//! ```
//!
//! λ comes from a quasi-Newton iteration on `g(q⁺(λ)) = 0` (`positions.rs`) with the
//! matrix `(h²/2) G(q) M⁻¹ G(q)ᵀ`, which the previous step's velocity solve has factored
//! (block Cholesky, `cholesky.rs`; the exact drift Jacobian at the current iterate
//! when the residual falls by less than 4x), started from `λ` extrapolated from the last
//! stages and run until the residual is at round-off; μ from one linear solve
//! (`velocities.rs`). One factorization per step. The end forces are the next
//! step's start forces. Symmetric (not symplectic: EA's midpoint drift, docs/theory/rigid.md
//! §9); keeps the total
//! linear and angular momentum when the forces and joints do.
//!
//! **Dampers** (hinge, slide and ball `damping`) are not conservative and make the step
//! neither symplectic nor energy-preserving. They are split off symmetrically
//! (`dampers.rs`): an explicit half-kick at the start velocities and an implicit one solved
//! with the μ-kick (conjugate gradients, one solve per iteration): the trapezoidal rule,
//! second order and A-stable; a row stiffer than `x = h d/(2I) = 2` takes backward Euler
//! at the start too (L-stable, first order).
//!
//! **Joint limits** are unilateral: a limit becomes an active equality row `q − bound = 0`
//! in a step whose position solve would cross it, and the step is redone with it; an
//! active row whose multiplier pulls (λ < 0 at a lower, > 0 at an upper bound) is released
//! and the step redone. The velocity row of an active limit makes the contact plastic
//! (zero rebound), so a step with a limit change loses the normal kinetic energy: the
//! method is symmetric only away from those steps, and first order at the impact instant.
//!
//! **Armature** on hinges (rotor inertia added in joint space) is exact: the rotational
//! kinetic energy becomes the constant form `½ Wᵀ 𝕁 W`, the drift one coupled solve over the
//! tree and the constraint solves see `𝕁` in tree order (`armature.rs`,
//! docs/theory/multibody.md §7); armature on other joints is refused.
//!
//! **Actuators** act as springs (their position part, a force of the configuration) and
//! dampers (their `kv`, held by the implicit damper half-kicks); **joint friction**
//! (`frictionloss`) is a bounded force chosen in both half-kicks (`friction.rs`), so a
//! joint sticks exactly when the other forces are smaller (docs/theory/multibody.md §8).
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, VII.1; B. Leimkuhler, S. Reich, *Simulating Hamiltonian Dynamics*,
//! Cambridge 2004, ch. 7-8; P. Krysl, Int. J. Numer. Meth. Engng 63 (2005) (LIEMID\[EA\]).

use crate::error::{Error, Result};
use crate::linalg::Vec3;

use super::method::{Drift, LimitState, MultibodyMethod, StepReport, MAX_LIMIT_PASSES};
use super::predictor::{extrapolate, push_front};
use super::state::MultibodyState;
use super::system::MultibodySystem;
use super::workspace::{Workspace, HISTORY};

/// The multibody integrator: the method (RATTLE/EA or a composition of it) and its
/// working memory, sized for one [`MultibodySystem`]; `step(&system, &mut state, h)`
/// allocates nothing.
///
/// Reference: docs/theory/multibody.md §3-§4.
pub struct Rattle {
    pub(super) method: MultibodyMethod,
    pub(super) work: Workspace,
}

impl core::fmt::Debug for Rattle {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Rattle")
            .field("method", &self.method)
            .field("bodies", &self.work.c_new.len())
            .field("joints", &self.work.lambda.len())
            .finish_non_exhaustive()
    }
}

impl Rattle {
    /// Factor the start's constraint matrix `G M⁻¹ Gᵀ` at `state` once, to find before
    /// the first step a model whose rows are dependent there (a body of zero mass or
    /// inertia, a joint set with redundant rows). The cache is left invalid, so the first
    /// step computes exactly what it computes without this check.
    pub(super) fn check_start_rows(
        &mut self,
        system: &MultibodySystem,
        state: &MultibodyState,
    ) -> core::result::Result<(), super::blocks::SingularPivot> {
        let w = &mut self.work;
        w.start_rows_at(system, state);
        let result = w
            .solver
            .factor_symmetric(&system.mass, system.rotational_blocks(), &system.pairs, &w.rows0);
        w.reset();
        result
    }

    /// The integrator of `system` by `method`: every scratch array and the tree
    /// factorization sized once.
    #[must_use]
    pub fn new(system: &MultibodySystem, method: MultibodyMethod) -> Self {
        let stages = method.scheme().map_or(0, |s| s.stages());
        Rattle {
            method,
            work: Workspace::new(system, method.name(), stages),
        }
    }

    /// The torque-free rotation of the drift ([`Drift::Midpoint`] by default).
    #[must_use]
    pub fn drift(&self) -> Drift {
        self.work.drift
    }

    /// Choose the torque-free rotation of the drift: EA's midpoint pair (the default) or the
    /// variational pair of LIEMID\[EAV\], a Lie–Poisson drift (docs/theory/rigid.md §9).
    /// The λ predictor's history is kept (both drifts agree to second order).
    pub fn set_drift(&mut self, drift: Drift) {
        self.work.drift = drift;
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> MultibodyMethod {
        self.method
    }

    /// Choose the method (the caches stay valid: they depend on the state only).
    pub fn set_method(&mut self, method: MultibodyMethod) {
        self.method = method;
        let w = &mut self.work;
        w.method_name = method.name();
        let n = method.scheme().map_or(0, |s| s.stages()) * w.lambda.len();
        w.stage_lambda.resize(n, [[0.0; 6]; HISTORY]);
        w.scheme_steps = [f64::NAN; HISTORY];
        // The sub-steps change, and with them the corrections' contractions.
        w.forget_contractions();
    }

    /// Forget the cached forces, rows and multipliers and the learned contractions of the
    /// position solve's corrections (after editing a state by hand the cache is detected
    /// as stale anyway).
    pub fn reset(&mut self) {
        self.work.reset();
    }

    /// The numerical rank and the size of the loop Schur complement at the last
    /// factorization (equal when the loop rows are independent; the four-bar of four
    /// hinges gives `(2, 5)`).
    #[must_use]
    pub fn loop_rank(&self) -> (usize, usize) {
        self.work.solver.loop_rank()
    }

    /// Switch timing on or off (and reset it): with it on, every step and every
    /// factorization and solve of `G M⁻¹ Gᵀ` is timed with [`std::time::Instant`].
    pub fn set_profiling(&mut self, on: bool) {
        let w = &mut self.work;
        w.profiling = on;
        w.solver_time = std::time::Duration::ZERO;
        w.step_time = std::time::Duration::ZERO;
    }

    /// Time spent since [`Rattle::set_profiling`] in the constraint solves
    /// (factorizations and solves) and in whole steps.
    #[must_use]
    pub fn profile(&self) -> (std::time::Duration, std::time::Duration) {
        (self.work.solver_time, self.work.step_time)
    }

    /// The current state of joint `k`'s limit.
    #[must_use]
    pub fn limit_state(&self, k: usize) -> Option<LimitState> {
        self.work.limit.get(k).copied()
    }

    /// The active limits of every joint, in joint order (for
    /// [`MultibodySystem::constraint_violation_with`]).
    #[must_use]
    pub fn limits(&self) -> &[LimitState] {
        &self.work.limit
    }

    /// The relative position and velocity constraint violations of `state` (as in
    /// [`StepReport`]), with the active limit rows of this integrator.
    #[must_use]
    pub fn constraint_violation(&self, system: &MultibodySystem, state: &MultibodyState) -> (f64, f64) {
        system.constraint_violation_with(state, &self.work.limit)
    }

    /// The contacts touching at the end of the last step, with `state` that step's end:
    /// each contact's point and the force of the step's closing half-kick (the μ-kick) on
    /// its first body from its second (or the world), `[x, y, z, f_x, f_y, f_z]` (m, N),
    /// appended to `out`. Nothing before a step, without contacts, or after a composition
    /// (which runs without contacts). Reference: docs/theory/multibody.md §6.
    pub fn contact_forces(&self, state: &MultibodyState, out: &mut Vec<[f64; 6]>) {
        self.work.contact_forces(&state.c, &state.rotation, out);
    }

    /// Set the state's time to `t` (a driver's exact step times) keeping the cache of the
    /// start-of-step forces and rows.
    pub fn set_time(&mut self, state: &mut MultibodyState, t: f64) {
        self.work.set_time(state, t);
    }

    /// One step of the method from `state` with step `h` (negative steps run backwards).
    ///
    /// # Errors
    /// [`Error::InvalidStep`]; [`Error::NewtonDidNotConverge`] with the residual when the
    /// position solve or a midpoint solve does not converge; [`Error::StepTooLarge`];
    /// [`Error::InvalidModel`] when the tree rows become dependent or the state or this
    /// integrator does not fit the system; the state is unchanged on error.
    pub fn step(&mut self, system: &MultibodySystem, state: &mut MultibodyState, h: f64) -> Result<StepReport> {
        crate::error::check_step(h)?;
        let w = &mut self.work;
        if state.c.len() != system.mass.len()
            || w.c_new.len() != system.mass.len()
            || w.lambda.len() != system.joints.len()
        {
            return Err(Error::InvalidModel {
                reason: format!(
                    "state has {} bodies, the system {} bodies and {} joints, the integrator was built for {} and {}",
                    state.c.len(),
                    system.mass.len(),
                    system.joints.len(),
                    w.c_new.len(),
                    w.lambda.len()
                ),
            });
        }
        let t0 = state.t;
        let start = w.profiling.then(std::time::Instant::now);
        let mut report = StepReport::default();
        match self.method.scheme() {
            None if system.contact.is_some() => {
                w.backup.copy_from(state);
                if let Err(e) = w.split_stage(system, state, h, &mut report, 0) {
                    state.copy_from(&w.backup);
                    w.cache_valid = false;
                    return Err(e);
                }
            }
            None => w.stage(system, state, h, &mut report, None)?,
            Some(s) => {
                w.backup.copy_from(state);
                for k in 0..s.stages() {
                    if let Err(e) = w.stage(system, state, s.gamma(k) * h, &mut report, Some((k, h))) {
                        state.copy_from(&w.backup);
                        w.cache_valid = false;
                        w.scheme_steps = [f64::NAN; HISTORY];
                        return Err(e);
                    }
                }
                if report.limit_changes == 0 {
                    push_front(&mut w.scheme_steps, h);
                } else {
                    w.scheme_steps = [f64::NAN; HISTORY];
                }
                // The stages' times sum to `t0 + h` up to rounding: keep the end's cache
                // (forces, rows, factorization) for the next step, as the drivers do.
                w.set_time(state, t0 + h);
            }
        }
        if let Some(start) = start {
            w.step_time += start.elapsed();
        }
        Ok(report)
    }
}

/// Most halvings of a contact step whose solve failed (`Workspace::split_stage`).
const MAX_SPLITS: u32 = 4;

impl Workspace {
    /// A contact step from `state` over `h`; where its solve fails (a cone problem that
    /// stalls, a contact impulse that turns a light body beyond the midpoint equation's
    /// reach), the step is redone as two steps of `h/2` from the same start, each split
    /// again where it fails, `MAX_SPLITS` times at most (to `h/16`), where it is tried once
    /// more with friction in the closing kick only (below). A contact step is
    /// dissipative and first order at an impact, so its step size is not part of any
    /// structure the method keeps; the run keeps its output times. `depth` counts the
    /// halvings so far. On error `state` may hold the first halves (the caller restores).
    fn split_stage(
        &mut self,
        sys: &MultibodySystem,
        state: &mut MultibodyState,
        h: f64,
        report: &mut StepReport,
        depth: u32,
    ) -> Result<()> {
        self.split_lambda.copy_from_slice(&self.lambda);
        self.split_lambda_prev.copy_from_slice(&self.lambda_prev);
        self.split_limit.copy_from_slice(&self.limit);
        let e = match self.stage(sys, state, h, report, None) {
            Ok(()) => return Ok(()),
            Err(e) => e,
        };
        let numerical = matches!(
            e,
            Error::NewtonDidNotConverge { .. } | Error::StepTooLarge { .. } | Error::NonFiniteResult { .. }
        );
        if !numerical {
            return Err(e);
        }
        // Either recourse starts again from the multipliers and limits of the step's start.
        self.lambda.copy_from_slice(&self.split_lambda);
        self.lambda_prev.copy_from_slice(&self.split_lambda_prev);
        self.limit.copy_from_slice(&self.split_limit);
        self.cache_valid = false;
        if depth >= MAX_SPLITS {
            // The last resort, at h/16 (whichever solve failed): the drift holds no contact
            // by friction, and friction acts in the closing μ-kick only, as in velocity-level
            // contact methods (a sticking contact slides `h² a_t / 2` within such a step,
            // where `a_t` is its tangential acceleration). Its position problem has normal
            // rows only, a problem Gauss–Seidel converges on; the velocity solve still holds
            // Coulomb's law exactly. Counted (`StepReport::frictionless_drifts`).
            self.contact.frictionless_drift = true;
            let retry = self.stage(sys, state, h, report, None);
            self.contact.frictionless_drift = false;
            if retry.is_err() {
                return Err(e);
            }
            report.frictionless_drifts += 1;
            return Ok(());
        }
        report.split_steps += 1;
        let t0 = state.t;
        self.split_stage(sys, state, 0.5 * h, report, depth + 1)?;
        self.split_stage(sys, state, 0.5 * h, report, depth + 1)?;
        self.set_time(state, t0 + h);
        Ok(())
    }

    /// One RATTLE/EA stage (the whole step of [`MultibodyMethod::Liemid`]); `stage` is the
    /// stage's index in a composition and the composed step.
    fn stage(
        &mut self,
        sys: &MultibodySystem,
        state: &mut MultibodyState,
        h: f64,
        report: &mut StepReport,
        stage: Option<(usize, f64)>,
    ) -> Result<()> {
        self.prepare(sys, state);
        let nb = sys.mass.len();
        let hh = 0.5 * h;
        let t = state.t;
        if sys.has_damping {
            self.start_dampers(sys, state, t, hh, report)?;
        }
        if sys.has_friction {
            if !sys.has_damping {
                self.damp_f.iter_mut().for_each(|v| *v = Vec3::ZERO);
                self.damp_t.iter_mut().for_each(|v| *v = Vec3::ZERO);
            }
            self.start_friction(sys, (&state.c, &state.rotation), (&state.p, &state.pi), t, hh, report)?;
        }
        for i in 0..nb {
            let (df, dt) = if sys.has_damping || sys.has_friction {
                (self.damp_f[i], self.damp_t[i])
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            self.pb[i] = state.p[i] + (self.force[i] + df) * hh;
            self.pib[i] = state.pi[i] + (self.torque[i] + dt) * hh;
        }
        let start = self.start_multipliers(h, stage);
        let limit_changes = report.limit_changes;
        let mut positions = |w: &mut Workspace, report: &mut StepReport, first: bool| {
            let (extrapolated, points) = if first { start } else { (false, 0) };
            w.positions(sys, state, h, report, stage, extrapolated, points)
        };
        self.contact_positions(sys, state, h, report, &mut positions)?;
        // End forces (position-dependent: cached for the next step).
        let t1 = t + h;
        sys.forces(t1, &self.c_new, &self.r_new, &mut self.force1, &mut self.torque1);
        self.solve_velocities(sys, t, h, report)?;
        // Commit.
        for i in 0..nb {
            let ok = self.p_half[i].is_finite() && self.pi_new[i].is_finite() && self.r_new[i].is_finite();
            if !ok {
                return Err(Error::NonFiniteResult {
                    method: self.method_name,
                    t,
                    h,
                });
            }
        }
        state.t = t1;
        state.c.copy_from_slice(&self.c_new);
        state.rotation.copy_from_slice(&self.r_new);
        state.p.copy_from_slice(&self.p_half);
        state.pi.copy_from_slice(&self.pi_new);
        core::mem::swap(&mut self.rows0, &mut self.rows1);
        // The velocity solve's factorization (at `rows1`, now `rows0`) is the next position
        // solve's quasi-Newton matrix.
        self.factor_rows0 = self.rows0.iter().any(|r| r.n > 0);
        if report.limit_changes == limit_changes {
            push_front(&mut self.lambda_steps, h);
        } else {
            self.lambda_steps = [f64::NAN; 4];
        }
        if let Some((k, _)) = stage {
            let nj = self.lambda.len();
            for (hist, l) in self.stage_lambda[k * nj..(k + 1) * nj].iter_mut().zip(&self.lambda) {
                push_front(hist, *l);
            }
        }
        core::mem::swap(&mut self.force, &mut self.force1);
        core::mem::swap(&mut self.torque, &mut self.torque1);
        self.remember(sys, state);
        Ok(())
    }

    /// The position solve with the joint limits: the quasi-Newton iteration from the
    /// multipliers in `lambda` (`extrapolated` from `points` past stages), redone with the
    /// limits switched on or off, and from safer starts when an extrapolated one fails.
    #[allow(clippy::too_many_arguments)]
    fn positions(
        &mut self,
        sys: &MultibodySystem,
        state: &MultibodyState,
        h: f64,
        report: &mut StepReport,
        stage: Option<(usize, f64)>,
        mut extrapolated: bool,
        mut points: usize,
    ) -> Result<()> {
        let mut passes = 0;
        loop {
            if let Err(e) = self.solve_positions(sys, state, h, report) {
                if !extrapolated {
                    return Err(e);
                }
                // An extrapolated start far from the root (steps too long for the
                // extrapolation) can lead the iteration astray: a composition's stage tries
                // again from the cubic through its last four steps (the degree-6 start
                // overshoots first: the spacecraft's liemid4 at h = 0.04, stages turning
                // the hub by up to 0.8 rad), then from the last `λ`, and no extrapolation
                // until the histories are rebuilt.
                if let (Some((k, _)), true) = (stage, points > 4) {
                    let nj = self.lambda.len();
                    let hist = &self.stage_lambda[k * nj..(k + 1) * nj];
                    for (l, hist) in self.lambda.iter_mut().zip(hist) {
                        *l = extrapolate(4, hist);
                    }
                    points = 0;
                    continue;
                }
                extrapolated = false;
                for (l, prev) in self.lambda.iter_mut().zip(&self.lambda_prev) {
                    *l = prev[0];
                }
                self.lambda_steps = [f64::NAN; 4];
                self.scheme_steps = [f64::NAN; HISTORY];
                continue;
            }
            if !self.update_limits_after_positions(sys) {
                break;
            }
            report.limit_changes += 1;
            passes += 1;
            if passes > MAX_LIMIT_PASSES {
                break;
            }
            self.factor_rows0 = false;
            self.start_rows_at(sys, state);
        }
        Ok(())
    }
}
