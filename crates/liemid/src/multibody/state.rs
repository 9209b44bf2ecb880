//! The multibody state (docs/theory/multibody.md §1) and the system's readouts of it
//! (frames, joint coordinates, energy, momenta, constraint violations).

use crate::linalg::{Mat3, Vec3};
use crate::so3::Quaternion;

use super::constraints::{ball_angle, pose, rows_at, JointRows};
use super::method::LimitState;
use super::model::JointKind;
use super::system::MultibodySystem;

/// The state of `n` bodies in maximal coordinates: per body `i` the centre of mass `c_i`,
/// the linear momentum `p_i = m_i v_i`, the attitude `R_i` (body to space) and the body
/// angular momentum `Π_i = I_i Ω_i` about the centre of mass.
///
/// Reference: docs/theory/multibody.md §1; E. Hairer, C. Lubich, G. Wanner, *Geometric
/// Numerical Integration*, VII.1.
#[derive(Clone, Debug, PartialEq)]
pub struct MultibodyState {
    /// Time (s).
    pub t: f64,
    /// Centres of mass (m), space.
    pub c: Vec<Vec3>,
    /// Linear momenta (kg m/s), space.
    pub p: Vec<Vec3>,
    /// Attitudes, body to space.
    pub rotation: Vec<Mat3>,
    /// Body angular momenta about the centres of mass (kg m²/s), body frame.
    pub pi: Vec<Vec3>,
}

impl MultibodyState {
    /// `n` bodies at the origin, at rest, unrotated, `t = 0`.
    #[must_use]
    pub fn zeros(n: usize) -> Self {
        MultibodyState {
            t: 0.0,
            c: vec![Vec3::ZERO; n],
            p: vec![Vec3::ZERO; n],
            rotation: vec![Mat3::IDENTITY; n],
            pi: vec![Vec3::ZERO; n],
        }
    }

    /// Number of bodies.
    #[must_use]
    pub fn len(&self) -> usize {
        self.c.len()
    }

    /// Whether there are no bodies.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.c.is_empty()
    }

    /// Copy `other` into `self` without allocating (same number of bodies; otherwise the
    /// vectors are resized).
    pub fn copy_from(&mut self, other: &MultibodyState) {
        self.t = other.t;
        self.c.clone_from(&other.c);
        self.p.clone_from(&other.p);
        self.rotation.clone_from(&other.rotation);
        self.pi.clone_from(&other.pi);
    }

    /// Reverse the motion: `p → −p`, `Π → −Π` (the time-reversal symmetry of the step).
    pub fn negate_momenta(&mut self) {
        self.p.iter_mut().for_each(|p| *p = -*p);
        self.pi.iter_mut().for_each(|p| *p = -*p);
    }

    /// Largest componentwise difference of the positions (m) and attitudes, and of the
    /// momenta, `(max |Δc|, max |ΔR|, max |Δp|, max |ΔΠ|)`.
    #[must_use]
    pub fn distance(&self, other: &MultibodyState) -> [f64; 4] {
        let mut d = [0.0f64; 4];
        for i in 0..self.len().min(other.len()) {
            d[0] = d[0].max((self.c[i] - other.c[i]).max_abs());
            d[1] = d[1].max((self.rotation[i] - other.rotation[i]).max_abs());
            d[2] = d[2].max((self.p[i] - other.p[i]).max_abs());
            d[3] = d[3].max((self.pi[i] - other.pi[i]).max_abs());
        }
        d
    }

    /// Whether every number is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.t.is_finite()
            && self.c.iter().all(|v| v.is_finite())
            && self.p.iter().all(|v| v.is_finite())
            && self.rotation.iter().all(|r| r.is_finite())
            && self.pi.iter().all(|v| v.is_finite())
    }
}

impl MultibodySystem {
    /// MuJoCo's `xpos` of body `i`: the frame origin `c_i − R_i s_i`.
    #[must_use]
    pub fn frame_origin(&self, state: &MultibodyState, i: usize) -> Vec3 {
        state.c[i] - state.rotation[i] * self.com[i]
    }

    /// MuJoCo's `xquat` of body `i` (w, x, y, z, `w ≥ 0`).
    #[must_use]
    pub fn quaternion(&self, state: &MultibodyState, i: usize) -> [f64; 4] {
        let q = Quaternion::from_matrix(&state.rotation[i]);
        [q.w, q.x, q.y, q.z]
    }

    /// The coordinate of joint `k` computed from the bodies: hinge angle in `(−π, π]`
    /// (rad), slide offset (m); `None` for other kinds.
    #[must_use]
    pub fn joint_coordinate(&self, state: &MultibodyState, k: usize) -> Option<f64> {
        let g = self.joints.get(k)?;
        let (pi, pj) = pose(g, &state.c, &state.rotation);
        g.coordinate(pi, pj).map(|(q, _)| q)
    }

