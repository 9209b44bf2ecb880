//! The beam domain: the corotational element's forces against its energy, the three
//! benchmarks, order in time, momentum and energy, stability, threads.

use liemid::beam::{element, problems, BeamMethod, BeamSystem, ElementStiffness, Frame, Newmark, Section, Support};
use liemid::random::Rng;
use liemid::{so3, Mat3, Vec3};

fn stiffness() -> ElementStiffness {
    ElementStiffness {
        length: 1.3,
        axial: 7.0,
        torsion: 0.8,
        bending2: 1.7,
        bending3: 2.9,
    }
}

/// A deformed configuration of one element: ends displaced and turned by moderate amounts.
fn configuration(rng: &mut Rng) -> (Vec3, Vec3, Mat3, Mat3) {
    configuration_scaled(rng, 0.6)
}

/// As [`configuration`], the end turns up to `turn` rad per axis.
fn configuration_scaled(rng: &mut Rng, turn_scale: f64) -> (Vec3, Vec3, Mat3, Mat3) {
    let k = stiffness();
    let base = rng.rotation();
    let xa = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
    let xb = xa
        + base
            * Vec3::new(
                k.length * (1.0 + 0.1 * rng.uniform()),
                0.3 * turn_scale * rng.uniform(),
                0.3 * turn_scale * rng.uniform(),
            );
    let turn =
        |rng: &mut Rng| so3::exp(Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * turn_scale);
    (xa, xb, base * turn(rng), base * turn(rng))
}

#[test]
fn element_forces_are_minus_the_gradient_of_the_strain_energy() {
    let k = stiffness();
    let mut rng = Rng::new(7);
    let mut worst: f64 = 0.0;
    // Large local rotations (the log map) and small ones (below |sin θ| = 0.01 the element
    // takes a series for θ/sin θ): the forces are the energy's gradient in both.
    for case in 0..100 {
        let (xa, xb, ta, tb) = configuration_scaled(&mut rng, if case % 2 == 0 { 0.6 } else { 0.01 });
        let f = element::end_forces(&k, xa, xb, &ta, &tb);
        let v = |xa: Vec3, xb: Vec3, ta: &Mat3, tb: &Mat3| element::strain_energy(&k, xa, xb, ta, tb);
        let eps = 1e-6;
        let scale = f.force_a.norm() + f.moment_a.norm() + f.moment_b.norm() + 1.0;
        for axis in 0..3 {
            let mut d = [0.0; 3];
            d[axis] = eps;
            let d = Vec3::from_array(d);
            let checks = [
                (
                    (v(xa + d, xb, &ta, &tb) - v(xa - d, xb, &ta, &tb)) / (2.0 * eps),
                    -f.force_a[axis],
                ),
                (
                    (v(xa, xb + d, &ta, &tb) - v(xa, xb - d, &ta, &tb)) / (2.0 * eps),
                    -f.force_b[axis],
                ),
                (
                    (v(xa, xb, &(so3::exp(d) * ta), &tb) - v(xa, xb, &(so3::exp(-d) * ta), &tb)) / (2.0 * eps),
                    -f.moment_a[axis],
                ),
                (
                    (v(xa, xb, &ta, &(so3::exp(d) * tb)) - v(xa, xb, &ta, &(so3::exp(-d) * tb))) / (2.0 * eps),
                    -f.moment_b[axis],
                ),
            ];
            for (numeric, analytic) in checks {
                worst = worst.max((numeric - analytic).abs() / scale);
            }
        }
    }
    // Central differences with eps = 1e-6: truncation ~eps² ‖V'''‖, rounding ~1e-16/eps.
    assert!(worst < 1e-8, "largest gradient mismatch {worst:e}");
}

