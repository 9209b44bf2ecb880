//! The multibody model: bodies, joints and the world, as a loader (MJCF, URDF, TOML) or
//! code builds them. Plain data; `Model::validate` checks it, the multibody system is
//! built from a validated model. All quantities in SI units, positions in metres, angles
//! in radians. (SHARED CONTRACT between the core and the loaders: keep these types and
//! field names; add methods freely.)

use crate::linalg::{Mat3, Vec3};

/// Which body a joint or an anchor belongs to: the fixed world or a body of the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Link {
    /// The fixed world frame (`R = I`, origin at 0).
    World,
    /// `Model::bodies[i]`.
    Body(usize),
}

/// One rigid body. Its frame is the model's body frame (MJCF `<body>`, URDF `<link>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// The name from the model file (unique within a model).
    pub name: String,
    /// Mass (kg), > 0.
    pub mass: f64,
    /// Centre of mass in body coordinates, `s` (m).
    pub com: Vec3,
    /// Inertia tensor about the centre of mass in body-frame axes (kg m²), full 3x3,
    /// symmetric positive definite, principal moments obeying the triangle inequality.
    pub inertia: Mat3,
    /// The body frame's origin in world coordinates in the reference configuration (m).
    pub position: Vec3,
    /// The body frame's attitude (body to world) in the reference configuration.
    pub rotation: Mat3,
}

/// The kind of a joint; axes are unit vectors in the **child** body's frame (MJCF and
/// URDF both give them so).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// Three rotational degrees of freedom about the anchor (qpos: quaternion w,x,y,z;
    /// qvel: angular velocity in the child frame).
    Ball,
    /// One rotation about `axis` through the anchor (qpos, qvel: angle, rate).
    Hinge {
        /// Unit axis in the child frame.
        axis: Vec3,
    },
    /// One translation along `axis` (qpos, qvel: offset, rate).
    Slide {
        /// Unit axis in the child frame.
        axis: Vec3,
    },
    /// Two rotations about axes through the anchor (a universal or Cardan joint): the
    /// relative attitude is `Qᵀ R_iᵀ R_j = exp(θ₁ first) exp(θ₂ second)`, `Q` the joint's
    /// reference rotation. Both axes are unit vectors in the **child** frame at the
    /// reference configuration (as MJCF gives two hinges of one body); `first` (nearer the
    /// parent) then stays fixed in the parent (`Q first` in the parent frame) and `second`
    /// fixed in the child. The axes must be independent (`|first × second| ≥`
    /// [`AXIS_INDEPENDENCE`]); the joint has no gimbal lock. (qpos, qvel: the two angles
    /// and their rates.)
    Universal {
        /// The first axis (child frame at the reference configuration; fixed in the parent).
        first: Vec3,
        /// The second axis (child frame; fixed in the child).
        second: Vec3,
    },
    /// No relative motion.
    Weld,
    /// Six degrees of freedom, no constraint rows (qpos: position of the child frame's
    /// origin in the parent frame (world for a root), then quaternion w,x,y,z; qvel: linear
    /// velocity in the parent frame, angular velocity in the child frame, as MuJoCo).
    Free,
}

/// A joint between a parent (or the world) and a child body.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// The name from the model file (generated when the file gives none).
    pub name: String,
    /// Kind and axis.
    pub kind: JointKind,
    /// The parent (world for a root joint).
    pub parent: Link,
    /// The child body; in a tree each body is the child of exactly one joint. A joint
    /// whose child already has a tree joint closes a loop (`Model::loop_joints`).
    pub child: usize,
    /// The joint's point in the parent's frame coordinates (from the frame origin, not the
    /// centre of mass) (m).
    pub anchor_parent: Vec3,
    /// The same point in the child's frame coordinates (m).
    pub anchor_child: Vec3,
    /// Relative attitude of the child frame in the parent frame at the reference
    /// configuration (zero joint coordinate): what weld, hinge and slide rows lock.
    pub reference_rotation: Mat3,
    /// Joint limit (rad or m) for hinge and slide, `None` when unlimited.
    pub range: Option<(f64, f64)>,
    /// Spring stiffness (N m/rad or N/m) towards `spring_ref`, hinge and slide only.
    pub stiffness: f64,
    /// The spring's rest coordinate (MJCF `springref`, default 0).
    pub spring_ref: f64,
    /// Viscous damping (N m s/rad or N s/m) on the joint rate of a hinge or slide, or on
    /// the relative angular velocity of a ball (`−d (ω_child − ω_parent)`).
    pub damping: f64,
    /// MJCF `armature` (kg m² or kg); 0 when absent.
    pub armature: f64,
    /// Dry friction (MJCF `frictionloss`, N m or N) of a hinge or slide: the joint sticks
    /// while the other generalized forces on it stay below it (docs/theory/multibody.md §8).
    pub frictionloss: f64,
    /// MJCF `actuatorfrcrange`: the clamp of the summed actuator force on this joint (after
    /// each actuator's own clamp and gear), `None` when unlimited.
    pub actuator_force_range: Option<(f64, f64)>,
}

