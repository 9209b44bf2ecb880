//! Joint-space kinematics: each joint's pose and motion subspace, the bodies' velocities
//! and velocity-product accelerations, `q̇ = Q(q) v`, and the observables (poses, centre-of-
//! mass states, energy, momentum).
//!
//! ## Reference
//!
//! R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, ch. 2 and 4.

use super::spatial::{add6, ang, basis, cross_motion, lin, sv, Xform, ZERO6};
use super::{check_len, quat_at, quat_rate, JointSpaceModel, Kind};
use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
use crate::so3::{exp, Quaternion};

impl JointSpaceModel {
    /// The pose `(r, E)` of body `i` in its parent and the joint's motion subspace, into
    /// the scratch, with the world poses.
    pub(super) fn kinematics(&mut self, q: &[f64]) -> Result<()> {
        check_len("q", q, self.nq)?;
        let w = &mut self.w;
        for (i, n) in self.nodes.iter().enumerate() {
            let qj = &q[n.iq..];
            let b = n.anchor;
            let s = &mut w.s[i];
            let xf = match n.kind {
                Kind::Weld => Xform { e: n.e0, r: n.t0 },
                Kind::Hinge(u) => {
                    s[0] = sv(u, b.cross(u));
                    let e = n.e0 * exp(u * qj[0]);
                    Xform {
                        e,
                        r: n.t0 + n.e0 * b - e * b,
                    }
                }
                Kind::Universal(a, a2) => {
                    let second = exp(a2 * qj[1]);
                    let a1 = second.tr_mul_vec(a);
                    s[0] = sv(a1, b.cross(a1));
                    s[1] = sv(a2, b.cross(a2));
                    let e = n.e0 * exp(a * qj[0]) * second;
                    Xform {
                        e,
                        r: n.t0 + n.e0 * b - e * b,
                    }
                }
                Kind::Slide(u) => {
                    s[0] = sv(Vec3::ZERO, u);
                    Xform {
                        e: n.e0,
                        r: n.t0 + (n.e0 * u) * qj[0],
                    }
                }
                Kind::Ball => {
                    let e = n.e0 * quat_at(&qj[..4])?.to_matrix();
                    for (k, col) in s.iter_mut().take(3).enumerate() {
                        let ek = basis(k);
                        *col = sv(ek, b.cross(ek));
                    }
                    Xform {
                        e,
                        r: n.t0 + n.e0 * b - e * b,
                    }
                }
                Kind::Free => {
                    let e = quat_at(&qj[3..7])?.to_matrix();
                    let et = e.transpose();
                    for k in 0..3 {
                        s[k] = sv(Vec3::ZERO, et.col(k));
                        let ek = basis(k);
                        s[k + 3] = sv(ek, Vec3::ZERO);
                    }
                    Xform {
                        e,
                        r: Vec3::new(qj[0], qj[1], qj[2]),
                    }
                }
            };
            w.xf[i] = xf;
            w.xm[i] = xf.matrix();
            let (xp, rp) = match n.parent {
                None => (Vec3::ZERO, Mat3::IDENTITY),
                Some(p) => (w.pos[p], w.rot[p]),
            };
            w.rot[i] = rp * xf.e;
            w.pos[i] = xp + rp * xf.r;
        }
        Ok(())
    }