#[test]
fn element_forces_have_zero_resultant_force_and_moment() {
    let k = stiffness();
    let mut rng = Rng::new(11);
    for _ in 0..50 {
        let (xa, xb, ta, tb) = configuration(&mut rng);
        let f = element::end_forces(&k, xa, xb, &ta, &tb);
        let scale = f.force_a.norm() * (xa.norm() + xb.norm()) + f.moment_a.norm() + f.moment_b.norm();
        let force = f.force_a + f.force_b;
        let moment = xa.cross(f.force_a) + xb.cross(f.force_b) + f.moment_a + f.moment_b;
        assert!(force.norm() <= 1e-15 * scale, "force {force:?}");
        assert!(moment.norm() <= 1e-14 * scale, "moment {moment:?}");
        // Rigid motions change nothing: the energy is invariant.
        let q = rng.rotation();
        let shift = Vec3::new(1.0, -2.0, 0.5);
        let v0 = element::strain_energy(&k, xa, xb, &ta, &tb);
        let v1 = element::strain_energy(&k, q * xa + shift, q * xb + shift, &(q * ta), &(q * tb));
        assert!((v0 - v1).abs() <= 1e-13 * v0.abs().max(1.0), "{v0} vs {v1}");
    }
}

/// Zero crossings of `u(t)` sampled every `h`, linearly interpolated; `ω` from the first
/// and last.
fn omega_from_crossings(samples: &[f64], h: f64) -> f64 {
    let mut crossings = Vec::new();
    for (k, w) in samples.windows(2).enumerate() {
        if w[0].signum() != w[1].signum() {
            crossings.push(k as f64 * h + h * w[0] / (w[0] - w[1]));
        }
    }
    let n = crossings.len();
    assert!(n >= 10, "only {n} zero crossings");
    std::f64::consts::PI * (n - 1) as f64 / (crossings[n - 1] - crossings[0])
}

#[test]
fn cantilever_bending_frequencies_match_euler_bernoulli_within_one_percent() {
    for mode in 1..=3 {
        let p = problems::cantilever_vibration(20, mode).unwrap();
        let mut s = p.system().unwrap();
        let h0 = s.stability(0).default_step(BeamMethod::Splitting);
        let steps = (p.t_end / h0).ceil() as usize;
        let h = p.t_end / steps as f64;
        let tip = p.frame.named("tip").unwrap();
        let mut u = vec![s.displacement(tip).z];
        for _ in 0..steps {
            s.step(h).unwrap();
            u.push(s.displacement(tip).z);
        }
        let omega = omega_from_crossings(&u, h);
        let exact = problems::cantilever_omega(mode);
        let relative = (omega - exact).abs() / exact;
        println!(
            "mode {mode}: omega {omega:.5}, Euler-Bernoulli {exact:.5}, {:.3} %",
            100.0 * relative
        );
        assert!(relative < 0.01, "mode {mode}: {omega} vs {exact}");
    }
}

#[test]
fn torsional_frequency_of_the_cantilever_matches_the_shaft_formula() {
    let p = problems::cantilever_vibration(20, 1).unwrap();
    let mut s = p.frame.build().unwrap();
    for node in 0..s.frame.nodes.len() {
        let x = s.frame.nodes[node];
        s.set_pose(
            node,
            x,
            so3::exp(Vec3::new(1e-3 * (std::f64::consts::FRAC_PI_2 * x.x).sin(), 0.0, 0.0)),
        );
    }
    let sec = p.frame.elements[0].section;
    let exact = std::f64::consts::FRAC_PI_2 * (sec.torsional_stiffness / sec.rotary_inertia.x).sqrt();
    let h = s.stability(0).default_step(BeamMethod::Splitting);
    let tip = p.frame.named("tip").unwrap();
    let steps = (20.0 * std::f64::consts::TAU / exact / h).ceil() as usize;
    let mut twist = vec![so3::log(&s.rotation(tip)).x];
    for _ in 0..steps {
        s.step(h).unwrap();
        twist.push(so3::log(&s.rotation(tip)).x);
    }
    let omega = omega_from_crossings(&twist, h);
    // 20 elements: the lumped shaft's first frequency is low by (π/2)²/(24·20²) = 0.026 %.
    assert!((omega - exact).abs() < 1e-3 * exact, "{omega} vs {exact}");
}

/// The published curves (digitised), `(node, t, u_z)`.
fn published() -> Vec<(String, f64, f64)> {
    let data = include_str!("../data/simo_vu_quoc_1988_right_angle.csv");
    data.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("node"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].to_string(), f[1].parse().unwrap(), f[2].parse().unwrap())
        })
        .collect()
}

