//! Ball-joint springs (MJCF `stiffness` on a ball: the torque `−k θ`, `θ` the rotation
//! vector of the joint's relative attitude, the gradient of `½ k |θ|²`): a pinned isotropic
//! body oscillates at `√(k/I)` as the closed form says; the spatial test chain with a ball
//! spring converges to the joint-space reference at orders 2 and 4 and keeps its energy
//! (error O(h²), no drift).

use liemid::multibody::joint_space::JointSpaceModel;
use liemid::multibody::{mjcf, problems, Model, MultibodyMethod, Simulation};

#[test]
fn a_pinned_ball_on_a_spring_oscillates_at_the_closed_form_frequency() {
    // I = 0.2 about every axis, k = 5: ω = 5 rad/s; from θ = 0.4 rad about (1, 2, 2)/3 at
    // rest, θ(t) = 0.4 cos(5 t) about that axis (the motion stays on it).
    let (k, inertia, amplitude) = (5.0f64, 0.2f64, 0.4f64);
    let axis = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let (s, c) = (0.5 * amplitude).sin_cos();
    let text = format!(
        "<mujoco><option gravity=\"0 0 0\"/><worldbody><body name=\"ball\">\
         <joint name=\"pin\" type=\"ball\" stiffness=\"{k}\"/>\
         <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"{inertia} {inertia} {inertia}\"/></body></worldbody>\
         <keyframe><key qpos=\"{c} {} {} {}\"/></keyframe></mujoco>",
        s * axis[0],
        s * axis[1],
        s * axis[2]
    );
    let loaded = mjcf::parse(&text, "spring.xml").unwrap();
    assert!(loaded.ignored.is_empty(), "{:?}", loaded.ignored);
    let model = loaded.model;
    let omega = (k / inertia).sqrt();
    let t_end = 2.0;
    let mut errors = Vec::new();
    for h in [4e-3f64, 2e-3, 1e-3] {
        let mut sys = Simulation::new(&model, MultibodyMethod::Liemid).unwrap();
        let mut st = model.initial_state().unwrap();
        let e0 = sys.system.energy(&st);
        assert!((e0 - 0.5 * k * amplitude * amplitude).abs() < 1e-15, "{e0}");
        let n = (t_end / h).round() as usize;
        let mut worst: f64 = 0.0;
        for step in 1..=n {
            sys.step(&mut st, h).unwrap();
            let theta = liemid::so3::log(&st.rotation[0]);
            let exact = amplitude * (omega * step as f64 * h).cos();
            let along = theta.x * axis[0] + theta.y * axis[1] + theta.z * axis[2];
            worst = worst.max((along - exact).abs());
            // It stays on the axis.
            assert!((theta - liemid::Vec3::from_array(axis) * along).max_abs() < 1e-12);
        }
        errors.push(worst);
    }
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("ball spring against the closed form: errors {errors:?}, orders {orders:?}");
    for p in &orders {
        assert!((p - 2.0).abs() < 0.1, "{orders:?}");
    }
}

fn sprung_test_chain() -> Model {
    let mut m = problems::test_chain();
    m.joints[2].stiffness = 3.0;
    m
}

/// The largest body-origin difference at `t_end` between liemid at `h` and `reference`.
fn error(model: &Model, method: MultibodyMethod, h: f64, t_end: f64, reference: &[(liemid::Vec3, f64)]) -> f64 {
    let mut sys = Simulation::new(model, method).unwrap();
    let mut s = model.initial_state().unwrap();
    for _ in 0..(t_end / h).round() as usize {
        sys.step(&mut s, h).unwrap();
    }
    (0..s.len())
        .map(|i| (sys.system.frame_origin(&s, i) - reference[i].0).max_abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_ball_spring_chain_converges_to_the_joint_space_reference_and_keeps_its_energy() {
    let model = sprung_test_chain();
    let t_end = 1.0;
    let mut js = JointSpaceModel::new(&model).unwrap();
    let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    for _ in 0..10_000 {
        js.rk4_step(&mut q, &mut v, 1e-4).unwrap();
    }
    let reference: Vec<_> = js.body_poses(&q).unwrap().into_iter().map(|(x, _)| (x, 0.0)).collect();
    for (method, hs, order) in [
        (MultibodyMethod::Liemid, vec![5e-3, 2.5e-3, 1.25e-3], 2.0),
        (MultibodyMethod::Liemid4, vec![2e-2, 1e-2, 5e-3], 4.0),
    ] {
        let errors: Vec<f64> = hs
            .iter()
            .map(|&h| error(&model, method, h, t_end, &reference))
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!("{}: errors {errors:?}, orders {orders:?}", method.name());
        for p in &orders {
            assert!((p - order).abs() < 0.1, "{}: {orders:?}", method.name());
        }
    }
    // Energy (the spring's potential included): O(h²), halving the step quarters it.
    let worst = |h: f64| {
        let mut sys = Simulation::new(&model, MultibodyMethod::Liemid).unwrap();
        let mut s = model.initial_state().unwrap();
        let e0 = sys.system.energy(&s);
        let mut w: f64 = 0.0;
        for _ in 0..(4.0 / h).round() as usize {
            sys.step(&mut s, h).unwrap();
            w = w.max((sys.system.energy(&s) - e0).abs() / e0.abs());
        }
        w
    };
    let (a, b) = (worst(2e-3), worst(1e-3));
    println!("energy error to t = 4: {a:e} at 2e-3, {b:e} at 1e-3");
    assert!((a / b - 4.0).abs() < 0.4, "{a:e} / {b:e}");
}
