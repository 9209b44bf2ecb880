//! The MJCF and URDF loaders on the example files (hand-computed masses, inertias, poses,
//! default classes, degrees, geom-derived masses) and on every refusal.

use crate::model_files;
use model_files::refused;
use std::path::PathBuf;
use std::time::Instant;

use liemid::multibody::model::{JointKind, Link, Model};
use liemid::multibody::{mjcf, urdf, ShapeKind};
use liemid::{Mat3, Vec3};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/multibody")
        .join(name)
}

fn rx(t: f64) -> Mat3 {
    let (s, c) = t.sin_cos();
    Mat3::from_rows([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
}

fn ry(t: f64) -> Mat3 {
    let (s, c) = t.sin_cos();
    Mat3::from_rows([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
}

fn rz(t: f64) -> Mat3 {
    let (s, c) = t.sin_cos();
    Mat3::from_rows([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
}

#[track_caller]
fn close_v(a: Vec3, b: Vec3, tol: f64) {
    assert!((a - b).max_abs() <= tol, "{a:?} != {b:?}");
}

#[track_caller]
fn close_m(a: &Mat3, b: &Mat3, tol: f64) {
    assert!((*a - *b).max_abs() <= tol, "{a:?} != {b:?}");
}

#[track_caller]
fn close(a: f64, b: f64, tol: f64) {
    assert!((a - b).abs() <= tol * b.abs().max(1.0), "{a} != {b}");
}

fn body<'m>(m: &'m Model, name: &str) -> (usize, &'m liemid::multibody::model::Body) {
    m.bodies
        .iter()
        .enumerate()
        .find(|(_, b)| b.name == name)
        .unwrap_or_else(|| panic!("no body {name}"))
}

fn joint<'m>(m: &'m Model, name: &str) -> &'m liemid::multibody::model::Joint {
    m.joints
        .iter()
        .find(|j| j.name == name)
        .unwrap_or_else(|| panic!("no joint {name}"))
}

#[test]
fn double_pendulum_mjcf_matches_hand_values_and_urdf() {
    let x = mjcf::load(&example("double_pendulum.xml")).unwrap();
    let u = urdf::load(&example("double_pendulum.urdf")).unwrap();
    let m = &x.model;
    assert_eq!(m.name, "double_pendulum");
    assert_eq!(m.timestep, Some(0.001));
    assert_eq!(m.bodies.len(), 2);
    assert_eq!(m.joints.len(), 2);
    assert_eq!(m.qpos, None);
    // link1's principal axes turned 30° about x: diag(0.1, 0.1, 0.01) becomes
    // Iyy = 0.1 cos² + 0.01 sin², Izz = 0.1 sin² + 0.01 cos², Iyz = 0.09 sin cos.
    let (_, l1) = body(m, "link1");
    assert_eq!(l1.mass, 1.0);
    close_v(l1.com, Vec3::new(0.0, 0.0, -0.5), 0.0);
    let iyz = 0.09 * 3f64.sqrt() / 4.0;
    let expect = Mat3::from_rows([[0.1, 0.0, 0.0], [0.0, 0.0775, iyz], [0.0, iyz, 0.0325]]);
    close_m(&l1.inertia, &expect, 1e-15);
    close_v(l1.position, Vec3::new(0.0, 0.0, 2.0), 0.0);
    let (_, l2) = body(m, "link2");
    close_v(l2.position, Vec3::new(0.0, 0.0, 1.0), 1e-15);
    close_m(&l2.rotation, &rz(std::f64::consts::FRAC_PI_2), 1e-15);
    let elbow = joint(m, "elbow");
    assert_eq!(
        elbow.kind,
        JointKind::Hinge {
            axis: Vec3::new(1.0, 0.0, 0.0)
        }
    );
    assert_eq!(elbow.parent, Link::Body(0));
    close_v(elbow.anchor_parent, Vec3::new(0.0, 0.0, -1.0), 0.0);
    assert_eq!(joint(m, "shoulder").parent, Link::World);
    // The URDF is the same system.
    let n = &u.model;
    assert_eq!(n.bodies.len(), 2);
    for (a, b) in m.bodies.iter().zip(&n.bodies) {
        assert_eq!(a.name, b.name);
        close(a.mass, b.mass, 1e-12);
        close_v(a.com, b.com, 1e-12);
        close_m(&a.inertia, &b.inertia, 1e-12);
        close_v(a.position, b.position, 1e-12);
        close_m(&a.rotation, &b.rotation, 1e-12);
    }
    for (a, b) in m.joints.iter().zip(&n.joints) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.parent, b.parent);
        assert_eq!(a.child, b.child);
        match (a.kind, b.kind) {
            (JointKind::Hinge { axis: p }, JointKind::Hinge { axis: q }) => close_v(p, q, 1e-12),
            other => panic!("{other:?}"),
        }
        close_v(a.anchor_parent, b.anchor_parent, 1e-12);
        close_v(a.anchor_child, b.anchor_child, 1e-12);
        close_m(&a.reference_rotation, &b.reference_rotation, 1e-12);
        assert_eq!((a.range, b.range), (None, None));
    }
}

/// Mass, axial and transverse moments of a solid of revolution about the z axis with
/// radius `rho(z)` on `[z0, z1]` and density `d`, about its centre (by slices).
fn revolution(rho: impl Fn(f64) -> f64, z0: f64, z1: f64, d: f64) -> (f64, f64, f64) {
    let n = 200_000;
    let h = (z1 - z0) / n as f64;
    let (mut m, mut mz, mut axial, mut trans) = (0.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        let z = z0 + (k as f64 + 0.5) * h;
        let r = rho(z);
        let dm = d * std::f64::consts::PI * r * r * h;
        m += dm;
        mz += dm * z;
        axial += 0.5 * dm * r * r;
        trans += dm * (0.25 * r * r + z * z);
    }
    let zc = mz / m;
    (m, axial, trans - m * zc * zc)
}

#[test]
fn chain_of_ten_capsules_takes_masses_from_geoms() {
    let l = mjcf::load(&example("chain_10.xml")).unwrap();
    let m = &l.model;
    assert_eq!(m.bodies.len(), 10);
    assert!(m.joints.iter().all(|j| j.kind == JointKind::Ball));
    assert_eq!(m.timestep, Some(0.0005));
    // A capsule of radius 0.05 from z = 0 to z = -0.5 (hemispherical caps beyond).
    let (r, len) = (0.05f64, 0.5f64);
    let rho = |z: f64| {
        let below = (z + len).min(0.0);
        let above = z.max(0.0);
        let t = below.abs().max(above);
        (r * r - t * t).max(0.0).sqrt()
    };
    let (mass, axial, trans) = revolution(rho, -len - r, r, 1000.0);
    let exact_mass = 1000.0 * std::f64::consts::PI * (r * r * len + 4.0 / 3.0 * r.powi(3));
    close(mass, exact_mass, 1e-8);
    for (k, b) in m.bodies.iter().enumerate() {
        close(b.mass, exact_mass, 1e-14);
        close_v(b.com, Vec3::new(0.0, 0.0, -0.25), 1e-15);
        close(b.inertia.m[0][0], trans, 1e-7);
        close(b.inertia.m[1][1], trans, 1e-7);
        close(b.inertia.m[2][2], axial, 1e-7);
        close_v(b.position, Vec3::new(0.0, 0.0, -0.5 * k as f64), 1e-15);
    }
    // The ball joints' dampers are simulated (on the relative angular velocity).
    assert!(m.joints.iter().all(|j| j.damping == 0.001));
    assert!(!l.ignored.iter().any(|k| k.contains("damping")), "{:?}", l.ignored);
    // The capsules and the floor touch (contacts are simulated): none is ignored.
    assert!(!l.ignored.iter().any(|k| k.contains("contact")), "{:?}", l.ignored);
    assert_eq!(m.collision.shapes.len(), 11);
}

#[test]
fn box_and_sphere_geoms_combine_by_parallel_axes() {
    let text = r#"<mujoco>
      <worldbody>
        <body name="b">
          <joint type="free"/>
          <geom type="box" size="0.1 0.2 0.3" mass="6"/>
          <geom type="sphere" size="0.1" pos="0 0 1"/>
        </body>
        <body name="c" pos="0 0 3"><freejoint/><geom type="box" size="0.1 0.2 0.3"/></body>
      </worldbody>
    </mujoco>"#;
    let m = mjcf::parse(text, "boxes.xml").unwrap().model;
    // Box 0.2 x 0.4 x 0.6 of 6 kg: I = m (b² + c²) / 12 with full sides.
    let (ib, ms) = (
        [2.0 * 0.13, 2.0 * 0.10, 2.0 * 0.05],
        1000.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-3,
    );
    let total = 6.0 + ms;
    let zc = ms / total;
    let b = &m.bodies[0];
    close(b.mass, total, 1e-14);
    close_v(b.com, Vec3::new(0.0, 0.0, zc), 1e-15);
    let is = 0.4 * ms * 0.01;
    let shift = 6.0 * zc * zc + ms * (1.0 - zc) * (1.0 - zc);
    close(b.inertia.m[0][0], ib[0] + is + shift, 1e-13);
    close(b.inertia.m[1][1], ib[1] + is + shift, 1e-13);
    close(b.inertia.m[2][2], ib[2] + is, 1e-13);
    // Density 1000 by default: 48 kg.
    let c = &m.bodies[1];
    close(c.mass, 48.0, 1e-14);
    close(c.inertia.m[0][0], 48.0 * (0.04 + 0.09) / 3.0, 1e-14);
    assert_eq!(m.joints[1].kind, JointKind::Free);
}

#[test]
fn menagerie_style_arm() {
    let l = mjcf::load(&example("arm.xml")).unwrap();
    let m = &l.model;
    assert_eq!(m.name, "arm");
    assert_eq!(m.timestep, Some(0.002));
    let names: Vec<&str> = m.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["base", "link1", "link2", "hand"]);
    assert_eq!(m.joints[0].kind, JointKind::Weld);
    assert_eq!(m.joints[0].parent, Link::World);
    // Poses: axisangle, then a quaternion (normalised), then euler (radians here).
    let r1 = rz(0.5);
    let r2 = r1 * rx(-std::f64::consts::FRAC_PI_2);
    let r3 = r2 * rz(std::f64::consts::FRAC_PI_2);
    close_m(&body(m, "link1").1.rotation, &r1, 1e-15);
    close_m(&body(m, "link2").1.rotation, &r2, 1e-15);
    close_m(&body(m, "hand").1.rotation, &r3, 1e-15);
    close_v(body(m, "hand").1.position, Vec3::new(0.0, 0.0, 0.333 + 0.316), 1e-15);
    // fullinertia as given; diaginertia turned 45° about z by the inertial quat.
    let i1 = body(m, "link1").1.inertia;
    close_m(
        &i1,
        &Mat3::from_rows([[0.0166, 0.0, 0.0], [0.0, 0.0145, 0.0024], [0.0, 0.0024, 0.0049]]),
        0.0,
    );
    let i2 = body(m, "link2").1.inertia;
    close_m(
        &i2,
        &Mat3::from_rows([[0.025, 0.005, 0.0], [0.005, 0.025, 0.0], [0.0, 0.0, 0.015]]),
        1e-15,
    );
    // Default classes: joint1 and joint2 use the childclass "arm"; wrist its own class
    // "wrist", which inherits the armature of "arm" and overrides damping, range and ref.
    let j1 = joint(m, "joint1");
    assert_eq!(
        j1.kind,
        JointKind::Hinge {
            axis: Vec3::new(0.0, 0.0, 1.0)
        }
    );
    assert_eq!((j1.armature, j1.damping, j1.range), (0.1, 1.0, Some((-2.8973, 2.8973))));
    assert_eq!(joint(m, "joint2").range, Some((-1.7628, 1.7628)));
    let w = joint(m, "wrist");
    assert_eq!((w.armature, w.damping), (0.1, 0.5));
    // ref = 0.2: the model's coordinate is MuJoCo's qpos - 0.2.
    let (lo, hi) = w.range.unwrap();
    close(lo, -1.2, 1e-15);
    close(hi, 0.8, 1e-15);
    close(w.spring_ref, -0.2, 1e-15);
    let q = m.qpos.as_ref().unwrap();
    assert_eq!(q.len(), 3);
    close(q[1], 0.5, 0.0);
    close(q[2], -0.5, 1e-15);
    assert_eq!(m.qvel, None);
    // Actuators: two position servos of class "arm" (kp 100, dampratio 1: kv = 2 √(kp M₀)
    // at the reference pose) and a motor on the wrist, whose length is MuJoCo's qpos (the
    // model's coordinate + ref); the keyframe's ctrl.
    let names: Vec<&str> = m.actuators.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["actuator1", "actuator2", "actuator3"]);
    assert_eq!((m.actuators[0].gain[0], m.actuators[0].bias[1]), (100.0, -100.0));
    assert!(m.actuators[0].bias[2] < 0.0 && m.actuators[1].bias[2] < 0.0);
    assert_eq!(
        (m.actuators[2].ctrl_range, m.actuators[2].length_offset),
        (Some((-5.0, 5.0)), 0.2)
    );
    assert_eq!(m.ctrl, Some(vec![0.0, 0.5, 0.0]));
    assert!(
        !l.ignored.iter().any(|s| s.contains("actuator") || s.contains("ctrl")),
        "{:?}",
        l.ignored
    );
    for kind in ["sensor", "asset", "light", "site", "camera", "option integrator"] {
        assert!(l.ignored.iter().any(|s| s == kind), "{kind} not in {:?}", l.ignored);
    }
}

