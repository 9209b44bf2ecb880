//! The splitting with selective mass scaling of the axial waves (`liemid-sms`).

use liemid::beam::{problems, BeamMethod, BeamSystem};

use crate::beam_runs;
use beam_runs::advance;

/// The right-angle cantilever swinging after its load (t = 2).
fn swinging(per_leg: usize) -> BeamSystem {
    let p = problems::right_angle_cantilever(per_leg).unwrap();
    let mut s = p.system().unwrap();
    let h = 0.002;
    for _ in 0..1000 {
        s.step_with(BeamMethod::MassScaled, h).unwrap();
    }
    s
}

#[test]
fn default_mass_brings_the_axial_bound_to_the_bending_one() {
    let s = problems::right_angle_cantilever(16).unwrap().system().unwrap();
    let st = s.stability(0);
    // β = ((ω_a/ω_b)² − 1)/4 makes ω_a/√(1 + 4β) = ω_b.
    let r = st.omega_axial_bound / st.omega_bending_bound;
    assert!((s.axial_mass() - 0.25 * (r * r - 1.0)).abs() <= 1e-12 * s.axial_mass());
    let scaled = st.omega_axial_bound / (1.0 + 4.0 * st.axial_mass).sqrt();
    assert!((scaled - st.omega_bending_bound).abs() <= 1e-12 * scaled);
    assert_eq!(
        st.critical_step(BeamMethod::MassScaled),
        2.0 / st.omega_bound_of(BeamMethod::MassScaled)
    );
    // 5.7 times the splitting's step at 16 elements per leg.
    let gain = st.critical_step(BeamMethod::MassScaled) / st.critical_step(BeamMethod::Splitting);
    assert!((gain - r).abs() <= 1e-9 * r, "gain {gain}, ratio {r}");
}

#[test]
fn mass_scaled_splitting_is_second_order() {
    let start = swinging(4);
    let t = 1.0;
    let critical = start.stability(0).critical_step(BeamMethod::MassScaled);
    let h0 = t / (t / (0.5 * critical)).ceil();
    // The scaled model's own solution: the method itself at a 64th of the step.
    let reference = advance(&start, BeamMethod::MassScaled, h0 / 64.0, t);
    let errors: Vec<f64> = [1.0, 2.0, 4.0]
        .iter()
        .map(|d| {
            let x = advance(&start, BeamMethod::MassScaled, h0 / d, t);
            x.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
        })
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("liemid-sms: errors {errors:?}, orders {orders:?}");
    let mut s = start.clone();
    for _ in 0..100 {
        s.step_with(BeamMethod::MassScaled, h0).unwrap();
    }
    let taken = s.stretch_iterations() - start.stretch_iterations();
    println!("{} stretch iterations per step", taken as f64 / 100.0);
    for p in orders {
        assert!((p - 2.0).abs() < 0.2, "order {p}");
    }
}

#[test]
fn zero_axial_mass_is_the_splitting() {
    let p = problems::right_angle_cantilever(4).unwrap();
    let mut a = p.system().unwrap();
    a.set_axial_mass(0.0).unwrap();
    let mut b = a.clone();
    for _ in 0..200 {
        a.step_with(BeamMethod::MassScaled, 0.002).unwrap();
        b.step(0.002).unwrap();
    }
    assert_eq!(a.bodies.position, b.bodies.position);
    assert_eq!(a.bodies.momentum, b.bodies.momentum);
    assert!(a.set_axial_mass(-1.0).is_err());
    assert!(a.set_axial_mass(f64::NAN).is_err());
}

