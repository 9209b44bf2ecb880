//! The working memory of the multibody step: every scratch array of one integrator, sized
//! once for a system so that a step allocates nothing, the start-of-step cache (forces,
//! rows, the factorization of `G M⁻¹ Gᵀ`), the multipliers and their history, the joint
//! limits' states, the tree solver and the timers (as Pinocchio's `Data`, MuJoCo's `mjData`).
//! The model is [`MultibodySystem`]; the algorithm that fills this memory is in
//! `rattle.rs` (the stage), `positions.rs`, `velocities.rs` and `dampers.rs`.
//!
//! Reference: docs/theory/multibody.md §3-§4.

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};

use super::constraints::{rows_at, JointRows, Row};
use super::method::LimitState;
use super::solver::TreeSolver;
use super::state::MultibodyState;
use super::system::MultibodySystem;

/// The start of the learned contractions (logarithms) of the position solve's plain and
/// refined corrections: `1e-2` and `1e-6`, so that the first corrections are refined.
const RHO_PLAIN_START: f64 = -4.605_170_185_988_091;
const RHO_REFINED_START: f64 = -13.815_510_557_964_274;

/// How many converged multipliers of a composition's stage the extrapolated start of its
/// position solve uses at most: the polynomial through the last `HISTORY` values (degree
/// 6). Iterations per stage (`examples/profile_multibody.rs`), degree 3 (the cubic) against
/// 6: spacecraft liemid6 at h = 2.5e-3 3.10 → 2.02 (degree 4, 5, 7, 8, 9: 2.81, 2.40, 1.78,
/// 1.69, 1.76), liemid4 at 1e-3 1.99 → 1.00; double pendulum liemid4 at 1e-2 3.87 → 3.29,
/// at 2.5e-3 1.81 → 1.05. Degrees 7 to 9 were worse on the small steps (liemid4 at 1e-3
/// 1.06 to 1.52 iterations): the round-off of the converged values is amplified by the
/// weights' sum `2ⁿ − 1`.
pub(super) const HISTORY: usize = 7;

/// Scratch of the bounded friction rows, sized once for the system's friction joints.
#[derive(Clone, Debug, Default)]
pub(super) struct FrictionScratch {
    /// The joints with friction and their bounds `f_k`.
    pub(super) joints: Vec<usize>,
    pub(super) bound: Vec<f64>,
    /// The rows at the half-kick's configuration.
    pub(super) grad: Vec<Option<Row>>,
    pub(super) sigma: Vec<f64>,
    pub(super) rates0: Vec<f64>,
    pub(super) rates: Vec<f64>,
    /// `K`, column-major (`n × n`).
    pub(super) k: Vec<f64>,
    pub(super) linear: Vec<Vec3>,
    pub(super) angular: Vec<Vec3>,
}

impl FrictionScratch {
    pub(super) fn new(sys: &MultibodySystem) -> Self {
        let joints: Vec<usize> = (0..sys.joints.len())
            .filter(|&k| sys.params[k].frictionloss > 0.0)
            .collect();
        let n = joints.len();
        let nb = sys.mass.len();
        FrictionScratch {
            bound: joints.iter().map(|&k| sys.params[k].frictionloss).collect(),
            joints,
            grad: vec![None; n],
            sigma: vec![0.0; n],
            rates0: vec![0.0; n],
            rates: vec![0.0; n],
            k: vec![0.0; n * n],
            linear: vec![Vec3::ZERO; nb],
            angular: vec![Vec3::ZERO; nb],
        }
    }
}

