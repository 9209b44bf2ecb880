//! Hinge armature, exact in maximal coordinates (docs/theory/multibody.md §7): the
//! kinetic energy against the joint-space mass matrix, orders 2 and 4 against the
//! joint-space reference, reversal, constraints, energy, momenta, no allocation.

use liemid::linalg::Vec3;
use liemid::multibody::problems;
use liemid::multibody::{Drift, JointKind, JointSpaceModel, Link, Model, MultibodyMethod, MultibodyState, Simulation};
use liemid::random::Rng;

use crate::thread_counting;

/// A tree of four bodies on hinges with oblique axes (links 0-1-2 and a branch 3 on body
/// 1), armature on every hinge, started with joint rates.
fn tree(gravity: bool, floating: bool) -> Model {
    let mut m = problems::chain(4);
    let mut rng = Rng::new(47);
    let mut qpos = Vec::new();
    let mut qvel = Vec::new();
    for (k, j) in m.joints.iter_mut().enumerate() {
        j.kind = JointKind::Hinge {
            axis: rng.unit_vector(),
        };
        j.armature = [0.004, 0.002, 0.003, 0.005][k];
        qpos.push(0.3 * rng.normal());
        qvel.push(2.0 * rng.normal());
    }
    m.joints[3].parent = Link::Body(1);
    m.joints[3].anchor_parent = Vec3::new(0.0, 0.0, -0.2);
    if floating {
        m.joints[0].kind = JointKind::Free;
        m.joints[0].armature = 0.0;
        let mut q0 = vec![0.1, 0.0, -0.2, 1.0, 0.0, 0.0, 0.0];
        q0.extend_from_slice(&qpos[1..]);
        qpos = q0;
        let mut v0 = vec![0.3, -0.2, 0.1, 1.0, -2.0, 0.5];
        v0.extend_from_slice(&qvel[1..]);
        qvel = v0;
    }
    m.qpos = Some(qpos);
    m.qvel = Some(qvel);
    if !gravity {
        m.gravity = Vec3::ZERO;
    }
    m.name = "armature-tree".into();
    m
}

fn system(model: &Model, method: MultibodyMethod, drift: Drift) -> (Simulation, MultibodyState) {
    let mut sim = Simulation::new(model, method).unwrap();
    sim.integrator.set_drift(drift);
    (sim, model.initial_state().unwrap())
}

fn run(sim: &mut Simulation, s: &mut MultibodyState, h: f64, steps: usize) {
    for _ in 0..steps {
        sim.step(s, h).unwrap();
    }
}

/// The largest difference of frame origins and attitudes from the joint-space state `q`.
fn distance(sim: &Simulation, s: &MultibodyState, js: &mut JointSpaceModel, q: &[f64]) -> f64 {
    let poses = js.forward_kinematics(q).unwrap();
    let mut e: f64 = 0.0;
    for (i, (x, r)) in poses.iter().enumerate() {
        e = e.max((sim.system.frame_origin(s, i) - *x).max_abs());
        e = e.max((s.rotation[i] - *r).max_abs());
    }
    e
}

/// The joint-space reference at `t_end` (RK4 at a tiny step).
fn reference(model: &Model, t_end: f64, h: f64) -> (JointSpaceModel, Vec<f64>) {
    let mut js = JointSpaceModel::new(model).unwrap();
    let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    js.integrate_rk4(&mut q, &mut v, (0.0, t_end, h), |_, _, _, _| Ok(()))
        .unwrap();
    (js, q)
}

