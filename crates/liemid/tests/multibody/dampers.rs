//! Hinge and slide dampers in the multibody step, `BE_D(h/2) ∘ RATTLE(h) ∘ FE_D(h/2)`
//! (the end half-kick implicit, by conjugate gradients on `(diag(1/d) + (h/2) A) σ = −r₀`):
//! a damper turns a joint rate by `(1 − x)/(1 + x)` per step, `x = h d/(2I)` (the
//! trapezoidal rule), and above `x = 2` by `1/(1 + x)²` (backward Euler at the start too); second order against the joint-space reference (RK4 at a small
//! step) on a planar and on a spatial chain, order 4 composed; stable and constraint-exact
//! where the explicit damper failed; a composition's negative sub-step with `x ≥ 1` is an
//! error, not a blow-up; no allocation per step.

use liemid::multibody::joint_space::JointSpaceModel;
use liemid::multibody::{mjcf, problems, Model, MultibodyMethod, Simulation};
use liemid::Vec3;

use crate::thread_counting;
use thread_counting::allocations;

/// A wheel on a hinge to the world about its principal axis z (I_zz = 0.2 kg m²), centre
/// of mass on the axis, no gravity, spinning at 3 rad/s, with damping `d`.
fn wheel(d: f64) -> Model {
    let text = format!(
        "<mujoco><option gravity=\"0 0 0\"/><worldbody><body name=\"wheel\">\
         <joint name=\"axle\" axis=\"0 0 1\" damping=\"{d}\"/>\
         <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.5 0.5 0.2\"/></body></worldbody>\
         <keyframe><key qpos=\"0\" qvel=\"3\"/></keyframe></mujoco>"
    );
    mjcf::parse(&text, "wheel.xml").unwrap().model
}

/// Per step: the rate's factor and the drift's factor (the drift moves at that times the
/// start rate) of a damper with `x = h d/(2I)`: the trapezoidal rule up to `x = 2`,
/// backward Euler in both half-kicks above.
fn damper_factors(x: f64) -> (f64, f64) {
    if x > 2.0 {
        (1.0 / ((1.0 + x) * (1.0 + x)), 1.0 / (1.0 + x))
    } else {
        ((1.0 - x) / (1.0 + x), 1.0 - x)
    }
}

