//! Joints as holonomic constraints: the rows `g(q)` of docs/theory/multibody.md §2 and their
//! gradients with respect to the centres of mass `c` and the body-frame rotation
//! increments `R → R exp(δθ)` of the parent `i` and the child `j`.
//!
//! With anchors `a = o_i − s_i`, `b = o_j − s_j` (the joint's point from each centre of
//! mass, in body axes), the world having `c = 0`, `R = I`:
//!
//! ```text
//! ball      c_i + R_i a − c_j − R_j b                       ∂θ_i = −R_i hat(a), ∂θ_j = R_j hat(b)
//! dot(A,B)  (R_i A)·(R_j B)                                 ∂θ_i = A × R_iᵀR_j B, ∂θ_j = B × R_jᵀR_i A
//! hinge     ball and dot(e_k, u_j), e_k ⊥ u_i = Q u_j (k = 1, 2)
//! universal ball and dot(Q a, b) − a·b (a, b the first and second axis, child frame)
//! slide     dot(Q e_a, e_b) for (a, b) = (2,3), (3,1), (1,2), and (R_i e_k)·d,
//!           d = c_j + R_j b − c_i − R_i a:  ∂c = ∓R_i e_k, ∂θ_i = e_k × (R_iᵀ d + a), ∂θ_j = b × R_jᵀR_i e_k
//! weld      ball and the three dot rows of the slide
//! ```
//!
//! `Q` is the joint's reference rotation (child in parent at zero coordinate), so the dot
//! rows vanish at the reference attitude. The universal row: with `M = Qᵀ R_iᵀ R_j`,
//! `(R_i Q a)·(R_j b) = a·M b`, and `a·M b = a·b` holds exactly on the rotations
//! `M = exp(θ₁ a) exp(θ₂ b)` (`M b` must lie on the cone about `a` through `b`: turn `b`
//! onto it about `a`, and what is left fixes `b`); its gradient (the dot row's) vanishes
//! only where `M b ∥ a`, impossible for independent axes, so the joint has no gimbal lock. Joint readouts (hinge angle, slide offset) are
//! functions of the bodies with exact gradients, used for springs, dampers and limits.
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, VII.1; D. Baraff, "Linear-time dynamics using Lagrange multipliers",
//! SIGGRAPH 1996.

use crate::linalg::{Mat3, Vec3};

use super::method::LimitState;
use super::model::{JointKind, Link, Model};

/// Most rows of one joint: a weld's 6, or 5 of a hinge or slide plus a limit row.
pub const MAX_ROWS: usize = 6;

/// The gradient of one scalar row: with respect to the parent's centre `c_i` and body
/// rotation `θ_i`, and the child's `c_j`, `θ_j`. A multiplier `λ` of the row applies the
/// forces `λ ci`, `λ cj` (space) and the body-frame torques `λ ti`, `λ tj`.
///
/// Reference: docs/theory/multibody.md §1 (`G_cᵀ λ`, `G_θᵀ λ`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Row {
    /// `∂g/∂c_i`.
    pub ci: Vec3,
    /// `∂g/∂θ_i` (parent body frame).
    pub ti: Vec3,
    /// `∂g/∂c_j`.
    pub cj: Vec3,
    /// `∂g/∂θ_j` (child body frame).
    pub tj: Vec3,
}

impl Row {
    /// `ġ = ci·v_i + ti·Ω_i + cj·v_j + tj·Ω_j`.
    #[must_use]
    #[inline]
    pub fn rate(&self, vi: Vec3, wi: Vec3, vj: Vec3, wj: Vec3) -> f64 {
        self.ci.dot(vi) + self.ti.dot(wi) + self.cj.dot(vj) + self.tj.dot(wj)
    }
}

/// The rows of one joint at one configuration: values, gradients and whether each row is
/// a length (m; reported relative to the model's length scale) or dimensionless.
///
/// Reference: docs/theory/multibody.md §2.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointRows {
    /// Active rows.
    pub n: usize,
    /// `g_k`.
    pub value: [f64; MAX_ROWS],
    /// `∇g_k`.
    pub grad: [Row; MAX_ROWS],
    /// Whether row `k` is a length.
    pub length: [bool; MAX_ROWS],
}