impl Joint {
    /// The joint's axis in the child's frame and in the parent's (the reference rotation
    /// applied): a universal joint's second and first axes, `z` for a joint without one.
    #[must_use]
    pub fn axes(&self) -> (Vec3, Vec3) {
        match self.kind {
            JointKind::Universal { first, second } => (second, self.reference_rotation * first),
            kind => {
                let u = kind.axis().unwrap_or(Vec3::new(0.0, 0.0, 1.0));
                (u, self.reference_rotation * u)
            }
        }
    }
}

/// An actuator on a hinge or slide joint, as MuJoCo defines it with a joint transmission:
/// length `L = gear · qpos`, velocity `V = gear · q̇`, the control clamped to `ctrl_range`,
/// the scalar force `f = (g₀ + g₁ L + g₂ V) u + b₀ + b₁ L + b₂ V` clamped to `force_range`,
/// and the generalized force `gear · f` on the joint (MJCF `motor`: gain 1; `position`:
/// gain `kp`, bias `(0, −kp, −kv)`; `velocity`: gain `kv`, bias `(0, 0, −kv)`; `general`
/// with fixed or affine gain and bias, no activation dynamics).
///
/// Reference: docs/theory/multibody.md §8.
#[derive(Clone, Debug, PartialEq)]
pub struct Actuator {
    /// The name from the file (generated when it gives none).
    pub name: String,
    /// The joint it drives (an index into `Model::joints`, a tree hinge or slide).
    pub joint: usize,
    /// The transmission's gear (MJCF `gear`, first component).
    pub gear: f64,
    /// `(g₀, g₁, g₂)`: the gain `g₀ + g₁ L + g₂ V`.
    pub gain: [f64; 3],
    /// `(b₀, b₁, b₂)`: the bias `b₀ + b₁ L + b₂ V`.
    pub bias: [f64; 3],
    /// The control's clamp (MJCF `ctrlrange` when limited), `None` when unlimited.
    pub ctrl_range: Option<(f64, f64)>,
    /// The force's clamp (MJCF `forcerange` when limited), `None` when unlimited.
    pub force_range: Option<(f64, f64)>,
    /// MuJoCo's `qpos` minus the model's coordinate of the joint (its `ref`), so that
    /// `L = gear · (q + length_offset)`.
    pub length_offset: f64,
}

impl Actuator {
    /// The control clamped to `ctrl_range`.
    #[must_use]
    pub fn clamp_ctrl(&self, u: f64) -> f64 {
        match self.ctrl_range {
            Some((lo, hi)) => u.clamp(lo, hi),
            None => u,
        }
    }

    /// The scalar force (before the gear) at the model coordinate `q` and rate `qdot`,
    /// with the control `u` already clamped, clamped to `force_range` (MuJoCo's order).
    #[must_use]
    pub fn force(&self, u: f64, q: f64, qdot: f64) -> f64 {
        let l = self.gear * (q + self.length_offset);
        let v = self.gear * qdot;
        let f = (self.gain[0] + self.gain[1] * l + self.gain[2] * v) * u
            + self.bias[0]
            + self.bias[1] * l
            + self.bias[2] * v;
        match self.force_range {
            Some((lo, hi)) => f.clamp(lo, hi),
            None => f,
        }
    }

    /// The actuator's viscous part as a joint damping, `−gear² b₂` (N m s/rad or N s/m),
    /// the coefficient of `−q̇` in `gear · f` when no clamp acts.
    #[must_use]
    pub fn damping(&self) -> f64 {
        -self.gear * self.gear * self.bias[2]
    }
}