#[test]
fn degrees_euler_sequences_and_welds() {
    let text = r#"<mujoco>
      <worldbody>
        <body name="a" euler="90 90 0">
          <joint name="h" range="-90 45" ref="30" springref="60"/>
          <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
          <body name="tag" pos="1 0 0"/>
          <body name="w" pos="0 1 0"><inertial pos="0 0 0" mass="2" diaginertia="1 1 1"/></body>
        </body>
      </worldbody>
    </mujoco>"#;
    let l = mjcf::parse(text, "deg.xml").unwrap();
    let m = &l.model;
    let (h, d) = (std::f64::consts::FRAC_PI_2, std::f64::consts::PI / 180.0);
    close_m(&m.bodies[0].rotation, &(rx(h) * ry(h)), 1e-15);
    let j = joint(m, "h");
    let (lo, hi) = j.range.unwrap();
    close(lo, -120.0 * d, 1e-14);
    close(hi, 15.0 * d, 1e-14);
    close(j.spring_ref, 30.0 * d, 1e-14);
    // The massless body "tag" is merged; "w" is welded.
    assert_eq!(l.merged, [("tag".to_string(), "a".to_string())]);
    assert_eq!(joint(m, "w_weld").kind, JointKind::Weld);
    // Upper-case letters turn about fixed axes.
    let text = text.replace("<mujoco>", r#"<mujoco><compiler eulerseq="XYZ"/>"#);
    let m = mjcf::parse(&text, "deg.xml").unwrap().model;
    close_m(&m.bodies[0].rotation, &(ry(h) * rx(h)), 1e-15);
}

#[test]
fn ros_style_arm_lumps_fixed_joints() {
    let l = urdf::load(&example("arm.urdf")).unwrap();
    let m = &l.model;
    let names: Vec<&str> = m.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["base_link", "upper_arm", "forearm"]);
    let merged: Vec<(&str, &str)> = l.merged.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    assert_eq!(merged, [("base", "base_link"), ("tool", "forearm"), ("tcp", "forearm")]);
    let base = &m.bodies[0];
    assert_eq!(base.mass, 4.0);
    close_v(base.com, Vec3::new(0.0, 0.0, 0.15), 1e-16);
    assert_eq!(m.joints[0].kind, JointKind::Weld);
    assert_eq!(m.joints[0].parent, Link::World);
    // upper_arm: the inertial turned 30° about y.
    let ua = &m.bodies[1];
    close_v(ua.position, Vec3::new(0.0, 0.0, 0.3), 1e-16);
    close_m(&ua.rotation, &rz(0.5), 1e-15);
    let ixz = (0.004 - 0.03) * 3f64.sqrt() / 4.0;
    close_m(
        &ua.inertia,
        &Mat3::from_rows([[0.0235, 0.0, ixz], [0.0, 0.03, 0.0], [ixz, 0.0, 0.0105]]),
        1e-15,
    );
    // forearm with the tool lumped in: 1.5 kg at x = 0.2.
    let fa = &m.bodies[2];
    close_v(fa.position, Vec3::new(0.0, 0.0, 0.7), 1e-15);
    close_m(&fa.rotation, &(rz(0.5) * rx(std::f64::consts::FRAC_PI_2)), 1e-15);
    close(fa.mass, 1.5, 1e-15);
    close_v(fa.com, Vec3::new(0.2, 0.0, 0.0), 1e-15);
    close_m(
        &fa.inertia,
        &Mat3::from_diagonal(Vec3::new(0.0015, 0.0165, 0.0165)),
        1e-15,
    );
    let s = joint(m, "shoulder");
    assert_eq!((s.range, s.damping), (Some((-2.0, 2.0)), 0.5));
    assert_eq!(s.parent, Link::Body(0));
    close_v(s.anchor_parent, Vec3::new(0.0, 0.0, 0.3), 1e-16);
    assert_eq!(
        joint(m, "elbow").kind,
        JointKind::Hinge {
            axis: Vec3::new(0.0, 0.0, 1.0)
        }
    );
    for kind in ["material", "transmission", "joint friction"] {
        assert!(l.ignored.iter().any(|s| s == kind), "{kind} not in {:?}", l.ignored);
    }
    // The upper arm's `<collision>` cylinder is a contact shape (hidden group 3, friction 1),
    // alone in the model, so nothing touches.
    assert_eq!(m.collision.shapes.len(), 1);
    assert!(!m.collision.any());
    let collision = &m.collision.shapes[0];
    assert_eq!(
        (collision.group, collision.collision.as_ref().map(|c| c.friction)),
        (3, Some(1.0))
    );
    // The base's visual is a mesh: `package://arm/meshes/base.stl` found as `meshes/base.stl`
    // next to the URDF, and listed among the model's files (no output may replace it).
    assert_eq!(l.shapes.len(), 2, "{:?}", l.shapes);
    let ShapeKind::Mesh { file, path, scale, .. } = &l.shapes[0].kind else {
        panic!("{:?}", l.shapes[0]);
    };
    assert_eq!((file.as_str(), *scale), ("package://arm/meshes/base.stl", [1.0; 3]));
    let path = path.as_ref().unwrap();
    assert!(
        path.ends_with("meshes/base.stl") && path.is_file(),
        "{}",
        path.display()
    );
    assert!(l.files.contains(path));
    let dir = example("arm.urdf").parent().unwrap().to_path_buf();
    for (name, found) in [
        ("package://arm/meshes/base.stl", true),
        ("package://arm/meshes/none.stl", false),
        ("package://arm", false),
        ("http://example.invalid/base.stl", false),
    ] {
        assert_eq!(urdf::mesh_path(&dir, name).is_ok(), found, "{name}");
    }
    assert_eq!(urdf::mesh_path(&dir, "meshes/x.stl").unwrap(), dir.join("meshes/x.stl"));
}

