//! Joint-coordinate reference dynamics of a tree of rigid bodies: forward kinematics,
//! Featherstone's articulated-body algorithm (ABA), the composite-rigid-body mass matrix
//! (CRBA), recursive Newton-Euler inverse dynamics (RNEA), the energy, and classical RK4.
//!
//! This is the *reference* against which the maximal-coordinate RATTLE integrator of the
//! multibody domain is checked: the same [`Model`], the same state layout as MuJoCo
//! (`qpos`, `qvel`), the ordinary differential equation `q̇ = Q(q) v`, `v̇ = ABA(q, v, τ)`
//! solved to high accuracy by a general-purpose integrator.
//!
//! ## Kinematics
//!
//! Every body `i` has exactly one tree joint, from its parent `λ(i)` (a body or the
//! world). At zero joint coordinate the child's pose relative to its parent is the one of
//! the bodies' reference world poses: `E₀ = R_λᵀ R_i`, `t₀ = R_λᵀ (x_i − x_λ)` (attitude and
//! frame origin of the child in parent coordinates). With `b` the anchor in child
//! coordinates and `u` a joint axis in child coordinates, the child's pose in its parent
//! is `(r, E)`:
//!
//! | joint | `E` | `r` |
//! |---|---|---|
//! | weld | `E₀` | `t₀` |
//! | hinge, angle `θ` | `E₀ exp(θ û)` | `t₀ + E₀ b − E b` |
//! | ball, quaternion `Q` | `E₀ R(Q)` | `t₀ + E₀ b − E b` |
//! | slide, offset `s` | `E₀` | `t₀ + s E₀ u` |
//! | free, `(p, Q)` | `R(Q)` | `p` |
//!
//! and the world pose is `R_i = R_λ E`, `x_i = x_λ + R_λ r`. Hinge and ball joints turn
//! the child about the anchor point (which stays where it is in the parent); a free joint
//! gives the child frame's pose in the parent frame directly (for a root: in the world).
//! Quaternions are normalised before use, so the dynamics is defined on non-unit
//! quaternions too (as inside an RK4 step).
//!
//! ## Velocities
//!
//! Hinge, slide: the rate. Ball: the angular velocity `ω` of the child relative to the
//! parent in child coordinates, `Q̇ = ½ Q ⊗ (0, ω)`. Free: the velocity `ṗ` of the child
//! frame's origin in parent coordinates, then `ω` in child coordinates (MuJoCo's
//! convention), `Q̇ = ½ Q ⊗ (0, ω)`.
//!
//! ## Spatial algebra
//!
//! Spatial motion vectors `(ω; v)` and force vectors `(n; f)`, angular part first, in the
//! coordinates of each body's frame (origin at the frame origin, axes the body's). The
//! joint's motion subspace `S` (6 × `nv` of the joint), in child coordinates:
//! hinge `(u; b × u)`, slide `(0; u)`, ball `(1; b̂)`, free `[[0, 1]; [Eᵀ, 0]]`; the first
//! three are constant in child coordinates, the free joint's has the apparent derivative
//! `S̊ q̇ = (0; −ω × Eᵀ ṗ)`.
//!
//! ## Passive forces
//!
//! Hinge and slide joints carry the generalised force `−k (q − q_ref) − d q̇` (stiffness,
//! spring reference, damping) and their armature `a` adds `a q̈` to the joint's equation
//! (MuJoCo's rotor inertia, `½ a q̇²` in the kinetic energy). Joint ranges are not enforced.
//!
//! ## Reference
//!
//! R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008: spatial vectors
//! (ch. 2), joint models (ch. 4), RNEA (ch. 5), CRBA (ch. 6), ABA (ch. 7).

// Small dense blocks (6x6, the joint's nd x nd) are indexed as in the formulas.
#![allow(clippy::needless_range_loop)]

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
use crate::multibody::model::{JointKind, Link, Model};
use crate::rigid::inertia::Inertia;
use crate::so3::{exp, hat, Quaternion};

/// A spatial vector `(angular; linear)`.
type SV = [f64; 6];
/// A 6x6 matrix, row-major.
type M6 = [[f64; 6]; 6];

