//! The joint-space reference dynamics (`multibody::joint_space`): ABA against the closed
//! form of the compound double pendulum, ABA against CRBA + RNEA and the kinetic energy,
//! the kinematics against the joint constraints and finite differences, RK4's energy and
//! momentum errors falling as h⁴, the reference pose, and errors instead of panics.

use liemid::multibody::joint_space::JointSpaceModel;
use liemid::multibody::model::{Body, Joint, JointKind, Link, Model};
use liemid::random::Rng;
use liemid::{so3, Mat3, Vec3};

/// Counts this thread's allocations (tests run on separate threads).
use crate::thread_counting;
use thread_counting::allocations;

/// A physical full inertia tensor: principal moments obeying the triangle inequality,
/// turned by a random rotation.
fn full_inertia(rng: &mut Rng, scale: f64) -> Mat3 {
    let a = 1.0 + rng.uniform();
    let b = 1.0 + rng.uniform();
    let c = 0.5 * (a + b) * (0.6 + 0.8 * rng.uniform()); // |a − b| < c < a + b
    let r = rng.rotation();
    let m = r * Mat3::from_diagonal(Vec3::new(a, b, c) * scale) * r.transpose();
    // Exactly symmetric.
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

/// A joint between `parent` and `child` at the world point `at` of the reference
/// configuration: anchors and reference rotation from the bodies' reference poses.
fn joint(bodies: &[Body], name: &str, kind: JointKind, parent: Link, child: usize, at: Vec3) -> Joint {
    let (xp, rp) = match parent {
        Link::World => (Vec3::ZERO, Mat3::IDENTITY),
        Link::Body(p) => (bodies[p].position, bodies[p].rotation),
    };
    let c = &bodies[child];
    Joint {
        name: name.into(),
        kind,
        parent,
        child,
        anchor_parent: rp.tr_mul_vec(at - xp),
        anchor_child: c.rotation.tr_mul_vec(at - c.position),
        reference_rotation: rp.transpose() * c.rotation,
        range: None,
        stiffness: 0.0,
        spring_ref: 0.0,
        damping: 0.0,
        armature: 0.0,
        frictionloss: 0.0,
        actuator_force_range: None,
    }
}

fn model(name: &str, bodies: Vec<Body>, joints: Vec<Joint>, gravity: Vec3) -> Model {
    Model {
        name: name.into(),
        bodies,
        joints,
        gravity,
        timestep: None,
        qpos: None,
        qvel: None,
        actuators: Vec::new(),
        ctrl: None,
        collision: Default::default(),
    }
}

const G: f64 = 9.81;

/// Two uniform rods (mass m_k, length L_k, com at the middle, inertia m L²/12 about the
/// com across the rod) hanging along −z from hinges about y: rod 1 from the world origin,
/// rod 2 from rod 1's end.
fn double_pendulum(m1: f64, l1: f64, m2: f64, l2: f64) -> Model {
    let rod = |m: f64, l: f64| {
        let t = m * l * l / 12.0;
        Mat3::from_diagonal(Vec3::new(t, t, 1e-3 * t))
    };
    let bodies = vec![
        body(
            "rod1",
            m1,
            Vec3::new(0.0, 0.0, -0.5 * l1),
            rod(m1, l1),
            Vec3::ZERO,
            Mat3::IDENTITY,
        ),
        body(
            "rod2",
            m2,
            Vec3::new(0.0, 0.0, -0.5 * l2),
            rod(m2, l2),
            Vec3::new(0.0, 0.0, -l1),
            Mat3::IDENTITY,
        ),
    ];
    let y = JointKind::Hinge {
        axis: Vec3::new(0.0, 1.0, 0.0),
    };
    let joints = vec![
        joint(&bodies, "h1", y, Link::World, 0, Vec3::ZERO),
        joint(&bodies, "h2", y, Link::Body(0), 1, Vec3::new(0.0, 0.0, -l1)),
    ];
    model("double pendulum", bodies, joints, Vec3::new(0.0, 0.0, -G))
}

/// The compound double pendulum's Lagrange equations. With absolute angles φ₁ = θ₁,
/// φ₂ = θ₁ + θ₂ (θ the hinge angles, rotation about +y turns −z towards −x), the rods'
/// directions are (−sin φ, 0, −cos φ), and
///   T = ½ a φ̇₁² + ½ b φ̇₂² + c cos(φ₁ − φ₂) φ̇₁ φ̇₂,  V = −g (e₁ cos φ₁ + e₂ cos φ₂)
/// with a = m₁L₁²/3 + m₂L₁², b = m₂L₂²/3, c = m₂L₁L₂/2, e₁ = (m₁/2 + m₂) L₁, e₂ = m₂L₂/2:
///   a φ̈₁ + c cos Δ φ̈₂ + c sin Δ φ̇₂² + g e₁ sin φ₁ = Q₁
///   c cos Δ φ̈₁ + b φ̈₂ − c sin Δ φ̇₁² + g e₂ sin φ₂ = Q₂,   Δ = φ₁ − φ₂,
/// the generalised forces Q₁ = τ₁ − τ₂, Q₂ = τ₂ from the hinge torques (δW = τ·δθ).
/// Returns the hinge accelerations (θ̈₁, θ̈₂) = (φ̈₁, φ̈₂ − φ̈₁).
fn double_pendulum_closed_form(
    (m1, l1, m2, l2): (f64, f64, f64, f64),
    th: [f64; 2],
    thd: [f64; 2],
    tau: [f64; 2],
) -> [f64; 2] {
    let (p1, p2) = (th[0], th[0] + th[1]);
    let (w1, w2) = (thd[0], thd[0] + thd[1]);
    let a = m1 * l1 * l1 / 3.0 + m2 * l1 * l1;
    let b = m2 * l2 * l2 / 3.0;
    let c = 0.5 * m2 * l1 * l2;
    let e1 = (0.5 * m1 + m2) * l1;
    let e2 = 0.5 * m2 * l2;
    let d = p1 - p2;
    let r1 = tau[0] - tau[1] - c * d.sin() * w2 * w2 - G * e1 * p1.sin();
    let r2 = tau[1] + c * d.sin() * w1 * w1 - G * e2 * p2.sin();
    let (m11, m12, m22) = (a, c * d.cos(), b);
    let det = m11 * m22 - m12 * m12;
    let f1 = (m22 * r1 - m12 * r2) / det;
    let f2 = (m11 * r2 - m12 * r1) / det;
    [f1, f2 - f1]
}

#[test]
fn aba_matches_the_compound_double_pendulum_closed_form() {
    let mut rng = Rng::new(11);
    let mut worst: f64 = 0.0;
    for case in 0..50 {
        let p = (
            0.5 + rng.uniform(),
            0.5 + rng.uniform(),
            0.5 + rng.uniform(),
            0.5 + rng.uniform(),
        );
        let mut js = JointSpaceModel::new(&double_pendulum(p.0, p.1, p.2, p.3)).unwrap();
        assert_eq!((js.nq(), js.nv()), (2, 2));
        let th = [6.0 * rng.uniform() - 3.0, 6.0 * rng.uniform() - 3.0];
        let thd = [4.0 * rng.normal(), 4.0 * rng.normal()];
        let tau = if case % 2 == 0 {
            [0.0, 0.0]
        } else {
            [rng.normal(), rng.normal()]
        };
        let mut qdd = [0.0; 2];
        js.aba(&th, &thd, &tau, &mut qdd).unwrap();
        let want = double_pendulum_closed_form(p, th, thd, tau);
        let scale = want[0].abs().max(want[1].abs());
        let err = (qdd[0] - want[0]).abs().max((qdd[1] - want[1]).abs()) / scale;
        worst = worst.max(err);
    }
    println!("double pendulum: worst relative difference ABA vs closed form {worst:.2e}");
    assert!(worst < 1e-12, "{worst:e}");
}

/// Hinge (world) – ball – slide, with random reference attitudes, off-axis centres of
/// mass, full inertia tensors; springs on the hinge and the slide, and optionally dampers
/// and armatures.
fn chain(rng: &mut Rng, dissipative: bool) -> Model {
    let mut bodies = Vec::new();
    let positions = [
        Vec3::new(0.1, -0.05, 0.2),
        Vec3::new(0.4, 0.1, -0.3),
        Vec3::new(0.7, -0.2, -0.6),
    ];
    for (k, x) in positions.iter().enumerate() {
        let com = Vec3::new(0.1 * rng.normal(), 0.1 * rng.normal(), 0.1 * rng.normal());
        let m = 0.5 + rng.uniform();
        let inertia = full_inertia(rng, 0.05 * m);
        bodies.push(body(&format!("b{k}"), m, com, inertia, *x, rng.rotation()));
    }
    let mut joints = vec![
        joint(
            &bodies,
            "hinge",
            JointKind::Hinge {
                axis: rng.unit_vector(),
            },
            Link::World,
            0,
            Vec3::new(0.0, 0.0, 0.25),
        ),
        joint(
            &bodies,
            "ball",
            JointKind::Ball,
            Link::Body(0),
            1,
            Vec3::new(0.3, 0.0, -0.1),
        ),
        joint(
            &bodies,
            "slide",
            JointKind::Slide {
                axis: rng.unit_vector(),
            },
            Link::Body(1),
            2,
            Vec3::new(0.6, 0.0, -0.5),
        ),
    ];
    joints[0].stiffness = 2.0;
    joints[0].spring_ref = 0.3;
    joints[2].stiffness = 40.0;
    joints[2].spring_ref = -0.05;
    if dissipative {
        joints[0].damping = 0.3;
        joints[2].damping = 0.7;
        joints[0].armature = 0.02;
        joints[2].armature = 0.1;
    }
    model("chain", bodies, joints, Vec3::new(0.0, 0.0, -G))
}

/// Two bodies on universal joints with random (oblique) axes, off-axis centres of mass, full
/// inertia tensors.
fn universal_chain(rng: &mut Rng) -> Model {
    let mut bodies = Vec::new();
    for (k, x) in [Vec3::new(0.0, 0.1, -0.3), Vec3::new(0.2, -0.1, -0.7)]
        .iter()
        .enumerate()
    {
        let com = Vec3::new(0.1 * rng.normal(), 0.1 * rng.normal(), 0.1 * rng.normal());
        let m = 0.5 + rng.uniform();
        let inertia = full_inertia(rng, 0.05 * m);
        bodies.push(body(&format!("u{k}"), m, com, inertia, *x, rng.rotation()));
    }
    let mut kinds = Vec::new();
    for _ in 0..2 {
        kinds.push(JointKind::Universal {
            first: rng.unit_vector(),
            second: rng.unit_vector(),
        });
    }
    let joints = vec![
        joint(&bodies, "u0", kinds[0], Link::World, 0, Vec3::new(0.0, 0.0, 0.1)),
        joint(&bodies, "u1", kinds[1], Link::Body(0), 1, Vec3::new(0.1, 0.0, -0.5)),
    ];
    model("universal", bodies, joints, Vec3::new(0.0, 0.0, -G))
}

/// A free-floating base with two hinged children (one of them with a weld-attached body).
fn floating_base(rng: &mut Rng, gravity: Vec3) -> Model {
    let mut bodies = Vec::new();
    for (k, x) in [
        Vec3::new(0.2, 0.3, 1.0),
        Vec3::new(0.5, 0.3, 1.1),
        Vec3::new(-0.1, 0.2, 0.9),
        Vec3::new(-0.3, 0.25, 0.8),
    ]
    .iter()
    .enumerate()
    {
        let com = Vec3::new(0.1 * rng.normal(), 0.1 * rng.normal(), 0.1 * rng.normal());
        let m = 0.5 + rng.uniform();
        let inertia = full_inertia(rng, 0.05 * m);
        bodies.push(body(&format!("f{k}"), m, com, inertia, *x, rng.rotation()));
    }
    let mut joints = vec![
        joint(&bodies, "free", JointKind::Free, Link::World, 0, bodies[0].position),
        joint(
            &bodies,
            "left",
            JointKind::Hinge {
                axis: rng.unit_vector(),
            },
            Link::Body(0),
            1,
            Vec3::new(0.35, 0.3, 1.05),
        ),
        joint(
            &bodies,
            "right",
            JointKind::Hinge {
                axis: rng.unit_vector(),
            },
            Link::Body(0),
            2,
            Vec3::new(0.05, 0.25, 0.95),
        ),
        joint(
            &bodies,
            "weld",
            JointKind::Weld,
            Link::Body(2),
            3,
            Vec3::new(-0.2, 0.2, 0.85),
        ),
    ];
    // The free joint's anchors are those of the child frame origin.
    joints[0].anchor_child = Vec3::ZERO;
    joints[1].stiffness = 1.5;
    joints[2].damping = 0.2;
    model("floating base", bodies, joints, gravity)
}

fn random_quat(rng: &mut Rng) -> [f64; 4] {
    let q = so3::Quaternion::new(rng.normal(), rng.normal(), rng.normal(), rng.normal()).normalized();
    [q.w, q.x, q.y, q.z]
}

/// A random state: hinge and slide coordinates in (−1.5, 1.5), quaternions Haar, free
/// positions near the reference; velocities standard normal.
fn random_state(rng: &mut Rng, m: &Model, js: &JointSpaceModel) -> (Vec<f64>, Vec<f64>) {
    let mut q = Vec::new();
    for (k, j) in m.joints.iter().enumerate() {
        match j.kind {
            JointKind::Hinge { .. } | JointKind::Slide { .. } => q.push(3.0 * rng.uniform() - 1.5),
            JointKind::Universal { .. } => q.extend([3.0 * rng.uniform() - 1.5, 3.0 * rng.uniform() - 1.5]),
            JointKind::Ball => q.extend(random_quat(rng)),
            JointKind::Free => {
                let x = m.bodies[j.child].position;
                q.extend([x.x + rng.normal(), x.y + rng.normal(), x.z + rng.normal()]);
                q.extend(random_quat(rng));
            }
            JointKind::Weld => {}
        }
        let _ = k;
    }
    assert_eq!(q.len(), js.nq());
    let v = (0..js.nv()).map(|_| rng.normal()).collect();
    (q, v)
}

fn matvec(m: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n).map(|i| (0..n).map(|j| m[i * n + j] * x[j]).sum()).collect()
}

