//! The exact torque-free flow against the adaptive DOP853 baseline at rtol 1e-13 over 100
//! periods of the body angular momentum (issue 19), with the period from the classical
//! formula (Landau and Lifshitz, *Mechanics*, §37), independent of the library's own
//! parametrisation: after 100 periods `Π` is back at its start.

use liemid::{so3, FreeBody, FreeFlow, Inertia, Mat3, RigidState, Vec3};
use liemid_cli::rigid::baseline::dop853;

/// `K(m) = π / (2 AGM(1, √(1 − m)))`.
fn complete_k(m: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    // Quadratic convergence: 8 iterations reach round-off for m < 1 - 1e-12.
    for _ in 0..8 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

/// The period of `Π(t)` of a body with principal moments `i` (ascending) and body momentum
/// `pi`: `T = 4 K(k²) / ω_p` with, for `M² > 2E I₂`,
/// `k² = (I₂ − I₁)(2E I₃ − M²) / ((I₃ − I₂)(M² − 2E I₁))`,
/// `ω_p = √((I₃ − I₂)(M² − 2E I₁) / (I₁ I₂ I₃))`, and `I₁ ↔ I₃` exchanged otherwise.
fn period(i: [f64; 3], pi: Vec3) -> f64 {
    let m2 = pi.norm_squared();
    let e2 = pi.x * pi.x / i[0] + pi.y * pi.y / i[1] + pi.z * pi.z / i[2];
    let [i1, i2, i3] = if m2 > e2 * i[1] { i } else { [i[2], i[1], i[0]] };
    let k2 = (i2 - i1) * (e2 * i3 - m2) / ((i3 - i2) * (m2 - e2 * i1));
    let omega = ((i3 - i2) * (m2 - e2 * i1) / (i1 * i2 * i3)).sqrt();
    4.0 * complete_k(k2) / omega
}

#[test]
fn the_flow_agrees_with_dop853_at_rtol_1e_13_over_100_periods() {
    let q = so3::exp(Vec3::new(0.3, -0.7, 0.5));
    let r0 = so3::exp(Vec3::new(0.2, 0.5, -0.4));
    // (principal moments ascending, angular velocity, the body frame turned by `q` or not)
    let cases: [(&str, [f64; 3], Vec3, bool); 4] = [
        ("about the major axis", [1.0, 2.0, 3.0], Vec3::new(0.3, 0.4, 2.0), false),
        ("about the minor axis", [1.0, 2.0, 3.0], Vec3::new(3.0, 0.5, 0.2), false),
        ("near-symmetric", [1.0, 1.01, 2.0], Vec3::new(0.5, 0.3, 2.0), false),
        ("full tensor", [1.0, 2.0, 2.5], Vec3::new(0.7, -1.1, 2.3), true),
    ];
    for (name, moments, omega_principal, turned) in cases {
        let pi_principal = Vec3::new(
            moments[0] * omega_principal.x,
            moments[1] * omega_principal.y,
            moments[2] * omega_principal.z,
        );
        let t = 100.0 * period(moments, pi_principal);
        let (inertia, pi) = if turned {
            let m = q * Mat3::from_diagonal(Vec3::from_array(moments)) * q.transpose();
            let rows = std::array::from_fn(|k| m.row(k).to_array());
            (Inertia::from_matrix(rows).unwrap(), q * pi_principal)
        } else {
            (Inertia::principal(moments).unwrap(), pi_principal)
        };
        let flow = FreeFlow::new(&inertia).unwrap();
        let (p, r) = flow.flow(pi, &r0, t);
        // DOP853 at rtol 1e-13, as the issue asks, and at 1e-14. Over 100 periods the two
        // differ by up to 3e-11 in R and 1e-12 in Π (about the minor axis): DOP853's own
        // error is as large as the agreement to be shown, so each comparison is allowed
        // that difference on top of 1e-12 and 1e-11. `Π` is checked independently of any
        // integrator by its return after 100 periods.
        let body = FreeBody::new(inertia);
        let start = RigidState::new(0.0, pi, r0);
        let loose = dop853(&body, start, t, 1e-13).unwrap();
        let reference = dop853(&body, start, t, 1e-14).unwrap();
        let versus = |s: &RigidState| ((p - s.pi).norm() / pi.norm(), (r - s.rotation).norm_frobenius());
        let (dp, dr) = versus(&reference.state);
        let (dp13, dr13) = versus(&loose.state);
        let own = (loose.state.rotation - reference.state.rotation).norm_frobenius();
        let own_p = (loose.state.pi - reference.state.pi).norm() / pi.norm();
        // After whole periods Π is back where it started.
        let back = (p - pi).norm() / pi.norm();
        println!(
            "{name}: t = {t:.1} (100 periods); against DOP853 rtol 1e-14 ({} evaluations): Pi {dp:.2e}, R {dr:.2e}; \
             against rtol 1e-13: Pi {dp13:.2e}, R {dr13:.2e} (the two DOP853 runs differ by {own_p:.2e} in Pi, {own:.2e} in R); \
             Pi(t) - Pi(0) {back:.2e}",
            reference.evaluations
        );
        for (rtol, dp, dr) in [(1e-14, dp, dr), (1e-13, dp13, dr13)] {
            assert!(
                dp < 1e-12 + own_p && dr < 1e-11 + own,
                "{name}: against DOP853 at rtol {rtol:e}: Pi {dp:e}, R {dr:e}"
            );
        }
        assert!(back < 1e-12, "{name}: Pi after 100 periods is off by {back:e}");
    }
}