#[test]
fn a_damper_decays_by_the_trapezoidal_factor_at_any_stiffness() {
    let h = 0.01;
    // x = h d / (2 I): mild, near the switch, stiff and very stiff (the trapezoidal drift
    // would move at (1 − x) ω: 15 rad in a step at x = 500).
    for x in [0.05, 1.5, 5.0, 50.0, 500.0] {
        let d = 2.0 * 0.2 * x / h;
        let model = wheel(d);
        let mut sys = Simulation::new(&model, MultibodyMethod::Liemid).unwrap();
        let mut s = model.initial_state().unwrap();
        let (g, drift) = damper_factors(x);
        let (mut rate, mut angle) = (3.0f64, 0.0f64);
        for n in 1..=40 {
            sys.step(&mut s, h).unwrap();
            angle += h * drift * rate;
            rate *= g;
            // Each step's rounding is amplified by the conditioning of the implicit kick,
            // 1 + x: n steps, a few ulps each.
            let measured = s.pi[0].z / 0.2;
            assert!(
                (measured - rate).abs() <= n as f64 * (1.0 + x) * 8.0 * f64::EPSILON * 3.0,
                "x = {x}, step {n}: rate {measured} against {rate}"
            );
            let wrapped = (angle + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            let q = sys.system.joint_coordinate(&s, 0).unwrap();
            assert!(
                (q - wrapped).abs() <= 1e-12,
                "x = {x}, step {n}: angle {q} against {wrapped}"
            );
        }
    }
}

#[test]
fn a_ball_damper_decays_the_relative_spin_by_the_same_factor() {
    // A ball of isotropic inertia 0.2 about its centre, pinned there, spinning at
    // (3, −1, 2) rad/s: the damper −d ω turns ω by the wheel's factor per step.
    let h = 0.01;
    for x in [0.05, 1.5, 5.0] {
        let d = 2.0 * 0.2 * x / h;
        let text = format!(
            "<mujoco><option gravity=\"0 0 0\"/><worldbody><body name=\"ball\">\
             <joint name=\"pin\" type=\"ball\" damping=\"{d}\"/>\
             <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.2 0.2 0.2\"/></body></worldbody>\
             <keyframe><key qpos=\"1 0 0 0\" qvel=\"3 -1 2\"/></keyframe></mujoco>"
        );
        let model = mjcf::parse(&text, "ball.xml").unwrap().model;
        let mut sys = Simulation::new(&model, MultibodyMethod::Liemid).unwrap();
        let mut s = model.initial_state().unwrap();
        let (g, _) = damper_factors(x);
        let mut factor = 1.0f64;
        for n in 1..=40 {
            sys.step(&mut s, h).unwrap();
            factor *= g;
            // The body-frame spin of an isotropic body: Π / I, the start spin times g^n in
            // the body's axes (the spin axis is fixed in space and in the body).
            let omega = s.pi[0] * (1.0 / 0.2);
            let expected = Vec3::new(3.0, -1.0, 2.0) * factor;
            assert!(
                (omega - expected).max_abs() <= n as f64 * (1.0 + x) * 8.0 * f64::EPSILON * 3.0,
                "x = {x}, step {n}: {omega:?} against {expected:?}"
            );
        }
    }
}

/// The first two joint coordinates at `t_end` by liemid at `h`.
fn liemid_angles(model: &Model, method: MultibodyMethod, h: f64, t_end: f64) -> [f64; 2] {
    let mut sys = Simulation::new(model, method).unwrap();
    let mut s = model.initial_state().unwrap();
    let n = (t_end / h).round() as usize;
    for _ in 0..n {
        let r = sys.step(&mut s, h).unwrap();
        assert!(r.position_violation < 1e-12 && r.velocity_violation < 1e-12);
    }
    [
        sys.system.joint_coordinate(&s, 0).unwrap(),
        sys.system.joint_coordinate(&s, 1).unwrap(),
    ]
}

/// Observed orders of `method` on `model` (its first two joints hinges) at the steps `hs`,
/// against joint-space RK4 at h = 1e-4 (error below 1e-13 here).
fn observed_orders(model: &Model, method: MultibodyMethod, hs: &[f64], t_end: f64) -> Vec<f64> {
    let mut js = JointSpaceModel::new(model).unwrap();
    let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
    let h_ref: f64 = 1e-4;
    for _ in 0..(t_end / h_ref).round() as usize {
        js.rk4_step(&mut q, &mut v, h_ref).unwrap();
    }
    let errors: Vec<f64> = hs
        .iter()
        .map(|&h| {
            let a = liemid_angles(model, method, h, t_end);
            (a[0] - q[0]).abs().max((a[1] - q[1]).abs())
        })
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("{} {}: errors {errors:?}, orders {orders:?}", model.name, method.name());
    orders
}

fn damped_double_pendulum(d: f64) -> Model {
    let mut m = problems::double_pendulum();
    m.joints[0].damping = d;
    m.joints[1].damping = 0.5 * d;
    m
}

/// The spatial test chain of docs/theory/multibody.md §5 (hinge about y, hinge about x carried by the first link,
/// ball; centres off the axes, full inertias) with every joint damped.
fn damped_test_chain() -> Model {
    let mut m = problems::test_chain();
    m.joints[0].damping = 0.3;
    m.joints[1].damping = 0.2;
    m.joints[2].damping = 0.05;
    m
}

#[test]
fn damped_chains_converge_with_orders_two_and_four_to_the_joint_space_reference() {
    let hs = [2e-2, 1e-2, 5e-3, 2.5e-3];
    for model in [damped_double_pendulum(0.4), damped_test_chain()] {
        let orders = observed_orders(&model, MultibodyMethod::Liemid, &hs, 1.0);
        for p in &orders {
            assert!((p - 2.0).abs() < 0.1, "{}: orders {orders:?}", model.name);
        }
    }
    let orders = observed_orders(&damped_test_chain(), MultibodyMethod::Liemid4, &[4e-2, 2e-2, 1e-2], 1.0);
    for p in &orders {
        assert!((p - 4.0).abs() < 0.1, "liemid4: orders {orders:?}");
    }
}

#[test]
fn a_negative_sub_step_against_a_stiff_damper_is_an_error() {
    // liemid4's middle sub-step is −0.66 h: at x = h d/(2I) = 5 it anti-damps with |x| > 1.
    let h = 0.01;
    let model = wheel(2.0 * 0.2 * 5.0 / h);
    let mut sys = Simulation::new(&model, MultibodyMethod::Liemid4).unwrap();
    let mut s = model.initial_state().unwrap();
    let err = sys.step(&mut s, h).unwrap_err().to_string();
    assert!(err.contains("negative sub-step"), "{err}");
    // At x = 0.5 every sub-step is fine.
    let model = wheel(2.0 * 0.2 * 0.5 / h);
    let mut sys = Simulation::new(&model, MultibodyMethod::Liemid4).unwrap();
    let mut s = model.initial_state().unwrap();
    for _ in 0..100 {
        sys.step(&mut s, h).unwrap();
    }
    assert!(s.pi[0].z.abs() < 3.0 * 0.2 * 0.1);
}

#[test]
fn stiff_dampers_stay_stable_and_dissipate() {
    // x = h d / (2 I) = 30 and 15 at h = 1e-2 (each link's I about its joint 1/3 kg m²):
    // the explicit damper needs h below 6.7e-4 and 3.3e-4.
    let model = damped_double_pendulum(2000.0);
    let mut sys = Simulation::new(&model, MultibodyMethod::Liemid).unwrap();
    let mut s = model.initial_state().unwrap();
    let e0 = sys.system.energy(&s);
    let mut last = e0;
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let r = sys.step(&mut s, 1e-2).unwrap();
        worst = worst.max(r.position_violation.max(r.velocity_violation));
        last = sys.system.energy(&s);
        assert!(
            last.is_finite() && last <= e0 + 1e-12 * e0.abs(),
            "energy {last} above {e0}"
        );
    }
    println!("stiff dampers: energy {e0:.6} -> {last:.6}, constraints {worst:.1e}");
    assert!(worst < 1e-12 && last < e0);
}