/// `M(q) q̈ + bias(q, v) = τ` with `q̈` from ABA, `M` from CRBA and the bias from RNEA at
/// zero acceleration; RNEA inverts ABA; `M` is symmetric positive definite and is the
/// Hessian of the kinetic energy (`E(q, v) − E(q, 0) = ½ vᵀ M v`).
#[test]
fn aba_agrees_with_crba_rnea_and_the_kinetic_energy() {
    let mut rng = Rng::new(5);
    let models = [
        chain(&mut rng, true),
        floating_base(&mut rng, Vec3::new(0.0, 0.0, -G)),
        universal_chain(&mut rng),
    ];
    for m in &models {
        let mut js = JointSpaceModel::new(m).unwrap();
        let nv = js.nv();
        let (mut worst_eq, mut worst_inv, mut worst_ke): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for _ in 0..40 {
            let (q, v) = random_state(&mut rng, m, &js);
            let tau: Vec<f64> = (0..nv).map(|_| rng.normal()).collect();
            let mut qdd = vec![0.0; nv];
            js.aba(&q, &v, &tau, &mut qdd).unwrap();
            let mut mm = vec![0.0; nv * nv];
            js.mass_matrix(&q, &mut mm).unwrap();
            let mut bias = vec![0.0; nv];
            js.inverse_dynamics(&q, &v, &vec![0.0; nv], &mut bias).unwrap();
            let mq = matvec(&mm, &qdd);
            let scale = tau.iter().chain(&bias).chain(&mq).fold(1.0f64, |a, x| a.max(x.abs()));
            for i in 0..nv {
                worst_eq = worst_eq.max((mq[i] + bias[i] - tau[i]).abs() / scale);
            }
            let mut back = vec![0.0; nv];
            js.inverse_dynamics(&q, &v, &qdd, &mut back).unwrap();
            for i in 0..nv {
                worst_inv = worst_inv.max((back[i] - tau[i]).abs() / scale);
            }
            // Symmetric positive definite (Cholesky).
            for i in 0..nv {
                for j in 0..nv {
                    assert_eq!(mm[i * nv + j], mm[j * nv + i]);
                }
            }
            let mut l = mm.clone();
            for k in 0..nv {
                for p in 0..k {
                    l[k * nv + k] -= l[k * nv + p] * l[k * nv + p];
                }
                assert!(l[k * nv + k] > 0.0, "M not positive definite");
                l[k * nv + k] = l[k * nv + k].sqrt();
                for i in k + 1..nv {
                    for p in 0..k {
                        l[i * nv + k] -= l[i * nv + p] * l[k * nv + p];
                    }
                    l[i * nv + k] /= l[k * nv + k];
                }
            }
            let ke = js.energy(&q, &v).unwrap() - js.energy(&q, &vec![0.0; nv]).unwrap();
            let quad = 0.5 * v.iter().zip(matvec(&mm, &v)).map(|(a, b)| a * b).sum::<f64>();
            worst_ke = worst_ke.max((ke - quad).abs() / quad);
        }
        println!(
            "{}: |M qdd + bias - tau| {worst_eq:.2e}, |RNEA(ABA) - tau| {worst_inv:.2e}, \
             |T - v'Mv/2|/T {worst_ke:.2e}",
            m.name
        );
        assert!(worst_eq < 1e-12, "{worst_eq:e}");
        assert!(worst_inv < 1e-12, "{worst_inv:e}");
        assert!(worst_ke < 1e-12, "{worst_ke:e}");
    }
}

