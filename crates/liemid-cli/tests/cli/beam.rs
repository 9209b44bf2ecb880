//! `liemid beam` end to end: the JSON contract, files, the example against the built-in
//! problem, the variational drift, errors.

use crate::common;
use common::{examples, json, run_in, scratch, stderr, stdout};

fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn beam_writes_the_json_contract_with_tracked_histories() {
    let dir = scratch("beam-json");
    let o = run_in(&dir, &["beam", "--t-end", "3", "--sample", "0.1", "--json", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&stdout(&o));
    for key in ["elbow", "tip"] {
        let t = v["tracked"][key]["t"].as_array().unwrap();
        let u = v["tracked"][key]["u"].as_array().unwrap();
        assert_eq!(t.len(), 31, "{key}");
        assert_eq!(u.len(), 31);
        assert_eq!(u[0].as_array().unwrap().len(), 3);
    }
    assert_eq!(v["energy"].as_array().unwrap().len(), 31);
    assert!(v["steps"].as_u64().unwrap() > 1000);
    let h = v["step"].as_f64().unwrap();
    assert!(h <= v["critical_step"].as_f64().unwrap());
    assert!(v["wall_seconds"].as_f64().unwrap() > 0.0);
    assert!(v["element_steps_per_second"].as_f64().unwrap() > 1e5);
    // The elbow is pushed up: positive u_z by t = 1.
    let uz = v["tracked"]["elbow"]["u"][10][2].as_f64().unwrap();
    assert!(uz > 0.5, "{uz}");
}

#[test]
fn mass_scaled_method_reports_its_axial_mass_and_agrees_with_the_splitting() {
    let dir = scratch("beam-sms");
    let args = |m: &'static str| ["beam", "--t-end", "3", "--sample", "0.1", "--method", m, "--json", "-"];
    let (o, p) = (run_in(&dir, &args("liemid-sms")), run_in(&dir, &args("liemid")));
    assert!(o.status.success() && p.status.success(), "{}", stderr(&o));
    let (v, w) = (json(&stdout(&o)), json(&stdout(&p)));
    // 8 elements per leg: ω_a/ω_b = 11.4, β = (11.4² − 1)/4 ≈ 32, the step 11.4x the splitting's.
    let beta = v["axial_mass"].as_f64().unwrap();
    assert!(beta > 30.0 && beta < 34.0, "{beta}");
    let gain = v["step"].as_f64().unwrap() / w["step"].as_f64().unwrap();
    assert!(gain > 10.0, "{gain}");
    assert!(v["stretch_iterations_per_step"].as_f64().unwrap() >= 1.0);
    assert!(v["cpu_seconds"].as_f64().unwrap() >= 0.0);
    // The scaling changes the axial inertia only: the elbow's history stays within 1e-3 of
    // its largest value (the quasi-static estimate; measured 1e-5 at 16 per leg).
    let u = |x: &serde_json::Value| -> Vec<f64> {
        x["tracked"]["elbow"]["u"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r[2].as_f64().unwrap())
            .collect()
    };
    let (a, b) = (u(&v), u(&w));
    let size = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let d = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(d < 1e-3 * size, "{d} of {size}");
}

#[test]
fn the_example_file_gives_the_built_in_problem_bit_for_bit_on_any_thread_count() {
    let dir = scratch("beam-example");
    let file = examples().join("right_angle_cantilever.toml");
    let a = run_in(
        &dir,
        &[
            "beam",
            file.to_str().unwrap(),
            "--t-end",
            "2",
            "--json",
            "-",
            "--threads",
            "1",
        ],
    );
    let b = run_in(
        &dir,
        &[
            "beam",
            "--problem",
            "right-angle-cantilever",
            "--t-end",
            "2",
            "--sample",
            "0.05",
            "--json",
            "-",
            "--threads",
            "3",
        ],
    );
    assert!(a.status.success() && b.status.success(), "{}{}", stderr(&a), stderr(&b));
    let (a, b) = (json(&stdout(&a)), json(&stdout(&b)));
    assert_eq!(a["tracked"], b["tracked"]);
    assert_eq!(a["energy"], b["energy"]);
}

#[test]
fn beam_writes_csv_npy_and_a_plot_and_newmark_runs() {
    let dir = scratch("beam-files");
    let o = run_in(
        &dir,
        &[
            "beam",
            "--t-end",
            "2",
            "--sample",
            "0.5",
            "--out",
            "h.csv",
            "--plot",
            "h.svg",
            "--elements-per-member",
            "4",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(dir.join("h.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,energy,elbow_ux,elbow_uy,elbow_uz,tip_ux,tip_uy,tip_uz"
    );
    assert_eq!(lines.count(), 5);
    assert!(std::fs::read_to_string(dir.join("h.svg")).unwrap().contains("<svg"));
    let o = run_in(
        &dir,
        &[
            "beam", "--method", "newmark", "--t-end", "2", "--out", "n.npy", "--sample", "0.5",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("Newton iterations"), "{}", stdout(&o));
    let rows = common::read_npy_columns(&dir.join("n.npy"), 8);
    assert_eq!(rows.len(), 5);
    // Newmark has no energy column value: NaN.
    assert!(rows[1][1].is_nan());
}

#[test]
fn beam_input_errors_name_the_cause_and_exit_2() {
    let dir = scratch("beam-errors");
    let base = "[[section]]\nname = \"s\"\nEA = 1.0\nGJ = 1.0\nEI2 = 1.0\nEI3 = 1.0\nrhoA = 1.0\nrotary_inertia = [1.0, 0.5, 0.5]\n\
                [[member]]\nfrom = [0.0, 0.0, 0.0]\nto = [1.0, 0.0, 0.0]\nsection = \"s\"\norientation = [0.0, 0.0, 1.0]\n";
    for (extra, expected) in [
        ("[run]\nt_end = 1.0\nmethod = \"rk4\"\n", "unknown beam method"),
        ("[run]\nt_end = 1.0\nspeed = 3\n", "speed"),
        (
            "[[load]]\nat = [0.5, 0.3, 0.0]\nforce = [1.0, 0.0, 0.0]\n[run]\nt_end = 1.0\n",
            "no node at",
        ),
        (
            "[[node]]\nat = [0.0, 0.0, 0.0]\nsupport = \"glued\"\n[run]\nt_end = 1.0\n",
            "support `glued`",
        ),
        ("[run]\nt_end = 1.0\nstep = 10.0\n", "critical step"),
        (
            "[run]\nt_end = 1.0\ndrift = \"cayley\"\n",
            "[run] drift: unknown drift `cayley` (known: midpoint, variational)",
        ),
        (
            "[run]\nt_end = 1.0\nmethod = \"newmark\"\ndrift = \"variational\"\n",
            "newmark has none",
        ),
        ("", "t_end is missing"),
    ] {
        let file = write(&dir, "bad.toml", &format!("{base}{extra}"));
        let o = run_in(&dir, &["beam", file.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{extra}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains(expected), "{extra}: expected `{expected}` in {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    let o = run_in(&dir, &["beam", "--problem", "bridge"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("right-angle-cantilever"), "{}", stderr(&o));
    // No output may replace the input.
    let file = write(&dir, "ok.toml", &format!("{base}[run]\nt_end = 0.1\n"));
    let o = run_in(&dir, &["beam", file.to_str().unwrap(), "--out", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&file).unwrap().contains("[[member]]"));
}

/// `liemid beam` and `liemid spins` are held to the step bound like every run (they had
/// none: `--t-end 1e9` ran for days), and a beam run whose samples would not fit the memory
/// is refused before the first step, naming both sizes.
#[test]
fn beam_and_spins_runs_are_bounded_before_the_first_step() {
    let dir = scratch("beam-bounds");
    let o = run_in(&dir, &["beam", "--t-end", "1e9", "--out", "o.csv"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("more than the default bound of 1000000000"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.join("o.csv").exists());
    let o = run_in(&dir, &["beam", "--t-end", "1", "--max-steps", "10"]);
    assert!(stderr(&o).contains("steps, more than --max-steps 10"), "{}", stderr(&o));
    let available = liemid_app::shared::memory::available_memory().unwrap_or(0) as f64;
    if available < 1e13 {
        // About 1e10 samples of at least 40 bytes: 400 GB.
        let o = run_in(
            &dir,
            &[
                "beam",
                "--t-end",
                "10",
                "--sample",
                "1e-9",
                "--max-steps",
                "100000000000",
            ],
        );
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("of memory available"), "{}", stderr(&o));
    }
    let o = run_in(&dir, &["spins", "--t-end", "1e12"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("more than the default bound"), "{}", stderr(&o));
}

#[test]
fn the_variational_drift_is_a_choice_of_the_liemid_methods() {
    let dir = scratch("beam-drift");
    let args = ["beam", "--t-end", "1", "--sample", "0.5", "--json", "-"];
    let run = |extra: &[&str]| {
        let o = run_in(&dir, &[&args[..], extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        json(&stdout(&o))
    };
    let midpoint = run(&[]);
    assert_eq!(midpoint["drift"], "midpoint");
    for method in ["liemid", "liemid4", "liemid-mts", "liemid-sms"] {
        let [m, v] = ["midpoint", "variational"].map(|d| run(&["--method", method, "--drift", d]));
        assert_eq!(v["drift"], "variational", "{method}");
        // Both drifts second order: the elbow histories agree to the step's error, not to
        // the last bit.
        let elbow = |r: &serde_json::Value| r["tracked"]["elbow"]["u"][2][2].as_f64().unwrap();
        let d = (elbow(&m) - elbow(&v)).abs();
        assert!(
            d > 0.0 && d < 1e-4 * elbow(&m).abs(),
            "{method}: the drifts differ by {d:e}"
        );
    }
    // The file's key, overridden by the flag.
    let file = write(
        &dir,
        "drift.toml",
        &std::fs::read_to_string(examples().join("right_angle_cantilever.toml"))
            .unwrap()
            .replace("[run]", "[run]\ndrift = \"variational\""),
    );
    let from_file = run_in(
        &dir,
        &[
            "beam",
            file.to_str().unwrap(),
            "--t-end",
            "1",
            "--sample",
            "0.5",
            "--json",
            "-",
        ],
    );
    assert!(from_file.status.success(), "{}", stderr(&from_file));
    assert_eq!(json(&stdout(&from_file))["drift"], "variational");
    // Newmark has no drift to choose, and an unknown one is named.
    for (extra, expected) in [
        (
            &["--method", "newmark", "--drift", "variational"][..],
            "newmark has none",
        ),
        (&["--drift", "cayley"][..], "--drift: unknown drift `cayley`"),
    ] {
        let o = run_in(&dir, &[&args[..], extra].concat());
        assert_eq!(o.status.code(), Some(2), "{extra:?}");
        assert!(stderr(&o).contains(expected), "{extra:?}: {}", stderr(&o));
    }
    let newmark = run(&["--method", "newmark", "--step", "0.05"]);
    assert!(newmark["drift"].is_null());
}