const ZERO6: SV = [0.0; 6];
const ZERO66: M6 = [[0.0; 6]; 6];

#[inline]
fn sv(a: Vec3, l: Vec3) -> SV {
    [a.x, a.y, a.z, l.x, l.y, l.z]
}

/// The `k`-th unit vector.
#[inline]
fn basis(k: usize) -> Vec3 {
    let mut a = [0.0; 3];
    a[k] = 1.0;
    Vec3::from_array(a)
}

#[inline]
fn ang(s: &SV) -> Vec3 {
    Vec3::new(s[0], s[1], s[2])
}

#[inline]
fn lin(s: &SV) -> Vec3 {
    Vec3::new(s[3], s[4], s[5])
}

#[inline]
fn add6(a: &SV, b: &SV) -> SV {
    core::array::from_fn(|k| a[k] + b[k])
}

#[inline]
fn dot6(a: &SV, b: &SV) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The motion cross product `v × m = (ω × m_ω; ω × m_v + v × m_ω)`.
#[inline]
fn cross_motion(v: &SV, m: &SV) -> SV {
    let (w, l) = (ang(v), lin(v));
    let (mw, ml) = (ang(m), lin(m));
    sv(w.cross(mw), w.cross(ml) + l.cross(mw))
}

/// The force cross product `v ×* f = (ω × n + v × f; ω × f)`.
#[inline]
fn cross_force(v: &SV, f: &SV) -> SV {
    let (w, l) = (ang(v), lin(v));
    let (n, ff) = (ang(f), lin(f));
    sv(w.cross(n) + l.cross(ff), w.cross(ff))
}

#[inline]
fn mul6(a: &M6, x: &SV) -> SV {
    core::array::from_fn(|i| dot6(&a[i], x))
}

/// `Xᵀ A X` for 6x6 matrices.
fn congruence(x: &M6, a: &M6) -> M6 {
    let mut ax = ZERO66;
    for i in 0..6 {
        for j in 0..6 {
            ax[i][j] = (0..6).map(|k| a[i][k] * x[k][j]).sum();
        }
    }
    let mut out = ZERO66;
    for i in 0..6 {
        for j in 0..6 {
            out[i][j] = (0..6).map(|k| x[k][i] * ax[k][j]).sum();
        }
    }
    out
}

fn add66(a: &mut M6, b: &M6) {
    for i in 0..6 {
        for j in 0..6 {
            a[i][j] += b[i][j];
        }
    }
}

/// The pose `(r, E)` of a child frame in its parent frame: the Plücker transform
/// `ⁱX_λ = [[Eᵀ, 0]; [−Eᵀ r̂, Eᵀ]]` from parent to child coordinates.
#[derive(Clone, Copy, Debug)]
struct Xform {
    /// Child-to-parent rotation.
    e: Mat3,
    /// The child frame's origin in parent coordinates.
    r: Vec3,
}

impl Xform {
    const IDENTITY: Xform = Xform {
        e: Mat3::IDENTITY,
        r: Vec3::ZERO,
    };

    /// A motion vector from parent to child coordinates: `(Eᵀ ω; Eᵀ (v − r × ω))`.
    #[inline]
    fn motion(&self, m: &SV) -> SV {
        let w = ang(m);
        sv(self.e.tr_mul_vec(w), self.e.tr_mul_vec(lin(m) - self.r.cross(w)))
    }

    /// A force vector from child to parent coordinates, `Xᵀ f = (E n + r × E f; E f)`.
    #[inline]
    fn force_to_parent(&self, f: &SV) -> SV {
        let ef = self.e * lin(f);
        sv(self.e * ang(f) + self.r.cross(ef), ef)
    }

    /// The 6x6 matrix `ⁱX_λ`.
    fn matrix(&self) -> M6 {
        let et = self.e.transpose();
        let b = (et * hat(self.r)) * -1.0;
        let mut x = ZERO66;
        for i in 0..3 {
            for j in 0..3 {
                x[i][j] = et.m[i][j];
                x[i + 3][j + 3] = et.m[i][j];
                x[i + 3][j] = b.m[i][j];
            }
        }
        x
    }
}

