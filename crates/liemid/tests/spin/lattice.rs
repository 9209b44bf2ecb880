//! Spin dynamics: the lattice and its bond colouring, exact solutions (Larmor precession,
//! two coupled spins), the spin-wave dispersion, conservation, observed orders, damping,
//! and thread-count independence.

use liemid::spin::{problems, Lattice, LatticeKind, SpinIntegrator, SpinMethod, SpinSystem, GYROMAGNETIC_RATIO, MU_B};
use liemid::{so3, Vec3};

fn run(method: SpinMethod, system: &SpinSystem, spins: &[Vec3], h: f64, steps: usize) -> Vec<Vec3> {
    let mut s = spins.to_vec();
    let mut m = SpinIntegrator::new(method);
    for k in 0..steps {
        m.step(system, &mut s, k as f64 * h, h).unwrap();
    }
    s
}

fn max_difference(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).max_abs()).fold(0.0, f64::max)
}

fn observed_order(hs: &[f64], errs: &[f64]) -> f64 {
    liemid::observed_order(hs, errs).unwrap()
}

#[test]
fn bond_colours_are_matchings_and_every_pair_counts_once() {
    for (kind, size, periodic, bonds, colours) in [
        (LatticeKind::Square, vec![64, 64], true, 2 * 64 * 64, 4),
        (LatticeKind::Square, vec![5, 4], true, 2 * 20, 4),
        (LatticeKind::Square, vec![4, 3], false, 3 * 3 + 4 * 2, 4),
        (LatticeKind::Chain, vec![7], true, 7, 3),
        (LatticeKind::Chain, vec![8], false, 7, 2),
        (LatticeKind::Cubic, vec![4, 4, 4], true, 3 * 64, 6),
    ] {
        let l = Lattice::new(kind, &size, periodic).unwrap();
        assert_eq!(l.bonds().len(), bonds, "{kind:?} {size:?}");
        assert_eq!(l.colours(), colours, "{kind:?} {size:?}: {} colours", l.colours());
        let mut pairs = std::collections::HashSet::new();
        for c in 0..l.colours() {
            let mut seen = vec![false; l.sites()];
            for b in l.colour(c) {
                for i in b {
                    assert!(!seen[*i as usize], "colour {c} touches site {i} twice");
                    seen[*i as usize] = true;
                }
                assert!(pairs.insert((b[0].min(b[1]), b[0].max(b[1]))), "pair {b:?} twice");
            }
        }
        let degree: usize = (0..l.sites()).map(|i| l.neighbours(i).len()).sum();
        assert_eq!(degree, 2 * bonds);
    }
    assert!(Lattice::new(LatticeKind::Square, &[64], true).is_err());
    assert!(Lattice::new(LatticeKind::Chain, &[2], true).is_err());
    assert!(Lattice::from_bonds(3, &[[0, 1], [1, 0]]).is_err());
    assert!(Lattice::from_bonds(3, &[[0, 3]]).is_err());
}

#[test]
fn a_lone_spin_precesses_at_the_larmor_frequency() {
    // B = 2 T along z: S turns about z at γ|B|; the splitting's on-site flow is exact, so
    // after 10^4 steps the phase is exact to round-off.
    let lattice = Lattice::from_bonds(1, &[]).unwrap();
    let b = Vec3::new(0.0, 0.0, 2.0);
    let system = SpinSystem::new(lattice, 0.0, 0.0, Vec3::new(0.0, 0.0, 1.0), b, 1.0, 0.0).unwrap();
    let s0 = vec![Vec3::new(0.6, 0.0, 0.8)];
    let (h, steps) = (1e-2, 10_000);
    let t = h * steps as f64;
    let exact = so3::exp(b * (GYROMAGNETIC_RATIO * t)) * s0[0];
    let split = run(SpinMethod::Splitting, &system, &s0, h, steps);
    let err = (split[0] - exact).max_abs();
    assert!(err < 1e-12, "splitting phase error {err:e}");
    // The midpoint rule's Cayley map has a phase error of (γBh)³/12 per step.
    let mid = run(SpinMethod::Midpoint, &system, &s0, h, steps);
    let theta = GYROMAGNETIC_RATIO * 2.0 * h;
    let phase = (theta - 2.0 * (theta / 2.0).atan()) * steps as f64;
    let err = (mid[0] - exact).norm();
    assert!(
        (err / (0.6 * phase) - 1.0).abs() < 1e-3,
        "midpoint error {err:e}, predicted {:e}",
        0.6 * phase
    );
}

