//! Reversible adaptive steps (Hairer-Söderlind): orders in eps, time reversibility against
//! the run's measured sensitivity, the steps saved on the eccentric satellite, bounded
//! invariants over many orbits, and the refusals.

use liemid::composition::{Composition, Scheme};
use liemid::rigid::adaptive::{
    AdaptiveRun, AngularSpeed, CentralDensity, ReversibleStepper, RigidAdaptive, TorqueRate, VectorAdaptive,
};
use liemid::rigid::problems;
use liemid::rigid::satellite::{
    eccentric_satellite, SatelliteAdaptive, SatelliteDensity, SatelliteIntegrator, SatelliteProblem, SatelliteState,
};
use liemid::vector::problems::Kepler;
use liemid::vector::Verlet;
use liemid::{observed_order, Error, RotationMethod as M};

/// The unit round-off.
const U: f64 = f64::EPSILON / 2.0;

fn satellite_fixed(p: &SatelliteProblem, m: M, n: u64, t_end: f64) -> SatelliteState {
    let mut i = SatelliteIntegrator::new(m, &p.satellite).unwrap();
    let mut s = p.initial;
    i.advance(&p.satellite, &mut s, t_end, n).unwrap();
    s
}

fn satellite_adaptive(p: &SatelliteProblem, m: M, eps: f64, t_end: f64) -> (SatelliteState, u64) {
    let st = SatelliteAdaptive::new(&p.satellite, m, SatelliteDensity::Orbit).unwrap();
    let mut run = AdaptiveRun::new(st, p.initial, t_end, eps).unwrap();
    let stats = run.run_to_end().unwrap();
    assert_eq!(run.state().t, t_end, "the run lands exactly on t_end");
    (*run.state(), stats.steps)
}

fn attitude_error(a: &SatelliteState, b: &SatelliteState) -> f64 {
    (a.rotation - b.rotation).norm_frobenius()
}

/// The steps a curve `(steps, error)` needs for `error = target`, by log-log interpolation.
fn steps_at(curve: &[(f64, f64)], target: f64) -> f64 {
    for w in curve.windows(2) {
        let ((n0, e0), (n1, e1)) = (w[0], w[1]);
        if (e0 - target) * (e1 - target) <= 0.0 {
            let s = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            return (n0.ln() + s * (n1.ln() - n0.ln())).exp();
        }
    }
    panic!("{target:e} is outside the curve {curve:?}");
}

/// One orbit of the Molniya satellite: at equal final attitude error, the adaptive EA and
/// EX (orbit density) take at least 5 times fewer steps than at a fixed step.
#[test]
fn the_eccentric_satellite_needs_five_times_fewer_steps() {
    let p = eccentric_satellite();
    let t = p.period;
    let reference = satellite_fixed(&p, M::LieMidpointExact8, 10_000, t);
    let check = satellite_fixed(&p, M::LieMidpointAlternating8, 20_000, t);
    let agreement = attitude_error(&reference, &check);
    assert!(agreement < 1e-9, "references disagree by {agreement:e}");
    for m in [M::LieMidpointAlternating, M::LieMidpointExact] {
        let fixed: Vec<(f64, f64)> = [2000u64, 4000, 8000, 16_000]
            .iter()
            .map(|&n| (n as f64, attitude_error(&satellite_fixed(&p, m, n, t), &reference)))
            .collect();
        let adaptive: Vec<(f64, f64)> = [0.02, 0.01, 0.005, 0.0025]
            .iter()
            .map(|&eps| {
                let (s, n) = satellite_adaptive(&p, m, eps, t);
                (n as f64, attitude_error(&s, &reference))
            })
            .collect();
        for target in [1e-2, 3e-3, 1.5e-3] {
            let ratio = steps_at(&fixed, target) / steps_at(&adaptive, target);
            println!(
                "{}: attitude error {target:e}: fixed/adaptive steps = {ratio:.2}",
                m.key()
            );
            assert!(ratio >= 5.0, "{}: ratio {ratio} at {target:e}", m.key());
        }
    }
}