#[test]
fn free_flight_keeps_momenta_and_bounded_energy() {
    let p = problems::flying_beam(10).unwrap();
    let mut s = p.system().unwrap();
    s.set_axial_mass(4.0).unwrap();
    let h = s.stability(0).default_step(BeamMethod::MassScaled);
    // Through the loads (which end at t = 5), then free.
    while s.t() < s.loads_end() {
        s.step_with(BeamMethod::MassScaled, h).unwrap();
    }
    let start = s.totals_for(BeamMethod::MassScaled);
    let mut energy = Vec::new();
    for _ in 0..20_000 {
        s.step_with(BeamMethod::MassScaled, h).unwrap();
        energy.push(s.totals_for(BeamMethod::MassScaled).energy);
    }
    let end = s.totals_for(BeamMethod::MassScaled);
    let (l0, a0) = (start.linear_momentum, start.angular_momentum);
    let dl = (end.linear_momentum - l0).norm() / l0.norm();
    let da = (end.angular_momentum - a0).norm() / a0.norm();
    println!("momenta: linear {dl:.2e}, angular {da:.2e}");
    // Internal forces and the stretch inertia are invariant under rigid motions: the
    // discrete Noether theorem, to the round-off of 2·10⁴ steps and of the stretch solve
    // (1e-13 of an element length per step).
    assert!(dl < 1e-11 && da < 1e-10, "linear {dl:e}, angular {da:e}");
    let e0 = start.energy;
    let worst = |e: &[f64]| e.iter().map(|x| ((x - e0) / e0).abs()).fold(0.0, f64::max);
    let n = energy.len();
    let (first, last) = (worst(&energy[..n / 10]), worst(&energy[n - n / 10..]));
    println!("h {h}: energy change first tenth {first:.2e}, last tenth {last:.2e}");
    // Symplectic: an O(h²) oscillation of the scaled system's energy, no drift.
    assert!(
        first < 1e-4 && last < 2.0 * first.max(1e-9),
        "energy {first:e} then {last:e}"
    );
}

#[test]
fn mass_scaled_splitting_is_time_reversible() {
    let start = swinging(4);
    let mut s = start.clone();
    let h = s.stability(0).default_step(BeamMethod::MassScaled);
    for _ in 0..500 {
        s.step_with(BeamMethod::MassScaled, h).unwrap();
    }
    for _ in 0..500 {
        s.step_with(BeamMethod::MassScaled, -h).unwrap();
    }
    let back = s.bodies.position.iter().zip(&start.bodies.position);
    let dx = back.map(|(a, b)| (*a - *b).norm()).fold(0.0, f64::max);
    let scale = start.bodies.momentum.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let dp = s
        .bodies
        .momentum
        .iter()
        .zip(&start.bodies.momentum)
        .map(|(a, b)| (*a - *b).norm())
        .fold(0.0, f64::max);
    println!(
        "back after 500 steps: positions {dx:.2e}, momenta {:.2e} (relative)",
        dp / scale
    );
    // Symmetric (Φ₋ₕ ∘ Φₕ = id) up to the stretch solve's tolerance and round-off.
    assert!(dx < 1e-10 && dp < 1e-8 * scale, "positions {dx:e}, momenta {dp:e}");
}

#[test]
fn axial_mass_changes_the_elbow_history_less_than_its_quasi_static_estimate() {
    // The scaled axial inertia moves the lowest axial frequency (157 rad/s at 16 elements
    // per leg) down by √(1 + 4β) = 5.7, to 27.5 rad/s, against a response near 1 rad/s:
    // a quasi-static axial response changes by about (1/27.5)² = 1.3e-3 of the axial
    // motion, itself a small part of the elbow's.
    let p = problems::right_angle_cantilever(16).unwrap();
    let s0 = p.system().unwrap();
    let elbow = p.frame.named("elbow").unwrap();
    let run = |method: BeamMethod| -> Vec<liemid::Vec3> {
        let mut s = s0.clone();
        let h = s.stability(0).default_step(method);
        let every = (0.05 / h).ceil() as usize;
        let h = 0.05 / every as f64;
        let mut out = Vec::new();
        while s.t() < 10.0 - 1e-9 {
            for _ in 0..every {
                s.step_with(method, h).unwrap();
            }
            out.push(s.displacement(elbow));
        }
        out
    };
    let (scaled, plain) = (run(BeamMethod::MassScaled), run(BeamMethod::Splitting));
    let size = plain.iter().map(|u| u.norm()).fold(0.0, f64::max);
    let d = scaled
        .iter()
        .zip(&plain)
        .map(|(a, b)| (*a - *b).norm())
        .fold(0.0, f64::max)
        / size;
    println!("elbow history to t = 10: mass scaling changes it by {d:.2e} of its largest value");
    assert!(d < 1.3e-3, "{d:e}");
}
