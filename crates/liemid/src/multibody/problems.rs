//! Multibody test problems built in code. Each returns a [`Model`], the type the file
//! loaders produce, so problems and files share one path into [`super::MultibodySystem`].
//!
//! Reference: docs/theory/multibody.md §5 (the test chain); E. Hairer, C. Lubich, G. Wanner,
//! *Geometric Numerical Integration*, VII.1.

use crate::linalg::{Mat3, Vec3};
use crate::so3::{self, Quaternion};

use super::model::{Body, Joint, JointKind, Link, Model};

/// The inertia about the centre of a solid cylinder (slender rod) of mass `m`, length `l`
/// and radius `r` along the body axis `axis` (0, 1, 2): `m(3r² + l²)/12` across, `m r²/2`
/// along.
#[must_use]
pub fn rod_inertia(m: f64, l: f64, r: f64, axis: usize) -> Mat3 {
    let across = m * (3.0 * r * r + l * l) / 12.0;
    let mut d = [across; 3];
    d[axis] = 0.5 * m * r * r;
    Mat3::from_diagonal(Vec3::from_array(d))
}

/// The inertia about the centre of a solid box of mass `m` and edges `(a, b, c)` along the
/// body axes.
#[must_use]
pub fn box_inertia(m: f64, [a, b, c]: [f64; 3]) -> Mat3 {
    let k = m / 12.0;
    Mat3::from_diagonal(Vec3::new(k * (b * b + c * c), k * (a * a + c * c), k * (a * a + b * b)))
}

/// `Q D Qᵀ`: a principal tensor `d` turned into a full one by the rotation `Q`.
#[must_use]
pub fn rotated(d: Mat3, q: Mat3) -> Mat3 {
    let m = q * d * q.transpose();
    (m + m.transpose()) * 0.5
}

fn body(name: &str, mass: f64, com: Vec3, inertia: Mat3, position: Vec3, rotation: Mat3) -> Body {
    Body {
        name: name.into(),
        mass,
        com,
        inertia,
        position,
        rotation,
    }
}

#[allow(clippy::too_many_arguments)]
fn joint(
    name: &str,
    kind: JointKind,
    parent: Link,
    child: usize,
    anchor_parent: Vec3,
    anchor_child: Vec3,
    q: Mat3,
) -> Joint {
    Joint {
        name: name.into(),
        kind,
        parent,
        child,
        anchor_parent,
        anchor_child,
        reference_rotation: q,
        range: None,
        stiffness: 0.0,
        spring_ref: 0.0,
        damping: 0.0,
        armature: 0.0,
        frictionloss: 0.0,
        actuator_force_range: None,
    }
}

fn quat(axis_angle: Vec3) -> [f64; 4] {
    let q = Quaternion::from_matrix(&so3::exp(axis_angle));
    [q.w, q.x, q.y, q.z]
}

const Y: Vec3 = Vec3::new(0.0, 1.0, 0.0);
const X: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const G: Vec3 = Vec3::new(0.0, 0.0, -9.81);

