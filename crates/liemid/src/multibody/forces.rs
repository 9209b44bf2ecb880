//! Forces of the multibody step: gravity, constant body loads, joint springs and dampers
//! (generalized forces along the exact gradient of the joint coordinate), and a user hook.
//! Springs are conservative (`−k (q − q_ref) ∇q` is the gradient of `½ k (q − q_ref)²`);
//! dampers (`−d q̇ ∇q`, applied by the half-kicks of `dampers.rs`, which need the
//! velocities and so are the integrator's) are not, so they make the
//! step neither symplectic nor energy-preserving.
//! The hinge angle is read in `(−π, π]`, so a hinge spring's potential jumps where the
//! angle wraps at `±π` from its rest angle: springs are meant for hinges that stay within
//! half a turn of `spring_ref`.
//!
//! Reference: docs/theory/multibody.md §3; B. Leimkuhler, S. Reich, *Simulating Hamiltonian
//! Dynamics*, ch. 7.

use crate::linalg::{Mat3, Vec3};

use super::constraints::{apply, ball_angle, pose};
use super::model::JointKind;
use super::system::MultibodySystem;

impl MultibodySystem {
    /// The position-dependent forces (gravity, constant loads, springs, the hook) at
    /// `(t, c, R)` into `force`, `torque`.
    pub(super) fn forces(&self, t: f64, c: &[Vec3], r: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]) {
        for i in 0..self.mass.len() {
            force[i] = self.gravity * self.mass[i] + self.const_force[i];
            torque[i] = self.const_torque[i];
        }
        for (k, g) in self.joints.iter().enumerate() {
            let par = &self.params[k];
            if par.stiffness == 0.0 {
                continue;
            }
            let (pi, pj) = pose(g, c, r);
            if g.kind == JointKind::Ball {
                // V = ½ k |θ|², θ = log(Qᵀ R_iᵀ R_j): the child's torque −k θ (its frame), the
                // parent's k Q θ (its frame); exact, as θ is its own image under the
                // inverse Jacobians of log.
                let theta = ball_angle(g, pi.1, pj.1);
                torque[g.child] -= theta * par.stiffness;
                if let Some(p) = g.parent {
                    torque[p] += (g.q * theta) * par.stiffness;
                }
            } else if let Some((q, grad)) = g.coordinate(pi, pj) {
                apply(g, &grad, -par.stiffness * (q - par.spring_ref), force, torque);
            }
        }
        // Actuators (docs/theory/multibody.md §8): the control clamped, the force at the
        // coordinate without its viscous part (held by the dampers), clamped, times the
        // gear, summed on the joint and clamped by its actuatorfrcrange.
        for (k, acts) in &self.actuated {
            let g = &self.joints[*k];
            let (pi, pj) = pose(g, c, r);
            let Some((q, grad)) = g.coordinate(pi, pj) else {
                continue;
            };
            let mut total = 0.0;
            for a in acts.clone() {
                let act = &self.actuators[a];
                let u = act.clamp_ctrl(self.ctrl[self.actuator_order[a]]);
                total += act.gear * act.force(u, q, 0.0);
            }
            if let Some((lo, hi)) = self.joint_force_range[*k] {
                total = total.clamp(lo, hi);
            }
            apply(g, &grad, total, force, torque);
        }
        if let Some(hook) = self.hook.as_ref() {
            hook.add(t, c, r, force, torque);
        }
    }
}