/// Invert a small symmetric positive definite matrix (`n ≤ 6`, in the top-left corner) by
/// Gauss-Jordan elimination with partial pivoting; `None` on a pivot at round-off.
fn invert_small(a: &M6, n: usize) -> Option<M6> {
    let mut m = *a;
    let mut inv = ZERO66;
    for (i, row) in inv.iter_mut().enumerate().take(n) {
        row[i] = 1.0;
    }
    let scale = (0..n).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    for col in 0..n {
        let piv = (col..n).max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))?;
        let p = m[piv][col];
        if !p.is_finite() || p.abs() <= 1e-14 * scale {
            return None;
        }
        m.swap(col, piv);
        inv.swap(col, piv);
        for j in 0..n {
            m[col][j] /= p;
            inv[col][j] /= p;
        }
        for r in 0..n {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    for j in 0..n {
                        m[r][j] -= f * m[col][j];
                        inv[r][j] -= f * inv[col][j];
                    }
                }
            }
        }
    }
    Some(inv)
}

/// The joint kinds as this module uses them (axes unit, in child coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Weld,
    Hinge(Vec3),
    Slide(Vec3),
    Ball,
    Free,
}

/// One body with its tree joint.
#[derive(Clone, Debug)]
struct Node {
    kind: Kind,
    /// Parent body, `None` for the world.
    parent: Option<usize>,
    /// Offsets of the joint's coordinates in `q` and `v`.
    iq: usize,
    iv: usize,
    /// Degrees of freedom of the joint.
    nd: usize,
    /// Child pose in the parent at zero joint coordinate.
    e0: Mat3,
    t0: Vec3,
    /// Anchor in child coordinates.
    anchor: Vec3,
    stiffness: f64,
    spring_ref: f64,
    damping: f64,
    armature: f64,
    mass: f64,
    com: Vec3,
    inertia_com: Mat3,
    /// Spatial inertia about the frame origin in body coordinates.
    inertia: M6,
}

/// Per-body scratch of the recursions, allocated once.
#[derive(Clone, Debug)]
struct Work {
    xf: Vec<Xform>,
    xm: Vec<M6>,
    pos: Vec<Vec3>,
    rot: Vec<Mat3>,
    /// Motion subspace columns.
    s: Vec<[SV; 6]>,
    vel: Vec<SV>,
    /// Velocity-product acceleration `c = S̊ q̇ + v × v_J`.
    c: Vec<SV>,
    ia: Vec<M6>,
    pa: Vec<SV>,
    /// `U = Iᴬ S`.
    u: Vec<[SV; 6]>,
    dinv: Vec<M6>,
    /// `u = τ − Sᵀ pᴬ`.
    uu: Vec<[f64; 6]>,
    acc: Vec<SV>,
    /// RK4 stage buffers over `y = [q; v]`.
    y0: Vec<f64>,
    yt: Vec<f64>,
    k: [Vec<f64>; 4],
}

/// The joint-space dynamics of a tree-structured [`Model`], with preallocated scratch so
/// that [`aba`](Self::aba), [`mass_matrix`](Self::mass_matrix),
/// [`inverse_dynamics`](Self::inverse_dynamics), [`derivative`](Self::derivative) and
/// [`rk4_step`](Self::rk4_step) do not allocate.
///
/// State: `q` of length [`nq`](Self::nq) and `v` of length [`nv`](Self::nv) in MuJoCo's
/// layout over the tree joints in the model's order (free 7: position, quaternion
/// `w, x, y, z`; ball 4; hinge 1; slide 1; weld 0 — free 6: linear velocity in the parent
/// frame, angular velocity in the child frame; ball 3; hinge 1; slide 1).
///
/// ## Reference
///
/// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008.
#[derive(Clone, Debug)]
pub struct JointSpaceModel {
    nodes: Vec<Node>,
    gravity: Vec3,
    nq: usize,
    nv: usize,
    qpos0: Vec<f64>,
    q_init: Vec<f64>,
    v_init: Vec<f64>,
    w: Work,
}

fn invalid(reason: String) -> Error {
    Error::InvalidModel { reason }
}

