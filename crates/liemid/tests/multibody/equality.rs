//! MJCF `<equality>` `connect` and `weld` as exact loop-closing joints: the four-bar written
//! with a `connect` moves as the built-in four-bar closed by a hinge; anchors and relative
//! poses by hand; the projection of a start that does not close its loop; refusals.

use crate::model_files;
use model_files::refused;
use std::path::PathBuf;

use liemid::multibody::{mjcf, problems, JointKind, Link, Model, MultibodyMethod, Simulation};
use liemid::{Mat3, Vec3};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/multibody")
        .join(name)
}

#[track_caller]
fn close_v(a: Vec3, b: Vec3, tol: f64) {
    assert!((a - b).max_abs() <= tol, "{a:?} != {b:?}");
}

/// Joint coordinates of the tree joints after `n` steps of `h`, and the largest constraint
/// violation on the way.
fn run(model: &Model, h: f64, n: usize) -> (Vec<f64>, f64) {
    let mut sys = Simulation::new(model, MultibodyMethod::Liemid).unwrap();
    let mut s = model.initial_state().unwrap();
    let mut worst: f64 = 0.0;
    for _ in 0..n {
        let r = sys.step(&mut s, h).unwrap();
        worst = worst.max(r.position_violation).max(r.velocity_violation);
    }
    let q = (0..model.tree_joint_count())
        .map(|k| sys.system.joint_coordinate(&s, k).unwrap())
        .collect();
    (q, worst)
}

#[test]
fn a_connect_closes_the_four_bar_as_the_built_in_hinge_does() {
    let loaded = mjcf::load(&example("four_bar.xml")).unwrap();
    let m = &loaded.model;
    assert_eq!((m.bodies.len(), m.joints.len()), (3, 4));
    let d = &m.joints[3];
    assert_eq!(
        (d.name.as_str(), d.kind, d.parent, d.child),
        ("D", JointKind::Ball, Link::World, 2)
    );
    close_v(d.anchor_parent, Vec3::new(1.0, 0.0, 0.0), 1e-14);
    close_v(d.anchor_child, Vec3::new(0.8, 0.0, 0.0), 0.0);
    assert!(
        loaded.ignored.iter().any(|k| k.starts_with("equality solref")),
        "{:?}",
        loaded.ignored
    );
    // Same mechanism, other loop rows (a ball of 3 rows against a hinge of 5): RATTLE's
    // step depends only on the constraint manifold, so the motions agree to round-off.
    let (q_connect, worst) = run(m, 1e-3, 2000);
    let (q_hinge, _) = run(&problems::closed_loop(), 1e-3, 2000);
    assert!(worst < 1e-12, "constraints {worst:e}");
    for (a, b) in q_connect.iter().zip(&q_hinge) {
        assert!((a - b).abs() < 1e-12, "{q_connect:?} against {q_hinge:?}");
    }
    assert!(q_connect[0].abs() > 0.1, "it moved");
}

fn two_bodies(equality: &str) -> String {
    format!(
        "<mujoco>\n<worldbody>\n<body name=\"a\">\n<freejoint/>\n<geom size=\"0.1\"/>\n</body>\n\
         <body name=\"b\" pos=\"1 0 0\" euler=\"0 0 90\">\n<freejoint/>\n<geom size=\"0.1\"/>\n</body>\n\
         <body name=\"ghost\" pos=\"0 1 0\"/>\n</worldbody>\n<equality>\n{equality}\n</equality>\n</mujoco>"
    )
}

