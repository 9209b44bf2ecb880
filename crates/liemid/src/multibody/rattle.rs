//! The multibody step: RATTLE with the rotation of LIEMID\[EA\] (multibody spec section 3).
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
//! step's start forces. Symmetric and, for conservative forces, symplectic; keeps the total
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
//! method is symplectic only away from those steps, and first order at the impact instant.
//!
//! **Armature** (rotor inertia added in joint space) has no exact counterpart in maximal
//! coordinates: a model with non-zero armature is refused.
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, VII.1; B. Leimkuhler, S. Reich, *Simulating Hamiltonian Dynamics*,
//! Cambridge 2004, ch. 7-8; P. Krysl, Int. J. Numer. Meth. Engng 63 (2005) (LIEMID\[EA\]).

use super::dampers::DamperScratch;
use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
use crate::rigid::inertia::Inertia;

use super::constraints::{JointGeometry, JointRows};
use super::forces::ForceHook;
use super::method::{JointParams, LimitState, MultibodyMethod, StepReport};
use super::model::{JointKind, Model};
use super::solver::TreeSolver;
use super::MultibodyState;

/// Iteration cap of the position (λ) solve.
pub const MAX_ITERATIONS: u32 = 60;
/// The start of the learned contractions (logarithms) of the position solve's plain and
/// refined corrections: `1e-2` and `1e-6`, so that the first corrections are refined.
const RHO_PLAIN_START: f64 = -4.605_170_185_988_091;
const RHO_REFINED_START: f64 = -13.815_510_557_964_274;

/// Most re-solves of one step for joint limits switching on or off.
pub const MAX_LIMIT_PASSES: u32 = 8;

/// A multibody system built from a validated [`Model`]: structure, mass properties,
/// forces, the factorization and every scratch array, so that a step allocates nothing.
///
/// Reference: multibody spec sections 1-4.
pub struct MultibodySystem {
    pub(super) name: String,
    pub(super) method: MultibodyMethod,
    pub(super) mass: Vec<f64>,
    pub(super) inertia: Vec<Inertia>,
    pub(super) inertia_matrix: Vec<Mat3>,
    pub(super) com: Vec<Vec3>,
    pub(super) joints: Vec<JointGeometry>,
    pub(super) pairs: Vec<(Option<usize>, usize)>,
    pub(super) params: Vec<JointParams>,
    pub(super) gravity: Vec3,
    pub(super) length: f64,
    pub(super) has_damping: bool,
    pub(super) const_force: Vec<Vec3>,
    pub(super) const_torque: Vec<Vec3>,
    pub(super) hook: Option<Box<dyn ForceHook>>,
    // Cached start-of-step quantities, valid for (cache_t, cache_c, cache_r).
    pub(super) cache_valid: bool,
    pub(super) cache_t: f64,
    pub(super) cache_c: Vec<Vec3>,
    pub(super) cache_r: Vec<Mat3>,
    pub(super) force: Vec<Vec3>,
    pub(super) torque: Vec<Vec3>,
    pub(super) rows0: Vec<JointRows>,
    pub(super) rows1: Vec<JointRows>,
    pub(super) limit: Vec<LimitState>,
    pub(super) lambda: Vec<[f64; 6]>,
    /// The converged `λ` of the three stages before the last, and the steps of the last
    /// four converged stages (NaN: none), for the extrapolated start of the position solve.
    pub(super) lambda_prev: Vec<[[f64; 6]; 3]>,
    pub(super) lambda_steps: [f64; 4],
    /// The converged `λ` of each stage of a composition (`stages × joints`, stage-major) in
    /// the last `HISTORY` steps, newest first, and those steps (NaN: none): stage `k` of a
    /// step is extrapolated from stage `k` of the steps before, which took the same sub-step.
    pub(super) stage_lambda: Vec<[[f64; 6]; HISTORY]>,
    pub(super) scheme_steps: [f64; HISTORY],
    pub(super) delta: Vec<[f64; 6]>,
    /// Scratch of the position solve's inner refinement (`positions.rs`).
    pub(super) inner_rhs: Vec<[f64; 6]>,
    pub(super) inner_delta: Vec<[f64; 6]>,
    /// Log-averages of the residual's contraction per position iteration with the plain
    /// and the refined correction, which decide whether to refine (`positions.rs`).
    pub(super) rho_plain: f64,
    pub(super) rho_refined: f64,
    /// The same with the correction refined toward the exact drift Jacobian.
    pub(super) rho_exact: f64,
    pub(super) rhs: Vec<[f64; 6]>,
    pub(super) pb: Vec<Vec3>,
    pub(super) pib: Vec<Vec3>,
    pub(super) p_half: Vec<Vec3>,
    pub(super) big_p: Vec<Vec3>,
    pub(super) c_new: Vec<Vec3>,
    pub(super) r_new: Vec<Mat3>,
    pub(super) pi_new: Vec<Vec3>,
    pub(super) force1: Vec<Vec3>,
    pub(super) torque1: Vec<Vec3>,
    pub(super) damp_f: Vec<Vec3>,
    pub(super) damp_t: Vec<Vec3>,
    /// Scratch of the implicit damper solve (`dampers.rs`).
    pub(super) dampers: DamperScratch,
    pub(super) vel: Vec<Vec3>,
    pub(super) omega: Vec<Vec3>,
    pub(super) solver: TreeSolver,
    pub(super) backup: MultibodyState,
    // The drift's midpoint data per body (Ψ₁, Ψ₂, P, Π_a) and the effective inertia blocks
    // `h (∂θ⁺/∂P)⁻¹` of the exact drift Jacobian.
    pub(super) psi1: Vec<Vec3>,
    pub(super) psi2: Vec<Vec3>,
    pub(super) pi_a: Vec<Vec3>,
    pub(super) effective: Vec<Mat3>,
    /// The drift's rotation per unit angular impulse over the step, `D / h` (`= I⁻¹` to
    /// leading order in `h`), from the same Jacobian.
    pub(super) drift_rate: Vec<Mat3>,
    /// Whether the solver holds the factorization of `G(q) M⁻¹ G(q)ᵀ` at `rows0` (the
    /// last velocity solve's, kept for the next position solve).
    pub(super) factor_rows0: bool,
    pub(super) profiling: bool,
    pub(super) solver_time: std::time::Duration,
    pub(super) step_time: std::time::Duration,
}