/// Elbow and tip `u_z` every 0.05 up to t = 30 with `per_leg` elements per leg.
fn right_angle_history(per_leg: usize) -> Vec<(f64, f64)> {
    let p = problems::right_angle_cantilever(per_leg).unwrap();
    let (elbow, tip) = (p.frame.named("elbow").unwrap(), p.frame.named("tip").unwrap());
    let mut s = p.system().unwrap();
    let sub = (0.05 / s.stability(0).default_step(BeamMethod::Splitting)).ceil() as usize;
    let h = 0.05 / sub as f64;
    let mut out = vec![(0.0, 0.0)];
    for _ in 0..600 {
        for _ in 0..sub {
            s.step(h).unwrap();
        }
        out.push((s.displacement(elbow).z, s.displacement(tip).z));
    }
    out
}

fn extremes(history: &[(f64, f64)], pick: fn(&(f64, f64)) -> f64) -> ((f64, f64), (f64, f64)) {
    let (mut max, mut min) = ((f64::MIN, 0.0), (f64::MAX, 0.0));
    for (k, v) in history.iter().enumerate() {
        let (u, t) = (pick(v), k as f64 * 0.05);
        if u > max.0 {
            max = (u, t);
        }
        if u < min.0 {
            min = (u, t);
        }
    }
    (max, min)
}

#[test]
fn right_angle_cantilever_reproduces_simo_and_vu_quoc() {
    let histories: Vec<Vec<(f64, f64)>> = [4, 8, 16].iter().map(|&n| right_angle_history(n)).collect();
    for (n, h) in [4, 8, 16].iter().zip(&histories) {
        let (emax, emin) = extremes(h, |v| v.0);
        let (tmax, tmin) = extremes(h, |v| v.1);
        println!(
            "{n:2} per leg: elbow max {:.3} at {:.2}, min {:.3} at {:.2}; tip max {:.3} at {:.2}, min {:.3} at {:.2}",
            emax.0, emax.1, emin.0, emin.1, tmax.0, tmax.1, tmin.0, tmin.1
        );
    }
    // Convergence in space: the 4 → 8 change is larger than the 8 → 16 change.
    let change = |a: &[(f64, f64)], b: &[(f64, f64)]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x.0 - y.0).abs().max((x.1 - y.1).abs()))
            .fold(0.0, f64::max)
    };
    let (c1, c2) = (
        change(&histories[0], &histories[1]),
        change(&histories[1], &histories[2]),
    );
    println!("largest change 4 -> 8: {c1:.4}, 8 -> 16: {c2:.4}");
    assert!(c2 < 0.5 * c1, "no convergence: {c1} then {c2}");
    // Against the published extremes (read from their points): tip +8.29 near t = 7.7 and
    // -9.67 near t = 16.0, elbow -3.87 near t = 10.8. Digitised curves: 3 % in amplitude,
    // 0.4 in time.
    let fine = &histories[2];
    let (tmax, tmin) = extremes(fine, |v| v.1);
    let (_, emin) = extremes(fine, |v| v.0);
    let data = published();
    let peak = |node: &str, sign: f64| {
        data.iter()
            .filter(|(n, _, _)| n == node)
            .map(|&(_, t, u)| (sign * u, t))
            .fold((f64::MIN, 0.0), |a, b| if b.0 > a.0 { b } else { a })
    };
    for ((ours, t_ours), (theirs, t_theirs), tolerance) in [
        (tmax, peak("tip", 1.0), 0.03),
        ((-tmin.0, tmin.1), peak("tip", -1.0), 0.03),
        ((-emin.0, emin.1), peak("elbow", -1.0), 0.06),
    ] {
        assert!(
            (ours - theirs).abs() < tolerance * theirs,
            "extreme {ours} vs published {theirs}"
        );
        assert!((t_ours - t_theirs).abs() < 0.4, "time {t_ours} vs published {t_theirs}");
    }
    // The whole curves: within 1.0 (10 % of the swing) at every published point.
    for (node, t, u) in &data {
        let k = ((t / 0.05).floor() as usize).min(599);
        let w = t / 0.05 - k as f64;
        let pick = |v: &(f64, f64)| if node == "elbow" { v.0 } else { v.1 };
        let ours = pick(&fine[k]) * (1.0 - w) + pick(&fine[k + 1]) * w;
        assert!((ours - u).abs() < 1.0, "{node} at t = {t}: {ours} vs published {u}");
    }
}

