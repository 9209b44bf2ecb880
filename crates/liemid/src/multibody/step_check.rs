//! The step check before a run: every hinge and slide row with a damper (the joint's
//! `damping`, an actuator's `kv`) or an actuator's stiffness (`kp`) must be held by the
//! method at the requested step, else the run is refused before its first step, naming
//! the joint and the largest step that holds it.
//!
//! Each row is taken alone as the scalar model the step applies to it: coordinate `q`,
//! rate `v`, response `a = D P M⁻¹ Dᵀ` (the row's own constrained response at the start,
//! from one projected solve; its inverse the effective inertia), stiffness
//! `k = k_joint + Σ gear² kp` and damping `d = d_joint + Σ gear² kv`. One stage of step
//! `τ` (`γ_s h` in a composition) is, with `x = τ d a / 2`,
//!
//! ```text
//!     v½ = v + (τ/2) a (−k q − d v)            (x ≤ 2; above: v½ = (v − (τ/2) a k q) / (1 + x))
//!     q⁺ = q + τ v½
//!     v⁺ = (v½ − (τ/2) a k q⁺) / (1 + x)
//! ```
//!
//! (`dampers.rs`: the trapezoidal damper, backward Euler at the start above `x = 2`; the
//! spring kicks of RATTLE). The composed 2x2 map must have spectral radius at most 1 and
//! every `1 + x > 0` (a negative sub-step with `x ≤ −1` has no solution). The row's own
//! response is at most the largest of the coupled rows, so a refused row is one the run
//! cannot hold (no run that holds is refused); coupling between rows can still fail a
//! run later, which the step reports as today.
//!
//! Reference: docs/theory/multibody.md §8; E. Hairer, C. Lubich, G. Wanner, *Geometric
//! Numerical Integration*, 2nd ed., Springer 2006, I.5 and II.4 (stability of
//! Störmer–Verlet and its compositions).

use crate::error::{Error, Result};
use crate::linalg::Vec3;

use super::constraints::{apply, pose};
use super::method::MultibodyMethod;
use super::rattle::Rattle;
use super::state::MultibodyState;
use super::system::MultibodySystem;
use super::workspace::Matrix;

/// The scalar model's amplification over one composed step of `h` (module docs);
/// `None` when a negative sub-step cannot be solved (`1 + x ≤ 0`).
fn amplification(method: MultibodyMethod, h: f64, a: f64, k: f64, d: f64) -> Option<f64> {
    let stages: Vec<f64> = match method.scheme() {
        None => vec![1.0],
        Some(s) => (0..s.stages()).map(|i| s.gamma(i)).collect(),
    };
    // The map on (q, v) as a 2x2 matrix, columns the images of (1, 0) and (0, 1).
    let mut m = [[1.0, 0.0], [0.0, 1.0]];
    for g in stages {
        let tau = g * h;
        let x = 0.5 * tau * d * a;
        if 1.0 + x <= 0.0 {
            return None;
        }
        let stage = |q: f64, v: f64| {
            let vh = if x > 2.0 {
                (v - 0.5 * tau * a * k * q) / (1.0 + x)
            } else {
                v + 0.5 * tau * a * (-k * q - d * v)
            };
            let q1 = q + tau * vh;
            (q1, (vh - 0.5 * tau * a * k * q1) / (1.0 + x))
        };
        let c0 = stage(m[0][0], m[1][0]);
        let c1 = stage(m[0][1], m[1][1]);
        m = [[c0.0, c1.0], [c0.1, c1.1]];
    }
    // Eigenvalues of a 2x2 matrix.
    let (tr, det) = (m[0][0] + m[1][1], m[0][0] * m[1][1] - m[0][1] * m[1][0]);
    let disc = 0.25 * tr * tr - det;
    Some(if disc >= 0.0 {
        (0.5 * tr).abs() + disc.sqrt()
    } else {
        det.abs().sqrt()
    })
}

fn holds(method: MultibodyMethod, h: f64, a: f64, k: f64, d: f64) -> bool {
    amplification(method, h, a, k, d).is_some_and(|r| r.is_finite() && r <= 1.0 + 1e-9)
}

