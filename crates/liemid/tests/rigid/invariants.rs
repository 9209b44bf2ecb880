//! Invariants: what each method keeps to round-off, and the bounded energy error of the
//! time-reversible EA over long runs.

use liemid::{integrate, integrate_to, rigid::problems, RotationIntegrator, RotationMethod};

const MIDPOINT_FAMILY: [RotationMethod; 4] = [
    RotationMethod::LieMidpointE1,
    RotationMethod::LieMidpointE2,
    RotationMethod::LieMidpointAlternating,
    RotationMethod::LieMidpointImplicit,
];

#[test]
fn torque_free_midpoint_methods_keep_body_momentum_norm_and_spatial_momentum() {
    // The tennis-racket body flips repeatedly: a hard test of |Π| and π.
    let body = problems::free_body();
    let h = 1e-3;
    let t_end = 100.0; // 10⁵ steps
    for method in MIDPOINT_FAMILY {
        let s = integrate_to(&mut method.integrator(), &body.system, body.initial, t_end, h).unwrap();
        assert_eq!(s.steps, 100_000);
        let norm0 = s.initial.body_momentum_norm;
        let dnorm = s.max_body_momentum_norm_change / norm0;
        let dpi = s.max_spatial_momentum_change.max_abs() / s.initial.spatial_momentum.norm();
        println!("{:<11} |Π| {dnorm:.2e}, π {dpi:.2e}", method.name());
        assert!(dnorm < 1e-12, "{}: |Π| changed by {dnorm:e} (relative)", method.name());
        assert!(dpi < 1e-12, "{}: π changed by {dpi:e} (relative)", method.name());
    }
    // NMB is not momentum conserving: the same test sees its drift, so the check can fail.
    let s = integrate_to(
        &mut RotationMethod::KryslEndresNewmark.integrator(),
        &body.system,
        body.initial,
        t_end,
        h,
    )
    .unwrap();
    let dpi = s.max_spatial_momentum_change.max_abs() / s.initial.spatial_momentum.norm();
    assert!(dpi > 1e-6, "NMB keeps π to {dpi:e}?");
}

#[test]
fn heavy_top_vertical_spatial_momentum_is_kept_by_the_explicit_family() {
    let top = problems::fast_top();
    let h = 1e-4;
    let t_end = 10.0; // 10⁵ steps
    for method in [
        RotationMethod::LieMidpointE1,
        RotationMethod::LieMidpointE2,
        RotationMethod::LieMidpointAlternating,
    ] {
        let s = integrate_to(&mut method.integrator(), &top.system, top.initial, t_end, h).unwrap();
        let d = s.max_spatial_momentum_change.z / s.initial.spatial_momentum.norm();
        println!("{:<11} π·e3 changed by {d:.2e} (relative)", method.name());
        assert!(d < 1e-12, "{}: π·e3 changed by {d:e}", method.name());
    }
}

/// Largest relative energy error over the first and over the last tenth of a run, and the
/// final orthogonality defect.
fn energy_error_tenths<M: RotationIntegrator>(mut method: M, h: f64, steps: u64) -> (f64, f64, f64) {
    let top = problems::fast_top();
    let t_end = h * steps as f64;
    let e0 = liemid::Diagnostics::of(&top.system, &top.initial).energy;
    let (mut first, mut last) = (0.0f64, 0.0f64);
    let tenth = steps / 10;
    let s = integrate(&mut method, &top.system, top.initial, t_end, h, 1, |k, _, d| {
        let e = ((d.energy - e0) / e0).abs();
        if k <= tenth {
            first = first.max(e);
        }
        if k >= steps - tenth {
            last = last.max(e);
        }
        Ok(())
    })
    .unwrap();
    assert_eq!(s.steps, steps);
    (first, last, s.last.orthogonality_defect)
}

#[test]
fn ea_energy_error_is_bounded_without_drift_and_attitude_stays_orthogonal_over_a_million_steps() {
    let (first, last, defect) = energy_error_tenths(liemid::LieMidpointAlternating::new(), 1e-4, 1_000_000);
    println!("EA, 10⁶ steps: max energy error first tenth {first:.3e}, last tenth {last:.3e}; defect {defect:.2e}");
    // Reversible (EA is not symplectic, tests/rigid/lie_poisson.rs): for this integrable,
    // reversible problem a reversible method keeps the energy error bounded without drift
    // (Hairer-Lubich-Wanner XI), so it oscillates with the same amplitude at the end as at
    // the start.
    assert!(last < 1.5 * first, "energy drift: {first:e} -> {last:e}");
    // Bounded at the size of the O(h²) modified-energy difference: halving the step
    // divides the largest error by four.
    let (coarse, _, _) = energy_error_tenths(liemid::LieMidpointAlternating::new(), 2e-4, 500_000);
    let order = (coarse / first).log2();
    println!("energy error at h = 2e-4: {coarse:.3e}; observed order {order:.2}");
    assert!((order - 2.0).abs() < 0.2, "energy error order {order}");
    // No re-orthonormalisation: products of exact exponentials stay orthogonal.
    assert!(defect < 1e-10, "orthogonality defect {defect:e}");
}

#[test]
fn the_drift_check_does_see_rk4_drift() {
    // The same check on a method that is neither symplectic nor reversible, at a coarse
    // step: its energy drifts.
    let (first, last, _) = energy_error_tenths(liemid::RungeKutta4Quaternion::new(), 5e-4, 100_000);
    println!("RK4: max energy error first tenth {first:.3e}, last tenth {last:.3e}");
    assert!(last > 3.0 * first, "RK4 shows no drift: {first:e} -> {last:e}");
}
