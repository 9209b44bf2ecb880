//! The round-off of the total angular momentum over long adaptive runs of the eccentric
//! satellite: an ensemble of runs from starts one part in 1e-12 apart, the RMS over the
//! ensemble of `|L(t) − L(0)| / |L(0)|` at every tenth of the run, and the exponent `α` of
//! its growth `∝ t^α` fitted over the last nine tenths (0.5: a random walk of rounding
//! errors; 1: a drift). The energy error per tenth beside it.
//!
//! `cargo run --release -p liemid --example satellite_roundoff [ORBITS] [RUNS]`
use liemid::rigid::adaptive::AdaptiveRun;
use liemid::rigid::satellite::{eccentric_satellite, SatelliteAdaptive, SatelliteDensity};
use liemid::RotationMethod;

fn main() {
    let mut args = std::env::args().skip(1);
    let orbits: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000.0);
    let runs: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(8);
    let p = eccentric_satellite();
    let sat = p.satellite;
    let t_end = orbits * p.period;
    let mut sum_l2 = [0.0f64; 10];
    let mut max_e = [0.0f64; 10];
    for k in 0..runs {
        let mut start = p.initial;
        start.velocity = start.velocity * (1.0 + 1e-12 * k as f64);
        let (e0, l0) = (sat.energy(&start), sat.angular_momentum(&start));
        let st = SatelliteAdaptive::new(&sat, RotationMethod::LieMidpointAlternating4, SatelliteDensity::Orbit)
            .expect("EA4 is symmetric");
        let mut run = AdaptiveRun::new(st, start, t_end, 0.05).expect("valid run");
        let mut next = 1;
        while !run.is_done() {
            run.step().expect("the run steps");
            let s = run.state();
            let tenth = ((s.t / t_end * 10.0) as usize).min(9);
            max_e[tenth] = max_e[tenth].max(((sat.energy(s) - e0) / e0).abs());
            if next <= 10 && s.t >= t_end * next as f64 / 10.0 * (1.0 - 1e-12) {
                let dl = (sat.angular_momentum(s) - l0).norm() / l0.norm();
                sum_l2[next - 1] += dl * dl;
                next += 1;
            }
        }
    }
    let rms: Vec<f64> = sum_l2.iter().map(|s| (s / runs as f64).sqrt()).collect();
    println!("{orbits} orbits, {runs} runs, EA4 eps 0.05:");
    for (k, (r, e)) in rms.iter().zip(&max_e).enumerate() {
        println!(
            "  t = {:.1} T: momentum error RMS {r:.3e}; max energy error over the tenth {e:.4e}",
            orbits * (k + 1) as f64 / 10.0
        );
    }
    // Least squares of ln(rms) against ln(t) over tenths 2..10.
    let pts: Vec<(f64, f64)> = (1..10).map(|k| (((k + 1) as f64).ln(), rms[k].ln())).collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (sxx, sxy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0 * p.0, a.1 + p.0 * p.1));
    let alpha = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    println!("  growth exponent of the momentum error: {alpha:.2} (0.5 random walk, 1 drift)");
}