impl core::fmt::Debug for MultibodySystem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("MultibodySystem")
            .field("name", &self.name)
            .field("method", &self.method)
            .field("bodies", &self.mass.len())
            .field("joints", &self.joints.len())
            .finish_non_exhaustive()
    }
}

impl MultibodySystem {
    /// Build the system of a model: validate it, precompute the joint geometry, size every
    /// scratch array and the tree factorization.
    ///
    /// # Errors
    /// [`Model::validate`]'s errors; [`Error::InvalidModel`] for a joint with armature
    /// (not representable exactly in maximal coordinates).
    pub fn new(model: &Model, method: MultibodyMethod) -> Result<Self> {
        model.validate()?;
        let nb = model.bodies.len();
        let nj = model.joints.len();
        for (k, j) in model.joints.iter().enumerate() {
            if j.armature != 0.0 {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "joint `{}` ({k}): armature = {} is not supported: a rotor inertia in joint space has no exact \
                         counterpart in maximal coordinates (remove it or model the rotor as a body)",
                        j.name, j.armature
                    ),
                });
            }
        }
        let inertia = (0..nb).map(|i| model.inertia(i)).collect::<Result<Vec<_>>>()?;
        let joints: Vec<JointGeometry> = (0..nj).map(|k| JointGeometry::new(model, k)).collect();
        let pairs: Vec<_> = joints.iter().map(|g| (g.parent, g.child)).collect();
        let params: Vec<_> = model
            .joints
            .iter()
            .map(|j| {
                let one_dof = matches!(j.kind, JointKind::Hinge { .. } | JointKind::Slide { .. });
                JointParams {
                    stiffness: if one_dof || j.kind == JointKind::Ball {
                        j.stiffness
                    } else {
                        0.0
                    },
                    spring_ref: j.spring_ref,
                    damping: if one_dof || j.kind == JointKind::Ball {
                        j.damping
                    } else {
                        0.0
                    },
                    range: if one_dof { j.range } else { None },
                }
            })
            .collect();
        let tree_rows: Vec<bool> = joints[..nb].iter().map(|g| g.kind.rows() > 0).collect();
        let parents: Vec<Option<usize>> = joints[..nb].iter().map(|g| g.parent).collect();
        let loops: Vec<_> = (nb..nj).map(|k| (k, joints[k].parent, joints[k].child)).collect();
        let z3 = vec![Vec3::ZERO; nb];
        Ok(MultibodySystem {
            name: model.name.clone(),
            method,
            mass: model.bodies.iter().map(|b| b.mass).collect(),
            inertia_matrix: inertia.iter().map(|i| *i.matrix()).collect(),
            inertia,
            com: model.bodies.iter().map(|b| b.com).collect(),
            has_damping: params.iter().any(|p| p.damping > 0.0),
            params,
            pairs,
            joints,
            gravity: model.gravity,
            length: model.length_scale(),
            const_force: z3.clone(),
            const_torque: z3.clone(),
            hook: None,
            cache_valid: false,
            cache_t: 0.0,
            cache_c: z3.clone(),
            cache_r: vec![Mat3::IDENTITY; nb],
            force: z3.clone(),
            torque: z3.clone(),
            rows0: vec![JointRows::default(); nj],
            rows1: vec![JointRows::default(); nj],
            limit: vec![LimitState::Inactive; nj],
            lambda: vec![[0.0; 6]; nj],
            lambda_prev: vec![[[0.0; 6]; 3]; nj],
            lambda_steps: [f64::NAN; 4],
            stage_lambda: vec![[[0.0; 6]; HISTORY]; method.scheme().map_or(0, |s| s.stages()) * nj],
            scheme_steps: [f64::NAN; HISTORY],
            delta: vec![[0.0; 6]; nj],
            inner_rhs: vec![[0.0; 6]; nj],
            inner_delta: vec![[0.0; 6]; nj],
            rho_plain: RHO_PLAIN_START,
            rho_refined: RHO_REFINED_START,
            rho_exact: RHO_REFINED_START,
            rhs: vec![[0.0; 6]; nj],
            pb: z3.clone(),
            pib: z3.clone(),
            p_half: z3.clone(),
            big_p: z3.clone(),
            c_new: z3.clone(),
            r_new: vec![Mat3::IDENTITY; nb],
            pi_new: z3.clone(),
            force1: z3.clone(),
            torque1: z3.clone(),
            damp_f: z3.clone(),
            damp_t: z3.clone(),
            dampers: DamperScratch::new(3 * nj, nb),
            vel: z3.clone(),
            omega: z3,
            solver: TreeSolver::new(&parents, &tree_rows, &loops),
            backup: MultibodyState::zeros(nb),
            psi1: vec![Vec3::ZERO; nb],
            psi2: vec![Vec3::ZERO; nb],
            pi_a: vec![Vec3::ZERO; nb],
            effective: vec![Mat3::IDENTITY; nb],
            drift_rate: vec![Mat3::IDENTITY; nb],
            factor_rows0: false,
            profiling: false,
            solver_time: std::time::Duration::ZERO,
            step_time: std::time::Duration::ZERO,
        })
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> MultibodyMethod {
        self.method
    }

    /// Choose the method (the caches stay valid: they depend on the state only).
    pub fn set_method(&mut self, method: MultibodyMethod) {
        self.method = method;
        let n = method.scheme().map_or(0, |s| s.stages()) * self.joints.len();
        self.stage_lambda.resize(n, [[0.0; 6]; HISTORY]);
        self.scheme_steps = [f64::NAN; HISTORY];
        // The sub-steps change, and with them the corrections' contractions.
        self.forget_contractions();
    }

    /// The model's length scale `L` (see [`Model::length_scale`]).
    #[must_use]
    pub fn length_scale(&self) -> f64 {
        self.length
    }

    /// The floor `√(|g| L)` of the velocity scale of the relative velocity violation, so
    /// that a body at rest (against a limit, at the bottom of a swing) does not divide a
    /// round-off rate by a round-off speed.
    #[must_use]
    pub fn velocity_floor(&self) -> f64 {
        (self.gravity.norm() * self.length).sqrt()
    }

    /// Number of bodies.
    #[must_use]
    pub fn body_count(&self) -> usize {
        self.mass.len()
    }

    /// The numerical rank and the size of the loop Schur complement at the last
    /// factorization (equal when the loop rows are independent; the four-bar of four
    /// hinges gives `(2, 5)`).
    #[must_use]
    pub fn loop_rank(&self) -> (usize, usize) {
        self.solver.loop_rank()
    }

    /// Forget the cached forces, rows and multipliers and the learned contractions of the
    /// position solve's corrections (after editing a state by hand the cache is detected
    /// as stale anyway).
    pub fn reset(&mut self) {
        self.cache_valid = false;
        self.factor_rows0 = false;
        self.lambda_steps = [f64::NAN; 4];
        self.scheme_steps = [f64::NAN; HISTORY];
        self.lambda.iter_mut().for_each(|l| *l = [0.0; 6]);
        self.forget_contractions();
    }

    /// The position solve's learned contractions back to their starting values.
    fn forget_contractions(&mut self) {
        self.rho_plain = RHO_PLAIN_START;
        self.rho_refined = RHO_REFINED_START;
        self.rho_exact = RHO_REFINED_START;
    }

    /// Switch timing on or off (and reset it): with it on, every step and every
    /// factorization and solve of `G M⁻¹ Gᵀ` is timed with [`std::time::Instant`].
    pub fn set_profiling(&mut self, on: bool) {
        self.profiling = on;
        self.solver_time = std::time::Duration::ZERO;
        self.step_time = std::time::Duration::ZERO;
    }

    /// Time spent since [`MultibodySystem::set_profiling`] in the constraint solves
    /// (factorizations and solves) and in whole steps.
    #[must_use]
    pub fn profile(&self) -> (std::time::Duration, std::time::Duration) {
        (self.solver_time, self.step_time)
    }

    /// The current state of joint `k`'s limit.
    #[must_use]
    pub fn limit_state(&self, k: usize) -> Option<LimitState> {
        self.limit.get(k).copied()
    }

    /// The rows (with active limit rows) of every joint at `(c, R)` into `out`.
    pub(super) fn rows_at(
        joints: &[JointGeometry],
        limit: &[LimitState],
        params: &[JointParams],
        c: &[Vec3],
        r: &[Mat3],
        out: &mut [JointRows],
    ) {
        for (k, g) in joints.iter().enumerate() {
            let (pi, pj) = pose(g, c, r);
            g.rows(pi, pj, &mut out[k]);
            if limit[k] != LimitState::Inactive {
                if let (Some((q, grad)), Some((lo, hi))) = (g.coordinate(pi, pj), params[k].range) {
                    let bound = if limit[k] == LimitState::Lower { lo } else { hi };
                    let length = matches!(g.kind, JointKind::Slide { .. });
                    out[k].push(q - bound, grad, length);
                }
            }
        }
    }

    /// Make the start-of-step forces and rows current for `state`.
    fn prepare(&mut self, state: &MultibodyState) {
        let valid = self.cache_valid
            && self.cache_t == state.t
            && self.cache_c == state.c
            && self.cache_r.iter().zip(&state.rotation).all(|(a, b)| a.bitwise_eq(b));
        if valid {
            return;
        }
        let (mut f, mut tq) = (core::mem::take(&mut self.force), core::mem::take(&mut self.torque));
        self.forces(state.t, &state.c, &state.rotation, &mut f, &mut tq);
        self.force = f;
        self.torque = tq;
        Self::rows_at(
            &self.joints,
            &self.limit,
            &self.params,
            &state.c,
            &state.rotation,
            &mut self.rows0,
        );
        self.factor_rows0 = false;
        self.lambda_steps = [f64::NAN; 4];
        self.scheme_steps = [f64::NAN; HISTORY];
        self.remember(state);
    }

    /// Set the state's time to `t` (the driver's exact step times), keeping the cache.
    pub(super) fn set_time(&mut self, state: &mut MultibodyState, t: f64) {
        if self.cache_valid && self.cache_t == state.t {
            self.cache_t = t;
        }
        state.t = t;
    }

    fn remember(&mut self, state: &MultibodyState) {
        self.cache_t = state.t;
        self.cache_c.copy_from_slice(&state.c);
        self.cache_r.copy_from_slice(&state.rotation);
        self.cache_valid = true;
    }

    /// One step of the method from `state` with step `h` (negative steps run backwards).
    ///
    /// # Errors
    /// [`Error::InvalidStep`]; [`Error::NewtonDidNotConverge`] with the residual when the
    /// position solve or a midpoint solve does not converge; [`Error::StepTooLarge`];
    /// [`Error::InvalidModel`] when the tree rows become dependent; the state is unchanged
    /// on error.
    pub fn step(&mut self, state: &mut MultibodyState, h: f64) -> Result<StepReport> {
        crate::rigid::rotation::check_step(h)?;
        if state.c.len() != self.mass.len() {
            return Err(Error::InvalidModel {
                reason: format!("state has {} bodies, the system {}", state.c.len(), self.mass.len()),
            });
        }
        let t0 = state.t;
        let start = self.profiling.then(std::time::Instant::now);
        let mut report = StepReport::default();
        match self.method.scheme() {
            None => self.stage(state, h, &mut report, None)?,
            Some(s) => {
                self.backup.copy_from(state);
                for k in 0..s.stages() {
                    if let Err(e) = self.stage(state, s.gamma(k) * h, &mut report, Some((k, h))) {
                        state.copy_from(&self.backup);
                        self.cache_valid = false;
                        self.scheme_steps = [f64::NAN; HISTORY];
                        return Err(e);
                    }
                }
                if report.limit_changes == 0 {
                    push_front(&mut self.scheme_steps, h);
                } else {
                    self.scheme_steps = [f64::NAN; HISTORY];
                }
                // The stages' times sum to `t0 + h` up to rounding: keep the end's cache
                // (forces, rows, factorization) for the next step, as the drivers do.
                self.set_time(state, t0 + h);
            }
        }
        if let Some(start) = start {
            self.step_time += start.elapsed();
        }
        Ok(report)
    }

    /// One RATTLE/EA stage (the whole step of [`MultibodyMethod::Liemid`]); `stage` is the
    /// stage's index in a composition and the composed step.
    fn stage(
        &mut self,
        state: &mut MultibodyState,
        h: f64,
        report: &mut StepReport,
        stage: Option<(usize, f64)>,
    ) -> Result<()> {
        self.prepare(state);
        let nb = self.mass.len();
        let hh = 0.5 * h;
        let t = state.t;
        if self.has_damping {
            self.start_dampers(state, t, hh, report)?;
        }
        for i in 0..nb {
            let (df, dt) = if self.has_damping {
                (self.damp_f[i], self.damp_t[i])
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            self.pb[i] = state.p[i] + (self.force[i] + df) * hh;
            self.pib[i] = state.pi[i] + (self.torque[i] + dt) * hh;
        }
        let (mut extrapolated, mut points) = self.start_multipliers(h, stage);
        let limit_changes = report.limit_changes;
        let mut passes = 0;
        loop {
            if let Err(e) = self.solve_positions(state, h, report) {
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
                    let nj = self.joints.len();
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
            if !self.update_limits_after_positions() {
                break;
            }
            report.limit_changes += 1;
            passes += 1;
            if passes > MAX_LIMIT_PASSES {
                break;
            }
            self.factor_rows0 = false;
            Self::rows_at(
                &self.joints,
                &self.limit,
                &self.params,
                &state.c,
                &state.rotation,
                &mut self.rows0,
            );
        }
        // End forces (position-dependent: cached for the next step).
        let t1 = t + h;
        let (mut f1, mut t1q) = (core::mem::take(&mut self.force1), core::mem::take(&mut self.torque1));
        let (cn, rn) = (core::mem::take(&mut self.c_new), core::mem::take(&mut self.r_new));
        self.forces(t1, &cn, &rn, &mut f1, &mut t1q);
        self.force1 = f1;
        self.torque1 = t1q;
        self.c_new = cn;
        self.r_new = rn;
        self.solve_velocities(t, h, report)?;
        // Commit.
        for i in 0..nb {
            let ok = self.p_half[i].is_finite() && self.pi_new[i].is_finite() && self.r_new[i].is_finite();
            if !ok {
                return Err(Error::NonFiniteResult {
                    method: self.method.name(),
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
            let nj = self.joints.len();
            for (hist, l) in self.stage_lambda[k * nj..(k + 1) * nj].iter_mut().zip(&self.lambda) {
                push_front(hist, *l);
            }
        }
        core::mem::swap(&mut self.force, &mut self.force1);
        core::mem::swap(&mut self.torque, &mut self.torque1);
        self.remember(state);
        Ok(())
    }

    /// The start of the position solve, an extrapolation of earlier converged `λ` (only
    /// the iteration's start: the solution is the same to round-off).
    ///
    /// - Stage `k` of a composition, after steps of the same `h` whose stage `k` converged
    ///   with the same rows: the polynomial of degree 6 through stage `k` of the last
    ///   [`HISTORY`] = 7 steps, `λ = 7 λₙ − 21 λₙ₋₁ + 35 λₙ₋₂ − 35 λₙ₋₃ + 21 λₙ₋₄ − 7 λₙ₋₅ +
    ///   λₙ₋₆` (an `O(h⁷)` error; the one through fewer values after fewer such steps). The
    ///   stages of one step differ in their sub-step (and sign), and RATTLE's `λ` is the
    ///   constraint force plus a term odd in the sub-step, so the previous stage's `λ` is a
    ///   poor start there.
    /// - Otherwise (the base step, or a composition's first steps): the cubic
    ///   `λ = 4 λₙ − 6 λₙ₋₁ + 4 λₙ₋₂ − λₙ₋₃` over the last stages when they took the same
    ///   step `h` with the same rows (the quadratic or linear one after three or two, the
    ///   previous `λ` after fewer). At the base step's usual small steps the cubic's error is
    ///   already near the round-off of the converged values, which the higher degrees
    ///   amplify (iterations per step at h = 1e-4, degree 3 / 4 / 6: spacecraft 0.80 / 0.85 /
    ///   0.97, chain-1000 0.93 / 1.00 / 1.00).
    ///
    /// Steps count as the same when they agree to `1e-9` relative (a driver's steps
    /// `t_{k+1} − t_k` differ from `h` in the last bits). Returns whether the start is an
    /// extrapolation (the last `λ` is then in `lambda_prev[..][0]`: a position solve that
    /// fails from the extrapolation is restarted from it) and how many of a stage's
    /// converged values it used (0 for the base step's). On the spacecraft (liemid6,
    /// `h = 2.5e-3`) the degree-6 start took 2.0 quasi-Newton iterations per stage, the
    /// cubic 3.1, the quadratic 3.7 and the previous stage's `λ` 4.6
    /// (`examples/profile_multibody.rs`).
    fn start_multipliers(&mut self, h: f64, stage: Option<(usize, f64)>) -> (bool, usize) {
        if let Some((k, step)) = stage {
            let same = same_steps(&self.scheme_steps, step);
            if same > 0 {
                let nj = self.joints.len();
                let hist = &self.stage_lambda[k * nj..(k + 1) * nj];
                // The higher degree only where it agrees with the cubic to a tenth of the
                // cubic's change from the last value: a history that is not smooth on the
                // step's scale (steps too long for the motion) keeps the cubic.
                let (mut gap, mut change) = (0.0f64, 0.0f64);
                if same > 4 {
                    for hist in hist {
                        let (high, cubic) = (extrapolate(same, hist), extrapolate(4, hist));
                        for r in 0..6 {
                            gap = gap.max((high[r] - cubic[r]).abs());
                            change = change.max((cubic[r] - hist[0][r]).abs());
                        }
                    }
                }
                let points = if gap <= 0.1 * change { same } else { 4 };
                for ((l, prev), hist) in self.lambda.iter_mut().zip(&mut self.lambda_prev).zip(hist) {
                    push_front(prev, *l);
                    *l = extrapolate(points, hist);
                }
                return (true, points);
            }
        }
        let same = same_steps(&self.lambda_steps, h);
        for (l, prev) in self.lambda.iter_mut().zip(&mut self.lambda_prev) {
            let hist = [*l, prev[0], prev[1], prev[2]];
            *prev = [hist[0], hist[1], hist[2]];
            if same >= 2 {
                *l = extrapolate(same, &hist);
            }
        }
        (same >= 2, 0)
    }

    pub(super) fn velocities(&mut self, p: &[Vec3], pi: &[Vec3]) {
        for i in 0..self.mass.len() {
            self.vel[i] = p[i] * (1.0 / self.mass[i]);
            self.omega[i] = self.inertia[i].apply_inverse(pi[i]);
        }
    }

    /// Factor a matrix of the constraint solve (see [`Matrix`]).
    pub(super) fn factor(&mut self, matrix: Matrix) -> Result<()> {
        let start = self.profiling.then(std::time::Instant::now);
        self.factor_rows0 = false;
        let result = match matrix {
            Matrix::Start => self
                .solver
                .factor_symmetric(&self.mass, &self.inertia_matrix, &self.pairs, &self.rows0),
            Matrix::End => self
                .solver
                .factor_symmetric(&self.mass, &self.inertia_matrix, &self.pairs, &self.rows1),
            Matrix::Exact => self
                .solver
                .factor(&self.mass, &self.effective, &self.pairs, &self.rows1, &self.rows0),
        };
        if let Some(start) = start {
            self.solver_time += start.elapsed();
        }
        self.factor_rows0 = result.is_ok() && matrix == Matrix::Start;
        result.map_err(|s| Error::InvalidModel {
            reason: format!(
                "dependent constraint rows at joint {:?} / body {:?}: relative pivot {:.3e} (a joint set with \
                     redundant rows in the tree, or a singular configuration)",
                s.joint, s.body, s.ratio
            ),
        })
    }

    pub(super) fn timed_solve(&mut self) {
        let start = self.profiling.then(std::time::Instant::now);
        self.solver.solve(&self.pairs, &self.rhs, &mut self.delta);
        if let Some(start) = start {
            self.solver_time += start.elapsed();
        }
    }
}

/// How many converged multipliers of a composition's stage the extrapolated start of its
/// position solve uses at most: the polynomial through the last `HISTORY` values (degree
/// 6). Iterations per stage (`examples/profile_multibody.rs`), degree 3 (the cubic) against
/// 6: spacecraft liemid6 at h = 2.5e-3 3.10 → 2.02 (degree 4, 5, 7, 8, 9: 2.81, 2.40, 1.78,
/// 1.69, 1.76), liemid4 at 1e-3 1.99 → 1.00; double pendulum liemid4 at 1e-2 3.87 → 3.29,
/// at 2.5e-3 1.81 → 1.05. Degrees 7 to 9 were worse on the small steps (liemid4 at 1e-3
/// 1.06 to 1.52 iterations): the round-off of the converged values is amplified by the
/// weights' sum `2ⁿ − 1`.
pub(super) const HISTORY: usize = 7;

/// `BINOMIAL[n - 1][j] = (−1)ʲ C(n, j + 1)`: the weights of the polynomial extrapolation
/// through `n` equally spaced values, newest first (`λ = Σ_j w_j λₙ₋ⱼ`).
const BINOMIAL: [[f64; HISTORY]; HISTORY] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0, -3.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    [4.0, -6.0, 4.0, -1.0, 0.0, 0.0, 0.0],
    [5.0, -10.0, 10.0, -5.0, 1.0, 0.0, 0.0],
    [6.0, -15.0, 20.0, -15.0, 6.0, -1.0, 0.0],
    [7.0, -21.0, 35.0, -35.0, 21.0, -7.0, 1.0],
];

/// The polynomial extrapolation to the next of equally spaced values, newest first:
/// constant, linear, ..., degree `n − 1` through the first `n = same` of `hist` (at most
/// `hist.len() ≤ HISTORY`).
#[inline]
fn extrapolate(same: usize, hist: &[[f64; 6]]) -> [f64; 6] {
    let n = same.clamp(1, hist.len());
    let w = &BINOMIAL[n - 1];
    let mut out = [0.0; 6];
    for (wj, hj) in w[..n].iter().zip(hist) {
        for (o, v) in out.iter_mut().zip(hj) {
            *o += wj * v;
        }
    }
    out
}

/// Shift `new` in at the front of a history (newest first), dropping the oldest.
#[inline]
fn push_front<T: Copy, const N: usize>(hist: &mut [T; N], new: T) {
    hist.copy_within(0..N - 1, 1);
    hist[0] = new;
}

/// How many of the latest `steps` (newest first) equal `h` to `1e-9` relative.
fn same_steps(steps: &[f64], h: f64) -> usize {
    steps.iter().take_while(|&&s| (s - h).abs() <= 1e-9 * h.abs()).count()
}

/// The matrices of the constraint solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Matrix {
    /// `G(q) M⁻¹ G(q)ᵀ` at the stage's start (`rows0`): the position solve's quasi-Newton
    /// matrix, which the previous stage's velocity solve has factored already.
    Start,
    /// `G(q⁺) M⁻¹ G(q⁺)ᵀ` at the end (`rows1`): the velocity solve's.
    End,
    /// `G(q⁺) D G(q)ᵀ` with `D` the exact drift Jacobian at the current iterate (the
    /// effective inertia blocks): the position solve's fallback when the quasi-Newton
    /// iteration converges slowly.
    Exact,
}

/// The poses `(c_i, R_i)`, `(c_j, R_j)` of a joint's parent (world: 0, I) and child.
#[inline]
pub(super) fn pose<'a>(g: &JointGeometry, c: &'a [Vec3], r: &'a [Mat3]) -> ((Vec3, &'a Mat3), (Vec3, &'a Mat3)) {
    const IDENTITY: &Mat3 = &Mat3::IDENTITY;
    let pi = g.parent.map_or((Vec3::ZERO, IDENTITY), |p| (c[p], &r[p]));
    (pi, (c[g.child], &r[g.child]))
}

/// Add the rows' impulse `Gᵀ (scale · multipliers)` to the bodies' linear and (body-frame)
/// angular momenta: the force on the centres of mass and the torque of each row, to the
/// parent (if not the world) and the child.
pub(super) fn add_impulse(
    joints: &[JointGeometry],
    rows: &[JointRows],
    multipliers: &[[f64; 6]],
    scale: f64,
    linear: &mut [Vec3],
    angular: &mut [Vec3],
) {
    for ((g, rows), mult) in joints.iter().zip(rows).zip(multipliers) {
        for (gr, &mu) in rows.grad[..rows.n].iter().zip(mult) {
            let m = mu * scale;
            if let Some(p) = g.parent {
                linear[p] += gr.ci * m;
                angular[p] += gr.ti * m;
            }
            linear[g.child] += gr.cj * m;
            angular[g.child] += gr.tj * m;
        }
    }
}

/// The rates `G v` of the rows: calls `f(joint, row, rate)` for every row of every joint,
/// with the bodies' velocities `linear` and angular rates `angular` (the transpose of
/// [`add_impulse`]).
pub(super) fn for_each_rate(
    joints: &[JointGeometry],
    rows: &[JointRows],
    linear: &[Vec3],
    angular: &[Vec3],
    mut f: impl FnMut(usize, usize, f64),
) {
    for (k, (g, jr)) in joints.iter().zip(rows).enumerate() {
        let (vi, wi) = g.parent.map_or((Vec3::ZERO, Vec3::ZERO), |p| (linear[p], angular[p]));
        let (vj, wj) = (linear[g.child], angular[g.child]);
        for (r, gr) in jr.grad[..jr.n].iter().enumerate() {
            f(k, r, gr.rate(vi, wi, vj, wj));
        }
    }
}