/// The kinematics obeys the joints' constraints of the maximal-coordinate method (anchor
/// points coincide for hinge, ball and weld, hinge axes aligned, slide attitude locked and
/// offset along the axis), and the bodies' velocities are the time derivatives of the
/// kinematics along `q̇ = Q(q) v` (central differences).
#[test]
fn kinematics_obeys_the_joints_and_velocities_differentiate_it() {
    let mut rng = Rng::new(23);
    let models = [
        chain(&mut rng, false),
        floating_base(&mut rng, Vec3::new(0.0, 0.0, -G)),
        universal_chain(&mut rng),
    ];
    for m in &models {
        let mut js = JointSpaceModel::new(m).unwrap();
        for _ in 0..20 {
            let (q, v) = random_state(&mut rng, m, &js);
            let poses = js.forward_kinematics(&q).unwrap();
            let pose = |l: Link| match l {
                Link::World => (Vec3::ZERO, Mat3::IDENTITY),
                Link::Body(p) => poses[p],
            };
            for j in &m.joints {
                let (xp, rp) = pose(j.parent);
                let (xc, rc) = poses[j.child];
                let gap = (xp + rp * j.anchor_parent - xc - rc * j.anchor_child).max_abs();
                let rel = rp.transpose() * rc;
                match j.kind {
                    JointKind::Ball => assert!(gap < 1e-14, "{}: {gap:e}", j.name),
                    JointKind::Hinge { axis } => {
                        assert!(gap < 1e-14, "{}: {gap:e}", j.name);
                        let a = (j.reference_rotation * axis - rel * axis).max_abs();
                        assert!(a < 1e-14, "{}: {a:e}", j.name);
                    }
                    JointKind::Weld => {
                        assert!(gap < 1e-14, "{}: {gap:e}", j.name);
                        assert!((rel - j.reference_rotation).max_abs() < 1e-14);
                    }
                    JointKind::Slide { axis } => {
                        assert!((rel - j.reference_rotation).max_abs() < 1e-14);
                        // The offset of the anchor points is along the axis, by q.
                        let d = rp.tr_mul_vec(xc + rc * j.anchor_child - xp - rp * j.anchor_parent);
                        let along = j.reference_rotation * axis;
                        assert!((d - along * d.dot(along)).max_abs() < 1e-14);
                    }
                    JointKind::Universal { first, second } => {
                        // The anchor is shared and (Q a)·(rel b) = a·b.
                        assert!(gap < 1e-14, "{}: {gap:e}", j.name);
                        let dot = (j.reference_rotation * first).dot(rel * second) - first.dot(second);
                        assert!(dot.abs() < 1e-14, "{}: {dot:e}", j.name);
                    }
                    JointKind::Free => {}
                }
            }
            // Velocities against central differences of the kinematics.
            let d = 1e-6;
            let mut qd = vec![0.0; js.nq()];
            js.qdot(&q, &v, &mut qd).unwrap();
            let shift = |s: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(a, b)| a + s * b).collect() };
            let states = js.com_states(&q, &v).unwrap();
            let plus = js.forward_kinematics(&shift(d)).unwrap();
            let minus = js.forward_kinematics(&shift(-d)).unwrap();
            for (i, b) in m.bodies.iter().enumerate() {
                let cp = plus[i].0 + plus[i].1 * b.com;
                let cm = minus[i].0 + minus[i].1 * b.com;
                let vc = (cp - cm) * (0.5 / d);
                let om = so3::log(&(plus[i].1 * minus[i].1.transpose())) * (0.5 / d);
                assert!(
                    (vc - states[i].1).max_abs() < 1e-7,
                    "{} {:?} {:?}",
                    b.name,
                    vc,
                    states[i].1
                );
                assert!(
                    (om - states[i].2).max_abs() < 1e-7,
                    "{} {:?} {:?}",
                    b.name,
                    om,
                    states[i].2
                );
            }
        }
    }
}