impl MultibodySystem {
    /// The stiffness and damping of each hinge and slide row (joint and actuators).
    fn row_coefficients(&self, k: usize) -> (f64, f64) {
        let mut stiffness = self.params[k].stiffness;
        for (j, acts) in &self.actuated {
            if *j == k {
                for a in acts.clone() {
                    let act = &self.actuators[a];
                    stiffness -= act.gear * act.gear * act.bias[1];
                }
            }
        }
        (stiffness, self.params[k].damping)
    }
}

impl Rattle {
    /// Check that the method holds every damper and actuator row of `system` at step `h`
    /// from `state` (module docs), with a scratch integrator of its own (this one is not
    /// touched, so the run's bits do not depend on the check).
    ///
    /// # Errors
    /// [`Error::InvalidModel`] naming the joint, its stiffness, damping and effective
    /// inertia, and the largest step that holds it.
    pub fn check_step(&self, system: &MultibodySystem, state: &MultibodyState, h: f64) -> Result<()> {
        let method = self.method;
        let rows: Vec<usize> = (0..system.joints.len())
            .filter(|&k| {
                let (s, d) = system.row_coefficients(k);
                (s > 0.0 || d > 0.0) && system.joints[k].kind.axis().is_some()
            })
            .collect();
        if rows.is_empty() || !h.is_finite() || h == 0.0 {
            return Ok(());
        }
        let mut scratch = Rattle::new(system, method);
        let w = &mut scratch.work;
        w.start_rows_at(system, state);
        let any_rows = w.rows0.iter().any(|r| r.n > 0);
        if any_rows {
            w.factor(system, Matrix::Start)?;
        }
        let nb = system.mass.len();
        let (mut lin, mut ang) = (vec![Vec3::ZERO; nb], vec![Vec3::ZERO; nb]);
        for k in rows {
            let g = &system.joints[k];
            let (pi, pj) = pose(g, &state.c, &state.rotation);
            let Some((_, row)) = g.coordinate(pi, pj) else { continue };
            lin.iter_mut().for_each(|v| *v = Vec3::ZERO);
            ang.iter_mut().for_each(|v| *v = Vec3::ZERO);
            apply(g, &row, 1.0, &mut lin, &mut ang);
            w.project_response(system, &mut lin, &mut ang, any_rows);
            let (vi, wi) = g.parent.map_or((Vec3::ZERO, Vec3::ZERO), |p| (w.vel[p], w.omega[p]));
            let a = row.rate(vi, wi, w.vel[g.child], w.omega[g.child]);
            let (stiffness, damping) = system.row_coefficients(k);
            if a.is_nan() || a <= 0.0 || holds(method, h.abs(), a, stiffness, damping) {
                continue;
            }
            let mut largest = h.abs();
            while largest > 1e-300 && !holds(method, largest, a, stiffness, damping) {
                largest *= 0.98;
            }
            return Err(Error::InvalidModel {
                reason: format!(
                    "{} cannot hold joint `{}` at step {}: its row (stiffness {}, damping {} against an effective \
                     inertia {:.4e}) is unstable or unsolvable there; the largest step that holds it is about {:.3e} \
                     (or take --method liemid, whose damper is A-stable)",
                    method.name(),
                    system.joint_names[k],
                    crate::error::Num(h),
                    crate::error::Num(stiffness),
                    crate::error::Num(damping),
                    1.0 / a,
                    largest
                ),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scalar_model_is_verlets_and_the_trapezoidal_rules() {
        // Undamped: Verlet holds ω h < 2.
        assert!(holds(MultibodyMethod::Liemid, 1.99, 1.0, 1.0, 0.0));
        assert!(!holds(MultibodyMethod::Liemid, 2.01, 1.0, 1.0, 0.0));
        // A damper alone holds at any step with liemid; a composition's negative sub-step
        // fails once |γ h| d a / 2 >= 1.
        assert!(holds(MultibodyMethod::Liemid, 1e6, 1.0, 0.0, 1.0));
        assert!(!holds(MultibodyMethod::Liemid4, 1e3, 1.0, 0.0, 1.0));
    }
}