// ---- refusals: each names the element and its line ----

fn one_body(inside: &str) -> String {
    format!("<mujoco>\n<worldbody>\n<body name=\"b\">\n{inside}\n</body>\n</worldbody>\n</mujoco>")
}

const JOINT: &str = "<joint name=\"j\"/>";

#[test]
fn refuses_bad_masses() {
    for (mass, words) in [
        ("-1", "must be positive"),
        ("0", "must be positive"),
        ("NaN", "not finite"),
    ] {
        let t = one_body(&format!(
            "{JOINT}\n<inertial pos=\"0 0 0\" mass=\"{mass}\" diaginertia=\"1 1 1\"/>"
        ));
        refused(mjcf::parse(&t, "m.xml"), 5, "inertial", &[words]);
    }
    let t = one_body(&format!("{JOINT}\n<geom type=\"sphere\" size=\"1\" mass=\"-2\"/>"));
    refused(mjcf::parse(&t, "m.xml"), 5, "geom", &["negative"]);
    for (value, words) in [
        ("-1", "negative"),
        ("nan", "not finite"),
        ("1 2", "has 2 values, 1 expected"),
    ] {
        let u = format!("<robot name=\"r\">\n<link name=\"a\">\n<inertial>\n<mass value=\"{value}\"/>\n</inertial></link>\n</robot>");
        refused(urdf::parse(&u, "m.urdf"), 4, "mass", &[words]);
    }
}