#[test]
fn flying_beam_keeps_momenta_to_round_off_and_energy_without_drift() {
    let p = problems::flying_beam(10).unwrap();
    let mut s = p.system().unwrap();
    let h = s.stability(0).default_step(BeamMethod::Splitting);
    let loads_end = s.loads_end();
    while s.t() < loads_end {
        s.step(h).unwrap();
    }
    let start = s.totals();
    assert!(start.linear_momentum.norm() > 1.0 && start.angular_momentum.norm() > 1.0);
    let steps = 100_000;
    let mut energy = Vec::with_capacity(steps);
    let (mut dp, mut dl): (f64, f64) = (0.0, 0.0);
    for _ in 0..steps {
        s.step(h).unwrap();
        let now = s.totals();
        energy.push((now.energy - start.energy).abs() / start.energy.abs());
        dp = dp.max((now.linear_momentum - start.linear_momentum).norm() / start.linear_momentum.norm());
        dl = dl.max((now.angular_momentum - start.angular_momentum).norm() / start.angular_momentum.norm());
    }
    let tenth = steps / 10;
    let first = energy[..tenth].iter().copied().fold(0.0, f64::max);
    let last = energy[steps - tenth..].iter().copied().fold(0.0, f64::max);
    println!("h {h}: momentum {dp:.2e}, angular momentum {dl:.2e}, energy first tenth {first:.2e}, last {last:.2e}");
    assert!(dp < 1e-12 && dl < 1e-12, "momenta changed by {dp:e}, {dl:e}");
    // Symplectic: the energy error oscillates; the last tenth is no worse than twice the
    // first (a drift would grow ten-fold from the first tenth to the last).
    assert!(last < 2.0 * first && last < 1e-3, "energy {first:e} then {last:e}");
}

use crate::beam_runs;
use beam_runs::advance;

#[test]
fn observed_order_is_two_and_four_on_the_beam() {
    // The right-angle cantilever swinging freely after its load (t = 2): large rotations,
    // smooth in time. Every run starts from the same state.
    let p = problems::right_angle_cantilever(4).unwrap();
    let mut start = p.system().unwrap();
    for _ in 0..1000 {
        start.step(0.002).unwrap();
    }
    let t = 1.0;
    let stability = start.stability(0);
    for (method, expected) in [(BeamMethod::Splitting, 2.0), (BeamMethod::Splitting4, 4.0)] {
        let h0 = t / (t / (0.5 * stability.critical_step(method))).ceil();
        let reference = advance(&start, BeamMethod::Splitting4, h0 / 64.0, t);
        // From a quarter of the critical step down (at half of it the fourth-order error
        // is not yet asymptotic: measured ratio 2^4.4).
        let errors: Vec<f64> = [2.0, 4.0, 8.0]
            .iter()
            .map(|d| {
                let x = advance(&start, method, h0 / d, t);
                x.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
            })
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!("{}: errors {errors:?}, orders {orders:?}", method.key());
        for p in orders {
            assert!((p - expected).abs() < 0.2, "{}: order {p}", method.key());
        }
    }
}

#[test]
fn the_bound_brackets_the_largest_frequency_and_steps_above_it_blow_up() {
    let p = problems::cantilever_vibration(20, 1).unwrap();
    let s = p.system().unwrap();
    let st = s.stability(400);
    let estimate = st.omega_estimate.unwrap();
    println!("omega bound {:.1}, power iteration {estimate:.1}", st.omega_bound);
    assert!(estimate <= st.omega_bound * (1.0 + 1e-9) && estimate > 0.95 * st.omega_bound);
    assert!(st
        .check(BeamMethod::Splitting, 0.99 * st.critical_step(BeamMethod::Splitting))
        .is_ok());
    let err = st
        .check(BeamMethod::Splitting, 1.01 * st.critical_step(BeamMethod::Splitting))
        .unwrap_err();
    assert!(err.to_string().contains("critical step"), "{err}");
    // Composition limits on the harmonic oscillator: Verlet 2, Suzuki's five stages larger.
    let verlet = liemid::beam::stability::composition_limit(None);
    assert!((verlet - 2.0).abs() < 1e-6, "{verlet}");
    // Just below the bound the run stays bounded; well above the true limit it explodes.
    let run = |h: f64| -> f64 {
        let mut s = p.system().unwrap();
        let tip = p.frame.named("tip").unwrap();
        let mut largest: f64 = 0.0;
        for _ in 0..3000 {
            if s.step(h).is_err() {
                return f64::INFINITY;
            }
            largest = largest.max(s.displacement(tip).norm());
        }
        largest
    };
    let stable = run(0.98 * st.critical_step(BeamMethod::Splitting));
    let unstable = run(1.1 * 2.0 / estimate);
    println!("largest tip displacement: below the bound {stable:e}, above the limit {unstable:e}");
    assert!(stable < 2e-4, "{stable}");
    assert!(unstable > 1e-2, "{unstable}");
}