/// The largest `|E(t) − E(0)| / |E(0)|` over `t ≤ t_end` with RK4 at step `h`.
fn rk4_energy_error(js: &mut JointSpaceModel, q0: &[f64], v0: &[f64], h: f64, t_end: f64) -> f64 {
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    let e0 = js.energy(&q, &v).unwrap();
    let n = (t_end / h).round() as usize;
    let mut worst: f64 = 0.0;
    for _ in 0..n {
        js.rk4_step(&mut q, &mut v, h).unwrap();
        worst = worst.max((js.energy(&q, &v).unwrap() - e0).abs() / e0.abs());
    }
    worst
}

/// Without dampers, RK4's energy error falls as h⁴: ABA is the exact dynamics of
/// `energy`, with the quaternion kinematics of the ball joint.
#[test]
fn rk4_energy_error_is_fourth_order() {
    let mut rng = Rng::new(7);
    let m = chain(&mut rng, false);
    let mut js = JointSpaceModel::new(&m).unwrap();
    let mut q = js.qpos0().to_vec();
    q[0] = 0.4;
    q[1..5].copy_from_slice(&random_quat(&mut rng));
    q[5] = 0.1;
    let v = vec![1.0, -2.0, 1.5, 2.5, 0.5];
    let hs = [1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0, 1.0 / 800.0];
    let errs: Vec<f64> = hs.iter().map(|&h| rk4_energy_error(&mut js, &q, &v, h, 1.0)).collect();
    println!(
        "chain RK4 energy errors (t <= 1) at h = 1/100 .. 1/800: {:?}",
        errs.iter().map(|e| format!("{e:.3e}")).collect::<Vec<_>>()
    );
    for w in errs.windows(2) {
        let order = (w[0] / w[1]).log2();
        println!("  observed order {order:.3}");
        assert!((order - 4.0).abs() < 0.2, "order {order}");
    }
    // The floating base under gravity, dampers off: free joint and hinges.
    let mut fb = floating_base(&mut rng, Vec3::new(0.0, 0.0, -G));
    fb.joints[2].damping = 0.0;
    let mut jf = JointSpaceModel::new(&fb).unwrap();
    let qf = jf.qpos0().to_vec();
    let vf = vec![0.2, -0.1, 0.3, 3.0, -5.0, 4.0, 2.0, -3.0];
    let errs: Vec<f64> = hs
        .iter()
        .map(|&h| rk4_energy_error(&mut jf, &qf, &vf, h, 1.0))
        .collect();
    println!(
        "floating base RK4 energy errors (t <= 1) at h = 1/100 .. 1/800: {:?}",
        errs.iter().map(|e| format!("{e:.3e}")).collect::<Vec<_>>()
    );
    for w in errs.windows(2) {
        let order = (w[0] / w[1]).log2();
        println!("  observed order {order:.3}");
        assert!((order - 4.0).abs() < 0.2, "order {order}");
    }
    // With the dampers on, the energy only falls.
    let md = chain(&mut Rng::new(7), true);
    let mut jd = JointSpaceModel::new(&md).unwrap();
    let (mut qq, mut vv) = (q.clone(), v.clone());
    let mut e = jd.energy(&qq, &vv).unwrap();
    for _ in 0..200 {
        jd.rk4_step(&mut qq, &mut vv, 1.0 / 400.0).unwrap();
        let e1 = jd.energy(&qq, &vv).unwrap();
        assert!(e1 < e, "{e1} >= {e}");
        e = e1;
    }
}