#[test]
fn refuses_bad_inertias() {
    let t = one_body("<inertial pos=\"0 0 0\" mass=\"1\" fullinertia=\"1 1 1 2 0 0\"/>");
    refused(mjcf::parse(&t, "i.xml"), 4, "inertial", &["not positive definite"]);
    let t = one_body("<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1 1 2.0000001\"/>");
    refused(mjcf::parse(&t, "i.xml"), 4, "inertial", &["triangle inequality"]);
    // Exactly planar (a + b = c) is a body.
    let t = one_body("<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.1 0.2 0.3\"/>");
    mjcf::parse(&t, "i.xml").unwrap();
    let u = "<robot name=\"r\">\n<link name=\"a\">\n<inertial><mass value=\"1\"/>\n\
             <inertia ixx=\"1\" iyy=\"1\" izz=\"3\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>\n</inertial></link>\n</robot>";
    refused(urdf::parse(u, "i.urdf"), 4, "inertia", &["triangle inequality"]);
}

#[test]
fn refuses_bad_axes_and_attribute_values() {
    let inertial = "<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1 1 1\"/>";
    for (attr, words) in [
        ("axis=\"0 0 0\"", "zero vector"),
        ("axis=\"nan 0 1\"", "not finite"),
        ("pos=\"1 2\"", "has 2 values, 3 expected"),
        ("pos=\"1 a 2\"", "`a` is not a number"),
        ("type=\"screw\"", "unknown joint type `screw`"),
    ] {
        let t = one_body(&format!("{inertial}\n<joint name=\"j\" {attr}/>"));
        refused(mjcf::parse(&t, "a.xml"), 5, "joint name=\"j\"", &[words]);
    }
    let u = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n\
             <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\n\
             <axis xyz=\"0 0 0\"/></joint>\n</robot>";
    refused(urdf::parse(u, "a.urdf"), 5, "axis", &["zero vector"]);
}