#[test]
fn two_coupled_spins_follow_the_analytic_solution() {
    // H = −J S₁·S₂ − μ_B B·(S₁ + S₂): both spins turn about L = S₁ + S₂ at γJ|L|/μ_B while
    // L turns about B at γ|B| (the flows commute).
    let lattice = Lattice::from_bonds(2, &[[0, 1]]).unwrap();
    let (j, b) = (1.5, Vec3::new(0.0, 0.0, 1.0));
    let system = SpinSystem::new(lattice, j, 0.0, Vec3::new(0.0, 0.0, 1.0), b, 1.0, 0.0).unwrap();
    let s0 = vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.6, 0.8)];
    let t = 5.0;
    let l = s0[0] + s0[1];
    let exchange = so3::exp(l * (GYROMAGNETIC_RATIO * j / MU_B * t));
    let zeeman = so3::exp(b * (GYROMAGNETIC_RATIO * t));
    let exact: Vec<Vec3> = s0.iter().map(|s| zeeman * (exchange * *s)).collect();
    let split = run(SpinMethod::Splitting, &system, &s0, 1e-2, 500);
    assert!(
        max_difference(&split, &exact) < 1e-13,
        "splitting: {:e}",
        max_difference(&split, &exact)
    );
    // The other methods converge to it at their order (error ratio 2^p per halving).
    for (method, h) in [
        (SpinMethod::Midpoint, 2e-3),
        (SpinMethod::DepondtMertens, 2e-3),
        (SpinMethod::Heun, 2e-3),
        (SpinMethod::RungeKutta4, 2.5e-3),
    ] {
        let err = |h: f64| max_difference(&run(method, &system, &s0, h, (t / h).round() as usize), &exact);
        let ratio = err(h) / err(h / 2.0);
        let expected = f64::from(1u32 << method.order());
        assert!(
            (ratio / expected - 1.0).abs() < 0.15,
            "{}: error ratio {ratio}, expected {expected}",
            method.key()
        );
    }
}

#[test]
fn the_spin_wave_dispersion_of_a_chain_matches_2j_1_minus_cos_k_plus_2k() {
    // Small random deviations from +z on a 64-spin periodic chain; each Fourier mode
    // a_k = Σ_j (S_x + i S_y)_j e^{−ikj} turns at ω(k) = γ/(μ_s μ_B) (2J(1 − cos k) + 2K).
    let p = problems::chain_64();
    let (h, steps) = (2e-3, 5000);
    let n = p.spins.len();
    let modes = |s: &[Vec3]| -> Vec<(f64, f64)> {
        (1..=n / 2)
            .map(|m| {
                let k = 2.0 * std::f64::consts::PI * m as f64 / n as f64;
                s.iter().enumerate().fold((0.0, 0.0), |(re, im), (j, v)| {
                    let (sn, cs) = (k * j as f64).sin_cos();
                    (re + v.x * cs + v.y * sn, im + v.y * cs - v.x * sn)
                })
            })
            .collect()
    };
    let mut s = p.spins.clone();
    let mut integ = SpinIntegrator::new(SpinMethod::Splitting);
    let mut phase = vec![0.0f64; n / 2];
    let mut last = modes(&s);
    for step in 0..steps {
        integ.step(&p.system, &mut s, step as f64 * h, h).unwrap();
        let now = modes(&s);
        for m in 0..n / 2 {
            let (a, b) = (last[m], now[m]);
            // arg(b / a), the turn of the mode over one step.
            phase[m] += (a.0 * b.1 - a.1 * b.0).atan2(a.0 * b.0 + a.1 * b.1);
        }
        last = now;
    }
    let t = h * steps as f64;
    let scale = GYROMAGNETIC_RATIO / MU_B;
    let mut worst = 0.0f64;
    for m in 1..=n / 2 {
        let k = 2.0 * std::f64::consts::PI * m as f64 / n as f64;
        let theory = scale * (2.0 * p.system.exchange * (1.0 - k.cos()) + 2.0 * p.system.anisotropy);
        let measured = phase[m - 1] / t;
        worst = worst.max((measured / theory - 1.0).abs());
    }
    println!("spin waves: largest relative frequency deviation over 32 modes {worst:.2e}");
    assert!(worst < 5e-3, "dispersion off by {worst:e}");
}

