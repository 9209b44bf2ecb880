//! Projections of a state onto the joints' constraints in the kinetic-energy metric: the
//! velocities onto `G (v, Ω) = 0` (one solve) and the positions onto `g(q) = 0`
//! (Gauss-Newton), for starts that do not respect loop-closing joints (a keyframe written
//! for MuJoCo's soft equalities, joint velocities across a loop).
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, IV.4 (projection methods) and VII.1 (RATTLE's velocity projection).

use crate::error::{Error, Result};
use crate::linalg::Vec3;

use super::model::Model;
use super::rattle::{add_impulse, Matrix};
use super::state::MultibodyState;
use super::MultibodySystem;

impl MultibodySystem {
    /// The rows at `state` into `rows1` and `G M⁻¹ Gᵀ` of them factored; `false` when
    /// there are no rows (nothing factored).
    fn factor_rows_of(&mut self, state: &MultibodyState) -> Result<bool> {
        Self::rows_at(
            &self.joints,
            &self.limit,
            &self.params,
            &state.c,
            &state.rotation,
            &mut self.rows1,
        );
        if self.rows1.iter().all(|r| r.n == 0) {
            return Ok(false);
        }
        self.factor(Matrix::End)?;
        Ok(true)
    }

    /// The start of `model` ([`Model::initial_state`]) brought onto its loop-closing joints
    /// when it has any: positions ([`Self::project_positions`]) then velocities
    /// ([`Self::project_velocities`]). Returns the state and the relative position and
    /// velocity violations found before (0 without loops). `model` is the one the system was
    /// built from.
    ///
    /// # Errors
    /// [`Model::initial_state`]'s errors and the projections'.
    pub fn initial_state_on_loops(&mut self, model: &Model) -> Result<(MultibodyState, f64, f64)> {
        let mut state = model.initial_state()?;
        if model.loop_joints().is_empty() {
            return Ok((state, 0.0, 0.0));
        }
        let position = self.project_positions(&mut state)?;
        let velocity = self.project_velocities(&mut state)?;
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
    pub fn project_velocities(&mut self, state: &mut MultibodyState) -> Result<f64> {
        let (_, before) = self.constraint_violation(state);
        if !self.factor_rows_of(state)? {
            return Ok(before);
        }
        self.velocities(&state.p, &state.pi);
        self.rates_rhs(false, -1.0);
        self.timed_solve();
        add_impulse(&self.joints, &self.rows1, &self.delta, 1.0, &mut state.p, &mut state.pi);
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
    pub fn project_positions(&mut self, state: &mut MultibodyState) -> Result<f64> {
        let (before, _) = self.constraint_violation(state);
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
            self.factor_rows_of(state)?;
            for (k, jr) in self.rows1.iter().enumerate() {
                for r in 0..jr.n {
                    self.rhs[k][r] = -jr.value[r];
                }
            }
            self.timed_solve();
            self.vel.iter_mut().for_each(|v| *v = Vec3::ZERO);
            self.omega.iter_mut().for_each(|v| *v = Vec3::ZERO);
            add_impulse(
                &self.joints,
                &self.rows1,
                &self.delta,
                1.0,
                &mut self.vel,
                &mut self.omega,
            );
            for i in 0..self.mass.len() {
                state.c[i] += self.vel[i] * (1.0 / self.mass[i]);
                state.rotation[i] = state.rotation[i] * crate::so3::exp(self.inertia[i].apply_inverse(self.omega[i]));
            }
            // Quadratic convergence down to round-off of the positions, which far from the
            // origin lies above 1e-14: stop where the decrease stalls below 1e-10.
            let next = self.constraint_violation(state).0;
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