#[test]
fn damped_steps_allocate_nothing() {
    // Mild dampers (the trapezoidal rule) under both methods, and stiff ones (x about 120
    // by the rows' own inertia: backward Euler at the start, solved there) under liemid.
    for (d, method) in [
        (5.0, MultibodyMethod::Liemid),
        (5.0, MultibodyMethod::Liemid4),
        (20_000.0, MultibodyMethod::Liemid),
    ] {
        let model = damped_double_pendulum(d);
        let mut sys = Simulation::new(&model, method).unwrap();
        let mut s = model.initial_state().unwrap();
        sys.step(&mut s, 1e-3).unwrap();
        let before = allocations();
        for _ in 0..100 {
            sys.step(&mut s, 1e-3).unwrap();
        }
        assert_eq!(allocations() - before, 0, "{} allocates (d = {d})", method.name());
    }
}

#[test]
fn a_stiff_damper_under_a_load_creeps_at_the_exact_rate() {
    // A 1 kg arm on a hinge about y at the world origin, its centre 0.1 m along x, I about
    // the axis 0.0101 kg m², d = 100: at h = 1e-2, x = h d/(2I) = 49.5 (backward Euler in
    // both half-kicks). Overdamped, it creeps at the rate where the damper holds gravity's
    // torque: θ' = −m g r cos θ / d (about 9.8e-3 rad/s), reached within I/d = 1e-4 s.
    let text = "<mujoco><worldbody><body name=\"arm\"><joint name=\"j\" axis=\"0 1 0\" damping=\"100\"/>\
                <inertial pos=\"0.1 0 0\" mass=\"1\" diaginertia=\"1e-4 1e-4 1e-4\"/></body></worldbody></mujoco>";
    let model = mjcf::parse(text, "creep.xml").unwrap().model;
    let mut sys = Simulation::new(&model, MultibodyMethod::Liemid).unwrap();
    let mut s = model.initial_state().unwrap();
    for _ in 0..20 {
        sys.step(&mut s, 1e-2).unwrap();
    }
    let theta = sys.system.joint_coordinate(&s, 0).unwrap();
    // The arm's rate about y: its body-frame spin Π / I_c (the axis is y in the body too).
    let omega_y = s.pi[0].y / 1e-4;
    // The hinge angle turns with the body about +y; gravity −z on the centre at x pulls it
    // down: torque about y = r × F = (0.1 cos θ, 0, −0.1 sin θ) × (0, 0, −9.81) → y: 0.981 cos θ.
    let expected = 0.981 * theta.cos() / 100.0;
    println!("creep: θ = {theta}, rate {omega_y}, expected {expected}");
    assert!(
        (omega_y - expected).abs() < 1e-3 * expected.abs(),
        "{omega_y} against {expected}"
    );
}
