//! The velocity solve of the multibody step: the μ-kick, one linear solve of
//! `(h/2) G M⁻¹ Gᵀ μ = −G (v, Ω)` at the end configuration so that `G(q⁺)(v⁺, Ω⁺) = 0`
//! (docs/theory/multibody.md §3), with the end damping force (solved implicitly with it, see
//! `dampers.rs`) and the release of plastic limit rows that pull.
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, VII.1 (RATTLE).

use crate::error::Result;
use crate::linalg::Vec3;

use super::constraints::{add_impulse, for_each_rate};
use super::method::{LimitState, StepReport, MAX_LIMIT_PASSES};
use super::system::MultibodySystem;
use super::workspace::{Matrix, Workspace};

impl Workspace {
    /// The μ-kick: one linear solve so that `G(q⁺)(v⁺, Ω⁺) = 0`; with dampers two, around
    /// the end damping half-kick (`dampers.rs`).
    pub(super) fn solve_velocities(
        &mut self,
        sys: &MultibodySystem,
        t: f64,
        h: f64,
        report: &mut StepReport,
    ) -> Result<()> {
        let nb = sys.mass.len();
        let hh = 0.5 * h;
        let any_rows = self.rows1.iter().any(|r| r.n > 0);
        if any_rows {
            self.factor(sys, Matrix::End)?;
            report.factorizations += 1;
        }
        self.damp_f.iter_mut().for_each(|v| *v = Vec3::ZERO);
        self.damp_t.iter_mut().for_each(|v| *v = Vec3::ZERO);
        if sys.has_damping {
            self.end_dampers(sys, t, hh, any_rows, report)?;
        } else {
            self.velocity_pass(sys, hh, any_rows, report)?;
        }
        if sys.has_friction {
            // The friction rows after the other forces (`friction.rs`), then the μ-kick
            // with them.
            self.end_friction(sys, t, hh, any_rows)?;
            self.velocity_pass(sys, hh, any_rows, report)?;
        }
        if sys.contact.is_some() && self.end_contacts(sys, t, hh, report)? {
            // The contact forces after the others (`contact/step.rs`), then the μ-kick.
            self.velocity_pass(sys, hh, any_rows, report)?;
        }
        // Apply the end kick into p_half / pi_new.
        for i in 0..nb {
            self.p_half[i] += (self.force1[i] + self.damp_f[i]) * hh;
            self.pi_new[i] += (self.torque1[i] + self.damp_t[i]) * hh;
        }
        if any_rows {
            add_impulse(
                &sys.joints,
                &self.rows1,
                &self.delta,
                hh,
                &mut self.p_half,
                &mut self.pi_new,
            );
        }
        // Velocity violation of the result.
        self.velocities_of_new(sys);
        let vscale = (0..nb).fold(sys.velocity_floor(), |m, i| {
            m.max(self.vel[i].norm() + sys.length * self.omega[i].norm())
        });
        let mut worst: f64 = 0.0;
        for_each_rate(&sys.joints, &self.rows1, &self.vel, &self.omega, |_, _, rate| {
            worst = worst.max(rate.abs());
        });
        if vscale > 0.0 {
            worst /= vscale;
        }
        report.velocity_violation = report.velocity_violation.max(worst);
        Ok(())
    }

    /// One solve for μ with the current damping forces: `w* = M⁻¹ (p' + (h/2)(F⁺ + D))`,
    /// then `(h/2) G M⁻¹ Gᵀ μ = −G w*` into `delta`. A plastic limit row whose μ pulls is
    /// released and the solve redone (at most [`MAX_LIMIT_PASSES`] times).
    pub(super) fn velocity_pass(
        &mut self,
        sys: &MultibodySystem,
        hh: f64,
        any_rows: bool,
        report: &mut StepReport,
    ) -> Result<()> {
        let mut limit_pass = 0;
        loop {
            if sys.armature.is_some() {
                for i in 0..sys.mass.len() {
                    self.vel[i] = (self.p_half[i] + (self.force1[i] + self.damp_f[i]) * hh) * (1.0 / sys.mass[i]);
                    self.omega[i] = self.pi_new[i] + (self.torque1[i] + self.damp_t[i]) * hh;
                }
                self.rates_in_place(sys);
            } else {
                for i in 0..sys.mass.len() {
                    self.vel[i] = (self.p_half[i] + (self.force1[i] + self.damp_f[i]) * hh) * (1.0 / sys.mass[i]);
                    self.omega[i] =
                        sys.inertia[i].apply_inverse(self.pi_new[i] + (self.torque1[i] + self.damp_t[i]) * hh);
                }
            }
            if !any_rows {
                return Ok(());
            }
            self.rates_rhs(sys, false, -1.0 / hh);
            self.timed_solve(sys);
            // A plastic limit row whose μ pulls is released and the solve redone.
            let mut released = false;
            for k in 0..sys.joints.len() {
                if self.limit[k] == LimitState::Inactive {
                    continue;
                }
                let m = self.delta[k][sys.joints[k].kind.rows()];
                if (self.limit[k] == LimitState::Lower && m < 0.0) || (self.limit[k] == LimitState::Upper && m > 0.0) {
                    self.limit[k] = LimitState::Inactive;
                    released = true;
                }
            }
            if !(released && limit_pass < MAX_LIMIT_PASSES) {
                return Ok(());
            }
            limit_pass += 1;
            report.limit_changes += 1;
            self.end_rows(sys);
            self.factor(sys, Matrix::End)?;
            report.factorizations += 1;
        }
    }

    /// `rhs = scale · G (v, Ω)` over the start rows `rows0` (`start`) or the end rows
    /// `rows1` at the velocities in `vel`, `omega`: the right side of a velocity solve.
    pub(super) fn rates_rhs(&mut self, sys: &MultibodySystem, start: bool, scale: f64) {
        let rhs = &mut self.rhs;
        let rows = if start { &self.rows0 } else { &self.rows1 };
        for_each_rate(&sys.joints, rows, &self.vel, &self.omega, |k, r, rate| {
            rhs[k][r] = scale * rate;
        });
    }

    /// Velocities after the provisional μ-kick (for the end dampers).
    pub(super) fn end_velocities(&mut self, sys: &MultibodySystem, hh: f64) {
        for i in 0..sys.mass.len() {
            self.vel[i] = self.p_half[i] + (self.force1[i] + self.damp_f[i]) * hh;
            self.omega[i] = self.pi_new[i] + (self.torque1[i] + self.damp_t[i]) * hh;
        }
        add_impulse(
            &sys.joints,
            &self.rows1,
            &self.delta,
            hh,
            &mut self.vel,
            &mut self.omega,
        );
        for i in 0..sys.mass.len() {
            self.vel[i] = self.vel[i] * (1.0 / sys.mass[i]);
        }
        self.rates_in_place(sys);
    }

    pub(super) fn velocities_of_new(&mut self, sys: &MultibodySystem) {
        if sys.armature.is_some() {
            for i in 0..sys.mass.len() {
                self.vel[i] = self.p_half[i] * (1.0 / sys.mass[i]);
            }
            self.omega.copy_from_slice(&self.pi_new);
            self.rates_in_place(sys);
            return;
        }
        for i in 0..sys.mass.len() {
            self.vel[i] = self.p_half[i] * (1.0 / sys.mass[i]);
            self.omega[i] = sys.inertia[i].apply_inverse(self.pi_new[i]);
        }
    }
}