/// A double pendulum: two slender rods of 1 m and 1 kg (radius 2 cm) hanging along `−z`,
/// hinged about `y` at the origin and at the end of the first rod, released from rest at
/// angles (1.0, 0.5) rad under `g = 9.81`.
#[must_use]
pub fn double_pendulum() -> Model {
    let inertia = rod_inertia(1.0, 1.0, 0.02, 2);
    let com = Vec3::new(0.0, 0.0, -0.5);
    let down = Vec3::new(0.0, 0.0, -1.0);
    Model {
        name: "double-pendulum".into(),
        bodies: vec![
            body("link1", 1.0, com, inertia, Vec3::ZERO, Mat3::IDENTITY),
            body("link2", 1.0, com, inertia, down, Mat3::IDENTITY),
        ],
        joints: vec![
            joint(
                "hinge1",
                JointKind::Hinge { axis: Y },
                Link::World,
                0,
                Vec3::ZERO,
                Vec3::ZERO,
                Mat3::IDENTITY,
            ),
            joint(
                "hinge2",
                JointKind::Hinge { axis: Y },
                Link::Body(0),
                1,
                down,
                Vec3::ZERO,
                Mat3::IDENTITY,
            ),
        ],
        gravity: G,
        timestep: Some(1e-3),
        qpos: Some(vec![1.0, 0.5]),
        qvel: None,
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}

/// A chain of `n` links on ball joints hanging from the world at the origin: links of
/// 0.1 m and 0.1 kg, the centre of mass off the link axis at `(0.01, 0.005, −0.05)` and a
/// full inertia tensor (a 2x3x10 cm box turned by `exp((0.1, 0.2, 0.3))`), released from
/// rest with the first joint tilted 0.4 rad about `x` and every other one 0.05 rad about
/// `x` or `y` in turn. `chain(10)` is `chain-10`, `chain(1000)` is `chain-1000`.
#[must_use]
pub fn chain(n: usize) -> Model {
    let l = 0.1;
    let m = 0.1;
    let inertia = rotated(box_inertia(m, [0.02, 0.03, 0.1]), so3::exp(Vec3::new(0.1, 0.2, 0.3)));
    let com = Vec3::new(0.01, 0.005, -0.05);
    let end = Vec3::new(0.0, 0.0, -l);
    let mut bodies = Vec::with_capacity(n);
    let mut joints = Vec::with_capacity(n);
    let mut qpos = Vec::with_capacity(4 * n);
    for k in 0..n {
        bodies.push(body(
            &format!("link{k}"),
            m,
            com,
            inertia,
            end * k as f64,
            Mat3::IDENTITY,
        ));
        let (parent, anchor) = if k == 0 {
            (Link::World, Vec3::ZERO)
        } else {
            (Link::Body(k - 1), end)
        };
        joints.push(joint(
            &format!("ball{k}"),
            JointKind::Ball,
            parent,
            k,
            anchor,
            Vec3::ZERO,
            Mat3::IDENTITY,
        ));
        let tilt = if k == 0 {
            Vec3::new(0.4, 0.0, 0.0)
        } else if k % 2 == 0 {
            Vec3::new(0.05, 0.0, 0.0)
        } else {
            Vec3::new(0.0, 0.05, 0.0)
        };
        qpos.extend(quat(tilt));
    }
    Model {
        name: format!("chain-{n}"),
        bodies,
        joints,
        gravity: G,
        timestep: Some(1e-4),
        qpos: Some(qpos),
        qvel: None,
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}

/// A spacecraft: a free hub (200 kg, 1 x 1 x 1.2 m box) spinning at 20 rad/s about
/// `(1, 0.5, 0.3)/|·|` in its frame (off its principal axes), with two 10 kg panels
/// (1 x 2 x 0.02 m) hinged about `x` at the middle of its `±y` faces, on springs of
/// 200 N m/rad; no gravity, no external load, so the total linear and angular momentum
/// are constant.
#[must_use]
pub fn spacecraft() -> Model {
    let hub = box_inertia(200.0, [1.0, 1.0, 1.2]);
    let panel = box_inertia(10.0, [1.0, 2.0, 0.02]);
    let w = Vec3::new(1.0, 0.5, 0.3);
    let w = w * (20.0 / w.norm());
    let mut joints = vec![
        joint(
            "hub",
            JointKind::Free,
            Link::World,
            0,
            Vec3::ZERO,
            Vec3::ZERO,
            Mat3::IDENTITY,
        ),
        joint(
            "hinge+",
            JointKind::Hinge { axis: X },
            Link::Body(0),
            1,
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::ZERO,
            Mat3::IDENTITY,
        ),
        joint(
            "hinge-",
            JointKind::Hinge { axis: X },
            Link::Body(0),
            2,
            Vec3::new(0.0, -0.5, 0.0),
            Vec3::ZERO,
            Mat3::IDENTITY,
        ),
    ];
    joints[1].stiffness = 200.0;
    joints[2].stiffness = 200.0;
    Model {
        name: "spacecraft".into(),
        bodies: vec![
            body("hub", 200.0, Vec3::ZERO, hub, Vec3::ZERO, Mat3::IDENTITY),
            body(
                "panel+",
                10.0,
                Vec3::new(0.0, 1.0, 0.0),
                panel,
                Vec3::new(0.0, 0.5, 0.0),
                Mat3::IDENTITY,
            ),
            body(
                "panel-",
                10.0,
                Vec3::new(0.0, -1.0, 0.0),
                panel,
                Vec3::new(0.0, -0.5, 0.0),
                Mat3::IDENTITY,
            ),
        ],
        joints,
        gravity: Vec3::ZERO,
        timestep: Some(1e-3),
        qpos: Some(vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        qvel: Some(vec![0.0, 0.0, 0.0, w.x, w.y, w.z, 0.0, 0.0]),
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}

/// A planar four-bar linkage of four hinges about `y` (the redundant joint set: 20 rows on
/// 18 coordinates, mobility one, so 3 loop rows are dependent and the solver's
/// pseudo-inverse takes the minimum-norm multipliers). Ground pivots at `(0, 0, 0)` and
/// `(1, 0, 0)`; crank 0.4 m at 60°, coupler 1.0 m, rocker 0.8 m, each a 1 kg rod of radius
/// 2 cm along its frame's `x`; released from rest under gravity. The last joint closes
/// the loop.
#[must_use]
pub fn closed_loop() -> Model {
    let a = Vec3::ZERO;
    let d = Vec3::new(1.0, 0.0, 0.0);
    let (lc, lk, lr) = (0.4, 1.0, 0.8);
    let phi = 60f64.to_radians();
    let b = a + Vec3::new(phi.cos(), 0.0, phi.sin()) * lc;
    // C: |C − B| = lk, |C − D| = lr, above the line BD.
    let bd = d - b;
    let dist = bd.norm();
    let along = (lk * lk - lr * lr + dist * dist) / (2.0 * dist);
    let h = (lk * lk - along * along).sqrt();
    let e = bd * (1.0 / dist);
    let normal = Vec3::new(-e.z, 0.0, e.x);
    let normal = if normal.z < 0.0 { -normal } else { normal };
    let c = b + e * along + normal * h;
    let frame = |from: Vec3, to: Vec3| {
        let v = to - from;
        so3::exp(Y * (-v.z).atan2(v.x))
    };
    let (rc, rk, rr) = (frame(a, b), frame(b, c), frame(c, d));
    let rod = |l: f64| rod_inertia(1.0, l, 0.02, 0);
    let half = |l: f64| Vec3::new(0.5 * l, 0.0, 0.0);
    let hinge = JointKind::Hinge { axis: Y };
    Model {
        name: "four-bar".into(),
        bodies: vec![
            body("crank", 1.0, half(lc), rod(lc), a, rc),
            body("coupler", 1.0, half(lk), rod(lk), b, rk),
            body("rocker", 1.0, half(lr), rod(lr), c, rr),
        ],
        joints: vec![
            joint("A", hinge, Link::World, 0, a, Vec3::ZERO, rc),
            joint(
                "B",
                hinge,
                Link::Body(0),
                1,
                Vec3::new(lc, 0.0, 0.0),
                Vec3::ZERO,
                rc.transpose() * rk,
            ),
            joint(
                "C",
                hinge,
                Link::Body(1),
                2,
                Vec3::new(lk, 0.0, 0.0),
                Vec3::ZERO,
                rk.transpose() * rr,
            ),
            joint("D", hinge, Link::World, 2, d, Vec3::new(lr, 0.0, 0.0), rr),
        ],
        gravity: G,
        timestep: Some(1e-3),
        qpos: None,
        qvel: None,
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}

/// The test chain (docs/theory/multibody.md §5): a hinge about `y` at the origin, a
/// hinge about `x` and a ball joint, links of 0.5 m and 1, 0.8, 0.6 kg along `−z` with the
/// centres of mass off the link axis and full inertia tensors, released from rest at the
/// hinge angles (0.5, −0.3) rad and the ball turned 0.3 rad about `(1, 1, 0)/√2`.
#[must_use]
pub fn test_chain() -> Model {
    let l = 0.5;
    let end = Vec3::new(0.0, 0.0, -l);
    let masses = [1.0, 0.8, 0.6];
    let coms = [
        Vec3::new(0.03, -0.02, -0.25),
        Vec3::new(-0.02, 0.04, -0.22),
        Vec3::new(0.05, 0.01, -0.27),
    ];
    let turns = [
        Vec3::new(0.2, -0.1, 0.4),
        Vec3::new(-0.3, 0.2, 0.1),
        Vec3::new(0.1, 0.5, -0.2),
    ];
    let bodies = (0..3)
        .map(|k| {
            let i = rotated(box_inertia(masses[k], [0.06, 0.08, l]), so3::exp(turns[k]));
            body(
                &format!("link{k}"),
                masses[k],
                coms[k],
                i,
                end * k as f64,
                Mat3::IDENTITY,
            )
        })
        .collect();
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let mut qpos = vec![0.5, -0.3];
    qpos.extend(quat(Vec3::new(s, s, 0.0) * 0.3));
    Model {
        name: "test-chain".into(),
        bodies,
        joints: vec![
            joint(
                "hinge-y",
                JointKind::Hinge { axis: Y },
                Link::World,
                0,
                Vec3::ZERO,
                Vec3::ZERO,
                Mat3::IDENTITY,
            ),
            joint(
                "hinge-x",
                JointKind::Hinge { axis: X },
                Link::Body(0),
                1,
                end,
                Vec3::ZERO,
                Mat3::IDENTITY,
            ),
            joint(
                "ball",
                JointKind::Ball,
                Link::Body(1),
                2,
                end,
                Vec3::ZERO,
                Mat3::IDENTITY,
            ),
        ],
        gravity: G,
        timestep: Some(1e-4),
        qpos: Some(qpos),
        qvel: None,
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}

/// The fast Lagrangian top of [`crate::rigid::problems::fast_top`] as one body on a ball joint at
/// a fixed point: the aluminium block with its frame at the pivot, centre of mass
/// `(0, 0, 0.12)`, tilted 0.05 rad about `x`, spinning at `313π` rad/s about its axis.
/// For this model the step is a maximal-coordinate version of LIEMID\[EA\].
#[must_use]
pub fn fast_top_ball() -> Model {
    let top = crate::rigid::HeavyTop::lagrangian_block();
    let s = top.center_of_mass;
    let about_pivot = *top.inertia.matrix();
    let shift = Mat3::IDENTITY * s.norm_squared() - Mat3::outer(s, s);
    let inertia = about_pivot - shift * top.mass;
    let spin = 313.0 * std::f64::consts::PI;
    let mut qpos = quat(Vec3::new(0.05, 0.0, 0.0)).to_vec();
    qpos.truncate(4);
    Model {
        name: "fast-top-ball".into(),
        bodies: vec![body("block", top.mass, s, inertia, Vec3::ZERO, Mat3::IDENTITY)],
        joints: vec![joint(
            "pivot",
            JointKind::Ball,
            Link::World,
            0,
            Vec3::ZERO,
            Vec3::ZERO,
            Mat3::IDENTITY,
        )],
        gravity: top.gravity,
        timestep: Some(1e-4),
        qpos: Some(qpos),
        qvel: Some(vec![0.0, 0.0, spin]),
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}