fn check_len(name: &'static str, x: &[f64], n: usize) -> Result<()> {
    if x.len() != n {
        return Err(Error::InvalidParameter {
            name,
            value: x.len() as f64,
            reason: "length differs from the model's dimension (nq for q, nv for v, tau, qdd)",
        });
    }
    if let Some(&bad) = x.iter().find(|a| !a.is_finite()) {
        return Err(Error::InvalidParameter {
            name,
            value: bad,
            reason: "not finite",
        });
    }
    Ok(())
}

fn quat_at(q: &[f64]) -> Result<Quaternion> {
    let quat = Quaternion::new(q[0], q[1], q[2], q[3]);
    let n = quat.norm();
    if n.is_nan() || n <= 1e-150 {
        return Err(Error::InvalidParameter {
            name: "q",
            value: n,
            reason: "a joint quaternion has zero norm",
        });
    }
    Ok(quat.normalized())
}

/// `½ Q ⊗ (0, ω)`.
#[inline]
fn quat_rate(q: &[f64], w: Vec3) -> [f64; 4] {
    let d = Quaternion::new(q[0], q[1], q[2], q[3]).mul(&Quaternion::new(0.0, w.x, w.y, w.z));
    [0.5 * d.w, 0.5 * d.x, 0.5 * d.y, 0.5 * d.z]
}

