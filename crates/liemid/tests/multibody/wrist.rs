//! A UR10e-style arm with armature (issue 47): `examples/multibody/ur10e_inertial.xml`, the
//! link frames, inertials, classes and servos of MuJoCo Menagerie's ur10e.xml without
//! meshes, armature 0.1 on every hinge, the wrists' damping 30, at the file's own step
//! 2e-3 (MuJoCo's default, which the published file uses). With the wrist class's damping
//! on every hinge, `liemid` and `liemid4` run at 2e-3 and converge at orders 2 and 4
//! against the joint-space RK4; without armature the wrist rows are stiff and `liemid4` is
//! refused before its first step, naming the joint and the largest step that holds it.
//!
//! The file as written (damping 350 on the shoulders, 200 on the elbow) is first order at
//! 2e-3 and 1e-3: the shoulder rows' stiffness test in `dampers.rs` takes the unconstrained
//! own response `D M⁻¹ Dᵀ` (the welded base's and the shoulder link's 𝕁 blocks), x = 6.0
//! and 3.2 at 2e-3 (constrained, MuJoCo's `(M⁻¹)ᵢᵢ`: 0.14 and 0.08), so they take backward
//! Euler. That case and a faster wrist (the position solve with armature has no exact
//! drift Jacobian) are the ignored tests below, which fail today.

use liemid::multibody::{mjcf, JointSpaceModel, Model, MultibodyMethod, MultibodyState, Simulation};

fn file_model() -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/multibody/ur10e_inertial.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    mjcf::parse(&text, "ur10e_inertial.xml").unwrap().model
}

/// The file's arm with the wrist class's damping (30) on every hinge.
fn wrist_model() -> Model {
    let mut m = file_model();
    for j in &mut m.joints {
        if j.damping > 0.0 {
            j.damping = 30.0;
        }
    }
    m
}

/// The largest frame-origin and attitude difference from the joint-space state `q`.
fn distance(sim: &Simulation, s: &MultibodyState, js: &mut JointSpaceModel, q: &[f64]) -> f64 {
    let poses = js.forward_kinematics(q).unwrap();
    let mut e: f64 = 0.0;
    for (i, (x, r)) in poses.iter().enumerate() {
        e = e.max((sim.system.frame_origin(s, i) - *x).max_abs());
        e = e.max((s.rotation[i] - *r).max_abs());
    }
    e
}

/// Errors of `method` at the steps against the joint-space RK4 at `h_ref`, all to `t_end`.
fn errors(model: &Model, method: MultibodyMethod, steps: &[f64], t_end: f64, h_ref: f64) -> Vec<f64> {
    let mut js = JointSpaceModel::new(model).unwrap();
    let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    js.integrate_rk4(&mut q, &mut v, (0.0, t_end, h_ref), |_, _, _, _| Ok(()))
        .unwrap();
    steps
        .iter()
        .map(|&h| {
            let prepared = Simulation::prepare(model, method).unwrap();
            assert!(prepared.notes.is_empty(), "{:?}", prepared.notes);
            let (mut sim, mut s) = (prepared.simulation, prepared.state);
            assert!(sim.system.has_armature());
            sim.check_step(&s, h).unwrap();
            for _ in 0..(t_end / h).round() as usize {
                sim.step(&mut s, h).unwrap();
            }
            distance(&sim, &s, &mut js, &q)
        })
        .collect()
}

fn assert_orders(model: &Model, what: &str) {
    let h0 = model.timestep.unwrap();
    assert_eq!(h0, 2e-3);
    let steps = [h0, h0 / 2.0, h0 / 4.0];
    for (method, order) in [(MultibodyMethod::Liemid, 2.0), (MultibodyMethod::Liemid4, 4.0)] {
        let e = errors(model, method, &steps, 0.2, 1e-5);
        let observed: Vec<f64> = e.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!(
            "{what}, {}: h {steps:?} errors {e:?} orders {observed:.3?}",
            method.name()
        );
        for o in observed {
            assert!((o - order).abs() < 0.1, "{what}, {}: orders of {e:?}", method.name());
        }
    }
}