/// `(max ||S_i| − 1|, |Σ S_z − Σ S_z(0)| / N)` along `steps` steps of `method`.
fn conservation(method: SpinMethod, steps: usize) -> (f64, f64) {
    let p = problems::square_64();
    let sz0 = p.system.total_spin(&p.spins).z;
    let mut s = p.spins.clone();
    let mut integ = SpinIntegrator::new(method);
    for k in 0..steps {
        integ.step(&p.system, &mut s, k as f64 * p.step, p.step).unwrap();
    }
    let norm = s.iter().map(|v| (v.norm() - 1.0).abs()).fold(0.0, f64::max);
    let sz = (p.system.total_spin(&s).z - sz0).abs() / sz0.abs();
    (norm, sz)
}

#[test]
fn the_splitting_keeps_every_spin_length_and_total_sz_on_the_64x64_lattice() {
    let (norm, sz) = conservation(SpinMethod::Splitting, 10_000);
    println!("square-64, 10^4 steps: max ||S|-1| {norm:.2e}, relative Sz change {sz:.2e}");
    assert!(norm < 1e-13 && sz < 1e-13, "{norm:e} {sz:e}");
}

#[test]
#[ignore = "10^5 steps of 4096 spins (about a minute); run with --ignored"]
fn the_splitting_keeps_every_spin_length_and_total_sz_over_1e5_steps() {
    let (norm, sz) = conservation(SpinMethod::Splitting, 100_000);
    println!("square-64, 10^5 steps: max ||S|-1| {norm:.2e}, relative Sz change {sz:.2e}");
    assert!(norm < 1e-13 && sz < 1e-13, "{norm:e} {sz:e}");
}

#[test]
fn the_splitting_energy_error_is_bounded_over_1e6_steps() {
    // An 8×8 lattice from the same kind of start, h = 1e-2: the largest energy error in
    // the last tenth of 10^6 steps is that of the first tenth.
    let lattice = Lattice::new(LatticeKind::Square, &[8, 8], true).unwrap();
    let system = SpinSystem::new(lattice, 1.0, 0.1, Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 1.0, 0.0).unwrap();
    let mut s = problems::near_z(64, 0.5, 3);
    let e0 = system.energy(&s);
    let steps = 1_000_000;
    let mut integ = SpinIntegrator::new(SpinMethod::Splitting);
    let (mut first, mut last) = (0.0f64, 0.0f64);
    for k in 0..steps {
        integ.step(&system, &mut s, k as f64 * 1e-2, 1e-2).unwrap();
        if k % 10 == 0 {
            let de = ((system.energy(&s) - e0) / e0).abs();
            if k < steps / 10 {
                first = first.max(de);
            } else if k >= steps - steps / 10 {
                last = last.max(de);
            }
        }
    }
    println!("8x8, 10^6 steps: energy error first tenth {first:.3e}, last tenth {last:.3e}");
    assert!(last < 1.5 * first && first < 1e-3, "energy error {first:e} -> {last:e}");
}