#[test]
fn newmark_agrees_with_the_explicit_splitting_on_the_right_angle_cantilever() {
    let p = problems::right_angle_cantilever(4).unwrap();
    let (elbow, tip) = (p.frame.named("elbow").unwrap(), p.frame.named("tip").unwrap());
    let explicit = right_angle_history(4);
    let mut nm = Newmark::new(&p.system().unwrap());
    let mut worst: f64 = 0.0;
    for (k, &(e_ref, t_ref)) in explicit.iter().enumerate().skip(1) {
        let iterations = nm.step(0.05).unwrap();
        assert!(iterations <= 10, "{iterations} Newton iterations at step {k}");
        let (e, t) = (nm.displacement(elbow).z, nm.displacement(tip).z);
        worst = worst.max((e - e_ref).abs()).max((t - t_ref).abs());
    }
    println!(
        "Newmark dt = 0.05 vs explicit: {worst:.4}, {} iterations",
        nm.iterations
    );
    // Newmark's own second-order error at dt = 0.05 (measured 0.030); the explicit step's is
    // far smaller.
    assert!(worst < 0.06, "{worst}");
}

fn big_frame(threads: usize) -> Vec<u64> {
    let section = Section::rectangle(1e6, 0.3, 1.0, 0.1, 0.1).unwrap();
    let mut frame = Frame::new();
    for k in 0..6 {
        let y = k as f64;
        let nodes = frame
            .add_member(
                Vec3::new(0.0, y, 0.0),
                Vec3::new(50.0, y, 1.0),
                400,
                section,
                Vec3::new(0.0, 0.0, 1.0),
            )
            .unwrap();
        frame.support(nodes[0], Support::Clamped).unwrap();
        frame.gravity = Vec3::new(0.0, 0.0, -9.81);
    }
    let mut s: BeamSystem = frame.build().unwrap();
    let h = s.stability(0).default_step(BeamMethod::Splitting);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        for _ in 0..50 {
            s.step(h).unwrap();
        }
    });
    s.bodies
        .position
        .iter()
        .chain(&s.bodies.pi)
        .flat_map(|v| v.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn results_are_bitwise_identical_for_one_two_and_three_threads() {
    let one = big_frame(1);
    assert_eq!(one, big_frame(2));
    assert_eq!(one, big_frame(3));
}

#[test]
fn bad_models_are_refused_with_the_cause() {
    let section = Section::rectangle(1.0, 0.3, 1.0, 0.1, 0.1).unwrap();
    let mut frame = Frame::new();
    let err = frame
        .add_member(
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            2,
            section,
            Vec3::new(2.0, 0.0, 0.0),
        )
        .unwrap_err();
    assert!(err.to_string().contains("orientation vector"), "{err}");
    frame
        .add_member(
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            2,
            section,
            Vec3::new(0.0, 1.0, 0.0),
        )
        .unwrap();
    frame.add_node(Vec3::new(5.0, 5.0, 5.0)).unwrap();
    let err = frame.build().unwrap_err();
    assert!(err.to_string().contains("belongs to no element"), "{err}");
    let err = Section::rectangle(-1.0, 0.3, 1.0, 0.1, 0.1).unwrap_err();
    assert!(err.to_string().contains("`E`"), "{err}");
    let err = problems::by_name("bridge", None).unwrap_err();
    assert!(err.to_string().contains("right-angle-cantilever"), "{err}");
}

#[test]
fn a_pinned_pinned_beam_vibrates_at_the_simply_supported_frequency() {
    // Pinned at both ends (translations held, rotations free): ω₁ = π² √(EI/(ρA L⁴)).
    let p = problems::cantilever_vibration(20, 1).unwrap();
    let mut frame = p.frame.clone();
    frame.support(0, Support::Pinned).unwrap();
    let last = frame.named("tip").unwrap();
    frame.support(last, Support::Pinned).unwrap();
    let mut s = frame.build().unwrap();
    let middle = frame.named("middle").unwrap();
    for node in 0..frame.nodes.len() {
        let x = frame.nodes[node];
        let (w, slope) = (
            1e-4 * (std::f64::consts::PI * x.x).sin(),
            1e-4 * std::f64::consts::PI * (std::f64::consts::PI * x.x).cos(),
        );
        s.set_pose(node, x + Vec3::new(0.0, 0.0, w), so3::exp(Vec3::new(0.0, -slope, 0.0)));
    }
    // The pinned ends stayed where they were.
    assert_eq!(s.displacement(0), Vec3::ZERO);
    let exact = std::f64::consts::PI.powi(2);
    let h = s.stability(0).default_step(BeamMethod::Splitting);
    let steps = (12.0 * std::f64::consts::TAU / exact / h).ceil() as usize;
    let mut u = vec![s.displacement(middle).z];
    for _ in 0..steps {
        s.step(h).unwrap();
        u.push(s.displacement(middle).z);
    }
    assert_eq!(s.displacement(0), Vec3::ZERO);
    let omega = omega_from_crossings(&u, h);
    assert!((omega - exact).abs() < 0.01 * exact, "{omega} vs {exact}");
}

#[test]
fn follower_loads_turn_with_the_node_and_spatial_loads_do_not() {
    use liemid::beam::{History, NodalLoad};
    use liemid::many::Interaction;
    let section = Section::rectangle(1e3, 0.3, 1.0, 0.1, 0.1).unwrap();
    let mut frame = Frame::new();
    let nodes = frame
        .add_member(
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            2,
            section,
            Vec3::new(0.0, 0.0, 1.0),
        )
        .unwrap();
    let f0 = Vec3::new(0.0, 1.0, 0.0);
    let m0 = Vec3::new(0.0, 0.0, 2.0);
    for follower in [true, false] {
        frame.loads.clear();
        frame
            .load(NodalLoad {
                node: nodes[2],
                force: f0,
                moment: m0,
                follower,
                history: History::constant(),
            })
            .unwrap();
        let mut s = frame.build().unwrap();
        // Turn the whole structure rigidly: no strain, so the end node's force is the load.
        let q = so3::exp(Vec3::new(0.3, -0.2, 0.9));
        for &n in &nodes {
            s.set_pose(n, q * frame.nodes[n], q);
        }
        let i = match s.nodes[nodes[2]] {
            liemid::beam::NodeRef::Body(i) => i,
            liemid::beam::NodeRef::Fixed(_) => unreachable!(),
        };
        let mut force = vec![Vec3::ZERO; s.bodies.len()];
        let mut torque = force.clone();
        s.structure.compute(s.bodies.configuration(), &mut force, &mut torque);
        let spatial_moment = s.bodies.rotation[i] * torque[i];
        let (f, m) = if follower { (q * f0, q * m0) } else { (f0, m0) };
        assert!((force[i] - f).norm() < 1e-12, "{follower}: {:?} vs {f:?}", force[i]);
        assert!(
            (spatial_moment - m).norm() < 1e-12,
            "{follower}: {spatial_moment:?} vs {m:?}"
        );
    }
}

#[test]
fn under_gravity_a_free_beam_falls_with_g_and_keeps_its_shape() {
    let p = problems::flying_beam(6).unwrap();
    let mut frame = p.frame.clone();
    frame.loads.clear();
    frame.gravity = Vec3::new(0.0, 0.0, -9.81);
    let mut s = frame.build().unwrap();
    let h = s.stability(0).default_step(BeamMethod::Splitting);
    let mass: f64 = s.bodies.mass.iter().sum();
    let steps = 1000;
    for _ in 0..steps {
        s.step(h).unwrap();
    }
    let t = steps as f64 * h;
    let p_total = s.totals().linear_momentum;
    // Each step adds exactly m g h of momentum (the internal forces sum to zero).
    assert!(
        (p_total.z + mass * 9.81 * t).abs() < 1e-10 * mass * 9.81 * t,
        "{p_total:?}"
    );
    for node in 0..frame.nodes.len() {
        let u = s.displacement(node);
        assert!(
            (u.z + 0.5 * 9.81 * t * t).abs() < 1e-8 && u.x.abs() < 1e-8,
            "node {node}: {u:?}"
        );
    }
}