/// The hinge rates read from the bodies (`joint_rate`: the Python `qvel` and the control
/// callback's) are the joint-space ones with armature: `Ω = 𝕁⁻¹ Π`, not `I⁻¹ Π` (which read
/// the wrists' rates wrong by the armature's momentum, and drove a PD controller 0.16 m
/// away from MuJoCo's in 2 s).
#[test]
fn joint_rates_with_armature_are_the_joint_space_ones() {
    let model = file_model();
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid4).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let joints = model.joints.len();
    let rates = |sim: &Simulation, s: &MultibodyState| -> Vec<f64> {
        (0..joints).filter_map(|k| sim.system.joint_rate(s, k)).collect()
    };
    let v0 = model.qvel.clone().unwrap();
    let got = rates(&sim, &s);
    assert_eq!(got.len(), v0.len());
    for (a, b) in got.iter().zip(&v0) {
        assert!(
            (a - b).abs() < 1e-12,
            "start rates {got:?} against the keyframe's {v0:?}"
        );
    }
    // After 0.1 s, against the joint-space RK4.
    let mut js = JointSpaceModel::new(&model).unwrap();
    let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    js.integrate_rk4(&mut q, &mut v, (0.0, 0.1, 1e-5), |_, _, _, _| Ok(()))
        .unwrap();
    for _ in 0..200 {
        sim.step(&mut s, 5e-4).unwrap();
    }
    let got = rates(&sim, &s);
    for (a, b) in got.iter().zip(&v) {
        assert!((a - b).abs() < 1e-8, "rates {got:?} against the joint-space {v:?}");
    }
}

#[test]
fn a_ur10e_style_wrist_with_armature_runs_at_its_own_step_at_orders_2_and_4() {
    assert_orders(&wrist_model(), "UR10e-style arm, damping 30");
}

#[test]
fn without_armature_the_stiff_wrist_is_refused_before_the_first_step() {
    let mut model = wrist_model();
    model.joints.iter_mut().for_each(|j| j.armature = 0.0);
    let h = model.timestep.unwrap();
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid4).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let start = s.clone();
    let err = sim
        .integrate(&mut s, 0.2, h, |_, _, _, _| Ok(()))
        .unwrap_err()
        .to_string();
    println!("{err}");
    assert!(
        err.contains("MB-LIEMID4") && err.contains("`wrist_") && err.contains("largest step"),
        "{err}"
    );
    assert_eq!(s.c, start.c, "refused before the first step");
    assert_eq!(s.t, start.t);
    let largest: f64 = err
        .split("holds it is about ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(largest < h, "{largest}");
    // Below the steps named (one row at a time: each check names the first row it
    // cannot hold), the check passes; with the armature it passes at 2e-3.
    let mut step = 0.99 * largest;
    for _ in 0..6 {
        let Err(e) = sim.check_step(&s, step) else { break };
        let e = e.to_string();
        println!("{e}");
        let next: f64 = e
            .split("holds it is about ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(next < step, "{e}");
        step = 0.99 * next;
    }
    sim.check_step(&s, step).unwrap();
    println!("without armature, liemid4 holds every row below {step:.3e}");
    let prepared = Simulation::prepare(&wrist_model(), MultibodyMethod::Liemid4).unwrap();
    prepared.simulation.check_step(&prepared.state, h).unwrap();
}

/// Fails today: the shoulder rows (damping 350) take backward Euler at 2e-3 and 1e-3 (the
/// stiffness test's unconstrained bound, module docs); measured against MuJoCo 4.0's RK4,
/// liemid 7.6e-6, 3.8e-6, 8.2e-8 m at 2e-3, 1e-3, 5e-4 (orders 1.02, 5.52).
#[test]
#[ignore = "the damper stiffness test's bound makes the shoulders first order at 2e-3 (issue 47)"]
fn the_file_as_written_runs_at_orders_2_and_4() {
    assert_orders(&file_model(), "UR10e-style arm as written");
}

/// Fails today: with the wrist's last hinge at 1.4 rad/s the position solve does not converge
/// at 2e-3 (its quasi-Newton matrix `G M⁻¹ Gᵀ` misses the drift's gyroscopic term, ratio
/// about `(h/2) a q̇ / I⊥` with `a = 0.1` against the link's `I⊥ = 1.4e-4`; the exact-
/// Jacobian fallback is not available with armature). The largest rate that converges scales
/// as 1/h: 1.2 rad/s at 2e-3, 2.6 at 1e-3, 5.2 at 5e-4.
#[test]
#[ignore = "the position solve with armature has no exact drift Jacobian (issue 47)"]
fn a_fast_wrist_converges_at_the_files_step() {
    let mut model = wrist_model();
    let qvel = model.qvel.as_mut().unwrap();
    let n = qvel.len();
    qvel[n - 1] = 2.0;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    for _ in 0..10 {
        sim.step(&mut s, 2e-3).unwrap();
    }
}