fn rz(degrees: f64) -> Mat3 {
    let (s, c) = degrees.to_radians().sin_cos();
    Mat3::from_rows([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
}

#[test]
fn anchors_and_relative_poses_by_hand() {
    // connect: the anchor (0.5, 0.2, 0) of `a` is, in the reference pose, the point
    // Rz(90)ᵀ((0.5, 0.2, 0) − (1, 0, 0)) = (0.2, 0.5, 0) of `b`.
    let m = mjcf::parse(
        &two_bodies("<connect body1=\"a\" body2=\"b\" anchor=\"0.5 0.2 0\"/>"),
        "c.xml",
    )
    .unwrap()
    .model;
    let j = &m.joints[2];
    assert_eq!(
        (j.kind, j.parent, j.child, j.name.as_str()),
        (JointKind::Ball, Link::Body(1), 0, "connect a-b")
    );
    close_v(j.anchor_parent, Vec3::new(0.2, 0.5, 0.0), 1e-15);
    close_v(j.anchor_child, Vec3::new(0.5, 0.2, 0.0), 0.0);
    // weld at the reference pose: b in a's frame is (1, 0, 0) turned by Rz(90); the weld
    // point (0.1, 0, 0) of b is (1, 0.1, 0) in a.
    let m = mjcf::parse(
        &two_bodies("<weld body1=\"a\" body2=\"b\" anchor=\"0.1 0 0\"/>"),
        "w.xml",
    )
    .unwrap()
    .model;
    let j = &m.joints[2];
    assert_eq!((j.kind, j.parent, j.child), (JointKind::Weld, Link::Body(0), 1));
    assert!((j.reference_rotation - rz(90.0)).max_abs() < 1e-15);
    close_v(j.anchor_parent, Vec3::new(1.0, 0.1, 0.0), 1e-15);
    // weld with relpose (quaternion (0, 0, 0, 1): Rz(180)).
    let m = mjcf::parse(
        &two_bodies("<weld body1=\"a\" body2=\"b\" relpose=\"0 2 0 0 0 0 1\" anchor=\"0.1 0 0\"/>"),
        "w.xml",
    )
    .unwrap()
    .model;
    let j = &m.joints[2];
    assert!((j.reference_rotation - rz(180.0)).max_abs() < 1e-15);
    // As MuJoCo: b's point (0.1, 0, 0) held on a's point (0, 2, 0): b's origin at (0.1, 2, 0).
    close_v(j.anchor_parent, Vec3::new(0.0, 2.0, 0.0), 0.0);
    close_v(j.anchor_child, Vec3::new(0.1, 0.0, 0.0), 0.0);
    close_v(
        j.anchor_parent - j.reference_rotation * j.anchor_child,
        Vec3::new(0.1, 2.0, 0.0),
        1e-15,
    );
    // connect from the world (body1 = world): the world point (1, 0.5, 0) on b.
    let m = mjcf::parse(
        &two_bodies("<connect body1=\"world\" body2=\"b\" anchor=\"1 0.5 0\"/>"),
        "c.xml",
    )
    .unwrap()
    .model;
    let j = &m.joints[2];
    assert_eq!((j.parent, j.child), (Link::World, 1));
    close_v(j.anchor_parent, Vec3::new(1.0, 0.5, 0.0), 0.0);
    close_v(j.anchor_child, Vec3::new(0.5, 0.0, 0.0), 1e-15);
    // weld of b to the world: b's pose in the world.
    let m = mjcf::parse(&two_bodies("<weld body1=\"b\"/>"), "w.xml").unwrap().model;
    let j = &m.joints[2];
    assert_eq!((j.kind, j.parent, j.child), (JointKind::Weld, Link::World, 1));
    assert!((j.reference_rotation - rz(90.0)).max_abs() < 1e-15);
    close_v(j.anchor_parent, Vec3::ZERO, 0.0);
    close_v(j.anchor_child, Vec3::new(0.0, 1.0, 0.0), 1e-15);
}

#[test]
fn other_equalities_are_named_and_inactive_ones_skipped() {
    let t = two_bodies(
        "<joint joint1=\"x\" joint2=\"y\"/>\n<connect body1=\"a\" body2=\"b\" anchor=\"0 0 0\" active=\"false\"/>",
    );
    let loaded = mjcf::parse(&t, "e.xml").unwrap();
    assert_eq!(loaded.model.joints.len(), 2);
    for kind in ["equality joint", "inactive equality"] {
        assert!(
            loaded.ignored.iter().any(|k| k == kind),
            "{kind} not in {:?}",
            loaded.ignored
        );
    }
}

#[test]
fn refuses_unknown_merged_and_site_bodies() {
    let line = 14;
    for (eq, words) in [
        (
            "<connect body1=\"a\" body2=\"nobody\" anchor=\"0 0 0\"/>",
            &["body2 `nobody` is not a body"][..],
        ),
        ("<connect anchor=\"0 0 0\"/>", &["needs body1 or body2"]),
        ("<connect body1=\"a\" body2=\"a\" anchor=\"0 0 0\"/>", &["to itself"]),
        ("<connect body1=\"a\" body2=\"b\"/>", &["needs an anchor"]),
        ("<connect site1=\"s\" site2=\"t\" anchor=\"0 0 0\"/>", &["site-based"]),
        (
            "<connect body1=\"a\" body2=\"ghost\" anchor=\"0 0 0\"/>",
            &["merged into `world`"],
        ),
        ("<weld body1=\"a\" body2=\"b\" relpose=\"0 0 0 1 2\"/>", &["relpose"]),
    ] {
        refused(mjcf::parse(&two_bodies(eq), "r.xml"), line, "", words);
    }
}

#[test]
fn a_start_off_the_loop_is_projected_onto_it() {
    let mut m = mjcf::load(&example("four_bar.xml")).unwrap().model;
    // The crank turned by 0.01 rad with the rest as in the reference: the loop is open.
    m.qpos = Some(vec![0.01, 0.0, 0.0]);
    let mut sys = Simulation::new(&m, MultibodyMethod::Liemid).unwrap();
    let mut s = m.initial_state().unwrap();
    let before = sys.project_positions(&mut s).unwrap();
    assert!(before > 1e-3, "{before}");
    let (after, _) = sys.constraint_violation(&s);
    assert!(after <= 1e-14, "{after:e}");
    sys.project_velocities(&mut s).unwrap();
    for _ in 0..100 {
        let r = sys.step(&mut s, 1e-3).unwrap();
        assert!(r.position_violation < 1e-12);
    }
    // 1 km from the origin the positions' round-off (about 1e-13 m) is above 1e-14 of the
    // links: the projection stops where its decrease stalls, well inside 1e-10.
    let text = std::fs::read_to_string(example("four_bar.xml")).unwrap();
    let far = text.replace("<body name=\"crank\" ", "<body name=\"crank\" pos=\"1000 0 0\" ");
    let mut m = mjcf::parse(&far, "far.xml").unwrap().model;
    m.qpos = Some(vec![0.01, 0.0, 0.0]);
    let mut sys = Simulation::new(&m, MultibodyMethod::Liemid).unwrap();
    let (s, before, _) = sys.initial_state_on_loops(&m).unwrap();
    let (after, _) = sys.constraint_violation(&s);
    assert!(before > 1e-3 && after <= 1e-10, "{before:e} -> {after:e}");
}