/// Observed orders 2, 4, 6, 8 in eps (the slow Lagrangian top, density |Ω|, against EA8
/// at a fixed step 1e-5), each within 0.2 of the method's order. The ranges of eps are
/// where the error is asymptotic and above the reference's 1e-12.
#[test]
fn orders_in_eps_are_the_methods_orders() {
    let top = problems::slow_top();
    let t_end = 0.8;
    let mut ea8 = M::LieMidpointAlternating8.integrator();
    let reference = liemid::integrate_to(&mut ea8, &top.system, top.initial, t_end, 1e-5)
        .unwrap()
        .state;
    let cases: [(M, &[f64]); 5] = [
        (M::LieMidpointAlternating, &[0.4, 0.28, 0.2, 0.14, 0.1]),
        (M::LieMidpointAlternating4, &[0.8, 0.56, 0.4, 0.28, 0.2]),
        (M::LieMidpointAlternating6, &[1.6, 1.13, 0.8, 0.56]),
        (M::LieMidpointAlternating8, &[2.0, 1.6, 1.3, 1.0]),
        (M::LieMidpointExact4, &[1.6, 1.13, 0.8, 0.56, 0.4]),
    ];
    for (m, epss) in cases {
        let errors: Vec<f64> = epss
            .iter()
            .map(|&eps| {
                let st = RigidAdaptive::new(&top.system, m, AngularSpeed).unwrap();
                let mut run = AdaptiveRun::new(st, top.initial, t_end, eps).unwrap();
                run.run_to_end().unwrap();
                (run.state().rotation - reference.rotation).norm_frobenius()
            })
            .collect();
        let order = observed_order(epss, &errors).unwrap();
        println!("{}: errors {errors:?}, observed order {order:.3}", m.key());
        assert!(errors.iter().all(|&e| e > 5e-12), "{}: {errors:?}", m.key());
        assert!((order - f64::from(m.order())).abs() < 0.2, "{}: order {order}", m.key());
    }
}

/// Verlet and its fourth-order composition on Kepler's problem at e = 0.74 with the orbit
/// density `|u|^{-3/2}`: orders 2 and 4 in eps against the exact solution.
#[test]
fn verlet_on_kepler_keeps_its_orders() {
    let e = 0.74;
    let t_end = 2.0 * std::f64::consts::PI;
    let exact = Kepler::exact(e, t_end);
    let system = Kepler::default();
    let run = |eps: f64, composed: bool| -> (f64, u64) {
        let state = Kepler::initial(e);
        let (end, steps) = if composed {
            let m = Composition::new(Verlet::default(), Scheme::SUZUKI4, "Verlet4");
            let mut r = AdaptiveRun::new(
                VectorAdaptive::new(&system, m, CentralDensity::default()),
                state,
                t_end,
                eps,
            )
            .unwrap();
            let s = r.run_to_end().unwrap();
            (r.state().clone(), s.steps)
        } else {
            let m = Verlet::default();
            let mut r = AdaptiveRun::new(
                VectorAdaptive::new(&system, m, CentralDensity::default()),
                state,
                t_end,
                eps,
            )
            .unwrap();
            let s = r.run_to_end().unwrap();
            (r.state().clone(), s.steps)
        };
        let d = (end.u[0] - exact.u[0]).hypot(end.u[1] - exact.u[1]);
        (d, steps)
    };
    for (composed, order, epss) in [
        (false, 2.0, [0.02, 0.014, 0.01, 0.007]),
        (true, 4.0, [0.1, 0.07, 0.05, 0.035]),
    ] {
        let errors: Vec<f64> = epss.iter().map(|&eps| run(eps, composed).0).collect();
        let observed = observed_order(&epss, &errors).unwrap();
        println!("Verlet (composed: {composed}): errors {errors:?}, order {observed:.3}");
        assert!((observed - order).abs() < 0.2, "order {observed}");
    }
    // The fixed step Verlet needs for the adaptive one's error at eps = 0.01.
    let (target, steps) = run(0.01, false);
    let mut n = steps;
    loop {
        let mut s = Kepler::initial(e);
        let h = t_end / n as f64;
        let mut v = Verlet::default();
        for _ in 0..n {
            liemid::vector::VectorIntegrator::step(&mut v, &system, &mut s, h).unwrap();
        }
        let d = (s.u[0] - exact.u[0]).hypot(s.u[1] - exact.u[1]);
        if d <= target {
            println!("Kepler e = 0.74: adaptive {steps} steps, fixed {n} steps for error {target:.3e}");
            assert!(n >= 5 * steps);
            break;
        }
        n *= 2;
    }
}

