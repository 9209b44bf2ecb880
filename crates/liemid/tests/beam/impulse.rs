//! The impulse method (`liemid-mts`) and Newmark's exact element tangent.

use liemid::beam::{element, impulse, problems, tangent, BeamMethod, ElementStiffness, Newmark, Tangent};
use liemid::{so3, Mat3, Vec3};

use crate::beam_runs;
use beam_runs::advance;

#[test]
fn impulse_method_is_second_order() {
    // The right-angle cantilever swinging after its load (t = 2), as for the splitting.
    let p = problems::right_angle_cantilever(4).unwrap();
    let mut start = p.system().unwrap();
    for _ in 0..1000 {
        start.step(0.002).unwrap();
    }
    let t = 1.0;
    let critical = start.stability(0).critical_step(BeamMethod::Impulse);
    let h0 = t / (t / (0.5 * critical)).ceil();
    let reference = advance(&start, BeamMethod::Splitting4, h0 / 64.0, t);
    let errors: Vec<f64> = [1.0, 2.0, 4.0]
        .iter()
        .map(|d| {
            let x = advance(&start, BeamMethod::Impulse, h0 / d, t);
            x.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
        })
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("liemid-mts: errors {errors:?}, orders {orders:?}");
    for p in orders {
        assert!((p - 2.0).abs() < 0.2, "order {p}");
    }
}

#[test]
fn impulse_method_keeps_the_energy_bounded_at_its_default_step() {
    let p = problems::right_angle_cantilever(8).unwrap();
    let mut s = p.system().unwrap();
    let h = s.stability(0).default_step(BeamMethod::Impulse);
    // The substeps: m = ⌈h ω_a / 1.8⌉.
    assert_eq!(
        impulse::substeps(h, s.stability(0).omega_axial_bound),
        (h * s.stability(0).omega_axial_bound / 1.8).ceil() as usize
    );
    let steps = (8.0 / h) as usize;
    let mut energy = Vec::new();
    for _ in 0..steps {
        s.step_with(BeamMethod::Impulse, h).unwrap();
        if s.t() >= 2.0 {
            energy.push(s.totals().energy);
        }
    }
    let e0 = energy[0];
    let worst = |e: &[f64]| e.iter().map(|x| ((x - e0) / e0).abs()).fold(0.0, f64::max);
    let n = energy.len();
    let (first, last) = (worst(&energy[..n / 3]), worst(&energy[2 * n / 3..]));
    println!("h {h}: energy change first third {first:.2e}, last third {last:.2e}");
    // Symplectic: an O(h²) oscillation, no drift (a resonant step drifts by orders of
    // magnitude: 9e-4 at 1.4x this step on 16 elements per leg).
    assert!(
        first < 1e-5 && last < 2.0 * first.max(1e-9),
        "energy {first:e} then {last:e}"
    );
}

#[test]
fn slow_and_axial_forces_sum_to_the_element_forces() {
    let k = ElementStiffness {
        length: 0.7,
        axial: 1e6 / 0.7,
        torsion: 1e3 / 0.7,
        bending2: 2e3 / 0.7,
        bending3: 1e3 / 0.7,
    };
    let (xa, xb) = (Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.79, 0.03, 0.12));
    let ta = so3::exp(Vec3::new(0.05, 0.3, 0.32));
    let tb = so3::exp(Vec3::new(-0.04, 0.25, 0.36));
    let full = element::end_forces(&k, xa, xb, &ta, &tb);
    let slow = element::bending_end_forces(&k, xa, xb, &ta, &tb);
    let ax = element::axial_force(&k, xa, xb);
    let scale = full.force_a.norm();
    assert!((slow.force_a + ax - full.force_a).norm() <= 1e-12 * scale);
    assert!((slow.force_b - ax - full.force_b).norm() <= 1e-12 * scale);
    assert_eq!(slow.moment_a, full.moment_a);
}

