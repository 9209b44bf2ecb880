//! Structural claims: adjointness, time reversibility, E1 = E2 torque-free, one torque
//! evaluation per step, and clear errors on bad input.

use liemid::{
    integrate, integrate_to, rigid::problems, CountingTorque, Error, Inertia, LieMidpointAlternating, LieMidpointE1,
    LieMidpointE2, RigidState, RotationIntegrator, RotationMethod, Vec3,
};

/// Relative momentum and absolute attitude distance.
fn distance(a: &RigidState, b: &RigidState) -> (f64, f64) {
    ((a.pi - b.pi).norm() / b.pi.norm(), (a.rotation - b.rotation).max_abs())
}

/// A few states along the fast and torque-dominated tops.
fn sample_states() -> Vec<(problems::RigidProblem<liemid::HeavyTop>, RigidState, f64)> {
    let mut out = Vec::new();
    for (top, h) in [(problems::fast_top(), 1e-3), (problems::torque_dominated_top(), 1e-2)] {
        for t in [0.0, 0.05, 0.3] {
            let s = if t == 0.0 {
                top.initial
            } else {
                integrate_to(&mut LieMidpointAlternating::new(), &top.system, top.initial, t, 1e-4)
                    .unwrap()
                    .state
            };
            out.push((top.clone(), s, h));
        }
    }
    out
}

#[test]
fn ea_is_time_reversible() {
    for (top, s0, h) in sample_states() {
        let mut ea = LieMidpointAlternating::new();
        let mut s = s0;
        ea.step(&top.system, &mut s, h).unwrap();
        ea.step(&top.system, &mut s, -h).unwrap();
        let (dp, dr) = distance(&s, &s0);
        assert!(
            dp < 1e-13 && dr < 1e-13,
            "{}: EA_-h o EA_h - id = {dp:e}, {dr:e}",
            top.name
        );
        assert!((s.t - s0.t).abs() < 1e-15);
    }
}

#[test]
fn e1_and_e2_are_adjoint() {
    for (top, s0, h) in sample_states() {
        let mut s = s0;
        LieMidpointE1::new().step(&top.system, &mut s, h).unwrap();
        LieMidpointE2::new().step(&top.system, &mut s, -h).unwrap();
        let (dp, dr) = distance(&s, &s0);
        assert!(
            dp < 1e-13 && dr < 1e-13,
            "{}: E2_-h o E1_h - id = {dp:e}, {dr:e}",
            top.name
        );
        // And the other way round: E1_-h o E2_h = id.
        let mut s = s0;
        LieMidpointE2::new().step(&top.system, &mut s, h).unwrap();
        LieMidpointE1::new().step(&top.system, &mut s, -h).unwrap();
        let (dp, dr) = distance(&s, &s0);
        assert!(
            dp < 1e-13 && dr < 1e-13,
            "{}: E1_-h o E2_h - id = {dp:e}, {dr:e}",
            top.name
        );
    }
}

#[test]
fn the_papers_printed_e1_is_not_the_adjoint() {
    // The printed form Π⁺ = exp(−Ψ)(Π + h T⁺) misses adjointness by O(h²) per step: the
    // check above would fail for it.
    let top = problems::torque_dominated_top();
    let (s0, h) = (top.initial, 1e-2);
    let (psi, _) = liemid::rigid::midpoint::solve(&top.system.inertia, s0.pi, h).unwrap();
    let q = liemid::so3::exp(psi);
    let r1 = s0.rotation * q;
    let printed_pi = q.tr_mul_vec(s0.pi + liemid::RigidBodySystem::torque(&top.system, &r1, h) * h);
    let mut s = RigidState::new(h, printed_pi, r1);
    LieMidpointE2::new().step(&top.system, &mut s, -h).unwrap();
    let (dp, _) = distance(&s, &s0);
    assert!(dp > 1e-6, "printed E1 looks adjoint: {dp:e}");
}

#[test]
fn torque_free_e1_and_e2_coincide() {
    let body = problems::free_body();
    let a = integrate_to(&mut LieMidpointE1::new(), &body.system, body.initial, 2.0, 1e-3)
        .unwrap()
        .state;
    let b = integrate_to(&mut LieMidpointE2::new(), &body.system, body.initial, 2.0, 1e-3)
        .unwrap()
        .state;
    let (dp, dr) = distance(&a, &b);
    assert!(dp == 0.0 && dr == 0.0, "torque-free E1 and E2 differ: {dp:e} {dr:e}");
}