impl JointRows {
    pub(crate) fn push(&mut self, value: f64, grad: Row, length: bool) {
        self.value[self.n] = value;
        self.grad[self.n] = grad;
        self.length[self.n] = length;
        self.n += 1;
    }
}

/// One joint's geometry, precomputed from the model: parent and child, anchors from the
/// centres of mass, reference rotation and the axes.
///
/// Reference: docs/theory/multibody.md §2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointGeometry {
    /// The kind and axis (child frame).
    pub kind: JointKind,
    /// The parent body, `None` for the world.
    pub parent: Option<usize>,
    /// The child body.
    pub child: usize,
    /// `a = o_i − s_i` (world coordinates for the world).
    pub a: Vec3,
    /// `b = o_j − s_j`.
    pub b: Vec3,
    /// `Q`, the child's attitude in the parent frame at zero coordinate.
    pub q: Mat3,
    /// The axis in the child frame `u_j` (`e_z` for ball, weld, free; a universal's second
    /// axis `b`).
    pub u_child: Vec3,
    /// The axis in the parent frame `u_i = Q u_j` (a universal's first axis, `Q a`).
    pub u_parent: Vec3,
    /// `e_1, e_2 ⊥ u_i` in the parent frame, `e_1 × e_2 = u_i`.
    pub e_parent: [Vec3; 2],
    /// `e, f ⊥ u_j` in the child frame, `e × f = u_j` (the hinge angle's reference).
    pub e_child: [Vec3; 2],
}

/// Two unit vectors completing the unit `u` to a right-handed orthonormal frame.
#[must_use]
pub fn perpendicular_pair(u: Vec3) -> [Vec3; 2] {
    let (ax, ay, az) = (u.x.abs(), u.y.abs(), u.z.abs());
    let t = if ax <= ay && ax <= az {
        Vec3::new(1.0, 0.0, 0.0)
    } else if ay <= az {
        Vec3::new(0.0, 1.0, 0.0)
    } else {
        Vec3::new(0.0, 0.0, 1.0)
    };
    let e1 = u.cross(t);
    let e1 = e1 * (1.0 / e1.norm());
    [e1, u.cross(e1)]
}

impl JointGeometry {
    /// The geometry of `model.joints[k]` (the model validated).
    #[must_use]
    pub fn new(model: &Model, k: usize) -> Self {
        let j = &model.joints[k];
        let (parent, a) = match j.parent {
            Link::World => (None, j.anchor_parent),
            Link::Body(p) => (Some(p), j.anchor_parent - model.bodies[p].com),
        };
        let (u_child, u_parent) = j.axes();
        JointGeometry {
            kind: j.kind,
            parent,
            child: j.child,
            a,
            b: j.anchor_child - model.bodies[j.child].com,
            q: j.reference_rotation,
            u_child,
            u_parent,
            e_parent: perpendicular_pair(u_parent),
            e_child: perpendicular_pair(u_child),
        }
    }

    /// The base rows of the joint (without a limit row) at the poses `(c_i, R_i)`,
    /// `(c_j, R_j)`, written into `out` from row 0.
    pub fn rows(&self, (ci, ri): (Vec3, &Mat3), (cj, rj): (Vec3, &Mat3), out: &mut JointRows) {
        out.n = 0;
        match self.kind {
            JointKind::Free => {}
            JointKind::Ball => self.ball(ci, ri, cj, rj, out),
            JointKind::Hinge { .. } => {
                self.ball(ci, ri, cj, rj, out);
                for e in self.e_parent {
                    dot_row(e, self.u_child, ri, rj, out);
                }
            }
            JointKind::Universal { first, second } => {
                self.ball(ci, ri, cj, rj, out);
                dot_row(self.u_parent, self.u_child, ri, rj, out);
                out.value[out.n - 1] -= first.dot(second);
            }
            JointKind::Weld => {
                self.ball(ci, ri, cj, rj, out);
                self.lock(ri, rj, out);
            }
            JointKind::Slide { .. } => {
                self.lock(ri, rj, out);
                let d = cj + *rj * self.b - ci - *ri * self.a;
                let di = ri.tr_mul_vec(d) + self.a;
                for e in self.e_parent {
                    let re = *ri * e;
                    let grad = Row {
                        ci: -re,
                        ti: e.cross(di),
                        cj: re,
                        tj: self.b.cross(rj.tr_mul_vec(re)),
                    };
                    out.push(re.dot(d), grad, true);
                }
            }
        }
    }

