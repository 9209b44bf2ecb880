//! Actuators (docs/theory/multibody.md §8): a motor's constant torque does work equal to
//! the energy change to O(h²); a position actuator holds an arm at its keyframe control
//! against gravity; the clamps in MuJoCo's order; the joint-space reference agrees; bad
//! input is refused naming the actuator.

use liemid::multibody::joint_space::JointSpaceModel;
use liemid::multibody::{mjcf, Model, MultibodyMethod, Simulation};

/// A rod (1 kg, centre 0.5 m from the hinge, I about the hinge 0.25 + 0.01) on a hinge to the
/// world about y, with the actuators `acts` (MJCF text) and the keyframe `key`.
fn arm(acts: &str, key: &str, joint_extra: &str) -> Model {
    let text = format!(
        "<mujoco><compiler angle=\"radian\"/><worldbody><body name=\"rod\">\
         <joint name=\"shoulder\" axis=\"0 1 0\" {joint_extra}/>\
         <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/></body></worldbody>\
         <actuator>{acts}</actuator><keyframe><key {key}/></keyframe></mujoco>"
    );
    mjcf::parse(&text, "arm.xml").unwrap().model
}

fn angle(sim: &Simulation, s: &liemid::multibody::MultibodyState) -> f64 {
    sim.system.joint_coordinate(s, 0).unwrap()
}

#[test]
fn a_motor_does_the_work_of_its_torque_to_second_order() {
    // A constant torque 3 N m under gravity: the energy change equals τ Δq, to O(h²).
    let mut errors = Vec::new();
    for h in [2e-3f64, 1e-3] {
        let model = arm("<motor joint=\"shoulder\" gear=\"1.5\"/>", "ctrl=\"2\"", "");
        let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
        let (mut sim, mut s) = (prepared.simulation, prepared.state);
        let (e0, q0) = (sim.system.energy(&s), angle(&sim, &s));
        let mut worst: f64 = 0.0;
        let mut unwrapped = q0;
        let mut last = q0;
        for _ in 0..(0.5 / h).round() as usize {
            sim.step(&mut s, h).unwrap();
            let q = angle(&sim, &s);
            let mut dq = q - last;
            dq -= (dq / std::f64::consts::TAU).round() * std::f64::consts::TAU;
            unwrapped += dq;
            last = q;
            let work = 3.0 * (unwrapped - q0);
            worst = worst.max((sim.system.energy(&s) - e0 - work).abs());
        }
        errors.push(worst);
    }
    let order = (errors[0] / errors[1]).log2();
    assert!(
        errors[1] < 2e-4 && (order - 2.0).abs() < 0.1,
        "errors {errors:?}, order {order}"
    );
}

#[test]
fn a_position_actuator_holds_the_arm_at_its_keyframe_control() {
    // kp = 500 against gravity's torque m g l = 4.905 N m at q = 0.3: the arm settles at
    // the angle where kp (u − q) balances gravity, with the joint damping; liemid and the
    // joint-space RK4 agree.
    let model = arm(
        "<position joint=\"shoulder\" kp=\"500\"/>",
        "qpos=\"0.3\" ctrl=\"0.3\"",
        "damping=\"5\"",
    );
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let h = 1e-3;
    sim.integrate(&mut s, 3.0, h, |_, _, _, _| Ok(())).unwrap();
    let q = angle(&sim, &s);
    // Statics about y: gravity's torque on the rod at angle q is −m g l cos q... about +y a
    // positive q lowers the tip (x → −z), so the torque is m g 0.5 cos q.
    let residual = 500.0 * (0.3 - q) + 9.81 * 0.5 * q.cos();
    assert!(residual.abs() < 1e-6, "q = {q}, residual torque {residual}");
    let mut js = JointSpaceModel::new(&model).unwrap();
    let (mut qq, mut vv) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    js.integrate_rk4(&mut qq, &mut vv, (0.0, 3.0, h), |_, _, _, _| Ok(()))
        .unwrap();
    assert!((qq[0] - q).abs() < 1e-8, "rk4 {} against liemid {q}", qq[0]);
}