    /// The rate of joint `k` (hinge rad/s, slide m/s): the coordinate's gradient applied
    /// to the bodies' velocities `v = p/m`, `Ω = I⁻¹ Π` (with hinge armature `Ω = 𝕁⁻¹ Π`,
    /// one solve over the tree, docs/theory/multibody.md §7); `None` for other kinds.
    #[must_use]
    pub fn joint_rate(&self, state: &MultibodyState, k: usize) -> Option<f64> {
        let g = self.joints.get(k)?;
        let (pi, pj) = pose(g, &state.c, &state.rotation);
        let (_, row) = g.coordinate(pi, pj)?;
        let rates = self.armature.as_ref().map(|a| {
            let mut w = state.pi.clone();
            a.solve(&mut w);
            w
        });
        let vel = |i: usize| {
            (
                state.p[i] * (1.0 / self.mass[i]),
                match &rates {
                    None => self.inertia[i].apply_inverse(state.pi[i]),
                    Some(w) => w[i],
                },
            )
        };
        let (vi, wi) = g
            .parent
            .map_or((crate::linalg::Vec3::ZERO, crate::linalg::Vec3::ZERO), vel);
        let (vj, wj) = vel(g.child);
        Some(row.rate(vi, wi, vj, wj))
    }

    /// The energy: `Σ |p|²/2m + ½ Π·I⁻¹Π − Σ (m g + F_i)·c + Σ ½ k (q − q_ref)²` (the
    /// constant body torques have no potential); with hinge armature `½ Πᵀ 𝕁⁻¹ Π` in place
    /// of `½ Π·I⁻¹Π`, which includes every `½ a q̇²` (docs/theory/multibody.md §7).
    #[must_use]
    pub fn energy(&self, state: &MultibodyState) -> f64 {
        let mut e = 0.0;
        let rates = self.armature.as_ref().map(|a| {
            let mut w = state.pi.clone();
            a.solve(&mut w);
            w
        });
        for i in 0..self.mass.len() {
            e += 0.5 * state.p[i].norm_squared() / self.mass[i];
            e += 0.5
                * match &rates {
                    None => state.pi[i].dot(self.inertia[i].apply_inverse(state.pi[i])),
                    Some(w) => state.pi[i].dot(w[i]),
                };
            e -= (self.gravity * self.mass[i] + self.const_force[i]).dot(state.c[i]);
        }
        for (k, g) in self.joints.iter().enumerate() {
            let par = &self.params[k];
            if par.stiffness == 0.0 {
                continue;
            }
            let (pi, pj) = pose(g, &state.c, &state.rotation);
            if g.kind == JointKind::Ball {
                e += 0.5 * par.stiffness * ball_angle(g, pi.1, pj.1).norm_squared();
            } else if let Some((q, _)) = g.coordinate(pi, pj) {
                e += 0.5 * par.stiffness * (q - par.spring_ref).powi(2);
            }
        }
        e
    }

    /// The total linear momentum `Σ p_i`.
    #[must_use]
    pub fn linear_momentum(&self, state: &MultibodyState) -> Vec3 {
        state.p.iter().fold(Vec3::ZERO, |s, p| s + *p)
    }

    /// The total angular momentum about the origin, in space: `Σ c_i × p_i + R_i Π_i`.
    #[must_use]
    pub fn angular_momentum(&self, state: &MultibodyState) -> Vec3 {
        (0..state.len()).fold(Vec3::ZERO, |s, i| {
            s + state.c[i].cross(state.p[i]) + state.rotation[i] * state.pi[i]
        })
    }

    /// The relative position and velocity constraint violations of `state` (as in
    /// [`super::StepReport`]) of the joints, without limit rows (an integrator's active
    /// limits: [`super::Rattle::constraint_violation`]).
    #[must_use]
    pub fn constraint_violation(&self, state: &MultibodyState) -> (f64, f64) {
        self.constraint_violation_with(state, &[])
    }

    /// As [`Self::constraint_violation`], with the limit rows active in `limits` (one per
    /// joint; missing entries are inactive).
    #[must_use]
    pub fn constraint_violation_with(&self, state: &MultibodyState, limits: &[LimitState]) -> (f64, f64) {
        let mut pos: f64 = 0.0;
        let mut vel: f64 = 0.0;
        let mut rows = JointRows::default();
        let mut vscale: f64 = self.velocity_floor();
        let rates = self.armature.as_ref().map(|a| {
            let mut w = state.pi.clone();
            a.solve(&mut w);
            w
        });
        let rate_of = |i: usize| match &rates {
            None => self.inertia[i].apply_inverse(state.pi[i]),
            Some(w) => w[i],
        };
        for i in 0..state.len() {
            let v = state.p[i] * (1.0 / self.mass[i]);
            let w = rate_of(i);
            vscale = vscale.max(v.norm() + self.length * w.norm());
        }
        for (k, g) in self.joints.iter().enumerate() {
            let one = core::slice::from_mut(&mut rows);
            let limit = [limits.get(k).copied().unwrap_or(LimitState::Inactive)];
            rows_at(
                core::slice::from_ref(g),
                &limit,
                &self.params[k..=k],
                &state.c,
                &state.rotation,
                one,
            );
            let vel_of = |i: Option<usize>| {
                i.map_or((Vec3::ZERO, Vec3::ZERO), |i| {
                    (state.p[i] * (1.0 / self.mass[i]), rate_of(i))
                })
            };
            let (vi, wi) = vel_of(g.parent);
            let (vj, wj) = vel_of(Some(g.child));
            for r in 0..rows.n {
                let v = rows.value[r].abs();
                pos = pos.max(if rows.length[r] { v / self.length } else { v });
                vel = vel.max(rows.grad[r].rate(vi, wi, vj, wj).abs());
            }
        }
        (pos, if vscale > 0.0 { vel / vscale } else { vel })
    }
}