    fn ball(&self, ci: Vec3, ri: &Mat3, cj: Vec3, rj: &Mat3, out: &mut JointRows) {
        let g = ci + *ri * self.a - cj - *rj * self.b;
        let units = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        for (k, e) in units.into_iter().enumerate() {
            let grad = Row {
                ci: e,
                ti: self.a.cross(ri.row(k)),
                cj: -e,
                tj: -self.b.cross(rj.row(k)),
            };
            out.push(g[k], grad, true);
        }
    }

    fn lock(&self, ri: &Mat3, rj: &Mat3, out: &mut JointRows) {
        for (a, b) in [(1, 2), (2, 0), (0, 1)] {
            dot_row(self.q.col(a), unit(b), ri, rj, out);
        }
    }

    /// The hinge angle `q ∈ (−π, π]` from the bodies, `exp(q u_j) = Qᵀ R_iᵀ R_j` on the
    /// constraint manifold, as `atan2(f·Q_rel e, e·Q_rel e)`, and its exact gradient (a
    /// conservative spring force is then `−k (q − q_ref) ∇q`).
    #[must_use]
    pub fn hinge_angle(&self, ri: &Mat3, rj: &Mat3) -> (f64, Row) {
        let [e, f] = self.e_child;
        let q_rel = self.q.transpose() * (ri.transpose() * *rj);
        let qe = q_rel * e;
        let (x, y) = (e.dot(qe), f.dot(qe));
        let n2 = x * x + y * y;
        let dx_j = e.cross(q_rel.tr_mul_vec(e));
        let dy_j = e.cross(q_rel.tr_mul_vec(f));
        let dx_i = self.q * e.cross(qe);
        let dy_i = self.q * f.cross(qe);
        let grad = Row {
            ci: Vec3::ZERO,
            ti: (dy_i * x - dx_i * y) * (1.0 / n2),
            cj: Vec3::ZERO,
            tj: (dy_j * x - dx_j * y) * (1.0 / n2),
        };
        (y.atan2(x), grad)
    }

    /// The slide offset `q = u_i · R_iᵀ d`, `d = c_j + R_j b − c_i − R_i a`, and its exact
    /// gradient.
    #[must_use]
    pub fn slide_offset(&self, (ci, ri): (Vec3, &Mat3), (cj, rj): (Vec3, &Mat3)) -> (f64, Row) {
        let d = cj + *rj * self.b - ci - *ri * self.a;
        let ru = *ri * self.u_parent;
        let grad = Row {
            ci: -ru,
            ti: self.u_parent.cross(ri.tr_mul_vec(d) + self.a),
            cj: ru,
            tj: self.b.cross(rj.tr_mul_vec(ru)),
        };
        (ru.dot(d), grad)
    }

    /// The joint coordinate of a hinge (angle) or slide (offset) with its gradient, `None`
    /// for other kinds.
    #[must_use]
    pub fn coordinate(&self, pi: (Vec3, &Mat3), pj: (Vec3, &Mat3)) -> Option<(f64, Row)> {
        match self.kind {
            JointKind::Hinge { .. } => Some(self.hinge_angle(pi.1, pj.1)),
            JointKind::Slide { .. } => Some(self.slide_offset(pi, pj)),
            _ => None,
        }
    }
}

fn unit(k: usize) -> Vec3 {
    let mut a = [0.0; 3];
    a[k] = 1.0;
    Vec3::from_array(a)
}