#[test]
fn kinetic_energy_is_the_joint_space_one() {
    for floating in [false, true] {
        let m = tree(false, floating);
        let sim = Simulation::new(&m, MultibodyMethod::Liemid).unwrap();
        assert!(sim.system.has_armature());
        let s = m.initial_state().unwrap();
        let mut js = JointSpaceModel::new(&m).unwrap();
        let (q, v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
        let (e_max, e_js) = (sim.system.energy(&s), js.energy(&q, &v).unwrap());
        println!("armature tree (floating {floating}): kinetic energy {e_max:.16e} vs joint space {e_js:.16e}");
        assert!((e_max - e_js).abs() <= 1e-13 * e_js.abs(), "{e_max} vs {e_js}");
        // Without armature the two differ by the rotors' ½ a q̇².
        let mut bare = m.clone();
        bare.joints.iter_mut().for_each(|j| j.armature = 0.0);
        let e_bare = Simulation::new(&bare, MultibodyMethod::Liemid)
            .unwrap()
            .system
            .energy(&bare.initial_state().unwrap());
        assert!((e_bare - e_js).abs() > 1e-3 * e_js.abs());
    }
}

#[test]
fn orders_2_and_4_against_the_joint_space_reference() {
    let m = tree(true, false);
    let t_end = 0.2;
    let (mut js, q) = reference(&m, t_end, 1e-5);
    let cases = [
        (MultibodyMethod::Liemid, [4e-3, 2e-3, 1e-3], 2.0),
        (MultibodyMethod::Liemid4, [1e-2, 5e-3, 2.5e-3], 4.0),
    ];
    for (method, steps, order) in cases {
        for drift in Drift::ALL {
            let e: Vec<f64> = steps
                .iter()
                .map(|&h| {
                    let (mut sim, mut s) = system(&m, method, drift);
                    run(&mut sim, &mut s, h, (t_end / h).round() as usize);
                    distance(&sim, &s, &mut js, &q)
                })
                .collect();
            let observed = liemid::observed_order(&steps, &e).unwrap();
            println!(
                "armature tree {} ({} drift): h {steps:?} errors {e:?} order {observed:.3}",
                method.name(),
                drift.key()
            );
            assert!((observed - order).abs() < 0.1, "observed order {observed}");
        }
    }
}

#[test]
fn reversible_constrained_and_energy_bounded() {
    let m = tree(true, false);
    let (mut sim, mut s) = system(&m, MultibodyMethod::Liemid, Drift::Midpoint);
    let s0 = s.clone();
    let h = 1e-3;
    run(&mut sim, &mut s, h, 200);
    run(&mut sim, &mut s, -h, 200);
    let d = s.distance(&s0);
    let back = d.iter().fold(0.0f64, |a, b| a.max(*b));
    println!("armature tree: back after 200 steps forward and back {back:.2e}");
    assert!(back < 1e-11, "{d:?}");
    let (mut sim, mut s) = system(&m, MultibodyMethod::Liemid, Drift::Midpoint);
    let e0 = sim.system.energy(&s);
    let (mut worst, mut pos, mut vel) = (0.0f64, 0.0f64, 0.0f64);
    let mut first = 0.0f64;
    for k in 0..20_000 {
        let r = sim.step(&mut s, h).unwrap();
        pos = pos.max(r.position_violation);
        vel = vel.max(r.velocity_violation);
        let e = (sim.system.energy(&s) - e0).abs() / e0.abs();
        worst = worst.max(e);
        if k < 2000 {
            first = first.max(e);
        }
    }
    let (p, v) = sim.system.constraint_violation(&s);
    println!(
        "armature tree 20000 steps of 1e-3: energy error {worst:.2e} (first 2000 {first:.2e}), constraints \
         {pos:.1e} {vel:.1e} (end {p:.1e} {v:.1e})"
    );
    assert!(pos <= 1e-12 && p <= 1e-12 && v <= 1e-12, "{pos:e} {p:e} {v:e}");
    // The velocity rows' worst over the run (relative to the fastest body's speed).
    assert!(vel <= 5e-12, "{vel:e}");
    // Bounded, no drift: the long run's worst within a small factor of the first tenth's.
    assert!(worst < 1e-4 && worst < 3.0 * first, "{worst:e} vs {first:e}");
}

#[test]
fn free_tree_keeps_momenta() {
    let m = tree(false, true);
    for drift in Drift::ALL {
        let (mut sim, mut s) = system(&m, MultibodyMethod::Liemid, drift);
        let (p0, l0) = (sim.system.linear_momentum(&s), sim.system.angular_momentum(&s));
        run(&mut sim, &mut s, 2e-3, 1000);
        let dp = (sim.system.linear_momentum(&s) - p0).max_abs();
        let dl = (sim.system.angular_momentum(&s) - l0).max_abs();
        println!(
            "armature free tree ({} drift): momenta changed by {dp:.1e}, {dl:.1e}",
            drift.key()
        );
        assert!(dp < 1e-12 && dl < 1e-12);
    }
}

#[test]
fn steps_with_armature_allocate_nothing() {
    let m = tree(true, false);
    let (mut sim, mut s) = system(&m, MultibodyMethod::Liemid4, Drift::Variational);
    run(&mut sim, &mut s, 1e-3, 3);
    let before = thread_counting::allocations();
    run(&mut sim, &mut s, 1e-3, 20);
    assert_eq!(thread_counting::allocations() - before, 0);
}