#[test]
fn torque_evaluations_per_step() {
    let top = problems::fast_top();
    let steps = 1000u64;
    for (method, expected) in [
        (RotationMethod::LieMidpointAlternating, steps + 1),
        (RotationMethod::LieMidpointE1, steps),
        (RotationMethod::LieMidpointE2, steps),
        (RotationMethod::KryslEndresNewmark, steps + 1),
        (RotationMethod::RungeKutta4, 4 * steps),
    ] {
        let counting = CountingTorque::new(top.system);
        let s = integrate_to(
            &mut method.integrator(),
            &counting,
            top.initial,
            steps as f64 * 1e-4,
            1e-4,
        )
        .unwrap();
        assert_eq!(s.steps, steps);
        assert_eq!(counting.count(), expected, "{}", method.name());
    }
}

#[test]
fn the_driver_lands_on_t_end_and_observes_every_k_steps() {
    let top = problems::fast_top();
    let mut seen = Vec::new();
    let s = integrate(
        &mut LieMidpointAlternating::new(),
        &top.system,
        top.initial,
        0.00105,
        1e-4,
        4,
        |k, st, _| {
            seen.push((k, st.t));
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(s.steps, 11);
    assert_eq!(s.state.t, 0.00105);
    let ks: Vec<u64> = seen.iter().map(|x| x.0).collect();
    assert_eq!(ks, vec![0, 4, 8, 11]);
    // An observer error stops the run with its message.
    let e = integrate(
        &mut LieMidpointAlternating::new(),
        &top.system,
        top.initial,
        0.01,
        1e-4,
        1,
        |k, _, _| {
            if k == 3 {
                Err("disk full".into())
            } else {
                Ok(())
            }
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::ObserverFailed { .. }) && e.to_string().contains("disk full"),
        "{e}"
    );
}

#[test]
fn bad_input_gives_distinct_descriptive_errors() {
    let top = problems::fast_top();
    let mut ea = LieMidpointAlternating::new();
    let run = |ea: &mut LieMidpointAlternating, s: RigidState, t_end: f64, h: f64| {
        integrate_to(ea, &top.system, s, t_end, h).unwrap_err()
    };

    let e = Inertia::principal([1.0, -2.0, 3.0]).unwrap_err();
    assert!(
        matches!(e, Error::InvalidInertia { .. }) && e.to_string().contains("I2 = -2"),
        "{e}"
    );

    let mut nan = top.initial;
    nan.pi.y = f64::NAN;
    let e = run(&mut ea, nan, 0.1, 1e-3);
    assert!(matches!(e, Error::NonFiniteState { field: "pi", .. }), "{e}");
    let mut inf = top.initial;
    inf.rotation.m[1][2] = f64::INFINITY;
    let e = run(&mut ea, inf, 0.1, 1e-3);
    assert!(matches!(e, Error::NonFiniteState { field: "rotation", .. }), "{e}");

    for h in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        let e = run(&mut ea, top.initial, 0.1, h);
        assert!(matches!(e, Error::InvalidStep { .. }), "h = {h}: {e}");
    }
    let mut s = top.initial;
    assert!(matches!(
        ea.step(&top.system, &mut s, 0.0),
        Err(Error::InvalidStep { .. })
    ));

    let e = run(&mut ea, top.initial, -0.1, 1e-3);
    assert!(
        matches!(e, Error::EndBeforeStart { .. }) && e.to_string().contains("before the start"),
        "{e}"
    );

    // Steps far too large for the spin rate: Newton fails or finds a spurious root turning
    // by more than half a turn; either way an error, and the state is left unchanged.
    let body = problems::free_body();
    let start = RigidState::new(0.0, Vec3::new(3.0, 20.0, 5.0), liemid::Mat3::IDENTITY);
    for (h, expect_newton) in [(2.0, true), (0.8, false)] {
        let mut s = start;
        let e = LieMidpointAlternating::new().step(&body.system, &mut s, h).unwrap_err();
        assert_eq!(s, start, "state changed by a failed step");
        if expect_newton {
            assert!(matches!(e, Error::NewtonDidNotConverge { .. }), "h = {h}: {e}");
            assert!(
                e.to_string().contains("did not converge") && e.to_string().contains("residual"),
                "{e}"
            );
        } else {
            assert!(matches!(e, Error::StepTooLarge { .. }), "h = {h}: {e}");
            assert!(e.to_string().contains("reduce the step"), "{e}");
        }
    }
    // Every implicit method reports such a step instead of returning a wrong state.
    for method in RotationMethod::ALL {
        let mut s = start;
        let r = method.integrator().step(&body.system, &mut s, 2.0);
        if let Err(e) = r {
            assert_eq!(s, start, "{}", method.name());
            assert!(!e.to_string().is_empty());
        }
    }
}
