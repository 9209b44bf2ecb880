//! The exact torque-free flow: against an eighth-order reference on every branch, its
//! invariants to round-off, reversibility, and exactness at any step.

use liemid::{integrate_to, so3, FreeBody, FreeFlow, Inertia, Mat3, RigidBodySystem, RigidState, RotationMethod, Vec3};

/// LIEMID[EA]8 at `h`: error `O(h⁸)`, about 1e-15 here.
fn reference(inertia: Inertia, pi: Vec3, r: Mat3, t: f64, h: f64) -> RigidState {
    let body = FreeBody::new(inertia);
    let mut ea8 = RotationMethod::LieMidpointAlternating8.integrator();
    integrate_to(&mut ea8, &body, RigidState::new(0.0, pi, r), t, h)
        .unwrap()
        .state
}

fn rotated(d: [f64; 3], q: Mat3) -> Inertia {
    let m = q * Mat3::from_diagonal(Vec3::from_array(d)) * q.transpose();
    let u = m.m;
    Inertia::from_matrix([
        [u[0][0], u[0][1], u[0][2]],
        [u[0][1], u[1][1], u[1][2]],
        [u[0][2], u[1][2], u[2][2]],
    ])
    .unwrap()
}

struct Case {
    name: &'static str,
    inertia: Inertia,
    omega: Vec3,
    /// How long the reference stays accurate to 1e-12: 20 s (10 to 30 turns), or less
    /// where the motion passes near the separatrix and amplifies every rounding (the
    /// tennis racket: references at h and h/2 differ by 5e-9 at t = 20).
    t: f64,
}

fn cases() -> Vec<Case> {
    let p = |d: [f64; 3]| Inertia::principal(d).unwrap();
    let q = so3::exp(Vec3::new(0.3, -0.7, 0.5));
    vec![
        // Circulation about the largest moment's axis (|Π|²/2H > I₂).
        Case {
            name: "about the major axis",
            inertia: p([1.0, 2.0, 3.0]),
            omega: Vec3::new(0.3, 0.4, 2.0),
            t: 20.0,
        },
        Case {
            name: "major axis, negative",
            inertia: p([1.0, 2.0, 3.0]),
            omega: Vec3::new(-0.3, 0.4, -2.0),
            t: 20.0,
        },
        // About the smallest moment's axis.
        Case {
            name: "about the minor axis",
            inertia: p([1.0, 2.0, 3.0]),
            omega: Vec3::new(3.0, 0.5, 0.2),
            t: 20.0,
        },
        Case {
            name: "minor axis, axes reordered",
            inertia: p([3.0, 1.0, 2.0]),
            omega: Vec3::new(0.2, -3.0, 0.5),
            t: 20.0,
        },
        // The tennis racket of issue 19: near the separatrix.
        Case {
            name: "tennis racket",
            inertia: p([1.0, 2.0, 3.0]),
            omega: Vec3::new(0.1, 10.0, 0.0),
            t: 2.0,
        },
        // Near-symmetric: k² = 1e-9.
        Case {
            name: "near-symmetric",
            inertia: p([1.0, 1.0 + 1e-9, 2.0]),
            omega: Vec3::new(0.5, 0.3, 2.0),
            t: 20.0,
        },
        Case {
            name: "symmetric (prolate)",
            inertia: p([2.0, 2.0, 1.0]),
            omega: Vec3::new(0.5, 0.3, 4.0),
            t: 20.0,
        },
        Case {
            name: "symmetric, axis 0",
            inertia: p([1.0, 2.0, 2.0]),
            omega: Vec3::new(4.0, 0.3, 0.5),
            t: 20.0,
        },
        Case {
            name: "sphere",
            inertia: p([1.5, 1.5, 1.5]),
            omega: Vec3::new(0.5, -0.3, 1.0),
            t: 20.0,
        },
        Case {
            name: "full tensor",
            inertia: rotated([1.0, 2.0, 2.5], q),
            omega: Vec3::new(0.7, -1.1, 2.3),
            t: 20.0,
        },
        Case {
            name: "full symmetric tensor",
            inertia: rotated([1.0, 2.0, 2.0], q),
            omega: Vec3::new(0.7, -1.1, 2.3),
            t: 20.0,
        },
    ]
}