/// The worst relative momentum error `max(|L − L₀|, |p − p₀|) / |L₀|` over `t ≤ 1` with
/// RK4 at step `h`.
fn rk4_momentum_error(js: &mut JointSpaceModel, q0: &[f64], v0: &[f64], h: f64) -> f64 {
    let (p0, l0) = js.momentum(q0, v0).unwrap();
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    let mut worst: f64 = 0.0;
    for _ in 0..(1.0 / h).round() as usize {
        js.rk4_step(&mut q, &mut v, h).unwrap();
        let (p, l) = js.momentum(&q, &v).unwrap();
        worst = worst.max((l - l0).norm() / l0.norm()).max((p - p0).norm() / l0.norm());
    }
    worst
}

/// Without gravity and without a joint to the world, the linear and angular momentum
/// (about the world origin) are invariants of the exact flow; RK4 keeps them to O(h⁴).
/// A single free body (off-origin centre of mass, full inertia: the free joint's
/// velocity-product term), and the floating base with its hinged children (internal
/// springs and dampers keep the momenta too).
#[test]
fn free_systems_keep_their_momenta_to_fourth_order() {
    let mut rng = Rng::new(3);
    let x = Vec3::new(0.3, -0.2, 0.5);
    let r = rng.rotation();
    let b = body(
        "free",
        1.3,
        Vec3::new(0.15, -0.1, 0.05),
        full_inertia(&mut rng, 0.1),
        x,
        r,
    );
    let bodies = vec![b];
    let mut j = joint(&bodies, "free", JointKind::Free, Link::World, 0, x);
    j.anchor_child = Vec3::ZERO;
    let single = model("free body", bodies, vec![j], Vec3::ZERO);
    let base = floating_base(&mut rng, Vec3::ZERO);
    for m in [&single, &base] {
        let mut js = JointSpaceModel::new(m).unwrap();
        let q = js.qpos0().to_vec();
        let mut v = vec![0.2, -0.1, 0.3, 3.0, -5.0, 4.0];
        v.resize(js.nv(), 1.0);
        let errs: Vec<f64> = [1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0, 1.0 / 800.0]
            .iter()
            .map(|&h| rk4_momentum_error(&mut js, &q, &v, h))
            .collect();
        println!(
            "{}: RK4 momentum errors (t <= 1) at h = 1/100 .. 1/800: {:?}",
            m.name,
            errs.iter().map(|e| format!("{e:.3e}")).collect::<Vec<_>>()
        );
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            println!("  observed order {order:.3}");
            assert!((order - 4.0).abs() < 0.2, "order {order}");
        }
    }
}

/// At `qpos0` the kinematics gives every body's reference world pose (to round-off), and
/// `qpos0` of a free root is the body's reference pose.
#[test]
fn reference_pose_reproduces_the_reference_world_poses() {
    let mut rng = Rng::new(99);
    let models = [
        chain(&mut rng, true),
        floating_base(&mut rng, Vec3::new(0.0, 0.0, -G)),
        double_pendulum(1.0, 1.0, 1.0, 1.0),
    ];
    let mut worst: f64 = 0.0;
    for m in &models {
        let mut js = JointSpaceModel::new(m).unwrap();
        let q0 = js.qpos0().to_vec();
        assert_eq!(js.initial_q(), &q0[..]);
        assert!(js.initial_v().iter().all(|&x| x == 0.0));
        let poses = js.forward_kinematics(&q0).unwrap();
        let quats = js.body_poses(&q0).unwrap();
        for (i, b) in m.bodies.iter().enumerate() {
            worst = worst
                .max((poses[i].0 - b.position).max_abs())
                .max((poses[i].1 - b.rotation).max_abs());
            assert_eq!(quats[i].0, poses[i].0);
            assert!((quats[i].1.to_matrix() - b.rotation).max_abs() < 1e-15 * 8.0);
        }
        if let JointKind::Free = m.joints[0].kind {
            let x = m.bodies[0].position;
            assert_eq!(&q0[..3], &[x.x, x.y, x.z]);
        }
    }
    println!("reference pose: worst difference from the reference world poses {worst:.2e}");
    assert!(worst <= 8.0 * f64::EPSILON, "{worst:e}");
}

