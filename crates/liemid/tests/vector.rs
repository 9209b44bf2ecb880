//! The vector-space impulse integrators: orders, invariants and adjointness on the
//! harmonic oscillator, the Kepler problem and the pendulum.

mod common;

use common::{halvings, observed_order};
use liemid::vector::problems::{HarmonicOscillator, Kepler, Pendulum};
use liemid::vector::{
    ExplicitNewmark, MassMatrix, MechanicalSystem, PhaseState, SymplecticEuler, SymplecticEulerAdjoint,
    VectorIntegrator, Verlet,
};
use liemid::{Composition, Error, Scheme};

fn run<M: VectorIntegrator, S: MechanicalSystem>(
    mut m: M,
    system: &S,
    s0: &PhaseState,
    t_end: f64,
    h: f64,
) -> PhaseState {
    let n = (t_end / h).round() as usize;
    let mut s = s0.clone();
    for _ in 0..n {
        m.step(system, &mut s, h).unwrap();
    }
    s
}

fn distance(a: &PhaseState, b: &PhaseState) -> f64 {
    a.p.iter()
        .zip(&b.p)
        .chain(a.u.iter().zip(&b.u))
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

fn order_of<M: VectorIntegrator, S: MechanicalSystem>(
    make: impl Fn() -> M,
    system: &S,
    s0: &PhaseState,
    t_end: f64,
    exact: &PhaseState,
    hs: &[f64],
) -> f64 {
    let errs: Vec<f64> = hs
        .iter()
        .map(|&h| distance(&run(make(), system, s0, t_end, h), exact))
        .collect();
    observed_order(hs, &errs)
}

/// A hand-written classical RK4, for the pendulum's reference.
fn rk4_reference<S: MechanicalSystem>(system: &S, s0: &PhaseState, t_end: f64, n: usize) -> PhaseState {
    let h = t_end / n as f64;
    let dim = system.dim();
    let rate = |p: &[f64], u: &[f64], t: f64| {
        let mut f = vec![0.0; dim];
        system.force(u, t, &mut f);
        let mut v = p.to_vec();
        system.mass().solve_in_place(&mut v);
        (f, v)
    };
    let mut s = s0.clone();
    for _ in 0..n {
        let add = |x: &[f64], d: &[f64], c: f64| x.iter().zip(d).map(|(a, b)| a + c * b).collect::<Vec<_>>();
        let (k1p, k1u) = rate(&s.p, &s.u, s.t);
        let (k2p, k2u) = rate(&add(&s.p, &k1p, h / 2.0), &add(&s.u, &k1u, h / 2.0), s.t + h / 2.0);
        let (k3p, k3u) = rate(&add(&s.p, &k2p, h / 2.0), &add(&s.u, &k2u, h / 2.0), s.t + h / 2.0);
        let (k4p, k4u) = rate(&add(&s.p, &k3p, h), &add(&s.u, &k3u, h), s.t + h);
        for i in 0..dim {
            s.p[i] += h / 6.0 * (k1p[i] + 2.0 * k2p[i] + 2.0 * k3p[i] + k4p[i]);
            s.u[i] += h / 6.0 * (k1u[i] + 2.0 * k2u[i] + 2.0 * k3u[i] + k4u[i]);
        }
        s.t += h;
    }
    s
}

#[test]
fn orders_on_the_harmonic_oscillator() {
    let osc = HarmonicOscillator::new(2.0, 3.0).unwrap();
    let s0 = PhaseState::new(0.0, vec![0.4], vec![1.0]).unwrap();
    let exact = osc.exact(0.4, 1.0, 5.0);
    let hs = halvings(0.05, 5);
    let cases: [(&str, f64, f64); 5] = [
        (
            "Euler",
            order_of(SymplecticEuler::default, &osc, &s0, 5.0, &exact, &hs),
            1.0,
        ),
        (
            "adjoint",
            order_of(SymplecticEulerAdjoint::default, &osc, &s0, 5.0, &exact, &hs),
            1.0,
        ),
        ("Verlet", order_of(Verlet::default, &osc, &s0, 5.0, &exact, &hs), 2.0),
        (
            "Newmark 1/2",
            order_of(|| ExplicitNewmark::new(0.5).unwrap(), &osc, &s0, 5.0, &exact, &hs),
            2.0,
        ),
        (
            "Newmark 0.6",
            order_of(|| ExplicitNewmark::new(0.6).unwrap(), &osc, &s0, 5.0, &exact, &hs),
            1.0,
        ),
    ];
    for (name, order, expected) in cases {
        println!("{name}: {order:.3}");
        assert!(
            (order - expected).abs() < 0.1,
            "{name}: order {order}, expected {expected}"
        );
    }
}

#[test]
fn kepler_orbit_orders_and_invariants() {
    let e = 0.5;
    let kepler = Kepler::default();
    let s0 = Kepler::initial(e);
    let period = 2.0 * std::f64::consts::PI;
    assert!(
        distance(&Kepler::exact(e, period), &s0) < 1e-14,
        "exact solution is periodic"
    );
    // Over a full period the first-order errors of symplectic Euler cancel by symmetry;
    // measure at an unremarkable time, with steps that divide it exactly.
    let t_end = 2.0;
    let exact = Kepler::exact(e, t_end);
    let hs = halvings(t_end / 500.0, 5);
    let ov = order_of(Verlet::default, &kepler, &s0, t_end, &exact, &hs);
    let oe = order_of(SymplecticEuler::default, &kepler, &s0, t_end, &exact, &hs);
    println!("Kepler: Verlet {ov:.3}, Euler {oe:.3}");
    assert!((ov - 2.0).abs() < 0.1 && (oe - 1.0).abs() < 0.1, "orders {ov} {oe}");

    // Central force: angular momentum to round-off; energy bounded over 100 orbits.
    let l0 = Kepler::angular_momentum(&s0);
    let e0 = kepler.energy(&s0);
    let mut verlet = Verlet::default();
    let mut s = s0.clone();
    let h = 2.0 * std::f64::consts::PI / 1000.0;
    let (mut max_dl, mut first, mut last) = (0.0f64, 0.0f64, 0.0f64);
    let n = 100_000;
    for k in 0..n {
        verlet.step(&kepler, &mut s, h).unwrap();
        max_dl = max_dl.max((Kepler::angular_momentum(&s) - l0).abs());
        let de = ((kepler.energy(&s) - e0) / e0).abs();
        if k < n / 10 {
            first = first.max(de);
        } else if k >= n - n / 10 {
            last = last.max(de);
        }
    }
    println!("Kepler: max |ΔL| {max_dl:.2e}, energy error first tenth {first:.2e}, last tenth {last:.2e}");
    assert!(max_dl < 1e-12 * l0.abs(), "angular momentum changed by {max_dl:e}");
    assert!(last < 1.5 * first, "energy drift {first:e} -> {last:e}");
}

#[test]
fn pendulum_orders_and_adjointness() {
    let pendulum = Pendulum::new(4.0);
    let s0 = PhaseState::new(0.0, vec![0.0], vec![2.5]).unwrap(); // large amplitude
    let t_end = 3.0;
    let reference = rk4_reference(&pendulum, &s0, t_end, 300_000);
    let hs = halvings(1e-2, 5);
    let ov = order_of(Verlet::default, &pendulum, &s0, t_end, &reference, &hs);
    let oa = order_of(SymplecticEulerAdjoint::default, &pendulum, &s0, t_end, &reference, &hs);
    println!("pendulum: Verlet {ov:.3}, adjoint Euler {oa:.3}");
    assert!((ov - 2.0).abs() < 0.1 && (oa - 1.0).abs() < 0.1, "orders {ov} {oa}");

    // Φ*_h = (Φ_{−h})⁻¹ and Verlet is symmetric.
    let h = 0.1;
    let mut s = s0.clone();
    SymplecticEulerAdjoint::default().step(&pendulum, &mut s, h).unwrap();
    SymplecticEuler::default().step(&pendulum, &mut s, -h).unwrap();
    assert!(distance(&s, &s0) < 1e-15, "Φ_-h o Φ*_h != id");
    let mut v = Verlet::default();
    let mut s = s0.clone();
    v.step(&pendulum, &mut s, h).unwrap();
    v.step(&pendulum, &mut s, -h).unwrap();
    assert!(distance(&s, &s0) < 1e-15, "Verlet not symmetric");
    // Verlet = Φ*_{h/2} ∘ Φ_{h/2}.
    let mut a = s0.clone();
    Verlet::default().step(&pendulum, &mut a, h).unwrap();
    let mut b = s0.clone();
    SymplecticEuler::default().step(&pendulum, &mut b, h / 2.0).unwrap();
    SymplecticEulerAdjoint::default()
        .step(&pendulum, &mut b, h / 2.0)
        .unwrap();
    assert!(distance(&a, &b) < 1e-15);
}

/// Two masses coupled by springs, with a dense mass matrix.
struct CoupledSprings {
    mass: MassMatrix,
}

impl MechanicalSystem for CoupledSprings {
    fn mass(&self) -> &MassMatrix {
        &self.mass
    }
    fn force(&self, u: &[f64], _t: f64, f: &mut [f64]) {
        f[0] = -2.0 * u[0] + u[1];
        f[1] = u[0] - 2.0 * u[1];
    }
    fn potential_energy(&self, u: &[f64], _t: f64) -> f64 {
        u[0] * u[0] + u[1] * u[1] - u[0] * u[1]
    }
}

#[test]
fn dense_mass_matrix_and_bad_input() {
    let springs = CoupledSprings {
        mass: MassMatrix::dense(2, &[2.0, 0.5, 0.5, 1.0]).unwrap(),
    };
    let s0 = PhaseState::new(0.0, vec![0.0, 0.0], vec![1.0, 0.0]).unwrap();
    let e0 = springs.energy(&s0);
    let mut v = Verlet::default();
    let mut s = s0.clone();
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        v.step(&springs, &mut s, 0.01).unwrap();
        worst = worst.max((springs.energy(&s) - e0).abs() / e0);
    }
    // Verlet keeps a modified energy: its error is O(h²) = O(1e-4) and does not grow.
    assert!(worst < 1e-4, "energy error {worst:e}");
    // M⁻¹ by Cholesky agrees with the explicit inverse.
    let mut x = vec![1.0, 2.0];
    springs.mass.solve_in_place(&mut x);
    let det = 2.0 * 1.0 - 0.25;
    assert!((x[0] - (1.0 * 1.0 - 0.5 * 2.0) / det).abs() < 1e-15 && (x[1] - (2.0 * 2.0 - 0.5) / det).abs() < 1e-15);

    assert!(matches!(
        MassMatrix::dense(2, &[1.0, 2.0, 2.0, 1.0]),
        Err(Error::InvalidMass { .. })
    ));
    assert!(matches!(
        MassMatrix::dense(2, &[1.0, 0.1, 0.2, 1.0]),
        Err(Error::InvalidMass { .. })
    ));
    assert!(matches!(
        MassMatrix::diagonal(vec![1.0, 0.0]),
        Err(Error::InvalidMass { .. })
    ));
    assert!(matches!(
        PhaseState::new(0.0, vec![f64::NAN], vec![0.0]),
        Err(Error::NonFiniteState { field: "p", .. })
    ));
    let mut s = s0.clone();
    assert!(matches!(v.step(&springs, &mut s, 0.0), Err(Error::InvalidStep { .. })));
    assert!(matches!(
        ExplicitNewmark::new(f64::NAN),
        Err(Error::InvalidParameter { .. })
    ));
}