#[test]
fn observed_orders_of_every_method() {
    // An 8×8 lattice with a field not along the anisotropy axis (the on-site terms then do
    // not commute), to t = 1 ps, against the eighth-order splitting at h = 1/640.
    let lattice = Lattice::new(LatticeKind::Square, &[8, 8], true).unwrap();
    let field = Vec3::new(1.0, 0.0, 0.5);
    let system = SpinSystem::new(lattice, 1.0, 0.3, Vec3::new(0.0, 0.0, 1.0), field, 1.0, 0.0).unwrap();
    let s0 = problems::near_z(64, 0.5, 4);
    let reference = run(SpinMethod::Splitting8, &system, &s0, 1.0 / 640.0, 640);
    let check = run(SpinMethod::Splitting8, &system, &s0, 1.0 / 320.0, 320);
    assert!(max_difference(&reference, &check) < 1e-13);
    for (method, h0) in [
        (SpinMethod::Splitting, 0.02),
        (SpinMethod::Splitting4, 0.05),
        (SpinMethod::Splitting6, 0.1),
        (SpinMethod::Midpoint, 0.02),
        (SpinMethod::Heun, 0.01),
        (SpinMethod::DepondtMertens, 0.01),
        (SpinMethod::RungeKutta4, 0.01),
    ] {
        let hs: Vec<f64> = (0..3).map(|k| h0 / f64::from(1u32 << k)).collect();
        let errs: Vec<f64> = hs
            .iter()
            .map(|&h| max_difference(&run(method, &system, &s0, h, (1.0 / h).round() as usize), &reference))
            .collect();
        let order = observed_order(&hs, &errs);
        println!("{}: observed order {order:.3}, errors {errs:?}", method.key());
        assert!(
            (order - f64::from(method.order())).abs() < 0.15,
            "{}: order {order}",
            method.key()
        );
    }
}

#[test]
fn observed_orders_of_the_splittings_with_commuting_on_site_terms() {
    // Field along the anisotropy axis: the on-site flow is one rotation, and the half flows
    // of adjacent stages of a composition are joined into one (and the bond sweeps run in
    // lanes where the processor has AVX); the orders must stay 2, 4, 6.
    let lattice = Lattice::new(LatticeKind::Square, &[8, 8], true).unwrap();
    let field = Vec3::new(0.0, 0.0, 0.7);
    let system = SpinSystem::new(lattice, 1.0, 0.3, Vec3::new(0.0, 0.0, 1.0), field, 1.0, 0.0).unwrap();
    let s0 = problems::near_z(64, 0.5, 4);
    let reference = run(SpinMethod::Splitting8, &system, &s0, 1.0 / 640.0, 640);
    let check = run(SpinMethod::Splitting8, &system, &s0, 1.0 / 320.0, 320);
    assert!(max_difference(&reference, &check) < 1e-13);
    for (method, h0) in [
        (SpinMethod::Splitting, 0.02),
        (SpinMethod::Splitting4, 0.05),
        (SpinMethod::Splitting6, 0.1),
    ] {
        let hs: Vec<f64> = (0..3).map(|k| h0 / f64::from(1u32 << k)).collect();
        let errs: Vec<f64> = hs
            .iter()
            .map(|&h| max_difference(&run(method, &system, &s0, h, (1.0 / h).round() as usize), &reference))
            .collect();
        let order = observed_order(&hs, &errs);
        println!("{}: observed order {order:.3}, errors {errs:?}", method.key());
        assert!(
            (order - f64::from(method.order())).abs() < 0.15,
            "{}: order {order}",
            method.key()
        );
    }
}