/// Bad models and states are errors, not panics.
#[test]
fn bad_input_is_an_error() {
    let mut rng = Rng::new(1);
    let m = chain(&mut rng, false);
    // A loop joint.
    let mut looped = m.clone();
    let extra = joint(
        &looped.bodies,
        "loop",
        JointKind::Ball,
        Link::World,
        2,
        looped.bodies[2].position,
    );
    looped.joints.push(extra);
    assert!(JointSpaceModel::new(&looped).is_err());
    // A body without a joint.
    let mut orphan = m.clone();
    orphan.joints.pop();
    assert!(JointSpaceModel::new(&orphan).is_err());
    // Inconsistent anchors, a non-unit axis, a bad mass, a wrong qpos length.
    let mut bad = m.clone();
    bad.joints[1].anchor_parent.x += 1e-3;
    assert!(JointSpaceModel::new(&bad).is_err());
    let mut bad = m.clone();
    bad.joints[0].kind = JointKind::Hinge {
        axis: Vec3::new(1.0, 1.0, 0.0),
    };
    assert!(JointSpaceModel::new(&bad).is_err());
    let mut bad = m.clone();
    bad.joints[2].anchor_child.y = f64::NAN;
    assert!(JointSpaceModel::new(&bad).is_err());
    let mut bad = m.clone();
    bad.bodies[1].mass = 0.0;
    assert!(JointSpaceModel::new(&bad).is_err());
    let mut bad = m.clone();
    bad.qpos = Some(vec![0.0; 3]);
    assert!(JointSpaceModel::new(&bad).is_err());

    let mut js = JointSpaceModel::new(&m).unwrap();
    let (nq, nv) = (js.nq(), js.nv());
    assert_eq!((nq, nv), (6, 5));
    let q = js.qpos0().to_vec();
    let v = vec![0.0; nv];
    let mut qdd = vec![0.0; nv];
    assert!(js.aba(&q[..5], &v, &v, &mut qdd).is_err());
    assert!(js.aba(&q, &v, &v[..4], &mut qdd).is_err());
    let mut nan = q.clone();
    nan[0] = f64::NAN;
    assert!(js.aba(&nan, &v, &v, &mut qdd).is_err());
    let mut zero = q.clone();
    zero[1..5].copy_from_slice(&[0.0; 4]);
    assert!(js.aba(&zero, &v, &v, &mut qdd).is_err());
    assert!(js.rk4_step(&mut q.clone(), &mut v.clone(), 0.0).is_err());
    assert!(js.rk4_step(&mut q.clone(), &mut v.clone(), f64::INFINITY).is_err());
    let mut dy = vec![0.0; nq + nv];
    assert!(js.derivative(0.0, &q, &mut dy).is_err());
    assert!(js.mass_matrix(&q, &mut [0.0; 3]).is_err());
    // And the good call still works after the failures.
    js.aba(&q, &v, &v, &mut qdd).unwrap();
    assert!(qdd.iter().all(|x| x.is_finite()));
}

/// ABA, RNEA, CRBA, the derivative and the RK4 step allocate nothing.
#[test]
fn dynamics_and_steps_allocate_nothing() {
    let mut rng = Rng::new(17);
    let m = floating_base(&mut rng, Vec3::new(0.0, 0.0, -G));
    let mut js = JointSpaceModel::new(&m).unwrap();
    let (nq, nv) = (js.nq(), js.nv());
    let (mut q, mut v) = random_state(&mut rng, &m, &js);
    let tau = vec![0.1; nv];
    let mut qdd = vec![0.0; nv];
    let mut back = vec![0.0; nv];
    let mut mm = vec![0.0; nv * nv];
    let y: Vec<f64> = q.iter().chain(&v).copied().collect();
    let mut dy = vec![0.0; nq + nv];
    let before = allocations();
    for _ in 0..10 {
        js.aba(&q, &v, &tau, &mut qdd).unwrap();
        js.inverse_dynamics(&q, &v, &qdd, &mut back).unwrap();
        js.mass_matrix(&q, &mut mm).unwrap();
        js.derivative(0.0, &y, &mut dy).unwrap();
        js.rk4_step(&mut q, &mut v, 1e-3).unwrap();
        js.energy(&q, &v).unwrap();
    }
    assert_eq!(allocations() - before, 0);
}

/// A body as MJCF gives it: pose relative to its parent, inertial, and its joint.
struct Spec {
    parent: Option<usize>,
    pos: [f64; 3],
    quat: [f64; 4],
    com: [f64; 3],
    mass: f64,
    /// MJCF `fullinertia`: ixx iyy izz ixy ixz iyz.
    full: [f64; 6],
    kind: JointKind,
    /// MJCF joint `pos` (in the body frame).
    at: [f64; 3],
    /// Stiffness, springref, damping, armature.
    passive: [f64; 4],
}

/// The `Model` of an MJCF-like nesting: world poses composed from the relative ones,
/// the joint anchor `at` in the child and its image in the parent.
fn from_specs(name: &str, specs: &[Spec]) -> Model {
    let mut bodies: Vec<Body> = Vec::new();
    let mut joints = Vec::new();
    for (i, s) in specs.iter().enumerate() {
        let (xp, rp) = match s.parent {
            None => (Vec3::ZERO, Mat3::IDENTITY),
            Some(p) => (bodies[p].position, bodies[p].rotation),
        };
        let rel = so3::Quaternion::new(s.quat[0], s.quat[1], s.quat[2], s.quat[3])
            .normalized()
            .to_matrix();
        let f = s.full;
        let inertia = Mat3::from_rows([[f[0], f[3], f[4]], [f[3], f[1], f[5]], [f[4], f[5], f[2]]]);
        bodies.push(body(
            &format!("b{i}"),
            s.mass,
            Vec3::from_array(s.com),
            inertia,
            xp + rp * Vec3::from_array(s.pos),
            rp * rel,
        ));
        let at = bodies[i].position + bodies[i].rotation * Vec3::from_array(s.at);
        let parent = s.parent.map_or(Link::World, Link::Body);
        let mut j = joint(&bodies, &format!("j{i}"), s.kind, parent, i, at);
        j.anchor_child = Vec3::from_array(s.at);
        [j.stiffness, j.spring_ref, j.damping, j.armature] = s.passive;
        joints.push(j);
    }
    model(name, bodies, joints, Vec3::new(0.0, 0.0, -G))
}

