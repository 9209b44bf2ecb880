//! Forces of the multibody step: gravity, constant body loads, joint springs and dampers
//! (generalized forces along the exact gradient of the joint coordinate), and a user hook.
//! Springs are conservative (`−k (q − q_ref) ∇q` is the gradient of `½ k (q − q_ref)²`);
//! dampers (`−d q̇ ∇q`, applied by the half-kicks of `dampers.rs`) are not, so they make the
//! step neither symplectic nor energy-preserving.
//! The hinge angle is read in `(−π, π]`, so a hinge spring's potential jumps where the
//! angle wraps at `±π` from its rest angle: springs are meant for hinges that stay within
//! half a turn of `spring_ref`.
//!
//! Reference: multibody spec section 3; B. Leimkuhler, S. Reich, *Simulating Hamiltonian
//! Dynamics*, ch. 7.

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};

use super::constraints::{JointGeometry, Row};
use super::model::JointKind;
use super::rattle::{pose, MultibodySystem};

/// A force law added to gravity, springs and constant loads: given the time and the
/// configuration (centres of mass `c`, attitudes `R`), add to each body's force (space,
/// at the centre of mass) and torque (body frame). Forces that depend on the positions
/// only keep the step symplectic when they are the gradient of a potential.
///
/// Reference: multibody spec section 3 (`F(q)`, `T(q)`).
pub trait ForceHook: Send {
    /// Add the forces and body torques at `(t, c, rotation)`.
    fn add(&mut self, t: f64, c: &[Vec3], rotation: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]);
}

impl<F> ForceHook for F
where
    F: FnMut(f64, &[Vec3], &[Mat3], &mut [Vec3], &mut [Vec3]) + Send,
{
    fn add(&mut self, t: f64, c: &[Vec3], rotation: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]) {
        self(t, c, rotation, force, torque);
    }
}

impl MultibodySystem {
    /// A constant force (space, at the centre of mass) and body-frame torque on body `i`;
    /// the force has the potential `−F·c` (included in the energy), the body torque none.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for an index out of range or a non-finite vector.
    pub fn set_body_load(&mut self, i: usize, force: Vec3, torque: Vec3) -> Result<()> {
        if i >= self.mass.len() || !force.is_finite() || !torque.is_finite() {
            return Err(Error::InvalidParameter {
                name: "body load",
                value: i as f64,
                reason: "body index out of range or load not finite",
            });
        }
        self.const_force[i] = force;
        self.const_torque[i] = torque;
        self.cache_valid = false;
        Ok(())
    }

    /// Install a force hook (replacing any earlier one).
    pub fn set_force_hook(&mut self, hook: Box<dyn ForceHook>) {
        self.hook = Some(hook);
        self.cache_valid = false;
    }

    /// The position-dependent forces (gravity, constant loads, springs, the hook) at
    /// `(t, c, R)` into `force`, `torque`.
    pub(super) fn forces(&mut self, t: f64, c: &[Vec3], r: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]) {
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
        if let Some(hook) = self.hook.as_mut() {
            hook.add(t, c, r, force, torque);
        }
    }
}

/// Add the generalized force `f` along the gradient `grad` to the bodies of joint `g`.
#[inline]
pub(super) fn apply(g: &JointGeometry, grad: &Row, f: f64, force: &mut [Vec3], torque: &mut [Vec3]) {
    if let Some(p) = g.parent {
        force[p] += grad.ci * f;
        torque[p] += grad.ti * f;
    }
    force[g.child] += grad.cj * f;
    torque[g.child] += grad.tj * f;
}

/// The rotation vector `θ = log(Qᵀ R_iᵀ R_j)` of a ball joint: the child's attitude relative
/// to the parent's at the reference configuration (its spring's coordinate).
pub(super) fn ball_angle(g: &JointGeometry, ri: &Mat3, rj: &Mat3) -> Vec3 {
    crate::so3::log(&(g.q.transpose() * (ri.transpose() * *rj)))
}