    /// Velocities `v_i = ⁱX_λ v_λ + S q̇` and velocity-product accelerations
    /// `c_i = S̊ q̇ + v_i × S q̇` of every body, after [`kinematics`](Self::kinematics).
    pub(super) fn velocities(&mut self, v: &[f64]) -> Result<()> {
        check_len("v", v, self.nv)?;
        let w = &mut self.w;
        for (i, n) in self.nodes.iter().enumerate() {
            let vj = &v[n.iv..n.iv + n.nd];
            let mut vjs = ZERO6;
            for (k, &x) in vj.iter().enumerate() {
                for (a, col) in vjs.iter_mut().zip(&w.s[i][k]) {
                    *a += col * x;
                }
            }
            let vp = match n.parent {
                None => ZERO6,
                Some(p) => w.xf[i].motion(&w.vel[p]),
            };
            let vi = add6(&vp, &vjs);
            let mut c = cross_motion(&vi, &vjs);
            if let Kind::Universal(_, a2) = n.kind {
                // S̊ q̇ = θ̇₁ θ̇₂ (d; b × d), d = −a₂ × a'.
                let d = a2.cross(ang(&w.s[i][0])) * (-vj[0] * vj[1]);
                let bd = n.anchor.cross(d);
                for k in 0..3 {
                    c[k] += d[k];
                    c[k + 3] += bd[k];
                }
            }
            if n.kind == Kind::Free {
                // S̊ q̇ = (0; −ω × Eᵀ ṗ).
                let om = Vec3::new(vj[3], vj[4], vj[5]);
                let lv = w.xf[i].e.tr_mul_vec(Vec3::new(vj[0], vj[1], vj[2]));
                let sd = om.cross(lv);
                c[3] -= sd.x;
                c[4] -= sd.y;
                c[5] -= sd.z;
            }
            w.vel[i] = vi;
            w.c[i] = c;
        }
        Ok(())
    }

    /// The time derivative of the coordinates, `q̇ = Q(q) v` (into `qdot`, length `nq`):
    /// hinge, slide and universal `q̇ = v`, ball `Q̇ = ½ Q ⊗ (0, ω)`, free `ṗ` then `Q̇ = ½ Q ⊗ (0, ω)`
    /// (on the quaternion as given, not normalised, so that the flow keeps `|Q|`).
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §4.5.
    pub fn qdot(&self, q: &[f64], v: &[f64], qdot: &mut [f64]) -> Result<()> {
        check_len("q", q, self.nq)?;
        check_len("v", v, self.nv)?;
        if qdot.len() != self.nq {
            return Err(Error::InvalidParameter {
                name: "qdot",
                value: qdot.len() as f64,
                reason: "length differs from nq",
            });
        }
        for n in &self.nodes {
            let (iq, iv) = (n.iq, n.iv);
            match n.kind {
                Kind::Weld => {}
                Kind::Hinge(_) | Kind::Slide(_) => qdot[iq] = v[iv],
                Kind::Universal(..) => qdot[iq..iq + 2].copy_from_slice(&v[iv..iv + 2]),
                Kind::Ball => {
                    let d = quat_rate(&q[iq..iq + 4], Vec3::new(v[iv], v[iv + 1], v[iv + 2]));
                    qdot[iq..iq + 4].copy_from_slice(&d);
                }
                Kind::Free => {
                    qdot[iq..iq + 3].copy_from_slice(&v[iv..iv + 3]);
                    let d = quat_rate(&q[iq + 3..iq + 7], Vec3::new(v[iv + 3], v[iv + 4], v[iv + 5]));
                    qdot[iq + 3..iq + 7].copy_from_slice(&d);
                }
            }
        }
        Ok(())
    }

    /// Forward kinematics: per body, its frame's origin in world coordinates and its
    /// attitude (body to world), `R_i = R_λ E`, `x_i = x_λ + R_λ r` with the joint
    /// transforms of the module documentation. At [`qpos0`](Self::qpos0) these are the
    /// bodies' reference world poses (to round-off).
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §4.1.
    pub fn forward_kinematics(&mut self, q: &[f64]) -> Result<Vec<(Vec3, Mat3)>> {
        self.kinematics(q)?;
        Ok(self.w.pos.iter().copied().zip(self.w.rot.iter().copied()).collect())
    }