/// The REBOUND protocol: forward to t_end, momenta negated, back to t0. The distance to
/// the negated start is round-off times the sensitivity of the run; `A` is measured by
/// perturbing the start (relative 1e-8), and the bound is `100 u max(A, 1) √(stages)`,
/// `stages` the steps times the composition's stages. An adaptive step whose `G` is not
/// odd under the reversal breaks it by orders of magnitude (the test can fail).
#[test]
fn forward_negate_back_returns_to_the_start() {
    let p = eccentric_satellite();
    let t = p.period;
    let check = |name: &str, distance: f64, sensitivity: f64, work: f64| {
        let bound = 100.0 * U * sensitivity.max(1.0) * work.sqrt();
        println!("{name}: distance {distance:.3e}, sensitivity {sensitivity:.2}, bound {bound:.3e}");
        distance <= bound
    };
    for (m, stages) in [(M::LieMidpointAlternating, 1.0), (M::LieMidpointExact8, 17.0)] {
        let go = |start: SatelliteState| {
            let st = SatelliteAdaptive::new(&p.satellite, m, SatelliteDensity::Orbit).unwrap();
            let mut run = AdaptiveRun::new(st, start, t, 0.01).unwrap();
            run.run_to_end().unwrap();
            run
        };
        let forward = go(p.initial);
        let end = *forward.state();
        let mut back = forward.reverse().unwrap();
        let steps = back.run_to_end().unwrap().steps;
        let b = back.state();
        assert_eq!(b.t, 0.0);
        let distance = (b.rotation - p.initial.rotation).norm_frobenius()
            + (b.pi + p.initial.pi).norm() / p.initial.pi.norm()
            + (b.position - p.initial.position).norm() / p.initial.position.norm()
            + (b.velocity + p.initial.velocity).norm() / p.initial.velocity.norm();
        let mut nudged = p.initial;
        nudged.pi = nudged.pi * (1.0 + 1e-8);
        let sensitivity = (go(nudged).state().rotation - end.rotation).norm_frobenius() / 1e-8;
        assert!(check(m.key(), distance, sensitivity, steps as f64 * stages));
    }
    // The heavy top, EA4 with the density |Ω| and with the torque's rate.
    let top = problems::fast_top();
    let distance = |density: bool| {
        let forward = if density {
            let st = RigidAdaptive::new(&top.system, M::LieMidpointAlternating4, TorqueRate).unwrap();
            let mut run = AdaptiveRun::new(st, top.initial, 0.05, 0.2).unwrap();
            run.run_to_end().unwrap();
            let mut back = run.reverse().unwrap();
            back.run_to_end().unwrap();
            *back.state()
        } else {
            let st = RigidAdaptive::new(&top.system, M::LieMidpointAlternating4, AngularSpeed).unwrap();
            let mut run = AdaptiveRun::new(st, top.initial, 0.05, 0.2).unwrap();
            run.run_to_end().unwrap();
            let mut back = run.reverse().unwrap();
            back.run_to_end().unwrap();
            *back.state()
        };
        (forward.rotation - top.initial.rotation).norm_frobenius()
            + (forward.pi + top.initial.pi).norm() / top.initial.pi.norm()
    };
    for density in [false, true] {
        let d = distance(density);
        println!("fast top EA4 (torque density: {density}): distance {d:.3e}");
        assert!(d < 1e-11, "{d:e}");
    }

    // A control whose G is even under the reversal (|G|): not reversible.
    #[derive(Clone)]
    struct EvenG<'a>(SatelliteAdaptive<'a>);
    impl ReversibleStepper for EvenG<'_> {
        type State = SatelliteState;
        fn name(&self) -> &'static str {
            "even G"
        }
        fn order(&self) -> u32 {
            2
        }
        fn density_name(&self) -> &'static str {
            "|G|"
        }
        fn step(&mut self, state: &mut SatelliteState, h: f64) -> liemid::Result<()> {
            self.0.step(state, h)
        }
        fn time(state: &SatelliteState) -> f64 {
            state.t
        }
        fn set_time(state: &mut SatelliteState, t: f64) {
            state.t = t;
        }
        fn negate_momenta(state: &mut SatelliteState) {
            SatelliteAdaptive::negate_momenta(state);
        }
        fn density(&mut self, state: &SatelliteState) -> (f64, f64) {
            let (rho, g) = self.0.density(state);
            (rho, g.abs())
        }
    }
    let st = SatelliteAdaptive::new(&p.satellite, M::LieMidpointAlternating, SatelliteDensity::Orbit).unwrap();
    let mut run = AdaptiveRun::new(EvenG(st), p.initial, t, 0.01).unwrap();
    run.run_to_end().unwrap();
    let mut back = run.reverse().unwrap();
    back.run_to_end().unwrap();
    let b = back.state();
    let d = (b.rotation - p.initial.rotation).norm_frobenius();
    println!("control with an even G: distance {d:.3e}");
    assert!(!check("even G", d, 11.0, 725.0), "the control should not be reversible");
}