/// Scratch of the dampers' implicit half-kicks (`dampers.rs`): per damper row its
/// gradient, damping, force and the conjugate-gradient vectors, per body a momentum pair.
#[derive(Clone, Debug, Default)]
pub(super) struct DamperScratch {
    /// The coordinate gradient of each damped joint at the half-kick's configuration.
    pub(super) grad: Vec<Option<Row>>,
    pub(super) damping: Vec<f64>,
    pub(super) sigma: Vec<f64>,
    pub(super) rates0: Vec<f64>,
    pub(super) residual: Vec<f64>,
    pub(super) direction: Vec<f64>,
    pub(super) image: Vec<f64>,
    /// The rows solved implicitly by the dampers' conjugate gradients.
    pub(super) active: Vec<bool>,
    /// Per body: the response's momenta.
    pub(super) linear: Vec<Vec3>,
    pub(super) angular: Vec<Vec3>,
}

impl DamperScratch {
    pub(super) fn new(rows: usize, bodies: usize) -> Self {
        DamperScratch {
            grad: vec![None; rows],
            damping: vec![0.0; rows],
            sigma: vec![0.0; rows],
            rates0: vec![0.0; rows],
            residual: vec![0.0; rows],
            direction: vec![0.0; rows],
            image: vec![0.0; rows],
            active: vec![false; rows],
            linear: vec![Vec3::ZERO; bodies],
            angular: vec![Vec3::ZERO; bodies],
        }
    }
}

/// The scratch of one multibody integrator (see the module docs).
pub(super) struct Workspace {
    /// The method's name, for errors.
    pub(super) method_name: &'static str,
    /// The torque-free rotation of the drift.
    pub(super) drift: super::method::Drift,
    /// Cached start-of-step quantities, valid for (cache_t, cache_c, cache_r) and the
    /// system's revision `cache_revision`.
    pub(super) cache_valid: bool,
    pub(super) cache_t: f64,
    pub(super) cache_revision: u64,
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
    /// The joint friction rows' scratch (`friction.rs`).
    pub(super) friction: FrictionScratch,
    /// The contact solves' scratch (`contact/step.rs`).
    pub(super) contact: super::contact::ContactScratch,
    pub(super) vel: Vec<Vec3>,
    pub(super) omega: Vec<Vec3>,
    pub(super) solver: TreeSolver,
    pub(super) backup: MultibodyState,
    /// The multipliers and limit states before a contact step, restored when it fails and
    /// is redone as two half steps (`rattle.rs`).
    pub(super) split_lambda: Vec<[f64; 6]>,
    pub(super) split_lambda_prev: Vec<[[f64; 6]; 3]>,
    pub(super) split_limit: Vec<LimitState>,
    // The drift's midpoint data per body (Ψ₁, Ψ₂, P, Π_a) and the effective inertia blocks
    // `h (∂θ⁺/∂P)⁻¹` of the exact drift Jacobian.
    pub(super) psi1: Vec<Vec3>,
    pub(super) psi2: Vec<Vec3>,
    pub(super) pi_a: Vec<Vec3>,
    pub(super) effective: Vec<Mat3>,
    /// The drift's rotation per unit angular impulse over the step, `D / h` (`= I⁻¹` to
    /// leading order in `h`), from the same Jacobian.
    pub(super) drift_rate: Vec<Mat3>,
    /// Scratch of the coupled drift with hinge armature (`armature.rs`; empty without):
    /// the inverted pivots of the Jacobians of its two solves (`Ψ₁`, then `Ψ₂`, each over
    /// the bodies) and the residual.
    pub(super) arm_dinv: Vec<Mat3>,
    pub(super) arm_g: Vec<Vec3>,
    /// Whether `arm_dinv` holds the factors of the last drift's two solves.
    pub(super) arm_factored: bool,
    /// Whether the solver holds the factorization of `G(q) M⁻¹ G(q)ᵀ` at `rows0` (the
    /// last velocity solve's, kept for the next position solve).
    pub(super) factor_rows0: bool,
    pub(super) profiling: bool,
    pub(super) solver_time: std::time::Duration,
    pub(super) step_time: std::time::Duration,
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

impl Workspace {
    /// The memory for stepping `sys` with `stages` stages of a composition (0 for the base
    /// step).
    pub(super) fn new(sys: &MultibodySystem, method_name: &'static str, stages: usize) -> Self {
        let nb = sys.mass.len();
        let nj = sys.joints.len();
        let tree_rows: Vec<bool> = sys.joints[..nb].iter().map(|g| g.kind.rows() > 0).collect();
        let parents: Vec<Option<usize>> = sys.joints[..nb].iter().map(|g| g.parent).collect();
        let loops: Vec<_> = (nb..nj)
            .map(|k| (k, sys.joints[k].parent, sys.joints[k].child))
            .collect();
        let z3 = vec![Vec3::ZERO; nb];
        Workspace {
            method_name,
            drift: super::method::Drift::Midpoint,
            cache_valid: false,
            cache_t: 0.0,
            cache_revision: 0,
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
            split_lambda: vec![[0.0; 6]; nj],
            split_lambda_prev: vec![[[0.0; 6]; 3]; nj],
            split_limit: vec![LimitState::Inactive; nj],
            stage_lambda: vec![[[0.0; 6]; HISTORY]; stages * nj],
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
            friction: FrictionScratch::new(sys),
            contact: super::contact::ContactScratch::new(sys.mass.len()),
            vel: z3.clone(),
            omega: z3,
            solver: {
                let mut solver = TreeSolver::new(&parents, &tree_rows, &loops);
                if let Some(a) = &sys.armature {
                    solver.set_armature(&a.coupling);
                }
                solver
            },
            backup: MultibodyState::zeros(nb),
            psi1: vec![Vec3::ZERO; nb],
            psi2: vec![Vec3::ZERO; nb],
            pi_a: vec![Vec3::ZERO; nb],
            effective: vec![Mat3::IDENTITY; nb],
            drift_rate: vec![Mat3::IDENTITY; nb],
            arm_dinv: if sys.armature.is_some() {
                vec![Mat3::ZERO; 2 * nb]
            } else {
                Vec::new()
            },
            arm_g: if sys.armature.is_some() {
                vec![Vec3::ZERO; nb]
            } else {
                Vec::new()
            },
            arm_factored: false,
            factor_rows0: false,
            profiling: false,
            solver_time: std::time::Duration::ZERO,
            step_time: std::time::Duration::ZERO,
        }
    }