/// A whole model: bodies, joints, gravity and the starting joint coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// The model's name (MJCF `<mujoco model>`, URDF `<robot name>`).
    pub name: String,
    /// Bodies, parents before children (the world is not a body).
    pub bodies: Vec<Body>,
    /// Joints: the tree joints first (body order), loop-closing joints after.
    pub joints: Vec<Joint>,
    /// Gravity (m/s²), world frame; MJCF default (0, 0, -9.81).
    pub gravity: Vec3,
    /// The file's suggested step (MJCF `option timestep`), if any.
    pub timestep: Option<f64>,
    /// Starting joint coordinates in MuJoCo's layout over the tree joints in order
    /// (free 7, ball 4, hinge 1, slide 1, weld 0); `None`: the reference pose.
    pub qpos: Option<Vec<f64>>,
    /// Starting joint velocities (free 6, ball 3, hinge 1, slide 1); `None`: at rest.
    pub qvel: Option<Vec<f64>>,
    /// Actuators (MJCF `<actuator>` on hinge and slide joints), in file order.
    pub actuators: Vec<Actuator>,
    /// The starting control, one value per actuator (MJCF keyframe `ctrl`); `None`: zero.
    pub ctrl: Option<Vec<f64>>,
    /// The shapes that touch and the contact options (empty: no contacts).
    pub collision: super::contact::Collision,
}

use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::so3::{self, Quaternion};

use super::MultibodyState;

/// Largest accepted `|‖u‖ − 1|` of a joint axis and `‖RᵀR − I‖_F` of a model rotation.
pub const UNIT_TOLERANCE: f64 = 1e-9;

/// Smallest accepted `|first × second|` of a universal joint's axes, and `|det(a, b, c)|`
/// of three hinge axes merged into a ball by the MJCF loader: nearly parallel axes leave
/// a nearly singular joint.
pub const AXIS_INDEPENDENCE: f64 = 1e-6;

impl JointKind {
    /// Joint coordinates in MuJoCo's `qpos` layout: free 7, ball 4, universal 2 (its two
    /// angles, as MuJoCo's two hinges), hinge 1, slide 1, weld 0 (MuJoCo documentation,
    /// "Joint").
    #[must_use]
    pub fn nq(&self) -> usize {
        match self {
            JointKind::Free => 7,
            JointKind::Ball => 4,
            JointKind::Universal { .. } => 2,
            JointKind::Hinge { .. } | JointKind::Slide { .. } => 1,
            JointKind::Weld => 0,
        }
    }

    /// Joint velocities in MuJoCo's `qvel` layout: free 6, ball 3, universal 2, hinge 1,
    /// slide 1, weld 0.
    #[must_use]
    pub fn nv(&self) -> usize {
        match self {
            JointKind::Free => 6,
            JointKind::Ball => 3,
            JointKind::Universal { .. } => 2,
            JointKind::Hinge { .. } | JointKind::Slide { .. } => 1,
            JointKind::Weld => 0,
        }
    }

    /// Holonomic constraint rows (docs/theory/multibody.md §2): ball 3, universal 4, hinge 5,
    /// slide 5, weld 6, free 0; that is `6 − nv`.
    #[must_use]
    pub fn rows(&self) -> usize {
        6 - self.nv()
    }

    /// The short kind name (`ball`, `universal`, `hinge`, `slide`, `weld`, `free`).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Free => "free",
            JointKind::Ball => "ball",
            JointKind::Universal { .. } => "universal",
            JointKind::Hinge { .. } => "hinge",
            JointKind::Slide { .. } => "slide",
            JointKind::Weld => "weld",
        }
    }

    /// The axis of a hinge or slide (child frame), `None` otherwise.
    #[must_use]
    pub fn axis(&self) -> Option<Vec3> {
        match *self {
            JointKind::Hinge { axis } | JointKind::Slide { axis } => Some(axis),
            _ => None,
        }
    }
}

fn invalid(reason: String) -> Error {
    Error::InvalidModel { reason }
}

fn check_rotation(what: &str, r: &Mat3) -> Result<()> {
    let defect = so3::orthogonality_defect(r);
    let det = r.determinant();
    if !r.is_finite() || defect > UNIT_TOLERANCE || det <= 0.0 {
        return Err(invalid(format!(
            "{what} is not a rotation: |R^T R - I|_F = {defect:.3e} (at most {UNIT_TOLERANCE:e}), det = {det}"
        )));
    }
    Ok(())
}

