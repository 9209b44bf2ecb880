//! Joint-space dynamics: the articulated-body algorithm (forward dynamics), recursive
//! Newton-Euler (inverse dynamics) and the composite-rigid-body mass matrix, with the
//! joints' springs, dampers and armature.
//!
//! ## Reference
//!
//! R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, ch. 5-7.

// Small dense blocks (6x6, the joint's nd x nd) are indexed as in the formulas.
#![allow(clippy::needless_range_loop)]

use super::spatial::{add6, add66, congruence, cross_force, dot6, invert_small, mul6, sv, ZERO6, ZERO66};
use super::{check_len, invalid, JointSpaceModel, Kind, Node};
use crate::error::{Error, Result};
use crate::linalg::Vec3;

impl JointSpaceModel {
    /// The passive generalised forces on the first velocities of a joint:
    /// `−k (q − q_ref) − d q̇` for a hinge or slide; for a ball `−k θ − d ω`, `θ` the rotation
    /// vector of its quaternion (MuJoCo's ball spring, the gradient of `½ k |θ|²`) and `ω`
    /// its relative angular velocity; 0 for the others.
    pub(super) fn passive(n: &Node, q: &[f64], v: &[f64]) -> [f64; 3] {
        match n.kind {
            Kind::Hinge(_) | Kind::Slide(_) => {
                [-n.stiffness * (q[n.iq] - n.spring_ref) - n.damping * v[n.iv], 0.0, 0.0]
            }
            Kind::Ball => {
                let theta = if n.stiffness == 0.0 {
                    Vec3::ZERO
                } else {
                    ball_angle(&q[n.iq..n.iq + 4])
                };
                let w = Vec3::new(v[n.iv], v[n.iv + 1], v[n.iv + 2]);
                (theta * -n.stiffness - w * n.damping).to_array()
            }
            _ => [0.0; 3],
        }
    }

    /// The armature of a hinge or slide joint, 0 for the others.
    pub(super) fn armature(n: &Node) -> f64 {
        match n.kind {
            Kind::Hinge(_) | Kind::Slide(_) => n.armature,
            _ => 0.0,
        }
    }

    /// Forward dynamics by the articulated-body algorithm: the accelerations `q̈` (into
    /// `qdd`, length `nv`) for the state `(q, v)` and the applied generalised forces `tau`
    /// (length `nv`, in the layout of `v`), with gravity and the joints' springs and
    /// dampers. `M(q) q̈ + C(q, v) + G(q) = τ − k (q − q_ref) − d q̇` is solved in O(bodies)
    /// by three passes: velocities out, articulated inertias `Iᴬ` and bias forces `pᴬ` in
    /// (`U = Iᴬ S`, `D = Sᵀ U + armature`, `u = τ − Sᵀ pᴬ`,
    /// `Iᵃ = Iᴬ − U D⁻¹ Uᵀ`, `pᵃ = pᴬ + Iᵃ c + U D⁻¹ u`), accelerations out
    /// (`a' = X a_λ + c`, `q̈ = D⁻¹ (u − Uᵀ a')`, `a = a' + S q̈`), gravity as the base
    /// acceleration `a₀ = (0; −g)`. No allocation.
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §7.3, table 7.1.
    pub fn aba(&mut self, q: &[f64], v: &[f64], tau: &[f64], qdd: &mut [f64]) -> Result<()> {
        check_len("tau", tau, self.nv)?;
        self.aba_inner(q, v, Some(tau), qdd)
    }