impl JointSpaceModel {
    /// Build the joint-space model of `model`.
    ///
    /// Requirements (each violation an [`Error::InvalidModel`] naming the body or joint):
    /// every body is the child of exactly one joint and no joint closes a loop (the joint
    /// tree is the whole model); parents come before children; masses positive, inertias
    /// physical ([`Inertia::from_matrix`]); hinge and slide axes unit to `1e-9`; for every
    /// joint but a free one, the anchors and `reference_rotation` agree with the bodies'
    /// reference poses to `1e-8` (relative to the model's size), so that the zero joint
    /// coordinate is the reference configuration the maximal-coordinate integrator locks;
    /// `qpos`, `qvel` of the right lengths and finite when given.
    ///
    /// ## Reference
    ///
    /// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §4.1-4.4.
    pub fn new(model: &Model) -> Result<Self> {
        let nb = model.bodies.len();
        if !model.gravity.is_finite() {
            return Err(invalid("gravity is not finite".into()));
        }
        let mut joint_of: Vec<Option<usize>> = vec![None; nb];
        for (k, j) in model.joints.iter().enumerate() {
            if j.child >= nb {
                return Err(invalid(format!("joint `{}`: child {} is not a body", j.name, j.child)));
            }
            if let Some(first) = joint_of[j.child] {
                return Err(invalid(format!(
                    "joint `{}` closes a loop (body `{}` already has joint `{}`); the joint-space \
                     reference handles trees only",
                    j.name, model.bodies[j.child].name, model.joints[first].name
                )));
            }
            joint_of[j.child] = Some(k);
        }
        let scale = model.bodies.iter().map(|b| b.position.max_abs()).fold(1.0, f64::max);
        let tol = 1e-8;
        let mut nodes: Vec<Option<Node>> = vec![None; nb];
        let (mut nq, mut nv) = (0, 0);
        let mut qpos0 = Vec::new();
        // Coordinates in joint order.
        for j in &model.joints {
            let i = j.child;
            let body = &model.bodies[i];
            let parent = match j.parent {
                Link::World => None,
                Link::Body(p) if p < i => Some(p),
                Link::Body(p) => {
                    return Err(invalid(format!(
                        "joint `{}`: parent body {p} does not come before its child {i}",
                        j.name
                    )))
                }
            };
            if !(body.mass > 0.0 && body.mass.is_finite() && body.com.is_finite()) {
                return Err(invalid(format!(
                    "body `{}`: mass {} must be positive and the centre of mass finite",
                    body.name, body.mass
                )));
            }
            let inertia_com = *Inertia::from_matrix(body.inertia.m)
                .map_err(|e| invalid(format!("body `{}`: {e}", body.name)))?
                .matrix();
            if !body.position.is_finite() || !body.rotation.is_finite() {
                return Err(invalid(format!("body `{}`: reference pose not finite", body.name)));
            }
            let (xp, rp) = match parent {
                None => (Vec3::ZERO, Mat3::IDENTITY),
                Some(p) => (model.bodies[p].position, model.bodies[p].rotation),
            };
            let e0 = rp.transpose() * body.rotation;
            let t0 = rp.tr_mul_vec(body.position - xp);
            let unit = |a: Vec3| -> Result<Vec3> {
                let n = a.norm();
                if (n - 1.0).abs() > 1e-9 {
                    return Err(invalid(format!("joint `{}`: axis {a:?} is not a unit vector", j.name)));
                }
                Ok(a * (1.0 / n))
            };
            let (kind, nqj, nd) = match j.kind {
                JointKind::Weld => (Kind::Weld, 0, 0),
                JointKind::Hinge { axis } => (Kind::Hinge(unit(axis)?), 1, 1),
                JointKind::Slide { axis } => (Kind::Slide(unit(axis)?), 1, 1),
                JointKind::Ball => (Kind::Ball, 4, 3),
                JointKind::Free => (Kind::Free, 7, 6),
            };
            if !(j.anchor_parent.is_finite() && j.anchor_child.is_finite() && j.reference_rotation.is_finite()) {
                return Err(invalid(format!(
                    "joint `{}`: anchors or reference_rotation not finite",
                    j.name
                )));
            }
            if kind != Kind::Free {
                let gap = (t0 + e0 * j.anchor_child - j.anchor_parent).max_abs();
                let rot = (e0 - j.reference_rotation).max_abs();
                if gap.is_nan() || rot.is_nan() || gap > tol * scale || rot > tol {
                    return Err(invalid(format!(
                        "joint `{}`: anchors or reference_rotation disagree with the bodies' reference \
                         poses (anchor gap {gap:.3e} m, rotation gap {rot:.3e})",
                        j.name
                    )));
                }
            }
            for (name, x) in [
                ("stiffness", j.stiffness),
                ("spring_ref", j.spring_ref),
                ("damping", j.damping),
                ("armature", j.armature),
            ] {
                if !x.is_finite() || (name != "spring_ref" && x < 0.0) {
                    return Err(invalid(format!(
                        "joint `{}`: {name} = {x} (must be finite, ≥ 0)",
                        j.name
                    )));
                }
            }
            match kind {
                Kind::Weld => {}
                Kind::Hinge(_) | Kind::Slide(_) => qpos0.push(0.0),
                Kind::Ball => qpos0.extend([1.0, 0.0, 0.0, 0.0]),
                Kind::Free => {
                    let qt = Quaternion::from_matrix(&e0);
                    qpos0.extend([t0.x, t0.y, t0.z, qt.w, qt.x, qt.y, qt.z]);
                }
            }
            let c = body.com;
            let ch = hat(c);
            let upper = inertia_com + ch * ch.transpose() * body.mass;
            let off = ch * body.mass;
            let mut inertia = ZERO66;
            for a in 0..3 {
                for b in 0..3 {
                    inertia[a][b] = upper.m[a][b];
                    inertia[a][b + 3] = off.m[a][b];
                    inertia[a + 3][b] = off.m[b][a];
                }
                inertia[a + 3][a + 3] = body.mass;
            }
            nodes[i] = Some(Node {
                kind,
                parent,
                iq: nq,
                iv: nv,
                nd,
                e0,
                t0,
                anchor: j.anchor_child,
                stiffness: j.stiffness,
                spring_ref: j.spring_ref,
                damping: j.damping,
                armature: j.armature,
                mass: body.mass,
                com: c,
                inertia_com,
                inertia,
            });
            nq += nqj;
            nv += nd;
        }
        let mut out = Vec::with_capacity(nb);
        for (i, n) in nodes.into_iter().enumerate() {
            out.push(n.ok_or_else(|| {
                invalid(format!(
                    "body `{}` has no joint (give it a weld joint to fix it to its parent)",
                    model.bodies[i].name
                ))
            })?);
        }
        let q_init = match &model.qpos {
            Some(q) => {
                check_len("qpos", q, nq)?;
                q.clone()
            }
            None => qpos0.clone(),
        };
        let v_init = match &model.qvel {
            Some(v) => {
                check_len("qvel", v, nv)?;
                v.clone()
            }
            None => vec![0.0; nv],
        };
        let w = Work {
            xf: vec![Xform::IDENTITY; nb],
            xm: vec![ZERO66; nb],
            pos: vec![Vec3::ZERO; nb],
            rot: vec![Mat3::IDENTITY; nb],
            s: vec![[ZERO6; 6]; nb],
            vel: vec![ZERO6; nb],
            c: vec![ZERO6; nb],
            ia: vec![ZERO66; nb],
            pa: vec![ZERO6; nb],
            u: vec![[ZERO6; 6]; nb],
            dinv: vec![ZERO66; nb],
            uu: vec![[0.0; 6]; nb],
            acc: vec![ZERO6; nb],
            y0: vec![0.0; nq + nv],
            yt: vec![0.0; nq + nv],
            k: core::array::from_fn(|_| vec![0.0; nq + nv]),
        };
        let mut m = JointSpaceModel {
            nodes: out,
            gravity: model.gravity,
            nq,
            nv,
            qpos0,
            q_init,
            v_init,
            w,
        };
        // The starting state must be a valid one.
        let q = m.q_init.clone();
        m.kinematics(&q)?;
        Ok(m)
    }

