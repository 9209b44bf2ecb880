//! Joint dry friction (`frictionloss`, docs/theory/multibody.md §8): a hinge under a torque
//! below its friction does not move; above it, it accelerates at exactly `(τ − f)/I`; a
//! pendulum held by friction stays, and released by a larger push it swings and stops;
//! the joint-space methods refuse it.

use liemid::multibody::joint_space::JointSpaceModel;
use liemid::multibody::{mjcf, Model, MultibodyMethod, Simulation};

/// A wheel (I_zz = 0.2 kg m², centre on the axis) on a hinge about z, no gravity, with
/// frictionloss `f` and a motor of constant torque `tau` (its keyframe ctrl).
fn wheel(f: f64, tau: f64) -> Model {
    let text = format!(
        "<mujoco><option gravity=\"0 0 0\"/><worldbody><body name=\"wheel\">\
         <joint name=\"axle\" axis=\"0 0 1\" frictionloss=\"{f}\"/>\
         <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.5 0.5 0.2\"/></body></worldbody>\
         <actuator><motor joint=\"axle\"/></actuator><keyframe><key ctrl=\"{tau}\"/></keyframe></mujoco>"
    );
    mjcf::parse(&text, "wheel.xml").unwrap().model
}

#[test]
fn a_torque_below_the_friction_does_not_move_the_hinge() {
    for method in [MultibodyMethod::Liemid, MultibodyMethod::Liemid4] {
        let model = wheel(1.0, 0.8);
        let prepared = Simulation::prepare(&model, method).unwrap();
        let (mut sim, mut s) = (prepared.simulation, prepared.state);
        let mut worst: f64 = 0.0;
        for _ in 0..10_000 {
            sim.step(&mut s, 1e-3).unwrap();
            worst = worst.max(sim.system.joint_coordinate(&s, 0).unwrap().abs());
        }
        assert!(worst <= 1e-12, "{method:?}: moved {worst:e} rad");
    }
}

#[test]
fn a_torque_above_the_friction_accelerates_at_its_excess() {
    let (f, tau, h) = (1.0, 1.5, 1e-3);
    let model = wheel(f, tau);
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let a = (tau - f) / 0.2;
    for k in 1..=1000 {
        sim.step(&mut s, h).unwrap();
        let t = k as f64 * h;
        let q = sim.system.joint_coordinate(&s, 0).unwrap();
        let w = sim.system.joint_rate(&s, 0).unwrap();
        assert!(
            (q - 0.5 * a * t * t).abs() <= 1e-12 * (1.0 + q.abs()),
            "t = {t}: q = {q}"
        );
        assert!((w - a * t).abs() <= 1e-12 * (1.0 + w.abs()), "t = {t}: rate {w}");
    }
}

#[test]
fn a_pendulum_held_by_friction_stays_and_a_pushed_one_stops() {
    // A rod at 0.3 rad from the horizontal... gravity's torque m g l cos q = 4.69 N m.
    let text = |f: f64, qvel: f64| {
        format!(
            "<mujoco><compiler angle=\"radian\"/><worldbody><body name=\"rod\">\
             <joint name=\"pin\" axis=\"0 1 0\" frictionloss=\"{f}\"/>\
             <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/></body></worldbody>\
             <keyframe><key qpos=\"0.3\" qvel=\"{qvel}\"/></keyframe></mujoco>"
        )
    };
    let model = mjcf::parse(&text(5.0, 0.0), "rod.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    sim.integrate(&mut s, 2.0, 1e-3, |_, _, _, _| Ok(())).unwrap();
    let q = sim.system.joint_coordinate(&s, 0).unwrap();
    assert!((q - 0.3).abs() < 1e-12, "held: {q}");
    // Pushed at 3 rad/s against friction 20 N m: it slows, stops and sticks.
    let model = mjcf::parse(&text(20.0, 3.0), "rod.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    sim.integrate(&mut s, 1.0, 1e-3, |_, _, _, _| Ok(())).unwrap();
    let q1 = sim.system.joint_coordinate(&s, 0).unwrap();
    sim.integrate(&mut s, 2.0, 1e-3, |_, _, _, _| Ok(())).unwrap();
    let q2 = sim.system.joint_coordinate(&s, 0).unwrap();
    assert!(q1 > 0.35 && (q2 - q1).abs() < 1e-12, "q1 {q1}, q2 {q2}");
    // The joint-space methods refuse friction, naming the joint.
    let err = JointSpaceModel::new(&model).unwrap_err().to_string();
    assert!(err.contains("`pin`") && err.contains("frictionloss"), "{err}");
}

#[test]
fn actuated_friction_steps_allocate_nothing() {
    use crate::thread_counting::allocations;
    // A two-link arm with servos (kp, kv), a clamp, friction on both joints, a control set
    // between steps.
    let text = "<mujoco><compiler angle=\"radian\"/><worldbody><body name=\"a\">\
         <joint name=\"j1\" axis=\"0 1 0\" frictionloss=\"0.3\" damping=\"0.2\"/>\
         <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/>\
         <body name=\"b\" pos=\"1 0 0\"><joint name=\"j2\" axis=\"0 1 0\" frictionloss=\"0.1\"/>\
         <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/></body></body></worldbody>\
         <actuator><position joint=\"j1\" kp=\"50\" kv=\"2\" forcerange=\"-20 20\"/>\
         <motor joint=\"j2\"/></actuator></mujoco>";
    let model = mjcf::parse(text, "arm2.xml").unwrap().model;
    for method in [MultibodyMethod::Liemid, MultibodyMethod::Liemid4] {
        let prepared = Simulation::prepare(&model, method).unwrap();
        let (mut sim, mut s) = (prepared.simulation, prepared.state);
        sim.step(&mut s, 1e-3).unwrap();
        let u = [[0.3, 0.5], [0.2, -0.5]];
        let before = allocations();
        for k in 0..100 {
            sim.set_ctrl(&u[k % 2]).unwrap();
            sim.step(&mut s, 1e-3).unwrap();
        }
        assert_eq!(allocations() - before, 0, "{} allocates", method.name());
    }
}