fn check_vec(what: &str, v: Vec3) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(format!("{what} = {v:?} is not finite")))
    }
}

impl Model {
    /// The number of tree joints: one per body (`joints[j].child == j` for `j <
    /// bodies.len()`); the joints after them close loops.
    #[must_use]
    pub fn tree_joint_count(&self) -> usize {
        self.bodies.len()
    }

    /// The loop-closing joints (indices into `joints`).
    #[must_use]
    pub fn loop_joints(&self) -> core::ops::Range<usize> {
        self.bodies.len().min(self.joints.len())..self.joints.len()
    }

    /// Length of `qpos` for the tree joints (MuJoCo layout).
    #[must_use]
    pub fn nq(&self) -> usize {
        self.joints.iter().take(self.bodies.len()).map(|j| j.kind.nq()).sum()
    }

    /// Length of `qvel` for the tree joints (MuJoCo layout).
    #[must_use]
    pub fn nv(&self) -> usize {
        self.joints.iter().take(self.bodies.len()).map(|j| j.kind.nv()).sum()
    }

    /// The body inertia tensor `I_i` (about the centre of mass, body axes), validated.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] naming the body when the tensor is not finite, not SPD or
    /// breaks the triangle inequality.
    pub fn inertia(&self, i: usize) -> Result<Inertia> {
        let b = &self.bodies[i];
        Inertia::from_matrix(b.inertia.m).map_err(|e| invalid(format!("body `{}` ({i}): {e}", b.name)))
    }

    /// A length scale of the model: the largest distance from a centre of mass to a joint
    /// anchor (1 m when there is none). Position constraint violations are reported
    /// relative to it.
    #[must_use]
    pub fn length_scale(&self) -> f64 {
        let mut l: f64 = 0.0;
        for j in &self.joints {
            l = l.max((j.anchor_child - self.bodies.get(j.child).map_or(Vec3::ZERO, |b| b.com)).norm());
            if let Link::Body(i) = j.parent {
                if let Some(b) = self.bodies.get(i) {
                    l = l.max((j.anchor_parent - b.com).norm());
                }
            }
        }
        if l > 0.0 && l.is_finite() {
            l
        } else {
            1.0
        }
    }

    /// The stiffest damper: over the hinge and slide joints with `damping d > 0`, the least
    /// `2 I / d` and its joint, where `I` is the child's moment of inertia about the joint
    /// axis through the anchor (its mass for a slide). With the parent held the joint rate
    /// decays as `q̇' = −(d/I) q̇`, and `x = h d / (2I)` measures how stiff the damper is at
    /// step `h`. The step's dampers are stable at any `x` (the trapezoidal rule, and
    /// backward Euler in both half-kicks for a row above `x = 2`), but a composition's
    /// negative sub-step anti-damps without a stable solution once its own `|x| ≥ 1`, i.e.
    /// above a sub-step of `2 I / d`. Inertia the rest of the tree adds to the joint's motion raises the bound,
    /// so this is the pessimistic one. MuJoCo models often keep `x` large and rely on
    /// `armature` (added to `I` in joint space, dropped in maximal coordinates).
    ///
    /// Reference: E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd
    /// ed., Springer 1996, IV.2-IV.3 (stiffness, A-stability of the trapezoidal rule).
    #[must_use]
    pub fn damper_step_bound(&self) -> Option<(usize, f64)> {
        let mut least: Option<(usize, f64)> = None;
        for (k, j) in self.joints.iter().enumerate() {
            let Some(b) = self.bodies.get(j.child) else { continue };
            let inertia = match j.kind {
                JointKind::Hinge { axis } => {
                    let arm = axis.cross(b.com - j.anchor_child);
                    axis.dot(b.inertia * axis) + b.mass * arm.norm_squared()
                }
                JointKind::Slide { .. } => b.mass,
                _ => continue,
            };
            if j.damping > 0.0 {
                let bound = 2.0 * inertia / j.damping;
                if least.is_none_or(|(_, h)| bound < h) {
                    least = Some((k, bound));
                }
            }
        }
        least
    }