fn robot(joints: &str) -> String {
    let link = |n: &str| {
        format!(
            "<link name=\"{n}\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" \
             ixz=\"0\" iyz=\"0\"/></inertial></link>"
        )
    };
    format!(
        "<robot name=\"r\">\n{}\n{}\n{}\n{joints}\n</robot>",
        link("a"),
        link("b"),
        link("c")
    )
}

fn urdf_joint(name: &str, ty: &str, parent: &str, child: &str) -> String {
    format!("<joint name=\"{name}\" type=\"{ty}\"><parent link=\"{parent}\"/><child link=\"{child}\"/></joint>")
}

#[test]
fn refuses_broken_urdf_trees() {
    let j = |n, t, p, c| urdf_joint(n, t, p, c);
    let t = robot(&format!(
        "{}\n{}\n{}",
        j("j1", "continuous", "a", "b"),
        j("j2", "continuous", "a", "c"),
        j("j3", "continuous", "b", "c")
    ));
    refused(urdf::parse(&t, "t.urdf"), 7, "joint name=\"j3\"", &["two parents"]);
    let t = robot(&format!(
        "{}\n{}\n{}",
        j("j1", "continuous", "a", "b"),
        j("j2", "continuous", "b", "c"),
        j("j3", "continuous", "c", "a")
    ));
    refused(urdf::parse(&t, "t.urdf"), 5, "joint name=\"j1\"", &["cycle"]);
    let t = robot(&format!(
        "{}\n{}\n{}",
        j("j1", "continuous", "a", "b"),
        j("j2", "continuous", "c", "c"),
        ""
    ));
    refused(urdf::parse(&t, "t.urdf"), 6, "joint name=\"j2\"", &["cycle"]);
    let t = robot(&j("j1", "continuous", "a", "nowhere"));
    refused(
        urdf::parse(&t, "t.urdf"),
        5,
        "joint name=\"j1\"",
        &["child link `nowhere` is not defined"],
    );
    let t = robot(&format!(
        "{}\n{}",
        j("j1", "gear", "a", "b"),
        j("j2", "fixed", "b", "c")
    ));
    refused(
        urdf::parse(&t, "t.urdf"),
        5,
        "joint name=\"j1\"",
        &["unknown joint type `gear`"],
    );
    let t = robot(&format!(
        "{}\n{}",
        j("j1", "planar", "a", "b"),
        j("j2", "fixed", "b", "c")
    ));
    refused(urdf::parse(&t, "t.urdf"), 5, "joint name=\"j1\"", &["planar"]);
    // A massless link that would move.
    let t = robot(&format!(
        "{}\n{}\n<link name=\"d\"/>\n{}",
        j("j1", "fixed", "a", "b"),
        j("j2", "fixed", "b", "c"),
        j("j3", "continuous", "c", "d")
    ));
    refused(urdf::parse(&t, "t.urdf"), 8, "joint name=\"j3\"", &["no mass"]);
}

