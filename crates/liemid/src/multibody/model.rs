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
    /// Viscous damping (N m s/rad or N s/m), hinge and slide only.
    pub damping: f64,
    /// MJCF `armature` (kg m² or kg); 0 when absent.
    pub armature: f64,
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
}