/// Many orbits with the adaptive EA: the energy error stays bounded (the largest over the
/// last tenth at most 1.2 times the largest over the first) and the total angular momentum
/// error at round-off.
#[test]
fn invariants_stay_bounded_over_many_orbits() {
    let p = eccentric_satellite();
    let orbits = 100.0;
    let t_end = orbits * p.period;
    let st = SatelliteAdaptive::new(&p.satellite, M::LieMidpointAlternating, SatelliteDensity::Orbit).unwrap();
    let mut run = AdaptiveRun::new(st, p.initial, t_end, 0.02).unwrap();
    let sat = p.satellite;
    let (e0, l0) = (sat.energy(&p.initial), sat.angular_momentum(&p.initial));
    let mut tenths = [(0.0f64, 0.0f64); 10];
    while !run.is_done() {
        run.step().unwrap();
        let s = run.state();
        let k = ((s.t / t_end * 10.0) as usize).min(9);
        let de = ((sat.energy(s) - e0) / e0).abs();
        let dl = (sat.angular_momentum(s) - l0).norm() / l0.norm();
        tenths[k] = (tenths[k].0.max(de), tenths[k].1.max(dl));
    }
    println!("energy, momentum errors per tenth: {tenths:?}");
    assert!(tenths[9].0 <= 1.2 * tenths[0].0, "energy drifts: {tenths:?}");
    // The momentum error is the rounding of its own evaluation, m r × v + R Π from the
    // rounded state (a few ulps, measured 3.8e-16 to 4.7e-16 per tenth), in every tenth: the
    // orbit is summed to twice the working precision with the central kick `c r` and the
    // drift `h v` added as exact products, so the kicks' rounding does not accumulate either
    // (before: a random walk, 6.8e-16 at 100 orbits; without any compensation u sqrt(n),
    // about 2e-14 over these ~3.6e4 steps).
    for (k, t) in tenths.iter().enumerate() {
        assert!(t.1 <= 1e-15, "momentum error above round-off in tenth {k}: {tenths:?}");
    }
}

#[test]
fn refuses_methods_that_are_not_symmetric_and_bad_parameters() {
    let top = problems::fast_top();
    for m in [
        M::RungeKutta4,
        M::LieMidpointE1,
        M::LieMidpointE2,
        M::RungeKuttaMuntheKaas4,
    ] {
        let e = RigidAdaptive::new(&top.system, m, AngularSpeed).unwrap_err();
        assert!(matches!(e, Error::NotReversible { .. }), "{e}");
        assert!(e.to_string().contains("not symmetric"), "{e}");
    }
    let p = eccentric_satellite();
    assert!(SatelliteIntegrator::new(M::RungeKutta4, &p.satellite).is_err());
    for eps in [0.0, -1.0, f64::NAN] {
        let st = RigidAdaptive::new(&top.system, M::LieMidpointAlternating, AngularSpeed).unwrap();
        assert!(matches!(
            AdaptiveRun::new(st, top.initial, 0.1, eps),
            Err(Error::InvalidParameter { name: "eps", .. })
        ));
    }
    // A body at rest has no density |Ω|.
    let mut rest = top.initial;
    rest.pi = liemid::Vec3::ZERO;
    let st = RigidAdaptive::new(&top.system, M::LieMidpointAlternating, AngularSpeed).unwrap();
    let e = AdaptiveRun::new(st, rest, 0.1, 0.1).unwrap_err();
    assert!(e.to_string().contains("rho = 0e0"), "{e}");
    // A run not finished cannot be reversed.
    let st = RigidAdaptive::new(&top.system, M::LieMidpointAlternating, AngularSpeed).unwrap();
    let mut run = AdaptiveRun::new(st, top.initial, 0.1, 0.1).unwrap();
    run.step().unwrap();
    assert!(run.reverse().is_err());
}