#[test]
fn clamps_apply_in_mujocos_order() {
    // ctrl 10 clamped to 2, force 2·kp... motor: force = u clamped to [−1.5, 1.5], times
    // gear 2 = 3, then the joint's actuatorfrcrange clamps the sum 3 + 3 to 4.
    let model = arm(
        "<motor joint=\"shoulder\" gear=\"2\" ctrlrange=\"-2 2\" forcerange=\"-1.5 1.5\"/>\
         <motor joint=\"shoulder\" gear=\"2\" ctrlrange=\"-2 2\" forcerange=\"-1.5 1.5\"/>",
        "ctrl=\"10 1\"",
        "actuatorfrcrange=\"-4 4\"",
    );
    let mut zero_g = model.clone();
    zero_g.gravity = liemid::Vec3::ZERO;
    let prepared = Simulation::prepare(&zero_g, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let h = 1e-3;
    sim.integrate(&mut s, 0.1, h, |_, _, _, _| Ok(())).unwrap();
    // τ = min(3 + 2·1, 4) = 4 on I = 0.26: q = ½ (4/0.26) t², to the step's O(h²) (the
    // centre of mass turns on a circle).
    let expected = 0.5 * 4.0 / 0.26 * 0.01;
    assert!(
        (angle(&sim, &s) - expected).abs() < 1e-7,
        "{} vs {expected}",
        angle(&sim, &s)
    );
    let mut js = JointSpaceModel::new(&zero_g).unwrap();
    let (mut qq, mut vv) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    js.integrate_rk4(&mut qq, &mut vv, (0.0, 0.1, h), |_, _, _, _| Ok(()))
        .unwrap();
    assert!((qq[0] - expected).abs() < 1e-12, "{} vs {expected}", qq[0]);
    // The control set later is held over the following steps.
    sim.set_ctrl(&[0.0, 0.0]).unwrap();
    let v = s.pi[0].y;
    sim.step(&mut s, h).unwrap();
    assert!((s.pi[0].y - v).abs() < 1e-13);
}

#[test]
fn bad_actuator_input_is_refused_naming_it() {
    let parse = |acts: &str, key: &str| {
        let text = format!(
            "<mujoco><worldbody><body name=\"rod\"><joint name=\"shoulder\" axis=\"0 1 0\"/>\
             <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/></body></worldbody>\
             <actuator>{acts}</actuator><keyframe><key {key}/></keyframe></mujoco>"
        );
        mjcf::parse(&text, "bad.xml").map(|l| l.model)
    };
    let err = parse("<motor name=\"m\" joint=\"elbow\"/>", "")
        .unwrap_err()
        .to_string();
    assert!(err.contains("`m`") && err.contains("`elbow`"), "{err}");
    let err = parse("<position name=\"p\" joint=\"shoulder\" kp=\"-3\"/>", "")
        .unwrap_err()
        .to_string();
    assert!(err.contains("`p`") && err.contains("negative kp"), "{err}");
    let err = parse("<motor name=\"m\" joint=\"shoulder\" forcerange=\"1 -1\"/>", "")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`m`") && err.contains("forcerange") && err.contains("upside down"),
        "{err}"
    );
    let err = parse("<motor name=\"m\" joint=\"shoulder\"/>", "ctrl=\"1 2\"")
        .unwrap_err()
        .to_string();
    assert!(err.contains("ctrl"), "{err}");
    let model = parse("<motor name=\"m\" joint=\"shoulder\"/>", "ctrl=\"1\"").unwrap();
    let mut sim = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap().simulation;
    let err = sim.set_ctrl(&[f64::NAN]).unwrap_err().to_string();
    assert!(err.contains("`m`") && err.contains("NaN"), "{err}");
    let err = sim.set_ctrl(&[1.0, 2.0]).unwrap_err().to_string();
    assert!(err.contains("2 values") && err.contains("1 actuators"), "{err}");
    // Not simulated: listed, and its keyframe control dropped.
    let text = "<mujoco><worldbody><body name=\"rod\"><joint name=\"shoulder\" axis=\"0 1 0\"/>\
             <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/></body></worldbody>\
             <tendon><fixed name=\"t\"><joint joint=\"shoulder\" coef=\"1\"/></fixed></tendon>\
             <actuator><motor tendon=\"t\"/><muscle joint=\"shoulder\"/><motor joint=\"shoulder\"/></actuator>\
             <keyframe><key ctrl=\"1 2 3\"/></keyframe></mujoco>";
    let loaded = mjcf::parse(text, "skip.xml").unwrap();
    assert_eq!(loaded.model.ctrl, Some(vec![3.0]));
    assert!(
        loaded.ignored.iter().any(|i| i.contains("tendon transmission")),
        "{:?}",
        loaded.ignored
    );
    assert!(
        loaded.ignored.iter().any(|i| i.contains("muscle")),
        "{:?}",
        loaded.ignored
    );
}

#[test]
fn rows_the_method_cannot_hold_are_refused_before_the_first_step() {
    // A servo of kp = 1e6 on I = 0.26 (ω = 1961 rad/s): liemid (Verlet's ω h < 2) holds it
    // below h = 1.02e-3 and is refused above, naming the joint and the largest step.
    let model = arm(
        "<position joint=\"shoulder\" kp=\"1e6\"/>",
        "qpos=\"0.1\" ctrl=\"0.1\"",
        "",
    );
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let start = s.clone();
    let err = sim
        .integrate(&mut s, 0.1, 2e-3, |_, _, _, _| Ok(()))
        .unwrap_err()
        .to_string();
    assert!(err.contains("`shoulder`") && err.contains("largest step"), "{err}");
    assert_eq!(s.c, start.c, "refused before the first step");
    let largest: f64 = err
        .split("holds it is about ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let omega = (1e6f64 / 0.26).sqrt();
    assert!(largest < 2.0 / omega && largest > 0.95 * 2.0 / omega, "{largest}");
    sim.integrate(&mut s, 0.1, 0.9 * largest, |_, _, _, _| Ok(())).unwrap();
    // A stiff damper (kv = 500, x = h d / (2 I) ≈ 1 at h = 1e-3) with liemid4: the negative
    // sub-step has no solution; refused, and liemid holds it.
    let model = arm("<velocity joint=\"shoulder\" kv=\"500\"/>", "ctrl=\"0\"", "");
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid4).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let err = sim
        .integrate(&mut s, 0.1, 1e-2, |_, _, _, _| Ok(()))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`shoulder`") && err.to_lowercase().contains("liemid4"),
        "{err}"
    );
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    sim.integrate(&mut s, 0.1, 1e-2, |_, _, _, _| Ok(())).unwrap();
}

#[test]
fn a_servo_with_kv_and_a_clamp_is_noted() {
    let model = arm(
        "<position joint=\"shoulder\" kp=\"50\" kv=\"5\" forcerange=\"-3 3\"/>",
        "ctrl=\"0.5\"",
        "",
    );
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    assert!(
        prepared
            .notes
            .contains(&liemid::multibody::ModelNote::ActuatorDampingUnclamped { actuators: 1 }),
        "{:?}",
        prepared.notes
    );
    // Without the clamp, no note.
    let model = arm("<position joint=\"shoulder\" kp=\"50\" kv=\"5\"/>", "ctrl=\"0.5\"", "");
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    assert!(prepared.notes.is_empty(), "{:?}", prepared.notes);
}
