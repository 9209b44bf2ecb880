//! Several hinges in one MJCF body: two through one point as a universal joint, three as a
//! ball. The universal's rows against central differences; the keyframe conversion against
//! MuJoCo's chain `R_p Q exp(θ₁a) exp(θ₂b) (exp(θ₃c))`; the maximal-coordinate run of a
//! universal and of a three-hinge pendulum against the joint-space reference (RK4 at a
//! small step); constraints at round-off; order 2 of `liemid`; each refusal.

use crate::model_files;
use liemid::linalg::{Mat3, Vec3};
use liemid::multibody::constraints::{JointGeometry, JointRows, Row};
use liemid::multibody::joint_space::JointSpaceModel;
use liemid::multibody::{mjcf, JointKind, Loaded, Model, MultibodyMethod, MultibodyState, Simulation};
use liemid::random::Rng;
use liemid::so3;
use model_files::refused;

/// Two links on universal joints (the second pair of axes not perpendicular, one `ref`),
/// off-axis centres of mass, full inertia tensors, started from a keyframe.
const UNIVERSAL: &str = r#"<mujoco model="universal">
  <worldbody>
    <body name="upper" euler="10 -20 30">
      <joint name="u1" axis="1 0 0" pos="0 0 0.05"/>
      <joint name="u2" axis="0.6 0.8 0" pos="0 0 0.05"/>
      <inertial pos="0.02 -0.01 -0.2" mass="1.3" fullinertia="0.02 0.025 0.01 0.001 -0.002 0.0015"/>
      <body name="lower" pos="0 0.01 -0.4">
        <joint name="v1" axis="0 1 0"/>
        <joint name="v2" axis="0.3 0 1" ref="5"/>
        <inertial pos="0.01 0.02 -0.15" mass="0.8" fullinertia="0.01 0.012 0.004 0.0005 0.001 -0.0008"/>
      </body>
    </body>
  </worldbody>
  <keyframe><key qpos="0.4 -0.3 0.6 0.2" qvel="1.0 -0.5 0.8 2.0"/></keyframe>
</mujoco>"#;

/// A hip-like three-hinge joint (x, z, y; one `ref`) hung from the world, and a second
/// body on three hinges with independent, non-perpendicular axes, from a keyframe.
const THREE_HINGES: &str = r#"<mujoco model="three-hinges">
  <worldbody>
    <body name="thigh" pos="0 0 1" euler="5 10 -15">
      <joint name="hip_x" axis="1 0 0" pos="0 0 0.02"/>
      <joint name="hip_z" axis="0 0 1" pos="0 0 0.02"/>
      <joint name="hip_y" axis="0 1 0" pos="0 0 0.02" ref="-10"/>
      <inertial pos="0.03 0.01 -0.2" mass="2.0" fullinertia="0.03 0.035 0.012 0.002 -0.001 0.003"/>
      <body name="shin" pos="0 0 -0.4">
        <joint name="k1" axis="1 0.2 0"/>
        <joint name="k2" axis="0 1 0.3"/>
        <joint name="k3" axis="0.2 0 1"/>
        <inertial pos="-0.01 0.02 -0.15" mass="1.1" fullinertia="0.012 0.014 0.005 -0.0007 0.0004 0.0009"/>
      </body>
    </body>
  </worldbody>
  <keyframe><key qpos="0.3 -0.5 0.7 0.2 0.4 -0.3" qvel="1.5 -0.7 0.9 -1.2 2.0 0.6"/></keyframe>
</mujoco>"#;

fn load(text: &str) -> Loaded {
    mjcf::parse(text, "merged.xml").unwrap()
}

#[test]
fn hinges_through_one_point_merge() {
    let l = load(UNIVERSAL);
    let m = &l.model;
    assert_eq!(m.joints.len(), 2);
    assert_eq!(m.joints[0].name, "u1+u2");
    match m.joints[1].kind {
        JointKind::Universal { first, second } => {
            assert_eq!(first, Vec3::new(0.0, 1.0, 0.0));
            let n = (0.09f64 + 1.0).sqrt();
            assert!((second - Vec3::new(0.3 / n, 0.0, 1.0 / n)).max_abs() < 1e-16);
        }
        k => panic!("{k:?}"),
    }
    assert_eq!((m.nq(), m.nv()), (4, 4));
    // ref = 5 degrees is subtracted from the second hinge's angle.
    let q = m.qpos.as_ref().unwrap();
    assert_eq!(&q[..3], &[0.4, -0.3, 0.6]);
    assert!((q[3] - (0.2 - 5f64.to_radians())).abs() < 1e-16);
    let l = load(THREE_HINGES);
    assert_eq!(l.model.joints[0].kind, JointKind::Ball);
    assert_eq!(l.model.joints[0].name, "hip_x+hip_z+hip_y");
    assert_eq!((l.model.nq(), l.model.nv()), (8, 6));
}

