//! Projections of a state onto the joints' constraints in the kinetic-energy metric: the
//! velocities onto `G (v, Ω) = 0` (one solve) and the positions onto `g(q) = 0`
//! (Gauss-Newton), for starts that do not respect loop-closing joints (a keyframe written
//! for MuJoCo's soft equalities, joint velocities across a loop).
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, IV.4 (projection methods) and VII.1 (RATTLE's velocity projection).

use crate::error::{Error, Result};
use crate::linalg::Vec3;

use super::constraints::add_impulse;
use super::model::Model;
use super::rattle::Rattle;
use super::state::MultibodyState;
use super::system::MultibodySystem;
use super::workspace::{Matrix, Workspace};

impl Rattle {
    /// The start of `model` ([`Model::initial_state`]) brought onto its loop-closing joints
    /// when it has any: positions ([`Rattle::project_positions`]) then velocities
    /// ([`Rattle::project_velocities`]). Returns the state and the relative position and
    /// velocity violations found before (0 without loops). `model` is the one `system` was
    /// built from.
    ///
    /// # Errors
    /// [`Model::initial_state`]'s errors and the projections'.
    pub fn initial_state_on_loops(
        &mut self,
        system: &MultibodySystem,
        model: &Model,
    ) -> Result<(MultibodyState, f64, f64)> {
        let mut state = model.initial_state()?;
        if model.loop_joints().is_empty() {
            return Ok((state, 0.0, 0.0));
        }
        let position = self.work.project_positions(system, &mut state)?;
        let velocity = self.work.project_velocities(system, &mut state)?;
        Ok((state, position, velocity))
    }

    /// Project the velocities of `state` onto the velocity constraints `G (v, Ω) = 0` in
    /// the kinetic-energy metric: `(G M⁻¹ Gᵀ) μ = −G (v, Ω)`, `p += G_cᵀ μ`,
    /// `Π += G_θᵀ μ` (minimum-norm `μ` for redundant loop rows). For joint velocities that
    /// do not respect loop-closing joints (a loader's `qvel` on a closed loop). Returns the
    /// relative velocity violation before the projection.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] when the tree rows are dependent at this configuration.
    ///
    /// Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, VII.1
    /// (the velocity projection of RATTLE).
    pub fn project_velocities(&mut self, system: &MultibodySystem, state: &mut MultibodyState) -> Result<f64> {
        self.work.project_velocities(system, state)
    }

    /// Project the positions of `state` onto the position constraints `g(q) = 0` in the
    /// kinetic-energy metric, by Gauss-Newton: `(G M⁻¹ Gᵀ) δ = −g`, `c += M⁻¹ G_cᵀ δ`,
    /// `R ← R exp(I⁻¹ G_θᵀ δ)` (minimum-norm `δ` for redundant loop rows), until the
    /// relative violation is at most `1e-14`, or stalls below `1e-10` (round-off of
    /// positions far from the origin; at most 30 iterations). For a start that does
    /// not close its loops exactly (a keyframe written for MuJoCo's soft equality
    /// constraints). Returns the relative position violation before the projection; the
    /// momenta are kept (project the velocities after).
    ///
    /// # Errors
    /// [`Error::InvalidModel`] when the rows are dependent in the tree, or when the violation
    /// does not fall below `1e-10` (a start too far from any closed pose).
    ///
    /// Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, IV.4
    /// (projection methods).
    pub fn project_positions(&mut self, system: &MultibodySystem, state: &mut MultibodyState) -> Result<f64> {
        self.work.project_positions(system, state)
    }
}

impl Workspace {
    /// The rows at `state` into `rows1` and `G M⁻¹ Gᵀ` of them factored; `false` when
    /// there are no rows (nothing factored).
    fn factor_rows_of(&mut self, sys: &MultibodySystem, state: &MultibodyState) -> Result<bool> {
        self.end_rows_at(sys, &state.c, &state.rotation);
        if self.rows1.iter().all(|r| r.n == 0) {
            return Ok(false);
        }
        self.factor(sys, Matrix::End)?;
        Ok(true)
    }

    /// Project the velocities of `state` onto the velocity constraints `G (v, Ω) = 0` in
    /// the kinetic-energy metric: `(G M⁻¹ Gᵀ) μ = −G (v, Ω)`, `p += G_cᵀ μ`,
    /// `Π += G_θᵀ μ` (minimum-norm `μ` for redundant loop rows). For joint velocities that
    /// do not respect loop-closing joints (a loader's `qvel` on a closed loop). Returns the
    /// relative velocity violation before the projection.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] when the tree rows are dependent at this configuration.
    ///
    /// Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, VII.1
    /// (the velocity projection of RATTLE).
    pub(super) fn project_velocities(&mut self, sys: &MultibodySystem, state: &mut MultibodyState) -> Result<f64> {
        let (_, before) = sys.constraint_violation_with(state, &self.limit);
        if !self.factor_rows_of(sys, state)? {
            return Ok(before);
        }
        self.velocities(sys, &state.p, &state.pi);
        self.rates_rhs(sys, false, -1.0);
        self.timed_solve(sys);
        add_impulse(&sys.joints, &self.rows1, &self.delta, 1.0, &mut state.p, &mut state.pi);
        self.cache_valid = false;
        self.factor_rows0 = false;
        Ok(before)
    }

    /// Project the positions of `state` onto the position constraints `g(q) = 0` in the
    /// kinetic-energy metric, by Gauss-Newton: `(G M⁻¹ Gᵀ) δ = −g`, `c += M⁻¹ G_cᵀ δ`,
    /// `R ← R exp(I⁻¹ G_θᵀ δ)` (minimum-norm `δ` for redundant loop rows), until the
    /// relative violation is at most `1e-14`, or stalls below `1e-10` (round-off of
    /// positions far from the origin; at most 30 iterations). For a start that does
    /// not close its loops exactly (a keyframe written for MuJoCo's soft equality
    /// constraints). Returns the relative position violation before the projection; the
    /// momenta are kept (project the velocities after).
    ///
    /// # Errors
    /// [`Error::InvalidModel`] when the rows are dependent in the tree, or when the violation
    /// does not fall below `1e-10` (a start too far from any closed pose).
    ///
    /// Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, IV.4
    /// (projection methods).
    pub(super) fn project_positions(&mut self, sys: &MultibodySystem, state: &mut MultibodyState) -> Result<f64> {
        let (before, _) = sys.constraint_violation_with(state, &self.limit);
        let mut violation = before;
        let mut iterations = 0;
        while violation > 1e-14 {
            if iterations == 30 || !violation.is_finite() {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "the start cannot be brought onto the joints' position constraints: relative violation \
                         {violation:.3e} after {iterations} Gauss-Newton iterations (a start far from any pose that \
                         closes the loops)"
                    ),
                });
            }
            iterations += 1;
            self.factor_rows_of(sys, state)?;
            for (k, jr) in self.rows1.iter().enumerate() {
                for r in 0..jr.n {
                    self.rhs[k][r] = -jr.value[r];
                }
            }
            self.timed_solve(sys);
            self.vel.iter_mut().for_each(|v| *v = Vec3::ZERO);
            self.omega.iter_mut().for_each(|v| *v = Vec3::ZERO);
            add_impulse(
                &sys.joints,
                &self.rows1,
                &self.delta,
                1.0,
                &mut self.vel,
                &mut self.omega,
            );
            if let Some(a) = &sys.armature {
                a.solve(&mut self.omega);
                for i in 0..sys.mass.len() {
                    state.c[i] += self.vel[i] * (1.0 / sys.mass[i]);
                    state.rotation[i] = state.rotation[i] * crate::so3::exp(self.omega[i]);
                }
            } else {
                for i in 0..sys.mass.len() {
                    state.c[i] += self.vel[i] * (1.0 / sys.mass[i]);
                    state.rotation[i] =
                        state.rotation[i] * crate::so3::exp(sys.inertia[i].apply_inverse(self.omega[i]));
                }
            }
            // Quadratic convergence down to round-off of the positions, which far from the
            // origin lies above 1e-14: stop where the decrease stalls below 1e-10.
            let next = sys.constraint_violation_with(state, &self.limit).0;
            let stalled = next > 0.5 * violation;
            violation = next;
            if stalled && violation <= 1e-10 {
                break;
            }
        }
        self.cache_valid = false;
        self.factor_rows0 = false;
        Ok(before)
    }
}