#[test]
fn refuses_what_maximal_coordinates_cannot_hold() {
    let t = one_body(
        "<joint name=\"x\" axis=\"1 0 0\"/>\n<joint name=\"y\" type=\"slide\" axis=\"0 1 0\"/>\n<geom size=\"1\"/>",
    );
    refused(mjcf::parse(&t, "u.xml"), 3, "body name=\"b\"", &["2 joints"]);
    let t = one_body("<joint/>\n<geom type=\"mesh\" mesh=\"shell\"/>");
    refused(mjcf::parse(&t, "u.xml"), 5, "geom", &["mesh geom `shell`"]);
    let t = one_body("<joint/>");
    refused(mjcf::parse(&t, "u.xml"), 3, "body name=\"b\"", &["no mass"]);
    let t = one_body("<joint range=\"0 1\" class=\"nope\"/>\n<geom size=\"1\"/>");
    refused(mjcf::parse(&t, "u.xml"), 4, "joint", &["unknown default class `nope`"]);
}

#[test]
fn refuses_doctype_deep_nesting_and_large_files() {
    let laughs = "<?xml version=\"1.0\"?>\n<!DOCTYPE lolz [\n <!ENTITY lol \"lol\">\n \
                  <!ENTITY lol2 \"&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;\">\n]>\n<mujoco>&lol2;</mujoco>";
    refused(mjcf::parse(laughs, "l.xml"), 2, "!DOCTYPE", &["refused"]);
    refused(urdf::parse(laughs, "l.urdf"), 2, "!DOCTYPE", &["refused"]);
    let depth = 100_000;
    let deep = format!("<mujoco>\n{}{}</mujoco>", "<a>".repeat(depth), "</a>".repeat(depth));
    let start = Instant::now();
    refused(mjcf::parse(&deep, "d.xml"), 2, "a", &["nested deeper than 200"]);
    assert!(start.elapsed().as_secs_f64() < 5.0);
    let big = format!("<mujoco>{}</mujoco>", " ".repeat(64 << 20));
    refused(mjcf::parse(&big, "big.xml"), 0, "", &["larger than the 64 MiB"]);
    refused(mjcf::load(&example("no_such_file.xml")), 0, "", &["cannot read"]);
    refused(
        mjcf::parse("<mujoco><worldbody></mujoco>", "x.xml"),
        1,
        "xml",
        &["not well-formed"],
    );
}

