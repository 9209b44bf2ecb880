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
//! | universal, axes `a`, `a₂`, angles `θ₁`, `θ₂` | `E₀ exp(θ₁ â) exp(θ₂ â₂)` | `t₀ + E₀ b − E b` |
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
//! Hinge, slide: the rate. Universal: the two rates, the child's angular velocity relative
//! to its parent being `exp(−θ₂ â₂) a θ̇₁ + a₂ θ̇₂` in child coordinates. Ball: the angular velocity `ω` of the child relative to the
//! parent in child coordinates, `Q̇ = ½ Q ⊗ (0, ω)`. Free: the velocity `ṗ` of the child
//! frame's origin in parent coordinates, then `ω` in child coordinates (MuJoCo's
//! convention), `Q̇ = ½ Q ⊗ (0, ω)`.
//!
//! ## Spatial algebra
//!
//! Spatial motion vectors `(ω; v)` and force vectors `(n; f)`, angular part first, in the
//! coordinates of each body's frame (origin at the frame origin, axes the body's). The
//! joint's motion subspace `S` (6 × `nv` of the joint), in child coordinates:
//! hinge `(u; b × u)`, slide `(0; u)`, ball `(1; b̂)`, universal `[(a'; b × a'), (a₂; b × a₂)]`
//! with `a' = exp(−θ₂ â₂) a`, free `[[0, 1]; [Eᵀ, 0]]`; hinge, slide and ball are
//! constant in child coordinates, the universal's first column has the apparent derivative
//! `S̊ q̇ = θ̇₁ θ̇₂ (d; b × d)`, `d = −a₂ × a'`, and the free joint's `S̊ q̇ = (0; −ω × Eᵀ ṗ)`.
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

mod dynamics;
mod kinematics;
mod rk4;
mod spatial;

use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};
use crate::multibody::model::{JointKind, Link, Model};
use crate::so3::{hat, Quaternion};

use spatial::{Xform, M6, SV, ZERO6, ZERO66};

/// The joint kinds as this module uses them (axes unit, in child coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Weld,
    Hinge(Vec3),
    /// First and second axis, child coordinates at the reference.
    Universal(Vec3, Vec3),
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
    /// The actuators' generalized forces over `v`.
    qfrc: Vec<f64>,
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
    /// The actuators with their joint's `(iq, iv)`, the joints' summed-force clamps (per
    /// `v` entry), the current control.
    actuators: Vec<(crate::multibody::model::Actuator, usize, usize)>,
    force_range: Vec<Option<(f64, f64)>>,
    ctrl: Vec<f64>,
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
                JointKind::Universal { first, second } => (Kind::Universal(unit(first)?, unit(second)?), 2, 2),
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
            if j.frictionloss != 0.0 {
                return Err(invalid(format!(
                    "joint `{}`: frictionloss = {} is not simulated by the joint-space methods (dry friction is \
                     a constraint, as MuJoCo treats it, which an ODE method cannot hold exactly; the liemid methods \
                     hold it)",
                    j.name, j.frictionloss
                )));
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
                Kind::Universal(..) => qpos0.extend([0.0, 0.0]),
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
            qfrc: vec![0.0; nv],
            y0: vec![0.0; nq + nv],
            yt: vec![0.0; nq + nv],
            k: core::array::from_fn(|_| vec![0.0; nq + nv]),
        };
        model.validate_actuators()?;
        let actuators = model
            .actuators
            .iter()
            .map(|a| (a.clone(), out[a.joint].iq, out[a.joint].iv))
            .collect();
        let mut force_range = vec![None; nv];
        for (k, j) in model.joints.iter().enumerate().take(nb) {
            if out[k].nd == 1 {
                force_range[out[k].iv] = j.actuator_force_range;
            }
        }
        let mut m = JointSpaceModel {
            actuators,
            force_range,
            ctrl: model.ctrl.clone().unwrap_or_else(|| vec![0.0; model.actuators.len()]),
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

    /// The current control, one value per actuator (the model's order).
    #[must_use]
    pub fn ctrl(&self) -> &[f64] {
        &self.ctrl
    }

    /// Set the control, held until set again (MuJoCo's `d.ctrl`).
    ///
    /// # Errors
    /// [`Error::InvalidModel`] naming the actuator for a wrong length or a value that is
    /// not finite.
    pub fn set_ctrl(&mut self, ctrl: &[f64]) -> Result<()> {
        if ctrl.len() != self.ctrl.len() {
            return Err(invalid(format!(
                "ctrl has {} values, the model has {} actuators",
                ctrl.len(),
                self.ctrl.len()
            )));
        }
        if let Some(k) = ctrl.iter().position(|x| !x.is_finite()) {
            return Err(invalid(format!(
                "ctrl[{k}] (actuator `{}`) = {} is not finite",
                self.actuators[k].0.name, ctrl[k]
            )));
        }
        self.ctrl.copy_from_slice(ctrl);
        Ok(())
    }

    /// The actuators' generalized forces at `(q, v)` into `qfrc` (MuJoCo's
    /// `qfrc_actuator`: each force clamped, times the gear, summed, the joint's clamp).
    fn actuator_forces(&mut self, q: &[f64], v: &[f64]) {
        let qfrc = &mut self.w.qfrc;
        qfrc.iter_mut().for_each(|x| *x = 0.0);
        for ((act, iq, iv), &u) in self.actuators.iter().zip(&self.ctrl) {
            qfrc[*iv] += act.gear * act.force(act.clamp_ctrl(u), q[*iq], v[*iv]);
        }
        for (f, r) in qfrc.iter_mut().zip(&self.force_range) {
            if let Some((lo, hi)) = r {
                *f = f.clamp(*lo, *hi);
            }
        }
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
}