    /// MuJoCo's `xpos` and `xquat` per body: the frame origin in world coordinates and the
    /// attitude as a unit quaternion (scalar first, non-negative scalar part).
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §4.1.
    pub fn body_poses(&mut self, q: &[f64]) -> Result<Vec<(Vec3, Quaternion)>> {
        self.kinematics(q)?;
        Ok(self
            .w
            .pos
            .iter()
            .zip(&self.w.rot)
            .map(|(x, r)| (*x, Quaternion::from_matrix(r)))
            .collect())
    }

    /// Per body, the centre-of-mass position `c_i = x_i + R_i s_i`, velocity
    /// `ċ_i = R_i (u_i + ω_i × s_i)` and angular velocity `R_i ω_i`, all in world
    /// coordinates (`(ω_i; u_i)` the body's spatial velocity in its own coordinates).
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §2.2.
    pub fn com_states(&mut self, q: &[f64], v: &[f64]) -> Result<Vec<(Vec3, Vec3, Vec3)>> {
        self.kinematics(q)?;
        self.velocities(v)?;
        Ok(self
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let (r, vel) = (self.w.rot[i], &self.w.vel[i]);
                let om = ang(vel);
                let vc = lin(vel) + om.cross(n.com);
                (self.w.pos[i] + r * n.com, r * vc, r * om)
            })
            .collect())
    }

    /// The total energy: kinetic `Σ ½ m_i |ċ_i|² + ½ ω_iᵀ I_i ω_i` (centre-of-mass velocity,
    /// body angular velocity and the inertia about the centre of mass) plus `½ a q̇²` of
    /// every armature, gravity's potential `−Σ m_i g · c_i`, and the springs'
    /// `½ k (q − q_ref)²`. Conserved by the exact flow of [`aba`](Self::aba) without
    /// dampers and applied forces.
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §2.13.
    pub fn energy(&mut self, q: &[f64], v: &[f64]) -> Result<f64> {
        self.kinematics(q)?;
        self.velocities(v)?;
        let mut e = 0.0;
        for (i, n) in self.nodes.iter().enumerate() {
            let vel = &self.w.vel[i];
            let om = ang(vel);
            let vc = lin(vel) + om.cross(n.com);
            e += 0.5 * n.mass * vc.norm_squared() + 0.5 * om.dot(n.inertia_com * om);
            let c = self.w.pos[i] + self.w.rot[i] * n.com;
            e -= n.mass * self.gravity.dot(c);
            if n.nd == 1 {
                let dq = q[n.iq] - n.spring_ref;
                e += 0.5 * n.stiffness * dq * dq + 0.5 * Self::armature(n) * v[n.iv] * v[n.iv];
            }
            if n.kind == Kind::Ball && n.stiffness != 0.0 {
                e += 0.5 * n.stiffness * super::dynamics::ball_angle(&q[n.iq..n.iq + 4]).norm_squared();
            }
        }
        Ok(e)
    }

    /// The total linear momentum `Σ m_i ċ_i` and angular momentum about the world origin
    /// `Σ c_i × m_i ċ_i + R_i I_i ω_i`, in world coordinates (docs/theory/multibody.md §5's
    /// `Σ c_i × p_i + R_i Π_i`); kept by the exact flow when no external force or joint to
    /// the world acts (armature, a rotor fixed in no body, is not counted).
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §2.12.
    pub fn momentum(&mut self, q: &[f64], v: &[f64]) -> Result<(Vec3, Vec3)> {
        self.kinematics(q)?;
        self.velocities(v)?;
        let (mut p, mut l) = (Vec3::ZERO, Vec3::ZERO);
        for (i, n) in self.nodes.iter().enumerate() {
            let (r, vel) = (self.w.rot[i], &self.w.vel[i]);
            let om = ang(vel);
            let vc = r * (lin(vel) + om.cross(n.com));
            let c = self.w.pos[i] + r * n.com;
            p += vc * n.mass;
            l += c.cross(vc * n.mass) + r * (n.inertia_com * om);
        }
        Ok((p, l))
    }
}