/// `(R_i A)·(R_j B)` with `∂θ_i = A × R_iᵀ R_j B`, `∂θ_j = B × R_jᵀ R_i A`.
fn dot_row(a: Vec3, b: Vec3, ri: &Mat3, rj: &Mat3, out: &mut JointRows) {
    let ra = *ri * a;
    let rb = *rj * b;
    let grad = Row {
        ci: Vec3::ZERO,
        ti: a.cross(ri.tr_mul_vec(rb)),
        cj: Vec3::ZERO,
        tj: b.cross(rj.tr_mul_vec(ra)),
    };
    out.push(ra.dot(rb), grad, false);
}

/// A joint's force and limit parameters as the step uses them: spring stiffness and rest
/// coordinate, damping, range (zero or `None` for the kinds that have none).
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointParams {
    pub stiffness: f64,
    pub spring_ref: f64,
    pub damping: f64,
    /// Dry friction of a hinge or slide (0 otherwise).
    pub frictionloss: f64,
    pub range: Option<(f64, f64)>,
}

/// The poses `(c_i, R_i)`, `(c_j, R_j)` of a joint's parent (world: 0, I) and child.
#[inline]
pub(super) fn pose<'a>(g: &JointGeometry, c: &'a [Vec3], r: &'a [Mat3]) -> ((Vec3, &'a Mat3), (Vec3, &'a Mat3)) {
    const IDENTITY: &Mat3 = &Mat3::IDENTITY;
    let pi = g.parent.map_or((Vec3::ZERO, IDENTITY), |p| (c[p], &r[p]));
    (pi, (c[g.child], &r[g.child]))
}

/// Add the rows' impulse `Gᵀ (scale · multipliers)` to the bodies' linear and (body-frame)
/// angular momenta: the force on the centres of mass and the torque of each row, to the
/// parent (if not the world) and the child.
pub(super) fn add_impulse(
    joints: &[JointGeometry],
    rows: &[JointRows],
    multipliers: &[[f64; 6]],
    scale: f64,
    linear: &mut [Vec3],
    angular: &mut [Vec3],
) {
    for ((g, rows), mult) in joints.iter().zip(rows).zip(multipliers) {
        for (gr, &mu) in rows.grad[..rows.n].iter().zip(mult) {
            let m = mu * scale;
            if let Some(p) = g.parent {
                linear[p] += gr.ci * m;
                angular[p] += gr.ti * m;
            }
            linear[g.child] += gr.cj * m;
            angular[g.child] += gr.tj * m;
        }
    }
}

/// The rates `G v` of the rows: calls `f(joint, row, rate)` for every row of every joint,
/// with the bodies' velocities `linear` and angular rates `angular` (the transpose of
/// [`add_impulse`]).
pub(super) fn for_each_rate(
    joints: &[JointGeometry],
    rows: &[JointRows],
    linear: &[Vec3],
    angular: &[Vec3],
    mut f: impl FnMut(usize, usize, f64),
) {
    for (k, (g, jr)) in joints.iter().zip(rows).enumerate() {
        let (vi, wi) = g.parent.map_or((Vec3::ZERO, Vec3::ZERO), |p| (linear[p], angular[p]));
        let (vj, wj) = (linear[g.child], angular[g.child]);
        for (r, gr) in jr.grad[..jr.n].iter().enumerate() {
            f(k, r, gr.rate(vi, wi, vj, wj));
        }
    }
}

/// The rows (with active limit rows) of every joint at `(c, R)` into `out`.
pub(super) fn rows_at(
    joints: &[JointGeometry],
    limit: &[LimitState],
    params: &[JointParams],
    c: &[Vec3],
    r: &[Mat3],
    out: &mut [JointRows],
) {
    for (k, g) in joints.iter().enumerate() {
        let (pi, pj) = pose(g, c, r);
        g.rows(pi, pj, &mut out[k]);
        if limit[k] != LimitState::Inactive {
            if let (Some((q, grad)), Some((lo, hi))) = (g.coordinate(pi, pj), params[k].range) {
                let bound = if limit[k] == LimitState::Lower { lo } else { hi };
                let length = matches!(g.kind, JointKind::Slide { .. });
                out[k].push(q - bound, grad, length);
            }
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