#[test]
fn the_flow_agrees_with_an_eighth_order_reference_on_every_branch() {
    let r0 = so3::exp(Vec3::new(0.2, 0.5, -0.4));
    for c in cases() {
        let flow = FreeFlow::new(&c.inertia).unwrap();
        let pi = c.inertia.apply(c.omega);
        // In one call and in 200 calls.
        let t = c.t;
        // Two references, at h and h/2: their difference bounds their own error (EA8's
        // truncation at 4e-3, its round-off over 10^4 steps of 17 stages at 2e-3).
        let reference = reference(c.inertia, pi, r0, t, 2e-3);
        let coarse = self::reference(c.inertia, pi, r0, t, 4e-3);
        let slack_p = 2.0 * (coarse.pi - reference.pi).max_abs() / pi.norm();
        let slack_r = 2.0 * (coarse.rotation - reference.rotation).max_abs();
        assert!(
            slack_p < 1e-11 && slack_r < 1e-10,
            "{}: the references differ by {slack_p:e}, {slack_r:e}",
            c.name
        );
        let (p1, r1) = flow.flow(pi, &r0, t);
        let (mut p, mut r) = (pi, r0);
        for _ in 0..200 {
            (p, r) = flow.flow(p, &r, t / 200.0);
        }
        for (how, pe, re) in [("one call", p1, r1), ("200 calls", p, r)] {
            let dp = (pe - reference.pi).max_abs() / pi.norm();
            let dr = (re - reference.rotation).max_abs();
            assert!(
                dp < 1e-12 + slack_p && dr < 1e-11 + slack_r,
                "{}: {how}: Pi {dp:e}, R {dr:e} (reference uncertainty {slack_p:e}, {slack_r:e})",
                c.name
            );
        }
    }
}

#[test]
fn invariants_are_kept_to_round_off_and_the_flow_is_reversible() {
    let r0 = so3::exp(Vec3::new(-0.3, 0.1, 0.9));
    for c in cases() {
        let flow = FreeFlow::new(&c.inertia).unwrap();
        let body = FreeBody::new(c.inertia);
        let pi0 = c.inertia.apply(c.omega);
        let e0 = 0.5 * pi0.dot(c.inertia.apply_inverse(pi0));
        let spatial0 = r0 * pi0;
        let (mut p, mut r) = (pi0, r0);
        let mut worst: f64 = 0.0;
        for _ in 0..10_000 {
            (p, r) = flow.flow(p, &r, 0.01);
            let e = 0.5 * p.dot(body.inertia().apply_inverse(p));
            worst = worst
                .max(((p.norm() - pi0.norm()) / pi0.norm()).abs())
                .max(((e - e0) / e0).abs())
                .max((r * p - spatial0).max_abs() / pi0.norm());
        }
        // Each call rounds the invariants by a few ulps (three 3x3 products, B(n), the
        // elliptic functions), a random walk: 10 ε per call × sqrt(10^4) × 3 = 7e-13.
        assert!(
            worst < 7e-13,
            "{}: invariants drift by {worst:e} over 10^4 calls",
            c.name
        );
        assert!(
            so3::orthogonality_defect(&r) < 7e-13,
            "{}: defect {:e}",
            c.name,
            so3::orthogonality_defect(&r)
        );
        // Forward then backward.
        let (pf, rf) = flow.flow(pi0, &r0, 0.7);
        let (pb, rb) = flow.flow(pf, &rf, -0.7);
        let back = (pb - pi0).max_abs() / pi0.norm() + (rb - r0).max_abs();
        // The rounding of the midpoint state is carried back with the flow's sensitivity
        // κ (measured: near the separatrix, nearby motions part at e^{λt}).
        let delta = 1e-8 * pi0.norm();
        let (pd, rd) = flow.flow(pi0 + Vec3::new(delta, delta, -delta), &r0, 0.7);
        let kappa = (((pd - pf).max_abs() + (rd - rf).max_abs() * pi0.norm()) / delta).max(1.0);
        assert!(
            back < 1e-14 * kappa,
            "{}: flow(h) then flow(-h) misses by {back:e} (sensitivity {kappa:.1})",
            c.name
        );
    }
}

#[test]
fn degenerate_states() {
    let inertia = Inertia::principal([1.0, 2.0, 3.0]).unwrap();
    let flow = FreeFlow::new(&inertia).unwrap();
    let r0 = so3::exp(Vec3::new(0.1, 0.2, 0.3));
    // No momentum: nothing moves.
    assert_eq!(flow.flow(Vec3::ZERO, &r0, 5.0), (Vec3::ZERO, r0));
    // Steady rotation about each principal axis, the unstable intermediate one included.
    for axis in 0..3 {
        let mut w = [0.0; 3];
        w[axis] = 2.0;
        let pi = inertia.apply(Vec3::from_array(w));
        let (p, r) = flow.flow(pi, &r0, 3.0);
        assert!((p - pi).max_abs() < 1e-15, "axis {axis}: {p:?}");
        let expected = r0 * so3::exp(Vec3::from_array(w) * 3.0);
        assert!((r - expected).max_abs() < 1e-14, "axis {axis}");
    }
    // On the separatrix: |Π|²/2H = I₂ exactly (Π = (1, 0, 1) for I = (1, 2, 3)... scaled).
    let pi = Vec3::new(3.0f64.sqrt(), 0.0, 3.0);
    let h2 = pi.x * pi.x / 1.0 + pi.z * pi.z / 3.0;
    assert!((pi.norm_squared() / h2 - 2.0).abs() < 1e-15);
    let (p, r) = flow.flow(pi, &r0, 1.0);
    let reference = reference(inertia, pi, r0, 1.0, 1e-3);
    assert!(
        (p - reference.pi).max_abs() < 1e-11 && (r - reference.rotation).max_abs() < 1e-11,
        "separatrix: {p:?}"
    );
}
