//! LIEMID[EX] and its compositions: the paper's numbers on the fast top, invariants,
//! symmetry, one torque evaluation per step, and exactness torque-free at any step.

mod common;

use common::{errors, run, shipped_fast_top_reference};
use liemid::{
    problems, so3, CountingTorque, FreeBody, FreeFlow, Inertia, LieMidpointExact, RigidBodySystem, RigidState,
    RotationIntegrator, RotationMethod, Vec3,
};

#[test]
fn fast_top_attitude_errors_are_those_of_the_torque_alone() {
    // Issue 19, measured with an independent script: 2.5e-6, 6.2e-7, 1.6e-7, 3.9e-8 at
    // h = 2e-3 ... 2.5e-4 (EA: 4.9e-3, 1.2e-3, 3.0e-4, 7.5e-5).
    let top = problems::fast_top();
    let reference = shipped_fast_top_reference(top.t_end);
    for (h, expected) in [(2e-3, 2.5e-6), (1e-3, 6.2e-7), (5e-4, 1.6e-7), (2.5e-4, 3.9e-8)] {
        let end = run(&mut LieMidpointExact::new(), &top.system, top.initial, top.t_end, h);
        let (_, dr) = errors(&end, &reference);
        assert!(
            dr / expected < 1.1 && expected / dr < 1.1,
            "h = {h}: attitude error {dr:e}, expected {expected:e}"
        );
    }
}

#[test]
fn momentum_invariants_to_round_off() {
    let top = problems::fast_top();
    let g = top.system.gravity * (1.0 / top.system.gravity.norm());
    let mut ex = LieMidpointExact::new();
    let mut state = top.initial;
    let along = |s: &RigidState| s.spatial_momentum().dot(g);
    let first = along(&state);
    let mut worst: f64 = 0.0;
    for _ in 0..100_000 {
        ex.step(&top.system, &mut state, 1e-4).unwrap();
        worst = worst.max((along(&state) - first).abs());
    }
    assert!(
        worst < 2e-14 * top.initial.pi.norm(),
        "pi.g drifts by {worst:e} over 1e5 steps"
    );
    // Energy error bounded: the same amplitude in the first and the last tenth.
    let energy = |s: &RigidState| liemid::Diagnostics::of(&top.system, s).energy;
    let (mut state, e0) = (top.initial, energy(&top.initial));
    let mut tenths = [0.0f64; 10];
    for k in 0..100_000 {
        ex.step(&top.system, &mut state, 1e-4).unwrap();
        tenths[k / 10_000] = tenths[k / 10_000].max(((energy(&state) - e0) / e0).abs());
    }
    assert!(tenths[9] < 1.5 * tenths[0] + 1e-14, "energy error grows: {tenths:?}");
}

#[test]
fn time_reversible_and_one_torque_evaluation_per_step() {
    let top = problems::torque_dominated_top();
    for method in [
        RotationMethod::LieMidpointExact,
        RotationMethod::LieMidpointExact4,
        RotationMethod::LieMidpointExact6,
        RotationMethod::LieMidpointExact8,
    ] {
        let mut m = method.integrator();
        let mut state = top.initial;
        m.step(&top.system, &mut state, 0.05).unwrap();
        m.step(&top.system, &mut state, -0.05).unwrap();
        state.t = top.initial.t;
        let (dp, dr) = errors(&state, &top.initial);
        assert!(
            dp < 1e-14 && dr < 1e-14,
            "{}: EX(-h) EX(h) misses by {dp:e}, {dr:e}",
            method.name()
        );
    }
    let counting = CountingTorque::new(top.system);
    let mut ex = LieMidpointExact::new();
    let mut state = top.initial;
    for _ in 0..1000 {
        ex.step(&counting, &mut state, 1e-3).unwrap();
    }
    assert_eq!(counting.count(), 1001);
}

#[test]
fn torque_free_it_is_exact_at_any_step() {
    let inertia = Inertia::principal([1.0, 2.0, 3.0]).unwrap();
    let body = FreeBody::new(inertia);
    let start = RigidState::new(
        0.0,
        inertia.apply(Vec3::new(0.3, 0.4, 2.0)),
        so3::exp(Vec3::new(0.1, 0.2, 0.3)),
    );
    let mut ex = LieMidpointExact::new();
    let mut one = start;
    ex.step(&body, &mut one, 10.0).unwrap();
    // Against the flow in 1000 pieces and against EA8 at a small step.
    let flow = FreeFlow::new(body.inertia()).unwrap();
    let (mut p, mut r) = (start.pi, start.rotation);
    for _ in 0..1000 {
        (p, r) = flow.flow(p, &r, 0.01);
    }
    let ea8 = run(
        &mut RotationMethod::LieMidpointAlternating8.integrator(),
        &body,
        start,
        10.0,
        2e-3,
    );
    let (dp, dr) = errors(&one, &ea8);
    assert!(dp < 1e-12 && dr < 1e-11, "one step of 10 s against EA8: {dp:e}, {dr:e}");
    assert!((one.pi - p).max_abs() < 1e-12 && (one.rotation - r).max_abs() < 1e-12);
}