    /// Forget the cached forces, rows and multipliers and the learned contractions of the
    /// position solve's corrections (after editing a state by hand the cache is detected
    /// as stale anyway).
    pub(super) fn reset(&mut self) {
        self.cache_valid = false;
        self.factor_rows0 = false;
        self.lambda_steps = [f64::NAN; 4];
        self.scheme_steps = [f64::NAN; HISTORY];
        self.lambda.iter_mut().for_each(|l| *l = [0.0; 6]);
        self.forget_contractions();
    }

    /// The position solve's learned contractions back to their starting values.
    pub(super) fn forget_contractions(&mut self) {
        self.rho_plain = RHO_PLAIN_START;
        self.rho_refined = RHO_REFINED_START;
        self.rho_exact = RHO_REFINED_START;
    }

    /// The start rows `rows0` (active limit rows included) at `state`.
    pub(super) fn start_rows_at(&mut self, sys: &MultibodySystem, state: &MultibodyState) {
        rows_at(
            &sys.joints,
            &self.limit,
            &sys.params,
            &state.c,
            &state.rotation,
            &mut self.rows0,
        );
    }

    /// The end rows `rows1` (active limit rows included) at the poses `(c, R)`.
    pub(super) fn end_rows_at(&mut self, sys: &MultibodySystem, c: &[Vec3], r: &[Mat3]) {
        rows_at(&sys.joints, &self.limit, &sys.params, c, r, &mut self.rows1);
    }

    /// The end rows `rows1` at the drift's end poses `c_new`, `r_new`.
    pub(super) fn end_rows(&mut self, sys: &MultibodySystem) {
        rows_at(
            &sys.joints,
            &self.limit,
            &sys.params,
            &self.c_new,
            &self.r_new,
            &mut self.rows1,
        );
    }