fn unit(a: [f64; 3]) -> Vec3 {
    let v = Vec3::from_array(a);
    v * (1.0 / v.norm())
}

fn unit_quat(q: [f64; 4]) -> [f64; 4] {
    let u = so3::Quaternion::new(q[0], q[1], q[2], q[3]).normalized();
    [u.w, u.x, u.y, u.z]
}

/// Compare ABA's accelerations and the kinematics with MuJoCo's `mj_forward` (`qacc`,
/// `xpos`, `xquat`; MuJoCo 4.0.0 from PyPI, the same models written as MJCF with
/// `fullinertia`, hinge/ball/slide/free joints, stiffness, springref, damping, armature,
/// and the applied forces in `qfrc_applied`; values copied at 17 digits). The MJCF needs
/// `<compiler angle="radian"/>`: MuJoCo reads a hinge's `springref` in degrees by default,
/// and `Model::spring_ref` is in radians.
fn check_against_mujoco(
    m: &Model,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    qacc: &[f64],
    xpos: &[[f64; 3]],
    xquat: &[[f64; 4]],
) -> (f64, f64) {
    let mut js = JointSpaceModel::new(m).unwrap();
    let mut qdd = vec![0.0; js.nv()];
    js.aba(q, v, tau, &mut qdd).unwrap();
    let scale = qacc.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let acc = qdd.iter().zip(qacc).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / scale;
    let poses = js.body_poses(q).unwrap();
    let mut pose: f64 = 0.0;
    for (i, (x, quat)) in poses.iter().enumerate() {
        pose = pose.max((*x - Vec3::from_array(xpos[i])).max_abs());
        let w = xquat[i];
        // q and −q are the same rotation.
        let s = if quat.w * w[0] + quat.x * w[1] + quat.y * w[2] + quat.z * w[3] < 0.0 {
            -1.0
        } else {
            1.0
        };
        for (a, b) in [quat.w, quat.x, quat.y, quat.z].iter().zip(w) {
            pose = pose.max((a - s * b).abs());
        }
    }
    (acc, pose)
}