#[test]
fn keyframe_length_is_checked() {
    let t = "<mujoco>\n<worldbody><body><joint/><geom size=\"1\"/></body></worldbody>\n\
             <keyframe>\n<key qpos=\"0 1\"/>\n</keyframe>\n</mujoco>";
    refused(mjcf::parse(t, "k.xml"), 4, "key", &["has 2 values, 1 expected"]);
}

#[test]
fn a_long_attribute_is_abbreviated_in_the_error() {
    // 200,000 numbers where three are expected: the message names the count and shows the
    // value's start, not 400 KB of it.
    let numbers = vec!["0.5"; 200_000].join(" ");
    let t = one_body(&format!(
        "<inertial pos=\"{numbers}\" mass=\"1\" diaginertia=\"1 1 1\"/>"
    ));
    let e = mjcf::parse(&t, "long.xml").unwrap_err().to_string();
    assert!(e.len() < 300, "{} characters: {}", e.len(), &e[..300.min(e.len())]);
    assert!(
        e.contains("has 200000 values, 3 expected") && e.contains("characters)"),
        "{e}"
    );
}

/// The shapes a file draws: the scene's floor on the world with its material's colour, the
/// humanoid's capsules and spheres on their bodies (posed in the body's frame: a `fromto`
/// capsule centred between its ends and turned along them), a geom's own `rgba` before its
/// material's, `group`, and meshes noted as not drawn.
#[test]
fn the_shapes_of_a_scene_are_read_with_their_poses_and_colours() {
    let l = mjcf::load(&example("humanoid_scene.xml")).unwrap();
    let floor: Vec<_> = l.shapes.iter().filter(|s| s.body.is_none()).collect();
    assert_eq!(floor.len(), 1);
    assert_eq!(floor[0].kind, ShapeKind::Plane { half: [0.0, 0.0] });
    assert_eq!(floor[0].rgba, [0.25, 0.3, 0.38, 1.0]);
    assert!(l.shapes.iter().filter(|s| s.body.is_some()).count() >= l.model.bodies.len());
    let text = r#"<mujoco><asset><material name="m" rgba="0 1 0 1"/></asset><worldbody>
        <body name="b" pos="0 0 1"><joint type="ball"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
          <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.05" material="m" rgba="1 0 0 0.5" group="3"/>
          <geom type="mesh" mesh="x"/>
        </body></worldbody></mujoco>"#;
    let l = mjcf::parse(text, "shapes.xml").unwrap();
    assert_eq!(l.shapes.len(), 2, "{:?}", l.shapes);
    // A mesh geom naming no declared mesh: a shape that says why it cannot be drawn.
    match &l.shapes[1].kind {
        ShapeKind::Mesh { file, path, half, .. } => {
            assert_eq!((file.as_str(), half), ("x", &None));
            assert!(path.as_ref().unwrap_err().contains("no <mesh name=\"x\">"), "{path:?}");
        }
        other => panic!("{other:?}"),
    }
    let s = &l.shapes[0];
    assert_eq!(s.body, Some(0));
    assert_eq!(
        s.kind,
        ShapeKind::Capsule {
            radius: 0.05,
            half_length: 0.2
        }
    );
    close_v(s.position, Vec3::new(0.2, 0.0, 0.0), 1e-15);
    close_v(s.rotation * Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0), 1e-15);
    assert_eq!(
        (s.rgba, s.group, s.shown_by_default()),
        ([1.0, 0.0, 0.0, 0.5], 3, false)
    );
    let bad = text.replace("rgba=\"1 0 0 0.5\"", "rgba=\"2 0 0 1\"");
    let e = mjcf::parse(&bad, "shapes.xml").unwrap_err().to_string();
    assert!(e.contains("rgba: each component must lie in [0, 1]"), "{e}");
}

