//! Symplecticity of every undamped spin method, measured: on the product of spheres
//! `|S_i| = 1` the symplectic form is the sum of the spheres' area forms,
//! `ω_S(u, v) = Σ_i S_i · (u_i × v_i)` for tangent vectors `u`, `v`; a step `Φ` is
//! symplectic (a Poisson map of the spin bracket) exactly when `ω_{Φ(S)}(DΦ u, DΦ v) =
//! ω_S(u, v)` for all tangent `u`, `v` (docs/spins.md). The tangent images `DΦ u` come from
//! central differences along great circles through `S_i`, extrapolated once (Richardson),
//! which resolve about 1e-10. A ring of five spins with exchange, anisotropy off the field,
//! a field and DMI (every on-site and bond term, none commuting), at two steps; a method is
//! called symplectic only where the defect is at the resolution.

use liemid::spin::{problems, DmiKind, Lattice, LatticeKind, SpinIntegrator, SpinMethod, SpinSystem};
use liemid::Vec3;

fn system() -> SpinSystem {
    let lattice = Lattice::new(LatticeKind::Chain, &[5], true).unwrap();
    let axis = Vec3::new(0.2, -0.1, 1.0);
    SpinSystem::new(lattice, 1.0, 0.3, axis, Vec3::new(1.0, 0.4, 0.5), 1.0, 0.0)
        .unwrap()
        .with_dmi(0.4, DmiKind::Bulk)
        .unwrap()
}

fn step(method: SpinMethod, system: &SpinSystem, spins: &[Vec3], h: f64) -> Vec<Vec3> {
    let mut s = spins.to_vec();
    SpinIntegrator::new(method).step(system, &mut s, 0.0, h).unwrap();
    s
}

/// Two unit tangent vectors at `s`.
fn tangents(s: Vec3) -> [Vec3; 2] {
    let helper = if s.x.abs() < 0.8 {
        Vec3::new(1.0, 0.0, 0.0)
    } else {
        Vec3::new(0.0, 1.0, 0.0)
    };
    let t1 = s.cross(helper);
    let t1 = t1 * (1.0 / t1.norm());
    [t1, s.cross(t1)]
}

/// The defect `max |ω_{Φ(S)}(DΦ u_a, DΦ u_b) − ω_S(u_a, u_b)|` over the tangent basis.
fn defect(method: SpinMethod, system: &SpinSystem, spins: &[Vec3], h: f64) -> f64 {
    let n = spins.len();
    let image = step(method, system, spins, h);
    // Basis vector (i, k): spin i moves along its k-th tangent.
    let mut pushed: Vec<Vec<Vec3>> = Vec::new();
    let mut before: Vec<(usize, Vec3)> = Vec::new();
    for i in 0..n {
        for t in tangents(spins[i]) {
            let moved = |e: f64| {
                let mut s = spins.to_vec();
                s[i] = spins[i] * e.cos() + t * e.sin();
                step(method, system, &s, h)
            };
            let central = |e: f64| -> Vec<Vec3> {
                let (plus, minus) = (moved(e), moved(-e));
                plus.iter().zip(&minus).map(|(a, b)| (*a - *b) * (0.5 / e)).collect()
            };
            let (coarse, fine) = (central(2e-3), central(1e-3));
            pushed.push(
                fine.iter()
                    .zip(&coarse)
                    .map(|(f, c)| (*f * 4.0 - *c) * (1.0 / 3.0))
                    .collect(),
            );
            before.push((i, t));
        }
    }
    let mut worst: f64 = 0.0;
    for a in 0..pushed.len() {
        for b in 0..pushed.len() {
            let after: f64 = (0..n).map(|i| image[i].dot(pushed[a][i].cross(pushed[b][i]))).sum();
            let start = if before[a].0 == before[b].0 {
                spins[before[a].0].dot(before[a].1.cross(before[b].1))
            } else {
                0.0
            };
            worst = worst.max((after - start).abs());
        }
    }
    worst
}

fn claimed_symplectic(method: SpinMethod) -> bool {
    method.key().starts_with("split")
}

#[test]
fn every_undamped_spin_method_measured_only_the_splittings_are_symplectic() {
    let system = system();
    let spins = problems::near_z(5, 0.6, 11);
    println!("method    claim           defect h=0.05  defect h=0.025  order");
    for method in SpinMethod::ALL {
        let d: Vec<f64> = [0.05, 0.025]
            .iter()
            .map(|&h| defect(method, &system, &spins, h))
            .collect();
        let order = (d[0] / d[1]).log2();
        let claim = if claimed_symplectic(method) {
            "symplectic"
        } else {
            "not symplectic"
        };
        println!(
            "{:<9} {claim:<15} {:<14.2e} {:<15.2e} {order:.2}",
            method.key(),
            d[0],
            d[1]
        );
        if claimed_symplectic(method) {
            assert!(d.iter().all(|&x| x < 1e-11), "{}: defect {d:?}", method.key());
        } else {
            assert!(d[0] > 1e-8, "{}: defect {d:?} is at the resolution", method.key());
        }
    }
}