    /// Check everything the multibody system relies on: masses positive and finite; inertia
    /// tensors SPD with the triangle inequality; finite centres, anchors and poses;
    /// rotations orthogonal; unit finite axes; one tree joint per body in body order
    /// (`joints[j].child == j`) with its parent a body before it (acyclic, parents before
    /// children) or the world; loop joints between existing bodies and not free; ranges
    /// ordered; stiffness, damping, armature non-negative; `qpos`/`qvel` lengths; finite
    /// gravity. Errors name the body or joint.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] with the reason and the numbers.
    pub fn validate(&self) -> Result<()> {
        let nb = self.bodies.len();
        if nb == 0 {
            return Err(invalid(format!("model `{}` has no bodies", self.name)));
        }
        check_vec("gravity", self.gravity)?;
        for (i, b) in self.bodies.iter().enumerate() {
            if !(b.mass.is_finite() && b.mass > 0.0) {
                return Err(invalid(format!(
                    "body `{}` ({i}): mass {} must be finite and > 0",
                    b.name, b.mass
                )));
            }
            self.inertia(i)?;
            check_vec(&format!("body `{}` ({i}) com", b.name), b.com)?;
            check_vec(&format!("body `{}` ({i}) position", b.name), b.position)?;
            check_rotation(&format!("body `{}` ({i}) rotation", b.name), &b.rotation)?;
        }
        if self.joints.len() < nb {
            return Err(invalid(format!(
                "{} joints for {nb} bodies: every body needs a tree joint (free for a floating body)",
                self.joints.len()
            )));
        }
        for (k, j) in self.joints.iter().enumerate() {
            let name = format!("joint `{}` ({k})", j.name);
            if j.child >= nb {
                return Err(invalid(format!("{name}: child {} out of range ({nb} bodies)", j.child)));
            }
            if k < nb && j.child != k {
                return Err(invalid(format!(
                    "{name}: tree joints come in body order, so its child must be body {k}, not {} (body `{}` \
                     would be the child of two tree joints or of none)",
                    j.child, self.bodies[j.child].name
                )));
            }
            if let Link::Body(p) = j.parent {
                if p >= nb {
                    return Err(invalid(format!("{name}: parent {p} out of range ({nb} bodies)")));
                }
                if k < nb && p >= k {
                    return Err(invalid(format!(
                        "{name}: parent body {p} does not come before its child {k} (the tree must list parents \
                         first; a cycle is not a tree)"
                    )));
                }
                if p == j.child {
                    return Err(invalid(format!("{name}: joins body {p} to itself")));
                }
            }
            if k >= nb && j.kind == JointKind::Free {
                return Err(invalid(format!(
                    "{name}: a free joint cannot close a loop (it has no rows)"
                )));
            }
            let axes = match j.kind {
                JointKind::Universal { first, second } => vec![first, second],
                kind => kind.axis().into_iter().collect(),
            };
            for u in &axes {
                if !u.is_finite() || (u.norm() - 1.0).abs() > UNIT_TOLERANCE {
                    return Err(invalid(format!(
                        "{name}: axis {u:?} is not a finite unit vector (|u| = {})",
                        u.norm()
                    )));
                }
            }
            if let JointKind::Universal { first, second } = j.kind {
                let sine = first.cross(second).norm();
                if sine < AXIS_INDEPENDENCE {
                    return Err(invalid(format!(
                        "{name}: universal axes {first:?} and {second:?} are parallel (|first x second| = \
                         {sine:.3e}, at least {AXIS_INDEPENDENCE:e})"
                    )));
                }
            }
            check_vec(&format!("{name} anchor_parent"), j.anchor_parent)?;
            check_vec(&format!("{name} anchor_child"), j.anchor_child)?;
            check_rotation(&format!("{name} reference_rotation"), &j.reference_rotation)?;
            if let Some((lo, hi)) = j.range {
                if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                    return Err(invalid(format!(
                        "{name}: range ({lo}, {hi}) must be finite with lower <= upper"
                    )));
                }
            }
            for (what, v) in [
                ("stiffness", j.stiffness),
                ("damping", j.damping),
                ("armature", j.armature),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(invalid(format!("{name}: {what} = {v} must be finite and >= 0")));
                }
            }
            if !j.spring_ref.is_finite() {
                return Err(invalid(format!("{name}: spring_ref = {} is not finite", j.spring_ref)));
            }
            if !(j.frictionloss.is_finite() && j.frictionloss >= 0.0) {
                return Err(invalid(format!(
                    "{name}: frictionloss = {} must be finite and >= 0",
                    j.frictionloss
                )));
            }
            let one_dof = matches!(j.kind, JointKind::Hinge { .. } | JointKind::Slide { .. });
            if j.frictionloss > 0.0 && !(one_dof && k < nb) {
                return Err(invalid(format!(
                    "{name}: frictionloss on a {} joint is not simulated (hinge and slide tree joints only)",
                    j.kind.name()
                )));
            }
            if let Some((lo, hi)) = j.actuator_force_range {
                if lo.is_nan() || hi.is_nan() || lo > hi {
                    return Err(invalid(format!(
                        "{name}: actuatorfrcrange ({lo}, {hi}) is upside down or NaN (lower <= upper)"
                    )));
                }
            }
        }
        self.validate_actuators()?;
        if let Some(q) = &self.qpos {
            if q.len() != self.nq() {
                return Err(invalid(format!(
                    "qpos has {} entries, the tree joints need {}",
                    q.len(),
                    self.nq()
                )));
            }
            if let Some(k) = q.iter().position(|x| !x.is_finite()) {
                return Err(invalid(format!("qpos[{k}] = {} is not finite", q[k])));
            }
        }
        if let Some(v) = &self.qvel {
            if v.len() != self.nv() {
                return Err(invalid(format!(
                    "qvel has {} entries, the tree joints need {}",
                    v.len(),
                    self.nv()
                )));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(invalid(format!("qvel[{k}] = {} is not finite", v[k])));
            }
        }
        Ok(())
    }

    /// Check the actuators and the starting control: each drives a tree hinge or slide, its
    /// gear, gain and bias finite, its ranges ordered (`lower <= upper`), no anti-damping
    /// bias (`b₂ > 0`); `ctrl` one finite value per actuator. Errors name the actuator.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] with the reason.
    pub fn validate_actuators(&self) -> Result<()> {
        let nb = self.bodies.len();
        for (a, act) in self.actuators.iter().enumerate() {
            let name = format!("actuator `{}` ({a})", act.name);
            let Some(j) = self.joints.get(act.joint).filter(|_| act.joint < nb) else {
                return Err(invalid(format!(
                    "{name}: joint index {} is not a tree joint of the model",
                    act.joint
                )));
            };
            if !matches!(j.kind, JointKind::Hinge { .. } | JointKind::Slide { .. }) {
                return Err(invalid(format!(
                    "{name}: drives joint `{}`, a {} joint (hinge and slide joints only)",
                    j.name,
                    j.kind.name()
                )));
            }
            let finite = act.gear.is_finite()
                && act.length_offset.is_finite()
                && act.gain.iter().chain(&act.bias).all(|x| x.is_finite());
            if !finite {
                return Err(invalid(format!(
                    "{name}: gear {}, gain {:?} and bias {:?} must be finite",
                    act.gear, act.gain, act.bias
                )));
            }
            if act.bias[2] > 0.0 {
                return Err(invalid(format!(
                    "{name}: velocity bias {} > 0 is anti-damping (a negative kv)",
                    act.bias[2]
                )));
            }
            for (what, r) in [("ctrlrange", act.ctrl_range), ("forcerange", act.force_range)] {
                if let Some((lo, hi)) = r {
                    if lo.is_nan() || hi.is_nan() || lo > hi {
                        return Err(invalid(format!(
                            "{name}: {what} ({lo}, {hi}) is upside down or NaN (lower <= upper)"
                        )));
                    }
                }
            }
        }
        if let Some(u) = &self.ctrl {
            if u.len() != self.actuators.len() {
                return Err(invalid(format!(
                    "ctrl has {} entries, the model has {} actuators",
                    u.len(),
                    self.actuators.len()
                )));
            }
            if let Some(k) = u.iter().position(|x| !x.is_finite()) {
                return Err(invalid(format!(
                    "ctrl[{k}] (actuator `{}`) = {} is not finite",
                    self.actuators[k].name, u[k]
                )));
            }
        }
        Ok(())
    }

    /// The joint coordinates of the reference configuration in MuJoCo's layout: hinge and
    /// slide 0, ball the identity quaternion, free the child frame's origin in the parent
    /// frame and the quaternion of `R_parentᵀ R_child` (MuJoCo's `qpos0`).
    #[must_use]
    pub fn reference_qpos(&self) -> Vec<f64> {
        let mut q = Vec::with_capacity(self.nq());
        for j in self.joints.iter().take(self.bodies.len()) {
            match j.kind {
                JointKind::Hinge { .. } | JointKind::Slide { .. } => q.push(0.0),
                JointKind::Universal { .. } => q.extend([0.0, 0.0]),
                JointKind::Ball => q.extend([1.0, 0.0, 0.0, 0.0]),
                JointKind::Weld => {}
                JointKind::Free => {
                    let child = &self.bodies[j.child];
                    let (x, r) = match j.parent {
                        Link::World => (Vec3::ZERO, Mat3::IDENTITY),
                        Link::Body(p) => (self.bodies[p].position, self.bodies[p].rotation),
                    };
                    let pos = r.tr_mul_vec(child.position - x);
                    let quat = Quaternion::from_matrix(&(r.transpose() * child.rotation));
                    q.extend([pos.x, pos.y, pos.z, quat.w, quat.x, quat.y, quat.z]);
                }
            }
        }
        q
    }

    /// The bodies' state from the joint coordinates (forward kinematics over the tree,
    /// parents first, MuJoCo's conventions):
    ///
    /// - attitudes: hinge `R_j = R_i Q exp(q u)`, universal `R_j = R_i Q exp(q₁ a) exp(q₂ b)`,
    ///   ball `R_j = R_i Q R(quat)`, slide and weld `R_j = R_i Q`, free `R_j = R_i R(quat)`
    ///   (`Q` the joint's reference rotation);
    /// - frame origins: the anchor `A = x_i + R_i o_i` is shared, `x_j = A − R_j o_j`, plus
    ///   `q R_j u` for a slide; a free joint puts `x_j = x_i + R_i pos`;
    /// - velocities: `ω_j = ω_i + R_j u q̇` (hinge), `ω_i + R_i Q a q̇₁ + R_j b q̇₂`
    ///   (universal), `ω_i + R_j w` (ball, free; `w` in the
    ///   child frame), `ω_i` (slide, weld); the anchor moves with the parent and the child's
    ///   centre of mass with `v_A + ω_j × (c_j − A)`, plus `R_j u q̇` for a slide; a free
    ///   joint's linear velocity is that of the child frame origin, in the parent frame.
    ///
    /// Then `c = x + R s`, `p = m v_c`, `Π = I Rᵀ ω` (plus the hinge armature's `a q̇ n_c` on
    /// the child and `−a q̇ n_p` on the parent: `Π = 𝕁 W`, docs/theory/multibody.md §7). Loop-closing joints are not used:
    /// the coordinates must satisfy them; check with
    /// [`super::MultibodySystem::constraint_violation`] and bring loop-violating velocities
    /// onto the constraints with [`super::Rattle::project_velocities`].
    ///
    /// # Errors
    /// Whatever [`Model::validate`] reports, and a zero quaternion.
    ///
    /// Reference: E. Todorov et al., MuJoCo documentation, "Computation" (kinematics).
    pub fn initial_state(&self) -> Result<MultibodyState> {
        self.validate()?;
        let nb = self.bodies.len();
        let reference;
        let qpos = match &self.qpos {
            Some(q) => q.as_slice(),
            None => {
                reference = self.reference_qpos();
                reference.as_slice()
            }
        };
        let zeros;
        let qvel = match &self.qvel {
            Some(v) => v.as_slice(),
            None => {
                zeros = vec![0.0; self.nv()];
                zeros.as_slice()
            }
        };
        // Frame origin, attitude, velocity of the frame origin's point... we keep the com
        // velocity and the spatial angular velocity per body.
        let mut x = vec![Vec3::ZERO; nb];
        let mut rot = vec![Mat3::IDENTITY; nb];
        let mut vc = vec![Vec3::ZERO; nb];
        let mut w = vec![Vec3::ZERO; nb];
        let mut c = vec![Vec3::ZERO; nb];
        let (mut iq, mut iv) = (0usize, 0usize);
        let quat = |q: &[f64], name: &str| -> Result<Mat3> {
            let qq = Quaternion::new(q[0], q[1], q[2], q[3]);
            let n = qq.norm();
            if n.is_nan() || n <= 0.0 {
                return Err(invalid(format!("joint `{name}`: zero quaternion in qpos")));
            }
            Ok(qq.normalized().to_matrix())
        };
        for j in 0..nb {
            let jt = &self.joints[j];
            let (xi, ri, ci, vi, wi) = match jt.parent {
                Link::World => (Vec3::ZERO, Mat3::IDENTITY, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO),
                Link::Body(p) => (x[p], rot[p], c[p], vc[p], w[p]),
            };
            let s = self.bodies[j].com;
            // velocity of a point y moving with the parent
            let v_at = |y: Vec3| vi + wi.cross(y - ci);
            let anchor = xi + ri * jt.anchor_parent;
            let q_ref = jt.reference_rotation;
            let (rj, xj, wj, vcj);
            match jt.kind {
                JointKind::Hinge { axis } => {
                    rj = ri * q_ref * so3::exp(axis * qpos[iq]);
                    xj = anchor - rj * jt.anchor_child;
                    wj = wi + rj * axis * qvel[iv];
                    vcj = v_at(anchor) + wj.cross(xj + rj * s - anchor);
                }
                JointKind::Universal { first, second } => {
                    rj = ri * q_ref * so3::exp(first * qpos[iq]) * so3::exp(second * qpos[iq + 1]);
                    xj = anchor - rj * jt.anchor_child;
                    wj = wi + ri * (q_ref * first) * qvel[iv] + rj * second * qvel[iv + 1];
                    vcj = v_at(anchor) + wj.cross(xj + rj * s - anchor);
                }
                JointKind::Slide { axis } => {
                    rj = ri * q_ref;
                    xj = anchor - rj * jt.anchor_child + rj * axis * qpos[iq];
                    wj = wi;
                    vcj = v_at(xj + rj * s) + rj * axis * qvel[iv];
                }
                JointKind::Ball => {
                    rj = ri * q_ref * quat(&qpos[iq..iq + 4], &jt.name)?;
                    xj = anchor - rj * jt.anchor_child;
                    wj = wi + rj * Vec3::new(qvel[iv], qvel[iv + 1], qvel[iv + 2]);
                    vcj = v_at(anchor) + wj.cross(xj + rj * s - anchor);
                }
                JointKind::Weld => {
                    rj = ri * q_ref;
                    xj = anchor - rj * jt.anchor_child;
                    wj = wi;
                    vcj = v_at(xj + rj * s);
                }
                JointKind::Free => {
                    rj = ri * quat(&qpos[iq + 3..iq + 7], &jt.name)?;
                    xj = xi + ri * Vec3::new(qpos[iq], qpos[iq + 1], qpos[iq + 2]);
                    wj = wi + rj * Vec3::new(qvel[iv + 3], qvel[iv + 4], qvel[iv + 5]);
                    let v_origin = v_at(xj) + ri * Vec3::new(qvel[iv], qvel[iv + 1], qvel[iv + 2]);
                    vcj = v_origin + wj.cross(rj * s);
                }
            }
            iq += jt.kind.nq();
            iv += jt.kind.nv();
            x[j] = xj;
            rot[j] = rj;
            w[j] = wj;
            vc[j] = vcj;
            c[j] = xj + rj * s;
        }
        let mut state = MultibodyState {
            t: 0.0,
            c,
            p: vec![Vec3::ZERO; nb],
            rotation: rot,
            pi: vec![Vec3::ZERO; nb],
        };
        for j in 0..nb {
            let inertia = self.inertia(j)?;
            state.p[j] = vc[j] * self.bodies[j].mass;
            state.pi[j] = inertia.apply(state.rotation[j].tr_mul_vec(w[j]));
        }
        // Hinge armature: `Π = 𝕁 W`, each armatured hinge adds `a q̇ n_c` to its child's
        // momentum and `−a q̇ n_p` to its parent's (docs/theory/multibody.md §7).
        for k in 0..nb {
            let a = self.joints[k].armature;
            if a == 0.0 || !matches!(self.joints[k].kind, JointKind::Hinge { .. }) {
                continue;
            }
            let joint = &self.joints[k];
            let (u_child, u_parent) = joint.axes();
            let parent = match joint.parent {
                Link::World => None,
                Link::Body(p) => Some(p),
            };
            let body_rate = |i: usize| state.rotation[i].tr_mul_vec(w[i]);
            let wp = parent.map_or(Vec3::ZERO, body_rate);
            let rate = u_child.dot(body_rate(joint.child)) - u_parent.dot(wp);
            state.pi[joint.child] += u_child * (a * rate);
            if let Some(p) = parent {
                state.pi[p] -= u_parent * (a * rate);
            }
        }
        Ok(state)
    }
}