#[test]
fn universal_rows_match_central_differences() {
    let mut rng = Rng::new(11);
    let model = load(UNIVERSAL).model;
    let g = JointGeometry::new(&model, 1);
    let row = |r: &Row, k: usize| [r.ci, r.ti, r.cj, r.tj][k / 3][k % 3];
    for _ in 0..5 {
        let ci = Vec3::new(rng.normal(), rng.normal(), rng.normal());
        let cj = Vec3::new(rng.normal(), rng.normal(), rng.normal());
        let (ri, rj) = (rng.rotation(), rng.rotation());
        let mut rows = JointRows::default();
        g.rows((ci, &ri), (cj, &rj), &mut rows);
        assert_eq!(rows.n, 4);
        let d = 1e-5;
        let mut worst: f64 = 0.0;
        for k in 0..12 {
            let at = |s: f64| {
                let mut e = [0.0; 3];
                e[k % 3] = s;
                let e = Vec3::from_array(e);
                let (mut a, mut b) = ((ci, ri), (cj, rj));
                let x = if k < 6 { &mut a } else { &mut b };
                if k % 6 < 3 {
                    x.0 += e;
                } else {
                    x.1 = x.1 * so3::exp(e);
                }
                let mut out = JointRows::default();
                g.rows((a.0, &a.1), (b.0, &b.1), &mut out);
                out
            };
            let (plus, minus) = (at(d), at(-d));
            for r in 0..4 {
                let fd = (plus.value[r] - minus.value[r]) / (2.0 * d);
                let an = row(&rows.grad[r], k);
                worst = worst.max((fd - an).abs() / an.abs().max(1.0));
            }
        }
        // Central differences: truncation d² |g'''|/6 ≈ 1e-11, round-off ε/d ≈ 2e-11.
        assert!(worst < 1e-8, "worst relative gradient error {worst:e}");
    }
}

/// MuJoCo's kinematics of a body with hinges `axes` (body frame) at angles `th` under a
/// parent at `(rp, wp)`: `R = R_p Q Π exp(θ_k a_k)`, `ω = ω_p + Σ R_p Q Π_{m<k} exp(θ_m a_m) a_k θ̇_k`.
fn chain(rp: Mat3, wp: Vec3, q: Mat3, axes: &[Vec3], th: &[f64], rate: &[f64]) -> (Mat3, Vec3) {
    let mut r = rp * q;
    let mut w = wp;
    for k in 0..axes.len() {
        w += r * axes[k] * rate[k];
        r = r * so3::exp(axes[k] * th[k]);
    }
    (r, w)
}

#[test]
fn keyframes_convert_to_the_merged_joints() {
    for (text, nh) in [(UNIVERSAL, 2), (THREE_HINGES, 3)] {
        let doc = roxml_key(text);
        let (qk, vk) = (&doc.0, &doc.1);
        let m = load(text).model;
        let state = m.initial_state().unwrap();
        let (mut rp, mut wp) = (Mat3::IDENTITY, Vec3::ZERO);
        let refs: Vec<f64> = if nh == 2 {
            vec![0.0, 0.0, 0.0, 5f64.to_radians()]
        } else {
            vec![0.0, 0.0, -10f64.to_radians(), 0.0, 0.0, 0.0]
        };
        for (i, j) in m.joints.iter().enumerate() {
            let axes: Vec<Vec3> = match j.kind {
                JointKind::Universal { first, second } => vec![first, second],
                JointKind::Ball => axes_of(text, i),
                k => panic!("{k:?}"),
            };
            let th: Vec<f64> = (0..nh).map(|k| qk[i * nh + k] - refs[i * nh + k]).collect();
            let (r, w) = chain(rp, wp, j.reference_rotation, &axes, &th, &vk[i * nh..(i + 1) * nh]);
            let inertia = m.inertia(i).unwrap();
            let w_state = state.rotation[i] * inertia.apply_inverse(state.pi[i]);
            assert!((r - state.rotation[i]).max_abs() < 1e-15, "{}", j.name);
            assert!(
                (w - w_state).max_abs() < 1e-14,
                "{}: {:e}",
                j.name,
                (w - w_state).max_abs()
            );
            (rp, wp) = (r, w);
        }
    }
}