#[test]
fn the_midpoint_rule_keeps_the_energy_and_with_damping_it_falls_to_the_ground_state() {
    let p = problems::square_64();
    let e0 = p.system.energy(&p.spins);
    let s = run(SpinMethod::Midpoint, &p.system, &p.spins, 1e-2, 200);
    let de = ((p.system.energy(&s) - e0) / e0).abs();
    let sz = (p.system.total_spin(&s).z - p.system.total_spin(&p.spins).z).abs() / p.system.total_spin(&p.spins).z;
    assert!(de < 1e-13 && sz < 1e-13, "midpoint: energy {de:e}, Sz {sz:e}");
    // α = 0.1 on an 8×8 lattice from within 1 rad of +z: the energy falls at every step to
    // the ground state E = −J·(bonds) − K·N.
    let lattice = Lattice::new(LatticeKind::Square, &[8, 8], true).unwrap();
    let system = SpinSystem::new(lattice, 1.0, 0.1, Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 1.0, 0.1).unwrap();
    let mut s = problems::near_z(64, 1.0, 5);
    let ground = -system.exchange * 128.0 - system.anisotropy * 64.0;
    let mut integ = SpinIntegrator::new(SpinMethod::Midpoint);
    let mut e = system.energy(&s);
    for k in 0..6000 {
        integ.step(&system, &mut s, k as f64 * 1e-2, 1e-2).unwrap();
        let now = system.energy(&s);
        assert!(now <= e + 1e-12 * e.abs(), "step {k}: energy rose from {e} to {now}");
        e = now;
    }
    assert!(
        (e - ground).abs() < 1e-6 * ground.abs(),
        "energy {e}, ground state {ground}"
    );
    // Every method accepts damping.
    for method in SpinMethod::ALL {
        assert!(method.handles_damping());
        assert!(SpinIntegrator::new(method).step(&system, &mut s, 0.0, 1e-2).is_ok());
    }
}

/// The damped 8×8 test lattice: `J = 1`, `K = 0.3` along `z`, a field `field`, `α = 0.1`.
fn damped_8x8(field: Vec3, damping: f64) -> SpinSystem {
    let lattice = Lattice::new(LatticeKind::Square, &[8, 8], true).unwrap();
    SpinSystem::new(lattice, 1.0, 0.3, Vec3::new(0.0, 0.0, 1.0), field, 1.0, damping).unwrap()
}

#[test]
fn observed_orders_of_the_damped_splittings() {
    // α = 0.1 on the 8×8 lattice, to t = 1 ps, with the field off the anisotropy axis and
    // along it, against the eighth-order splitting at h = 1/1280 (itself checked against
    // h = 1/640 and against RK4 at h = 1/5120, an independent method on the full field).
    for field in [Vec3::new(1.0, 0.0, 0.5), Vec3::new(0.0, 0.0, 0.7)] {
        let system = damped_8x8(field, 0.1);
        let s0 = problems::near_z(64, 0.5, 4);
        let reference = run(SpinMethod::Splitting8, &system, &s0, 1.0 / 1280.0, 1280);
        let check = run(SpinMethod::Splitting8, &system, &s0, 1.0 / 640.0, 640);
        let rk4 = run(SpinMethod::RungeKutta4, &system, &s0, 1.0 / 5120.0, 5120);
        let (d8, d4) = (max_difference(&reference, &check), max_difference(&reference, &rk4));
        println!("damped, field {field:?}: split8 h/2 vs h {d8:.2e}, vs RK4 {d4:.2e}");
        assert!(d8 < 1e-11 && d4 < 1e-11, "reference {d8:e}, against RK4 {d4:e}");
        for (method, h0) in [
            (SpinMethod::Splitting, 0.02),
            (SpinMethod::Splitting4, 0.05),
            (SpinMethod::Splitting6, 0.1),
        ] {
            let hs: Vec<f64> = (0..3).map(|k| h0 / f64::from(1u32 << k)).collect();
            let errs: Vec<f64> = hs
                .iter()
                .map(|&h| max_difference(&run(method, &system, &s0, h, (1.0 / h).round() as usize), &reference))
                .collect();
            let order = observed_order(&hs, &errs);
            println!("damped {}: observed order {order:.3}, errors {errs:?}", method.key());
            assert!(
                (order - f64::from(method.order())).abs() < 0.1,
                "{}: order {order}",
                method.key()
            );
        }
    }
}

