//! The joint-space right-hand side `y' = [Q(q) v; ABA(q, v, 0)]` and the classical RK4
//! driver on it.
//!
//! ## Reference
//!
//! E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd
//! ed., Springer 1993, §II.1.

use super::{check_len, quat_at, JointSpaceModel, Kind};
use crate::error::{Error, Result};

impl JointSpaceModel {
    /// The right-hand side of the first-order system on the flat state `y = [q; v]`
    /// (length `nq + nv`): `dy = [Q(q) v; ABA(q, v, 0)]`, unforced (gravity, springs and
    /// dampers only), autonomous (`t` unused). For a general-purpose integrator such as
    /// `ode_solvers`' Dop853 (whose `System::system` takes `&self`: wrap this model in a
    /// `RefCell`). No allocation.
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §7.3.
    pub fn derivative(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<()> {
        let _ = t;
        let (nq, nv) = (self.nq, self.nv);
        if y.len() != nq + nv || dy.len() != nq + nv {
            return Err(Error::InvalidParameter {
                name: "y",
                value: y.len().min(dy.len()) as f64,
                reason: "y and dy must both have length nq + nv",
            });
        }
        let (q, v) = y.split_at(nq);
        let (dq, dv) = dy.split_at_mut(nq);
        self.qdot(q, v, dq)?;
        self.aba_inner(q, v, None, dv)
    }

    /// One step of the classical fourth-order Runge-Kutta method on `(q, v)`, unforced,
    /// with the quaternions integrated through `Q̇ = ½ Q ⊗ (0, ω)` like the other
    /// coordinates and renormalised after the step. Fourth order; conserves neither
    /// energy nor momentum exactly (their errors are `O(h⁴)`). No allocation.
    ///
    /// ## Reference
    ///
    /// E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
    /// 2nd ed., Springer 1993, §II.1; the right-hand side from R. Featherstone, *Rigid Body
    /// Dynamics Algorithms*, Springer 2008.
    pub fn rk4_step(&mut self, q: &mut [f64], v: &mut [f64], h: f64) -> Result<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        check_len("q", q, self.nq)?;
        check_len("v", v, self.nv)?;
        let nq = self.nq;
        let mut y0 = core::mem::take(&mut self.w.y0);
        let mut yt = core::mem::take(&mut self.w.yt);
        let mut k = core::mem::take(&mut self.w.k);
        let r = (|| -> Result<()> {
            y0[..nq].copy_from_slice(q);
            y0[nq..].copy_from_slice(v);
            self.derivative(0.0, &y0, &mut k[0])?;
            for (stage, c) in [(1, 0.5), (2, 0.5), (3, 1.0)] {
                for ((t, a), b) in yt.iter_mut().zip(&y0).zip(&k[stage - 1]) {
                    *t = a + c * h * b;
                }
                let (done, rest) = k.split_at_mut(stage);
                let _ = done;
                self.derivative(0.0, &yt, &mut rest[0])?;
            }
            for (idx, y) in y0.iter_mut().enumerate() {
                *y += h / 6.0 * (k[0][idx] + 2.0 * k[1][idx] + 2.0 * k[2][idx] + k[3][idx]);
            }
            Ok(())
        })();
        if r.is_ok() {
            if y0.iter().any(|x| !x.is_finite()) {
                self.w.y0 = y0;
                self.w.yt = yt;
                self.w.k = k;
                return Err(Error::NonFiniteResult {
                    method: "joint-space RK4",
                    t: 0.0,
                    h,
                });
            }
            q.copy_from_slice(&y0[..nq]);
            v.copy_from_slice(&y0[nq..]);
            self.normalize_quaternions(q)?;
        }
        self.w.y0 = y0;
        self.w.yt = yt;
        self.w.k = k;
        r
    }

    /// Scale every ball and free joint quaternion in `q` to unit norm.
    pub fn normalize_quaternions(&self, q: &mut [f64]) -> Result<()> {
        check_len("q", q, self.nq)?;
        for n in &self.nodes {
            let at = match n.kind {
                Kind::Ball => n.iq,
                Kind::Free => n.iq + 3,
                _ => continue,
            };
            let u = quat_at(&q[at..at + 4])?;
            q[at..at + 4].copy_from_slice(&[u.w, u.x, u.y, u.z]);
        }
        Ok(())
    }
}