/// The MJCF of the two models (MuJoCo 4.0.0: `MjModel.from_xml_string`, `qpos`, `qvel`,
/// `qfrc_applied` set as below, `mj_forward`, then `qacc`, `xpos[1:]`, `xquat[1:]`):
///
/// ```xml
/// <mujoco><compiler angle="radian"/><option gravity="0 0 -9.81"/><worldbody>
///  <body name="b0" pos="0.1 -0.05 0.2" quat="0.9 0.1 -0.3 0.2">
///   <inertial pos="0.05 -0.02 0.03" mass="1.2" fullinertia="0.05 0.04 0.03 0.004 -0.002 0.003"/>
///   <joint name="hinge" type="hinge" pos="0.02 0.01 0.05" axis="0.3 -0.5 0.8" stiffness="2" springref="0.3" damping="0.3" armature="0.02"/>
///   <body name="b1" pos="0.3 0.1 -0.4" quat="0.7 -0.2 0.5 0.1">
///    <inertial pos="-0.03 0.06 0.01" mass="0.8" fullinertia="0.02 0.025 0.03 -0.003 0.001 0.002"/>
///    <joint name="ball" type="ball" pos="-0.05 0.02 0.1"/>
///    <body name="b2" pos="0.2 -0.1 -0.25" quat="0.8 0.4 0.1 -0.3">
///     <inertial pos="0.02 0.03 -0.04" mass="0.6" fullinertia="0.01 0.012 0.015 0.001 0.0005 -0.001"/>
///     <joint name="slide" type="slide" pos="0.01 0 0.02" axis="0.2 0.9 -0.4" stiffness="40" springref="-0.05" damping="0.7" armature="0.1"/>
///    </body>
///   </body>
///  </body>
/// </worldbody></mujoco>
/// <mujoco><compiler angle="radian"/><option gravity="0 0 -9.81"/><worldbody>
///  <body name="f0" pos="0.2 0.3 1.0" quat="0.6 0.2 -0.5 0.3">
///   <freejoint name="free"/>
///   <inertial pos="0.04 -0.03 0.02" mass="1.5" fullinertia="0.06 0.05 0.04 0.005 -0.003 0.002"/>
///   <body name="f1" pos="0.3 0 0.1" quat="0.9 0 0.3 0.1">
///    <inertial pos="0.1 0.01 -0.02" mass="0.7" fullinertia="0.01 0.02 0.025 0.001 -0.002 0.0015"/>
///    <joint name="left" type="hinge" pos="0.05 0 0" axis="0 1 0.2"/>
///   </body>
///   <body name="f2" pos="-0.3 -0.1 -0.1" quat="1 0.2 0.2 0">
///    <inertial pos="-0.05 0.02 0.03" mass="0.9" fullinertia="0.02 0.015 0.018 -0.002 0.001 0.001"/>
///    <joint name="right" type="hinge" pos="0.02 0.03 0" axis="1 0.3 0" stiffness="1.5" damping="0.2"/>
///   </body>
///  </body>
/// </worldbody></mujoco>
/// ```
#[test]
fn aba_and_kinematics_match_mujoco() {
    let none = [0.0; 4];
    let chain = from_specs(
        "mujoco chain",
        &[
            Spec {
                parent: None,
                pos: [0.1, -0.05, 0.2],
                quat: [0.9, 0.1, -0.3, 0.2],
                com: [0.05, -0.02, 0.03],
                mass: 1.2,
                full: [0.05, 0.04, 0.03, 0.004, -0.002, 0.003],
                kind: JointKind::Hinge {
                    axis: unit([0.3, -0.5, 0.8]),
                },
                at: [0.02, 0.01, 0.05],
                passive: [2.0, 0.3, 0.3, 0.02],
            },
            Spec {
                parent: Some(0),
                pos: [0.3, 0.1, -0.4],
                quat: [0.7, -0.2, 0.5, 0.1],
                com: [-0.03, 0.06, 0.01],
                mass: 0.8,
                full: [0.02, 0.025, 0.03, -0.003, 0.001, 0.002],
                kind: JointKind::Ball,
                at: [-0.05, 0.02, 0.1],
                passive: none,
            },
            Spec {
                parent: Some(1),
                pos: [0.2, -0.1, -0.25],
                quat: [0.8, 0.4, 0.1, -0.3],
                com: [0.02, 0.03, -0.04],
                mass: 0.6,
                full: [0.01, 0.012, 0.015, 0.001, 0.0005, -0.001],
                kind: JointKind::Slide {
                    axis: unit([0.2, 0.9, -0.4]),
                },
                at: [0.01, 0.0, 0.02],
                passive: [40.0, -0.05, 0.7, 0.1],
            },
        ],
    );
    let mut q = vec![0.4];
    q.extend(unit_quat([0.8, 0.3, -0.4, 0.33]));
    q.push(0.1);
    let (acc, pose) = check_against_mujoco(
        &chain,
        &q,
        &[1.0, -2.0, 1.5, 2.5, 0.5],
        &[0.3, -0.2, 0.1, 0.4, -0.5],
        &[
            -1.2266573282233388,
            -1.5919116995010079,
            -12.389879122371765,
            28.970235430462168,
            -19.904355925038207,
        ],
        &[
            [0.11095516688065628, -0.042680354340295906, 0.2054066645394606],
            [0.347136297235392, 0.500527101430573, 0.16928835372114406],
            [0.3724842837303934, 0.8348769585035847, 0.044671736718110804],
        ],
        &[
            [
                0.8349684409637033,
                0.12731968716847028,
                -0.3984310479187898,
                0.35758928942055945,
            ],
            [
                0.7030443747810546,
                0.15743733219534345,
                -0.08185110252017508,
                0.6886526632026921,
            ],
            [
                0.7528766213416573,
                0.382485578538307,
                0.34523198740261396,
                0.4095075702858594,
            ],
        ],
    );
    println!("hinge-ball-slide chain vs MuJoCo: qacc {acc:.2e} (relative), xpos/xquat {pose:.2e}");
    assert!(acc < 1e-12 && pose < 1e-14, "{acc:e} {pose:e}");

    let base = from_specs(
        "mujoco floating base",
        &[
            Spec {
                parent: None,
                pos: [0.2, 0.3, 1.0],
                quat: [0.6, 0.2, -0.5, 0.3],
                com: [0.04, -0.03, 0.02],
                mass: 1.5,
                full: [0.06, 0.05, 0.04, 0.005, -0.003, 0.002],
                kind: JointKind::Free,
                at: [0.0; 3],
                passive: none,
            },
            Spec {
                parent: Some(0),
                pos: [0.3, 0.0, 0.1],
                quat: [0.9, 0.0, 0.3, 0.1],
                com: [0.1, 0.01, -0.02],
                mass: 0.7,
                full: [0.01, 0.02, 0.025, 0.001, -0.002, 0.0015],
                kind: JointKind::Hinge {
                    axis: unit([0.0, 1.0, 0.2]),
                },
                at: [0.05, 0.0, 0.0],
                passive: none,
            },
            Spec {
                parent: Some(0),
                pos: [-0.3, -0.1, -0.1],
                quat: [1.0, 0.2, 0.2, 0.0],
                com: [-0.05, 0.02, 0.03],
                mass: 0.9,
                full: [0.02, 0.015, 0.018, -0.002, 0.001, 0.001],
                kind: JointKind::Hinge {
                    axis: unit([1.0, 0.3, 0.0]),
                },
                at: [0.02, 0.03, 0.0],
                passive: [1.5, 0.0, 0.2, 0.0],
            },
        ],
    );
    let mut q = vec![0.5, -0.2, 1.3];
    q.extend(unit_quat([0.5, 0.5, -0.3, 0.6]));
    q.extend([0.7, -0.4]);
    let (acc, pose) = check_against_mujoco(
        &base,
        &q,
        &[0.2, -0.1, 0.3, 3.0, -5.0, 4.0, 2.0, -3.0],
        &[0.1, 0.2, -0.3, 0.05, -0.02, 0.04, 0.3, -0.1],
        &[
            -0.2843357550875608,
            0.4037687799690698,
            -11.495454115591075,
            -11.91224228897877,
            4.3490573974607445,
            9.684977979909377,
            -25.794956197923295,
            67.88377640120821,
        ],
        &[
            [0.5, -0.2, 1.3],
            [0.5562468044686435, -0.2023200822696805, 1.645101788724936],
            [0.5518496178253592, -0.18201922282417288, 0.9775851852833978],
        ],
        &[
            [
                0.5129891760425771,
                0.5129891760425771,
                -0.30779350562554625,
                0.6155870112510925,
            ],
            [
                0.49290556217595843,
                -0.0374274803151875,
                -0.015528460961181406,
                0.8691387446164369,
            ],
            [
                0.5307477420618993,
                0.42084858844796813,
                -0.24610751357962252,
                0.6932707924449175,
            ],
        ],
    );
    println!("floating base vs MuJoCo: qacc {acc:.2e} (relative), xpos/xquat {pose:.2e}");
    assert!(acc < 1e-12 && pose < 1e-14, "{acc:e} {pose:e}");
}