/// The arm's mesh geoms: each asset's file found under `compiler meshdir` relative to the
/// main file (through the scene that includes it), listed among the model's files after the
/// XML files, a default class's mesh `scale` applied, and posed by the geom's own frame.
#[test]
fn mesh_geoms_find_their_files_as_mujoco_does_and_list_them_as_inputs() {
    let l = mjcf::load(&example("arm_scene.xml")).unwrap();
    let meshes: Vec<_> = l
        .shapes
        .iter()
        .filter_map(|s| match &s.kind {
            ShapeKind::Mesh { file, path, .. } => Some((s, file.as_str(), path.as_ref().unwrap())),
            _ => None,
        })
        .collect();
    let files: Vec<&str> = meshes.iter().map(|m| m.1).collect();
    assert_eq!(files, ["link0.stl", "link1.stl", "link2.stl", "hand.obj"]);
    for (s, file, path) in &meshes {
        assert!(
            path.ends_with(format!("multibody/meshes/{file}")) && path.is_file(),
            "{}",
            path.display()
        );
        assert!(l.files.contains(path));
        assert_eq!((s.group, s.position), (2, Vec3::ZERO));
    }
    assert!(l.files[0].ends_with("arm_scene.xml") && l.files[1].ends_with("arm.xml"));
    assert_eq!(l.files.len(), 6);
    let text = r#"<mujoco><compiler meshdir="/abs"/><default><mesh scale="2 2 2"/></default>
        <asset><mesh file="a/part.stl"/><mesh name="m" file="b.obj" scale="1 1 3"/></asset><worldbody>
        <body><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/><joint type="ball"/>
          <geom type="mesh" mesh="part" size="1 2 3"/><geom name="g" type="mesh" mesh="m"/></body>
        </worldbody></mujoco>"#;
    let l = mjcf::parse(text, "m.xml").unwrap();
    match (&l.shapes[0].kind, &l.shapes[1].kind) {
        (
            ShapeKind::Mesh {
                name: n0,
                scale: s0,
                half: h0,
                path: p0,
                ..
            },
            ShapeKind::Mesh {
                name: n1,
                scale: s1,
                half: h1,
                ..
            },
        ) => {
            assert_eq!((n0.as_str(), *s0, *h0), ("part", [2.0; 3], Some([1.0, 2.0, 3.0])));
            assert_eq!((n1.as_str(), *s1, *h1), ("g", [1.0, 1.0, 3.0], None));
            // Parsed from text: no directory to find the file in.
            assert!(p0.as_ref().unwrap_err().contains("parsed from text"));
        }
        other => panic!("{other:?}"),
    }
    assert!(l.files.is_empty());
}
