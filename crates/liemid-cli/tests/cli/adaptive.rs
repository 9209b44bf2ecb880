//! `liemid run --adaptive EPS`: the JSON summary's `adaptive` object beside `steps`, the run
//! landing on t_end, the eccentric satellite's orbit and attitude, and the refusals (exit 2,
//! one line).

use crate::common;
use common::{json, run_in, scratch, stderr, stdout};

#[test]
fn adaptive_summary_lands_on_t_end() {
    let dir = scratch("adaptive-run");
    let o = run_in(
        &dir,
        &["run", "--adaptive", "0.3", "--t-end", "0.05", "--no-output", "--json"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&stdout(&o));
    assert_eq!(v["t"].as_f64(), Some(0.05));
    assert!(v["step"].is_null());
    let a = &v["adaptive"];
    assert_eq!(a["eps"].as_f64(), Some(0.3));
    assert_eq!(a["rho"].as_str(), Some("omega"));
    let (lo, hi) = (a["min_step"].as_f64().unwrap(), a["max_step"].as_f64().unwrap());
    let last = v["last_step"].as_f64().unwrap();
    assert!(0.0 < lo && lo <= hi && 0.0 < last && last <= hi, "{v}");
    // The steps cover the interval: (steps - 1) full steps and the last.
    let n = v["steps"].as_u64().unwrap() as f64;
    assert!((n - 1.0) * lo + last <= 0.05 * (1.0 + 1e-12) && (n - 1.0) * hi + last >= 0.05 * (1.0 - 1e-12));
}

#[test]
fn eccentric_satellite_one_orbit() {
    let dir = scratch("adaptive-satellite");
    let o = run_in(
        &dir,
        &[
            "run",
            "--problem",
            "eccentric-satellite",
            "--adaptive",
            "0.05",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&stdout(&o));
    assert_eq!(v["adaptive"]["rho"].as_str(), Some("orbit"));
    assert_eq!(v["rotation"].as_array().map(Vec::len), Some(9));
    // Back at perigee after one period: |r| = a (1 - e) = 6.9056e6 m to the orbit's error.
    let r: Vec<f64> = v["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((norm / 6.9056e6 - 1.0).abs() < 1e-2, "{v}");
    // Total angular momentum at round-off (compensated orbit sums).
    assert!(v["max_angular_momentum_error"].as_f64().unwrap() < 1e-14, "{v}");
}

#[test]
fn refusals() {
    let dir = scratch("adaptive-refusals");
    for args in [
        &["run", "--method", "rk4", "--adaptive", "0.1", "--no-output"][..],
        &["run", "--adaptive", "0.1", "--step", "1e-3", "--no-output"],
        &["run", "--adaptive", "-1", "--no-output"],
        &["run", "--adaptive", "0.1", "--rho", "orbit", "--no-output"],
        &[
            "run",
            "--problem",
            "eccentric-satellite",
            "--method",
            "liemid-e1",
            "--adaptive",
            "0.1",
        ],
        &["run", "--orbits", "2", "--no-output"],
        // Options the satellite run does not honour are refused, never silently dropped.
        &["run", "--problem", "eccentric-satellite", "--out", "sat.csv"],
        &["run", "--problem", "eccentric-satellite", "--every", "10"],
        &["run", "--problem", "eccentric-satellite", "--t-end", "100"],
    ] {
        let o = run_in(&dir, args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.trim().is_empty(), "{args:?}");
    }
    assert!(!dir.join("sat.csv").exists());
}

/// An adaptive run that would take more steps than the bound (a tiny eps, a huge t_end) is
/// refused before the first step with the estimate at the start's pace; it used to run
/// without end.
#[test]
fn an_adaptive_run_beyond_the_step_bound_is_refused_before_the_first_step() {
    let dir = scratch("adaptive-bound");
    for args in [
        &["run", "--adaptive", "1e-300"][..],
        &["run", "--adaptive", "1e-3", "--t-end", "1e300"],
        &["run", "--adaptive", "1e-3", "--max-steps", "10"],
    ] {
        let o = run_in(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("steps at the start's step"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
    // Within the bound the run goes on as before.
    let o = run_in(
        &dir,
        &["run", "--adaptive", "1e-3", "--t-end", "0.01", "--max-steps", "1000000"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The satellite takes `--max-steps` like every run (it refused the flag, so a run could
/// not be bounded): fixed and adaptive runs beyond the bound are refused before the first
/// step, and a run within it completes.
#[test]
fn the_satellite_run_is_bounded_by_max_steps() {
    let dir = scratch("satellite-bound");
    let sat = ["run", "--problem", "eccentric-satellite"];
    for (extra, said) in [
        (&["--max-steps", "10"][..], "4308 steps, more than --max-steps 10"),
        (&["--orbits", "1e9"][..], "more than the default bound"),
        (&["--adaptive", "1e-300"][..], "more than the default bound"),
        (
            &["--adaptive", "1e-3", "--max-steps", "5"][..],
            "more than --max-steps 5",
        ),
    ] {
        let o = run_in(&dir, &[&sat[..], extra].concat());
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(said), "{extra:?}: {}", stderr(&o));
    }
    let o = run_in(&dir, &[&sat[..], &["--max-steps", "4308"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
}