#[test]
fn the_damped_splitting_energy_falls_at_every_step_to_the_ground_state() {
    // From within 1 rad of +z, α = 0.1, h = 0.01 ps: the splitting's step changes the
    // energy by the dissipation (O(α h)) plus a splitting term (O(h³)), so it falls at every
    // step here; checked, not guaranteed for any α and h (see docs/spins.md).
    for (field, damping) in [
        (Vec3::ZERO, 0.1),
        (Vec3::new(0.0, 0.0, 0.5), 0.1),
        (Vec3::new(0.3, 0.0, 0.5), 0.05),
    ] {
        let system = damped_8x8(field, damping);
        let mut s = problems::near_z(64, 1.0, 5);
        for method in [SpinMethod::Splitting, SpinMethod::Splitting4] {
            let mut integ = SpinIntegrator::new(method);
            let mut x = s.clone();
            let mut e = system.energy(&x);
            for k in 0..6000 {
                integ.step(&system, &mut x, k as f64 * 1e-2, 1e-2).unwrap();
                let now = system.energy(&x);
                assert!(
                    now <= e + 1e-12 * e.abs(),
                    "{} field {field:?}: step {k}: energy rose from {e} to {now}",
                    method.key()
                );
                e = now;
            }
            let unit = x.iter().map(|v| (v.norm() - 1.0).abs()).fold(0.0, f64::max);
            assert!(unit < 1e-14, "|S| off by {unit:e}");
            if field.x == 0.0 {
                // The ground state: all along +z.
                let ground = -128.0 - 0.3 * 64.0 - MU_B * field.z * 64.0;
                assert!(
                    (e - ground).abs() < 1e-6 * ground.abs(),
                    "energy {e}, ground state {ground}"
                );
            }
            s = x;
        }
    }
}

#[test]
fn the_damped_splitting_is_the_same_bits_fused_unfused_advanced_and_on_any_thread_count() {
    let square = problems::square_64();
    let chain = SpinSystem::new(
        Lattice::new(LatticeKind::Chain, &[7], true).unwrap(),
        1.0,
        0.1,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.2, 0.0, 0.3),
        1.0,
        0.2,
    )
    .unwrap();
    let chain_spins = problems::near_z(7, 0.4, 9);
    let lattice = square.system.lattice.clone();
    let z = Vec3::new(0.0, 0.0, 1.0);
    let systems = [
        SpinSystem::new(lattice.clone(), 1.0, 0.2, z, Vec3::ZERO, 1.0, 0.1).unwrap(),
        SpinSystem::new(lattice.clone(), 1.0, 0.0, z, Vec3::new(0.0, 0.0, 1.0), 1.0, 0.1).unwrap(),
        SpinSystem::new(lattice, -1.0, 0.2, z, Vec3::new(0.5, 0.0, 1.0), 1.0, 0.3).unwrap(),
    ];
    let mut cases: Vec<(&SpinSystem, &Vec<Vec3>)> = systems.iter().map(|s| (s, &square.spins)).collect();
    cases.push((&chain, &chain_spins));
    for (system, spins) in cases {
        for method in [SpinMethod::Splitting, SpinMethod::Splitting4] {
            let gammas: Vec<f64> = match method {
                SpinMethod::Splitting => vec![1.0],
                _ => {
                    let s = liemid::Scheme::SUZUKI4;
                    (0..s.stages()).map(|k| s.gamma(k)).collect()
                }
            };
            for h in [1e-2, 0.4] {
                let mut unfused = spins.clone();
                for _ in 0..7 {
                    liemid::spin::splitting_unfused(system, &mut unfused, h, &gammas);
                }
                let runs: Vec<(Vec<Vec3>, Vec<Vec3>)> = [1, 2, 3]
                    .iter()
                    .map(|&threads| {
                        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                        pool.install(|| {
                            let stepped = run(method, system, spins, h, 7);
                            let mut advanced = spins.clone();
                            SpinIntegrator::new(method)
                                .advance(system, &mut advanced, 0.0, h, 7)
                                .unwrap();
                            (stepped, advanced)
                        })
                    })
                    .collect();
                for (threads, (stepped, advanced)) in runs.iter().enumerate() {
                    assert!(
                        *stepped == unfused && *advanced == unfused,
                        "{} at {h}, {} threads, J {}: differs",
                        method.key(),
                        threads + 1,
                        system.exchange
                    );
                }
                assert!(unfused != *spins);
            }
        }
    }
}