    pub(super) fn aba_inner(&mut self, q: &[f64], v: &[f64], tau: Option<&[f64]>, qdd: &mut [f64]) -> Result<()> {
        if qdd.len() != self.nv {
            return Err(Error::InvalidParameter {
                name: "qdd",
                value: qdd.len() as f64,
                reason: "length differs from nv",
            });
        }
        self.kinematics(q)?;
        self.velocities(v)?;
        let actuated = !self.actuators.is_empty();
        if actuated {
            self.actuator_forces(q, v);
        }
        let w = &mut self.w;
        let nb = self.nodes.len();
        for (i, n) in self.nodes.iter().enumerate() {
            w.ia[i] = n.inertia;
            w.pa[i] = cross_force(&w.vel[i], &mul6(&n.inertia, &w.vel[i]));
        }
        for i in (0..nb).rev() {
            let n = &self.nodes[i];
            let nd = n.nd;
            let ia = w.ia[i];
            let pa = w.pa[i];
            let mut d = ZERO66;
            for k in 0..nd {
                w.u[i][k] = mul6(&ia, &w.s[i][k]);
                let tk = tau.map_or(0.0, |t| t[n.iv + k]);
                w.uu[i][k] = tk - dot6(&w.s[i][k], &pa);
            }
            for a in 0..nd {
                for b in 0..nd {
                    d[a][b] = dot6(&w.s[i][a], &w.u[i][b]);
                }
            }
            if nd == 1 {
                d[0][0] += Self::armature(n);
            }
            // (A free joint's six velocities carry no passive force.)
            for (u, f) in w.uu[i].iter_mut().zip(Self::passive(n, q, v)).take(nd) {
                *u += f;
            }
            if actuated && nd == 1 {
                w.uu[i][0] += w.qfrc[n.iv];
            }
            if nd > 0 {
                w.dinv[i] = invert_small(&d, nd).ok_or_else(|| {
                    invalid(format!(
                        "body {i}: the joint-space articulated inertia is singular or not finite"
                    ))
                })?;
            }
            if let Some(p) = n.parent {
                // Iᵃ = Iᴬ − U D⁻¹ Uᵀ, pᵃ = pᴬ + Iᵃ c + U D⁻¹ u.
                let mut iam = ia;
                let mut ud = [ZERO6; 6]; // U D⁻¹ columns
                for (a, col) in ud.iter_mut().enumerate().take(nd) {
                    for b in 0..nd {
                        let f = w.dinv[i][b][a];
                        for r in 0..6 {
                            col[r] += w.u[i][b][r] * f;
                        }
                    }
                }
                for (a, col) in ud.iter().enumerate().take(nd) {
                    let ua = &w.u[i][a];
                    for r in 0..6 {
                        for s in 0..6 {
                            iam[r][s] -= col[r] * ua[s];
                        }
                    }
                }
                let mut pam = add6(&pa, &mul6(&iam, &w.c[i]));
                for (a, col) in ud.iter().enumerate().take(nd) {
                    for r in 0..6 {
                        pam[r] += col[r] * w.uu[i][a];
                    }
                }
                let add = congruence(&w.xm[i], &iam);
                add66(&mut w.ia[p], &add);
                let fp = w.xf[i].force_to_parent(&pam);
                w.pa[p] = add6(&w.pa[p], &fp);
            }
        }
        let a0 = sv(Vec3::ZERO, -self.gravity);
        for (i, n) in self.nodes.iter().enumerate() {
            let ap = match n.parent {
                None => a0,
                Some(p) => w.acc[p],
            };
            let a1 = add6(&w.xf[i].motion(&ap), &w.c[i]);
            let mut rhs = [0.0; 6];
            for k in 0..n.nd {
                rhs[k] = w.uu[i][k] - dot6(&w.u[i][k], &a1);
            }
            let mut a = a1;
            for k in 0..n.nd {
                let x: f64 = (0..n.nd).map(|b| w.dinv[i][k][b] * rhs[b]).sum();
                qdd[n.iv + k] = x;
                for r in 0..6 {
                    a[r] += w.s[i][k][r] * x;
                }
            }
            w.acc[i] = a;
        }
        if let Some(bad) = qdd.iter().find(|x| !x.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "qdd",
                value: *bad,
                reason: "the accelerations came out non-finite",
            });
        }
        Ok(())
    }

    /// Inverse dynamics by the recursive Newton-Euler algorithm: the generalised forces
    /// `τ = M(q) q̈ + C(q, v) + G(q) + k (q − q_ref) + d q̇` (into `tau`) that produce the
    /// accelerations `qdd`; with `qdd = 0` the bias forces. Body accelerations out
    /// (`a_i = X a_λ + S q̈ + c_i`, `a₀ = (0; −g)`), forces `f_i = I a_i + v_i ×* I v_i`
    /// in, `τ_i = Sᵀ f_i`. The inverse of [`aba`](Self::aba). No allocation.
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §5.3, table 5.1.
    pub fn inverse_dynamics(&mut self, q: &[f64], v: &[f64], qdd: &[f64], tau: &mut [f64]) -> Result<()> {
        check_len("qdd", qdd, self.nv)?;
        if tau.len() != self.nv {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau.len() as f64,
                reason: "length differs from nv",
            });
        }
        self.kinematics(q)?;
        self.velocities(v)?;
        let actuated = !self.actuators.is_empty();
        if actuated {
            self.actuator_forces(q, v);
        }
        let w = &mut self.w;
        let a0 = sv(Vec3::ZERO, -self.gravity);
        // Forces accumulate in `pa`.
        for (i, n) in self.nodes.iter().enumerate() {
            let ap = match n.parent {
                None => a0,
                Some(p) => w.acc[p],
            };
            let mut a = add6(&w.xf[i].motion(&ap), &w.c[i]);
            for k in 0..n.nd {
                for r in 0..6 {
                    a[r] += w.s[i][k][r] * qdd[n.iv + k];
                }
            }
            w.acc[i] = a;
            let iv = mul6(&n.inertia, &w.vel[i]);
            w.pa[i] = add6(&mul6(&n.inertia, &a), &cross_force(&w.vel[i], &iv));
        }
        for i in (0..self.nodes.len()).rev() {
            let n = &self.nodes[i];
            for k in 0..n.nd {
                tau[n.iv + k] = dot6(&w.s[i][k], &w.pa[i]);
            }
            if n.nd == 1 {
                tau[n.iv] += Self::armature(n) * qdd[n.iv];
            }
            for (t, f) in tau[n.iv..n.iv + n.nd].iter_mut().zip(Self::passive(n, q, v)) {
                *t -= f;
            }
            if let Some(p) = n.parent {
                let fp = w.xf[i].force_to_parent(&w.pa[i]);
                w.pa[p] = add6(&w.pa[p], &fp);
            }
        }
        Ok(())
    }

    /// The joint-space mass matrix `M(q)` (into `m`, row-major `nv × nv`) by the
    /// composite-rigid-body algorithm: composite inertias `Iᶜ_λ += Xᵀ Iᶜ_i X` from the
    /// leaves in, then `M_ii = S_iᵀ Iᶜ_i S_i + armature`, and the off-diagonal blocks
    /// `M_ji = S_jᵀ F` with `F = Iᶜ_i S_i` carried to each ancestor `j` by `Xᵀ`. Symmetric
    /// positive definite for a valid model. No allocation.
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §6.2, table 6.2.
    pub fn mass_matrix(&mut self, q: &[f64], m: &mut [f64]) -> Result<()> {
        let nv = self.nv;
        if m.len() != nv * nv {
            return Err(Error::InvalidParameter {
                name: "m",
                value: m.len() as f64,
                reason: "length differs from nv * nv",
            });
        }
        self.kinematics(q)?;
        let w = &mut self.w;
        for (i, n) in self.nodes.iter().enumerate() {
            w.ia[i] = n.inertia;
        }
        for i in (0..self.nodes.len()).rev() {
            if let Some(p) = self.nodes[i].parent {
                let add = congruence(&w.xm[i], &w.ia[i]);
                add66(&mut w.ia[p], &add);
            }
        }
        m.iter_mut().for_each(|x| *x = 0.0);
        for (i, n) in self.nodes.iter().enumerate() {
            let mut f = [ZERO6; 6];
            for k in 0..n.nd {
                f[k] = mul6(&w.ia[i], &w.s[i][k]);
            }
            for a in 0..n.nd {
                for b in 0..=a {
                    // Exactly symmetric: the mean of the two round-offs.
                    let x = 0.5 * (dot6(&w.s[i][a], &f[b]) + dot6(&w.s[i][b], &f[a]));
                    m[(n.iv + a) * nv + n.iv + b] = x;
                    m[(n.iv + b) * nv + n.iv + a] = x;
                }
            }
            if n.nd == 1 {
                m[n.iv * nv + n.iv] += Self::armature(n);
            }
            let mut j = i;
            while let Some(p) = self.nodes[j].parent {
                for col in f.iter_mut().take(n.nd) {
                    *col = w.xf[j].force_to_parent(col);
                }
                j = p;
                let nj = &self.nodes[j];
                for a in 0..nj.nd {
                    for b in 0..n.nd {
                        let x = dot6(&w.s[j][a], &f[b]);
                        m[(nj.iv + a) * nv + n.iv + b] = x;
                        m[(n.iv + b) * nv + nj.iv + a] = x;
                    }
                }
            }
        }
        Ok(())
    }
}

/// The rotation vector `θ` of a ball joint's quaternion (w, x, y, z; normalised here).
pub(super) fn ball_angle(q: &[f64]) -> Vec3 {
    crate::so3::log(
        &crate::so3::Quaternion::new(q[0], q[1], q[2], q[3])
            .normalized()
            .to_matrix(),
    )
}