/// The keyframe's numbers of one of the models above.
fn roxml_key(text: &str) -> (Vec<f64>, Vec<f64>) {
    let grab = |attr: &str| -> Vec<f64> {
        let at = text.find(&format!("{attr}=\"")).unwrap() + attr.len() + 2;
        let end = text[at..].find('"').unwrap();
        text[at..at + end]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    (grab("qpos"), grab("qvel"))
}

/// The unit hinge axes of body `i` of the three-hinge model.
fn axes_of(text: &str, i: usize) -> Vec<Vec3> {
    assert_eq!(text, THREE_HINGES);
    let raw = if i == 0 {
        [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
    } else {
        [[1.0, 0.2, 0.0], [0.0, 1.0, 0.3], [0.2, 0.0, 1.0]]
    };
    raw.iter()
        .map(|a| {
            let v = Vec3::from_array(*a);
            v * (1.0 / v.norm())
        })
        .collect()
}

fn run(model: &Model, method: MultibodyMethod, h: f64, t_end: f64) -> (Simulation, MultibodyState, f64) {
    let mut sys = Simulation::new(model, method).unwrap();
    let mut s = model.initial_state().unwrap();
    let mut worst: f64 = 0.0;
    for _ in 0..(t_end / h).round() as usize {
        sys.step(&mut s, h).unwrap();
        let (p, v) = sys.constraint_violation(&s);
        worst = worst.max(p).max(v);
    }
    (sys, s, worst)
}

/// Body frame origins of the joint-space reference at `t_end` (RK4, step `h`).
fn reference(model: &Model, h: f64, t_end: f64) -> Vec<Vec3> {
    let mut js = JointSpaceModel::new(model).unwrap();
    let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    for _ in 0..(t_end / h).round() as usize {
        js.rk4_step(&mut q, &mut v, h).unwrap();
    }
    js.forward_kinematics(&q).unwrap().into_iter().map(|(x, _)| x).collect()
}

fn largest_gap(sys: &Simulation, s: &MultibodyState, xref: &[Vec3]) -> f64 {
    (0..s.len())
        .map(|i| (sys.system.frame_origin(s, i) - xref[i]).max_abs())
        .fold(0.0, f64::max)
}

/// As the CLI's test of the test chain (`multibody_cli.rs`, 1e-9 m there): `liemid8`
/// at h = 1 ms and joint-space RK4 at h = 1e-4 meet at t = 0.5 (measured 3e-15 and 8e-15
/// m, asserted below 1e-11), `liemid` at h = 1e-4 to its O(h²) (measured 9e-9, 2.4e-8 m;
/// asserted below 1e-7); and the constraints stay at round-off at every step.
#[test]
fn merged_pendulums_agree_with_the_joint_space_reference() {
    for text in [UNIVERSAL, THREE_HINGES] {
        let model = load(text).model;
        let xref = reference(&model, 1e-4, 0.5);
        let (sys, s, worst) = run(&model, MultibodyMethod::Liemid8, 1e-3, 0.5);
        let gap = largest_gap(&sys, &s, &xref);
        let (_, s2, worst2) = run(&model, MultibodyMethod::Liemid, 1e-4, 0.5);
        let gap2 = largest_gap(&sys, &s2, &xref);
        println!(
            "{}: liemid8 h=1e-3 vs RK4 h=1e-4: {gap:.2e} m (constraints {worst:.1e}); liemid h=1e-4: {gap2:.2e} m \
             (constraints {worst2:.1e})",
            model.name
        );
        assert!(gap < 1e-11, "{}: {gap:e}", model.name);
        assert!(gap2 < 1e-7, "{}: {gap2:e}", model.name);
        assert!(worst < 1e-12 && worst2 < 1e-12, "{}: {worst:e} {worst2:e}", model.name);
    }
}

#[test]
fn liemid_is_second_order_on_a_universal_joint() {
    let model = load(UNIVERSAL).model;
    let t_end = 0.5;
    let (sys, reference, _) = run(&model, MultibodyMethod::Liemid8, 1e-3, t_end);
    let steps = [4e-3, 2e-3, 1e-3];
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| {
            let (_, s, _) = run(&model, MultibodyMethod::Liemid, h, t_end);
            largest_gap(
                &sys,
                &s,
                &(0..s.len())
                    .map(|i| sys.system.frame_origin(&reference, i))
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    let order = liemid::observed_order(&steps, &errors).unwrap();
    println!("universal: liemid h {steps:?} errors {errors:?} order {order:.3}");
    assert!((order - 2.0).abs() < 0.1, "order {order}");
}

fn body_with(joints: &str) -> String {
    format!(
        "<mujoco>\n<worldbody>\n<body name=\"b\">\n{joints}\n<geom size=\"0.1\"/>\n</body>\n</worldbody>\n</mujoco>"
    )
}

#[test]
fn other_combinations_are_refused_naming_body_and_joints() {
    let cases: &[(&str, u32, &str, &[&str])] = &[
        (
            "<joint name=\"h\" axis=\"0 0 1\"/>\n<joint name=\"s\" type=\"slide\" axis=\"0 0 1\"/>",
            3,
            "body name=\"b\"",
            &["body `b`", "`h` (hinge)", "`s` (slide)", "a hinge and a slide"],
        ),
        (
            "<joint name=\"h\"/>\n<joint name=\"bj\" type=\"ball\"/>",
            3,
            "body name=\"b\"",
            &["`h` (hinge)", "`bj` (ball)"],
        ),
        ("<freejoint name=\"f\"/>\n<joint name=\"h\"/>", 3, "body name=\"b\"", &["`f` (free)", "`h` (hinge)"]),
        (
            "<joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"0 1 0\"/>\n<joint name=\"d\" axis=\"0 0 1\"/>\n\
             <joint name=\"e\" axis=\"1 1 0\"/>",
            3,
            "body name=\"b\"",
            &["4 joints", "four or more hinges"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"2 0 0\"/>",
            3,
            "body name=\"b\"",
            &["`a` (hinge), `c` (hinge)", "not independent", "universal"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"0 1 0\"/>\n<joint name=\"d\" axis=\"1 1 0\"/>",
            3,
            "body name=\"b\"",
            &["not independent", "ball"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"0 1 0\" pos=\"0 0 0.1\"/>",
            5,
            "joint name=\"c\"",
            &["body `b`", "different points", "universal"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\" range=\"-30 30\"/>\n<joint name=\"c\" axis=\"0 1 0\"/>",
            4,
            "joint name=\"a\"",
            &["joint `a` of body `b`", "a limit (range)", "universal"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"0 1 0\"/>\n<joint name=\"d\" stiffness=\"2\"/>",
            6,
            "joint name=\"d\"",
            &["joint `d` of body `b`", "a spring (stiffness)", "ball"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\" damping=\"0.1\"/>\n<joint name=\"c\" axis=\"0 1 0\"/>",
            4,
            "joint name=\"a\"",
            &["damping"],
        ),
        (
            "<joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"0 1 0\" armature=\"0.01\"/>",
            5,
            "joint name=\"c\"",
            &["armature"],
        ),
    ];
    for &(joints, line, element, words) in cases {
        refused(mjcf::parse(&body_with(joints), "r.xml"), line, element, words);
    }
    // Defaults reach merged hinges too: a limited class is refused, a bare one loads.
    let classed = "<mujoco>\n<default><joint range=\"-1 1\"/></default>\n<worldbody>\n<body name=\"b\">\n\
                   <joint name=\"a\" axis=\"1 0 0\"/>\n<joint name=\"c\" axis=\"0 1 0\"/>\n<geom size=\"0.1\"/>\n\
                   </body>\n</worldbody>\n</mujoco>";
    refused(
        mjcf::parse(classed, "r.xml"),
        5,
        "joint name=\"a\"",
        &["a limit (range)"],
    );
    mjcf::parse(&classed.replace("<joint range=\"-1 1\"/>", ""), "r.xml").unwrap();
}

#[test]
fn a_universal_joint_in_code_is_validated() {
    let mut m = load(UNIVERSAL).model;
    m.joints[1].kind = JointKind::Universal {
        first: Vec3::new(0.0, 1.0, 0.0),
        second: Vec3::new(0.0, -1.0, 1e-8) * (1.0 / (1.0f64 + 1e-16).sqrt()),
    };
    let err = m.validate().unwrap_err().to_string();
    assert!(err.contains("v1+v2") && err.contains("parallel"), "{err}");
    assert!(Simulation::new(&m, MultibodyMethod::Liemid).is_err());
    m.joints[1].kind = JointKind::Universal {
        first: Vec3::new(0.0, 1.0, 0.0),
        second: Vec3::new(0.0, 0.0, 2.0),
    };
    assert!(m.validate().unwrap_err().to_string().contains("unit"));
    assert!(JointSpaceModel::new(&m).is_err());
}