#[test]
fn fused_sweeps_and_multi_step_advances_equal_single_unfused_steps_bit_for_bit() {
    // The unfused path is scalar; the fused one runs in AVX lanes where the processor has
    // AVX, so this also checks the lanes' bits against the scalar path.
    // Periodic 64x64 (colour 0 is a perfect matching, so sweeps fuse), a field off the
    // anisotropy axis (the on-site flow is Strang-split), and an odd chain (no fusion).
    let square = problems::square_64();
    let tilted = SpinSystem::new(
        square.system.lattice.clone(),
        1.0,
        0.2,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.5, 0.0, 1.0),
        1.0,
        0.0,
    )
    .unwrap();
    let chain = SpinSystem::new(
        Lattice::new(LatticeKind::Chain, &[7], true).unwrap(),
        1.0,
        0.1,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::ZERO,
        1.0,
        0.0,
    )
    .unwrap();
    let chain_spins = problems::near_z(7, 0.4, 9);
    for (system, spins) in [
        (&square.system, &square.spins),
        (&tilted, &square.spins),
        (&chain, &chain_spins),
    ] {
        for method in [SpinMethod::Splitting, SpinMethod::Splitting4] {
            let gammas: Vec<f64> = match method {
                SpinMethod::Splitting => vec![1.0],
                _ => {
                    let s = liemid::Scheme::SUZUKI4;
                    (0..s.stages()).map(|k| s.gamma(k)).collect()
                }
            };
            // 0.4 ps turns some bonds by more than 1 rad in one sweep: their lane groups
            // take the scalar path's closed forms, the others stay in lanes.
            for h in [1e-2, 0.4] {
                let mut unfused = spins.clone();
                for _ in 0..7 {
                    liemid::spin::splitting_unfused(system, &mut unfused, h, &gammas);
                }
                let stepped = run(method, system, spins, h, 7);
                let mut advanced = spins.clone();
                SpinIntegrator::new(method)
                    .advance(system, &mut advanced, 0.0, h, 7)
                    .unwrap();
                assert!(
                    stepped == unfused && advanced == unfused,
                    "{} at {h} differs",
                    method.key()
                );
            }
        }
    }
}

#[test]
fn results_are_identical_for_one_two_and_three_threads() {
    let p = problems::square_64();
    for method in [SpinMethod::Splitting, SpinMethod::Midpoint, SpinMethod::RungeKutta4] {
        let runs: Vec<Vec<Vec3>> = [1, 2, 3]
            .iter()
            .map(|&threads| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| {
                    let mut s = run(method, &p.system, &p.spins, 1e-2, 10);
                    SpinIntegrator::new(method)
                        .advance(&p.system, &mut s, 0.1, 1e-2, 10)
                        .unwrap();
                    s
                })
            })
            .collect();
        assert!(
            runs[0] == runs[1] && runs[0] == runs[2],
            "{} differs between thread counts",
            method.key()
        );
        assert!(runs[0] != p.spins);
    }
}