#[test]
#[allow(clippy::needless_range_loop)]
fn analytic_tangent_matches_central_differences() {
    let k = ElementStiffness {
        length: 0.7,
        axial: 1e4 / 0.7,
        torsion: 1e3 / 0.7,
        bending2: 2e3 / 0.7,
        bending3: 1e3 / 0.7,
    };
    let (xa, xb) = (Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.79, 0.03, 0.12));
    let ra = so3::exp(Vec3::new(0.05, 0.3, 0.32));
    let rb = so3::exp(Vec3::new(-0.04, 0.25, 0.36));
    let (ca, cb) = (Mat3::IDENTITY, Mat3::IDENTITY);
    let q = |xa: Vec3, xb: Vec3, ra: &Mat3, rb: &Mat3| -> [f64; 12] {
        let f = element::end_forces(&k, xa, xb, ra, rb);
        let mut out = [0.0; 12];
        for (b, v) in [
            f.force_a,
            ra.tr_mul_vec(f.moment_a),
            f.force_b,
            rb.tr_mul_vec(f.moment_b),
        ]
        .iter()
        .enumerate()
        {
            out[3 * b..3 * b + 3].copy_from_slice(&v.to_array());
        }
        out
    };
    // The values equal the element's forces.
    let v = tangent::generalised_force_values(&k, xa, xb, &ra, &rb, &ca, &cb);
    let q0 = q(xa, xb, &ra, &rb);
    let scale = q0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for b in 0..4 {
        for r in 0..3 {
            assert!((v[b].to_array()[r] - q0[3 * b + r]).abs() <= 1e-12 * scale);
        }
    }
    let kt = tangent::element_tangent(&k, xa, xb, &ra, &rb, &ca, &cb);
    let eps = 1e-6;
    let mut worst: f64 = 0.0;
    let mut largest: f64 = 0.0;
    for col in 0..12 {
        let (end, kind, d) = (col / 6, (col / 3) % 2, col % 3);
        let mut unit = [0.0; 3];
        unit[d] = 1.0;
        let u = Vec3::from_array(unit);
        let shifted = |s: f64| {
            let (mut xa, mut xb, mut ra, mut rb) = (xa, xb, ra, rb);
            match (end, kind) {
                (0, 0) => xa += u * s,
                (0, _) => ra = ra * so3::exp(u * s),
                (_, 0) => xb += u * s,
                _ => rb = rb * so3::exp(u * s),
            }
            q(xa, xb, &ra, &rb)
        };
        let (p, m) = (shifted(eps), shifted(-eps));
        for row in 0..12 {
            let fd = -(p[row] - m[row]) / (2.0 * eps);
            worst = worst.max((fd - kt[row][col]).abs());
            largest = largest.max(kt[row][col].abs());
        }
    }
    // Central differences: truncation O(eps²) K''' and rounding O(u |Q|/eps): about 1e-8
    // of the largest entry here.
    println!("largest entry {largest:.3e}, largest difference {worst:.3e}");
    assert!(worst <= 1e-6 * largest, "{worst:e} of {largest:e}");
}

#[test]
fn newmark_with_either_tangent_gives_the_same_motion() {
    let p = problems::right_angle_cantilever(4).unwrap();
    let s = p.system().unwrap();
    let mut a = Newmark::new(&s);
    let mut b = Newmark::new(&s).with_tangent(Tangent::FiniteDifference);
    assert_eq!(a.tangent(), Tangent::Analytic);
    for _ in 0..60 {
        a.step(0.05).unwrap();
        b.step(0.05).unwrap();
    }
    let elbow = p.frame.named("elbow").unwrap();
    let (ua, ub) = (a.displacement(elbow), b.displacement(elbow));
    println!(
        "elbow {ua:?} against {ub:?}; iterations {} and {}",
        a.iterations, b.iterations
    );
    // Both converge Newton to a correction below 1e-10 of the size.
    assert!((ua - ub).norm() < 1e-8 * ua.norm(), "{ua:?} vs {ub:?}");
}