    /// Number of position coordinates (free 7, ball 4, hinge 1, slide 1, weld 0).
    #[must_use]
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// Number of velocity coordinates (free 6, ball 3, hinge 1, slide 1, weld 0).
    #[must_use]
    pub fn nv(&self) -> usize {
        self.nv
    }

    /// Number of bodies.
    #[must_use]
    pub fn body_count(&self) -> usize {
        self.nodes.len()
    }

    /// The reference coordinates `qpos0`: hinge and slide 0, ball the identity quaternion,
    /// free the child's reference pose in its parent (for a root: the body's reference
    /// world pose), at which [`forward_kinematics`](Self::forward_kinematics) reproduces the
    /// bodies' reference world poses.
    #[must_use]
    pub fn qpos0(&self) -> &[f64] {
        &self.qpos0
    }

    /// The model's starting coordinates: `Model::qpos`, or [`qpos0`](Self::qpos0).
    #[must_use]
    pub fn initial_q(&self) -> &[f64] {
        &self.q_init
    }

    /// The model's starting velocities: `Model::qvel`, or zero.
    #[must_use]
    pub fn initial_v(&self) -> &[f64] {
        &self.v_init
    }

    /// The pose `(r, E)` of body `i` in its parent and the joint's motion subspace, into
    /// the scratch, with the world poses.
    fn kinematics(&mut self, q: &[f64]) -> Result<()> {
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
    fn velocities(&mut self, v: &[f64]) -> Result<()> {
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

    /// The passive generalised force of a hinge or slide joint: `−k (q − q_ref) − d q̇`.
    fn passive(n: &Node, q: &[f64], v: &[f64]) -> f64 {
        match n.kind {
            Kind::Hinge(_) | Kind::Slide(_) => -n.stiffness * (q[n.iq] - n.spring_ref) - n.damping * v[n.iv],
            _ => 0.0,
        }
    }

    /// The armature of a hinge or slide joint, 0 for the others.
    fn armature(n: &Node) -> f64 {
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

    fn aba_inner(&mut self, q: &[f64], v: &[f64], tau: Option<&[f64]>, qdd: &mut [f64]) -> Result<()> {
        if qdd.len() != self.nv {
            return Err(Error::InvalidParameter {
                name: "qdd",
                value: qdd.len() as f64,
                reason: "length differs from nv",
            });
        }
        self.kinematics(q)?;
        self.velocities(v)?;
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
                w.uu[i][0] += Self::passive(n, q, v);
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
                tau[n.iv] += Self::armature(n) * qdd[n.iv] - Self::passive(n, q, v);
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

    /// The time derivative of the coordinates, `q̇ = Q(q) v` (into `qdot`, length `nq`):
    /// hinge and slide `q̇ = v`, ball `Q̇ = ½ Q ⊗ (0, ω)`, free `ṗ` then `Q̇ = ½ Q ⊗ (0, ω)`
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
        }
        Ok(e)
    }

    /// The total linear momentum `Σ m_i ċ_i` and angular momentum about the world origin
    /// `Σ c_i × m_i ċ_i + R_i I_i ω_i`, in world coordinates (the spec's
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