#[test]
fn verlet_compositions_reach_their_orders() {
    // Kepler e = 0.5 at an unremarkable time, against the exact solution.
    let kepler = Kepler::default();
    let s0 = Kepler::initial(0.5);
    let t_end = 2.0;
    let exact = Kepler::exact(0.5, t_end);
    for (scheme, h0, n) in [
        (Scheme::SUZUKI4, t_end / 50.0, 5),
        (Scheme::YOSHIDA4, t_end / 50.0, 5),
        (Scheme::KAHAN_LI6, t_end / 20.0, 4),
        (Scheme::KAHAN_LI8, t_end / 10.0, 3),
    ] {
        let hs = halvings(h0, n);
        let make = || Composition::new(Verlet::default(), scheme, "composed Verlet");
        let order = order_of(make, &kepler, &s0, t_end, &exact, &hs);
        println!("Verlet composed by {}: order {order:.3}", scheme.name);
        assert!(
            (order - f64::from(scheme.order)).abs() < 0.1,
            "{}: order {order}",
            scheme.name
        );
    }
}

/// The canonical symplecticity defect `max |Jᵀ Ω J − Ω|` of one step of `make()` on the
/// Kepler problem (phase space `(u, p)` of dimension 4), `J` by central differences
/// extrapolated once (resolution about 1e-10).
fn symplecticity_defect<M: VectorIntegrator>(make: impl Fn() -> M, h: f64) -> f64 {
    let kepler = Kepler::default();
    let x0 = Kepler::initial(0.5);
    let flat = |s: &PhaseState| [s.u[0], s.u[1], s.p[0], s.p[1]];
    let image = |x: [f64; 4]| {
        let mut s = PhaseState::new(0.0, vec![x[2], x[3]], vec![x[0], x[1]]).unwrap();
        make().step(&kepler, &mut s, h).unwrap();
        flat(&s)
    };
    let x = flat(&x0);
    let central = |e: f64, k: usize| {
        let (mut plus, mut minus) = (x, x);
        plus[k] += e;
        minus[k] -= e;
        let (a, b) = (image(plus), image(minus));
        [0, 1, 2, 3].map(|r| (a[r] - b[r]) * (0.5 / e))
    };
    // Columns of J.
    let j: Vec<[f64; 4]> = (0..4)
        .map(|k| {
            let (coarse, fine) = (central(2e-3, k), central(1e-3, k));
            [0, 1, 2, 3].map(|r| (4.0 * fine[r] - coarse[r]) / 3.0)
        })
        .collect();
    // ω(a, b) = a_u · b_p − a_p · b_u.
    let omega = |a: &[f64; 4], b: &[f64; 4]| a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
    let mut worst: f64 = 0.0;
    for a in 0..4 {
        for b in 0..4 {
            let unit = |k: usize| [0, 1, 2, 3].map(|r| if r == k { 1.0 } else { 0.0 });
            worst = worst.max((omega(&j[a], &j[b]) - omega(&unit(a), &unit(b))).abs());
        }
    }
    worst
}

#[test]
fn the_impulse_methods_are_symplectic_and_newmark_only_at_gamma_one_half() {
    for h in [0.1, 0.05] {
        let d = [
            ("symplectic Euler", symplecticity_defect(SymplecticEuler::default, h)),
            ("its adjoint", symplecticity_defect(SymplecticEulerAdjoint::default, h)),
            ("Verlet", symplecticity_defect(Verlet::default, h)),
            (
                "Newmark γ = 1/2",
                symplecticity_defect(|| ExplicitNewmark::new(0.5).unwrap(), h),
            ),
        ];
        for (name, defect) in d {
            println!("h = {h}: {name} defect {defect:.2e}");
            assert!(defect < 1e-9, "{name} at h = {h}: {defect:e}");
        }
        // γ ≠ ½ damps (γ > ½) or excites: not symplectic, and the test sees it.
        let newmark = symplecticity_defect(|| ExplicitNewmark::new(0.6).unwrap(), h);
        println!("h = {h}: Newmark γ = 0.6 defect {newmark:.2e}");
        assert!(newmark > 1e-4, "Newmark γ = 0.6 at h = {h}: {newmark:e}");
    }
}