    /// Make the start-of-step forces and rows current for `state`.
    pub(super) fn prepare(&mut self, sys: &MultibodySystem, state: &MultibodyState) {
        let valid = self.cache_valid
            && self.cache_revision == sys.revision
            && self.cache_t == state.t
            && self.cache_c == state.c
            && self.cache_r.iter().zip(&state.rotation).all(|(a, b)| a.bitwise_eq(b));
        if valid {
            return;
        }
        sys.forces(state.t, &state.c, &state.rotation, &mut self.force, &mut self.torque);
        self.start_rows_at(sys, state);
        self.factor_rows0 = false;
        self.lambda_steps = [f64::NAN; 4];
        self.scheme_steps = [f64::NAN; HISTORY];
        self.remember(sys, state);
    }

    /// Set the state's time to `t` (the driver's exact step times), keeping the cache.
    pub(super) fn set_time(&mut self, state: &mut MultibodyState, t: f64) {
        if self.cache_valid && self.cache_t == state.t {
            self.cache_t = t;
        }
        state.t = t;
    }

    pub(super) fn remember(&mut self, sys: &MultibodySystem, state: &MultibodyState) {
        self.cache_t = state.t;
        self.cache_revision = sys.revision;
        self.cache_c.copy_from_slice(&state.c);
        self.cache_r.copy_from_slice(&state.rotation);
        self.cache_valid = true;
    }

    pub(super) fn velocities(&mut self, sys: &MultibodySystem, p: &[Vec3], pi: &[Vec3]) {
        if let Some(a) = &sys.armature {
            for ((v, p), m) in self.vel.iter_mut().zip(p).zip(&sys.mass) {
                *v = *p * (1.0 / m);
            }
            self.omega.copy_from_slice(pi);
            a.solve(&mut self.omega);
            return;
        }
        for i in 0..sys.mass.len() {
            self.vel[i] = p[i] * (1.0 / sys.mass[i]);
            self.omega[i] = sys.inertia[i].apply_inverse(pi[i]);
        }
    }

    /// `omega ← I⁻¹ omega` per body, or `𝕁⁻¹ omega` in tree order with hinge armature
    /// (docs/theory/multibody.md §7).
    pub(super) fn rates_in_place(&mut self, sys: &MultibodySystem) {
        match &sys.armature {
            Some(a) => a.solve(&mut self.omega),
            None => {
                for i in 0..sys.mass.len() {
                    self.omega[i] = sys.inertia[i].apply_inverse(self.omega[i]);
                }
            }
        }
    }

    /// Factor a matrix of the constraint solve (see [`Matrix`]).
    pub(super) fn factor(&mut self, sys: &MultibodySystem, matrix: Matrix) -> Result<()> {
        let start = self.profiling.then(std::time::Instant::now);
        self.factor_rows0 = false;
        let blocks = sys.rotational_blocks();
        let result = match matrix {
            Matrix::Start => self.solver.factor_symmetric(&sys.mass, blocks, &sys.pairs, &self.rows0),
            Matrix::End => self.solver.factor_symmetric(&sys.mass, blocks, &sys.pairs, &self.rows1),
            Matrix::Exact => self
                .solver
                .factor(&sys.mass, &self.effective, &sys.pairs, &self.rows1, &self.rows0),
        };
        if let Some(start) = start {
            self.solver_time += start.elapsed();
        }
        self.factor_rows0 = result.is_ok() && matrix == Matrix::Start;
        result.map_err(|s| Error::InvalidModel {
            reason: format!(
                "dependent constraint rows at {}: relative pivot {:.3e} (a joint set with redundant rows in the \
                 tree, a body of near-zero mass or inertia, or a singular configuration)",
                sys.describe_block(&s),
                s.ratio
            ),
        })
    }

    pub(super) fn timed_solve(&mut self, sys: &MultibodySystem) {
        let start = self.profiling.then(std::time::Instant::now);
        self.solver.solve(&sys.pairs, &self.rhs, &mut self.delta);
        if let Some(start) = start {
            self.solver_time += start.elapsed();
        }
    }
}
