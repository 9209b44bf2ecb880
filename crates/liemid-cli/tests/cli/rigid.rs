//! End-to-end tests of the `liemid` binary.

use crate::common;

use common::*;

#[test]
fn run_without_a_file_runs_the_fast_top() {
    let dir = scratch("default");
    let o = run_in(&dir, &["run"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("LIEMID[EA]") && out.contains("steps                          8000"),
        "{out}"
    );
    assert!(
        out.contains("max relative energy error") && out.contains("wall time"),
        "{out}"
    );
    let rows = read_csv(&dir.join("trajectory.csv"));
    assert_eq!(rows.len(), 8001);
    let last = rows.last().unwrap();
    assert_eq!(last[0], 0.8);
    // Against the shipped reference at t = 0.8 (docs/theory/rigid.md §8): EA at h = 1e-4 is within
    // its error of about 1e-5.
    assert!((last[1] - 0.001294760157741989).abs() < 2e-5 && (last[2] - 0.008576777914107317).abs() < 2e-5);
    // The vertical spatial momentum column is constant to round-off.
    let piz0 = rows[0][16];
    assert!(rows.iter().all(|r| (r[16] - piz0).abs() < 1e-13));
    assert!(!dir.join("trajectory.csv.partial").exists());
}

#[test]
fn every_example_scenario_runs_and_writes_a_complete_trajectory() {
    let dir = scratch("examples");
    for (file, steps, every, out) in [
        ("fast_top.toml", 8000u64, 10u64, "fast_top.csv"),
        ("slow_top.toml", 4000, 10, "slow_top.csv"),
        ("tennis_racket.toml", 10000, 5, "tennis_racket.npy"),
    ] {
        let path = examples().join(file);
        let o = run_in(&dir, &["run", path.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{file}: {}", stderr(&o));
        let summary = json(&stdout(&o));
        for key in [
            "t",
            "pi",
            "rotation",
            "steps",
            "max_energy_error",
            "max_spatial_momentum_change",
            "max_orthogonality_defect",
        ] {
            assert!(summary.get(key).is_some(), "{file}: summary lacks {key}");
        }
        assert_eq!(summary["steps"], steps);
        assert_eq!(summary["rotation"].as_array().unwrap().len(), 9);
        let rows = if out.ends_with(".npy") {
            read_npy(&dir.join(out))
        } else {
            read_csv(&dir.join(out))
        };
        assert_eq!(rows.len() as u64, steps / every + 1, "{file}");
        assert_eq!(summary["trajectory"]["rows"], rows.len());
        // Rows are every `every` steps apart.
        let h = summary["step"].as_f64().unwrap();
        assert!((rows[1][0] - rows[0][0] - every as f64 * h).abs() < 1e-12);
        // The summary's final state is the last row.
        let pi = summary["pi"].as_array().unwrap();
        // (serde_json parses floats to within an ulp unless its float_roundtrip feature is on)
        let (a, b) = (rows.last().unwrap()[1], pi[0].as_f64().unwrap());
        assert!((a - b).abs() <= 4.0 * f64::EPSILON * a.abs(), "{a} vs {b}");
    }
    // The free body keeps its spatial momentum (columns pix, piy, piz) to round-off.
    let rows = read_npy(&dir.join("tennis_racket.npy"));
    for r in &rows {
        for c in 14..17 {
            assert!((r[c] - rows[0][c]).abs() < 1e-12 * 20.0, "spatial momentum drifted");
        }
    }
}

#[test]
fn command_line_overrides_and_npy_output() {
    let dir = scratch("overrides");
    let o = run_in(
        &dir,
        &[
            "run",
            "--problem",
            "slow-top",
            "--method",
            "rk4",
            "--step",
            "2e-4",
            "--t-end",
            "0.1",
            "--out",
            "x.npy",
            "--every",
            "7",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    assert_eq!(s["method"], "rk4");
    assert_eq!(s["steps"], 500);
    assert_eq!(s["t"], 0.1);
    // 500 steps, every 7th plus the first and the last: 0, 7, …, 497, 500.
    let rows = read_npy(&dir.join("x.npy"));
    assert_eq!(rows.len(), 500 / 7 + 2);
    assert_eq!(rows.last().unwrap()[0], 0.1);
    let o = run_in(&dir, &["run", "--no-output", "--t-end", "0.01"]);
    assert!(o.status.success());
    assert!(!dir.join("trajectory.csv").exists());
}

const GOOD: &str = "[body]\ninertia = [1.0, 2.0, 3.0]\n[initial]\nangular_velocity = [3.0, 10.0, 2.5]\n\
                    [integrator]\nmethod = \"liemid-ea\"\nstep = 1e-3\nt_end = 1.0\n";

#[test]
fn bad_input_is_one_line_naming_file_and_key_with_exit_code_2() {
    let dir = scratch("bad");
    let cases = [
        (
            "unknown.toml",
            GOOD.replace("step =", "stepp = 1.0\nstep ="),
            "[integrator] unknown key `stepp`",
        ),
        (
            "inertia.toml",
            GOOD.replace("[1.0, 2.0, 3.0]", "[1.0, 0.0, 3.0]"),
            "[body] inertia",
        ),
        ("syntax.toml", GOOD.replace("[integrator]", "[integrator"), "line 5"),
        (
            "method.toml",
            GOOD.replace("liemid-ea", "verlet"),
            "unknown method \"verlet\"",
        ),
    ];
    for (name, text, expected) in cases {
        let p = write(&dir, name, &text);
        let o = run_in(&dir, &["run", p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = stderr(&o);
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(name) && err.contains(expected), "{name}: {err}");
        assert!(!dir.join("trajectory.csv").exists());
    }
    let o = run_in(&dir, &["run", "missing.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("missing.toml: cannot read"));
    let o = run_in(&dir, &["run", "--step=-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--step must be a positive number"));
    // A negative number after a space is the option's value, not an unknown flag.
    let o = run_in(&dir, &["run", "--step", "-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--step must be a positive number, found -1"));
    // A mistyped exponent is refused before the first step and writes nothing (it used to
    // run until the disk was full).
    let files = std::fs::read_dir(&dir).unwrap().count();
    for args in [
        &["run", "--step", "1e-30"][..],
        &["run", "--t-end", "1e12", "--step", "1e-30"],
        &["many", "--step", "1e-300"],
    ] {
        let o = run_in(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains("is too small for t from 0 to"), "{args:?}: {err}");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), files, "{args:?} wrote a file");
    }
    let o = run_in(&dir, &["many", "--model", "dipoles", "--density", "-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("density -1: the dipolar fluid accepts 0 < density <= 1.2"));
    let o = run_in(&dir, &["run", "--every", "0"]);
    assert_eq!(o.status.code(), Some(2));
    let o = run_in(&dir, &["converge", "--methods", "liemid-ea,nope", "--no-plot"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("unknown method `nope`"));
}

#[test]
fn a_numerical_failure_exits_1_and_keeps_the_partial_trajectory() {
    let dir = scratch("numerical");
    // The step is fine at first; the torque spins the body up until one step turns it by
    // more than half a turn.
    let text = "[body]\ninertia = [1.0, 2.0, 3.0]\n[initial]\nangular_velocity = [0.0, 1.0, 0.0]\n\
                [torque]\nkind = \"constant\"\nbody = [500.0, 1000.0, 200.0]\n\
                [integrator]\nstep = 0.01\nt_end = 10.0\n[output]\npath = \"spin.csv\"\n";
    let p = write(&dir, "spinup.toml", text);
    let o = run_in(&dir, &["run", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("LIEMID[EA]") && err.contains("h = 0.01") && err.contains("t = "),
        "{err}"
    );
    assert!(
        !dir.join("spin.csv").exists(),
        "a failed run left a complete-looking file"
    );
    let rows = read_csv(&dir.join("spin.csv.partial"));
    assert!(rows.len() > 10, "the rows written before the failure are kept");
}

#[test]
fn converge_reproduces_the_papers_table_and_writes_both_plots() {
    let dir = scratch("converge");
    let o = run_in(&dir, &["converge", "--json", "study.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("reference: classical RK4"), "{out}");
    assert!(out.contains("observed order"), "{out}");
    for img in ["convergence.svg", "convergence.png"] {
        let meta = std::fs::metadata(dir.join(img)).unwrap();
        assert!(meta.len() > 10_000, "{img} is {} bytes", meta.len());
    }
    let svg = std::fs::read_to_string(dir.join("convergence.svg")).unwrap();
    assert!(svg.contains("LIEMID[EA]") && svg.contains("step h (s)") && svg.contains("slope 2"));
    let png = std::fs::read(dir.join("convergence.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");

    let study = json(&std::fs::read_to_string(dir.join("study.json")).unwrap());
    assert_eq!(study["problem"], "fast-top");
    assert_eq!(study["t_end"], 0.8);
    assert_eq!(study["reference"]["pi"].as_array().unwrap().len(), 3);
    assert_eq!(study["reference"]["rotation"].as_array().unwrap().len(), 9);
    let methods = study["methods"].as_array().unwrap();
    assert_eq!(methods.len(), 8);
    let ea = methods.iter().find(|m| m["name"] == "liemid-ea").unwrap();
    let steps: Vec<f64> = ea["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(steps.len(), 6);
    // docs/theory/rigid.md §8: EA at 1e-3, 2.5e-4, 1.25e-4.
    for (h, pm, pr) in [
        (1e-3, 8.2e-4, 1.2e-3),
        (2.5e-4, 5.1e-5, 7.5e-5),
        (1.25e-4, 1.3e-5, 1.9e-5),
    ] {
        let k = steps.iter().position(|s| (s - h).abs() < 1e-12).unwrap();
        let em = ea["momentum_error"][k].as_f64().unwrap();
        let er = ea["attitude_error"][k].as_f64().unwrap();
        assert!(em / pm < 1.5 && pm / em < 1.5, "h = {h}: momentum {em}");
        assert!(er / pr < 1.5 && pr / er < 1.5, "h = {h}: attitude {er}");
    }
    let order = ea["observed_order_attitude"].as_f64().unwrap();
    assert!((order - 2.0).abs() < 0.1, "EA order {order}");
    // The reference agrees with the shipped DOP853 solution (docs/theory/rigid.md §8) to 1e-9.
    let r = study["reference"]["rotation"].as_array().unwrap();
    assert!((r[0].as_f64().unwrap() - 0.30596975078721866).abs() < 1e-9);
}

#[test]
fn converge_json_to_stdout_and_a_single_plot() {
    let dir = scratch("converge-stdout");
    let o = run_in(
        &dir,
        &[
            "converge",
            "--problem",
            "torque-top",
            "--methods",
            "liemid-e1,liemid-e2",
            "--steps",
            "1e-2,5e-3,2.5e-3,1.25e-3",
            "--t-end",
            "1",
            "--json",
            "-",
            "--plot",
            "orders.svg",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let study = json(&stdout(&o));
    for m in study["methods"].as_array().unwrap() {
        let order = m["observed_order_attitude"].as_f64().unwrap();
        assert!((order - 1.0).abs() < 0.1, "{}: order {order}", m["name"]);
    }
    assert!(stderr(&o).contains("observed order"));
    assert!(dir.join("orders.svg").exists() && !dir.join("orders.png").exists());
    // Steps far too large for the fast top: the methods fail and say why, but the reference
    // is bounded by the rotation rate (0.01 / |Ω₀|), not only by the smallest step, so it
    // stays accurate and the study completes (RK4 at 0.25 / 64 used to blow up).
    let o = run_in(
        &dir,
        &[
            "converge",
            "--methods",
            "liemid-ea",
            "--steps",
            "0.5,0.25",
            "--no-plot",
            "--json",
            "-",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let study = json(&stdout(&o));
    let reference = &study["reference"];
    assert!(reference["step"].as_f64().unwrap() <= 0.01 / 983.0, "{reference}");
    assert!(reference["estimated_error"].as_f64().unwrap() < 1e-6, "{reference}");
    assert!(stderr(&o).contains("more than half a turn"), "{}", stderr(&o));
}

#[test]
fn listings_and_help() {
    let o = liemid().arg("methods").output().unwrap();
    let out = stdout(&o);
    for key in [
        "liemid-e1",
        "liemid-e2",
        "liemid-ea",
        "liemid-i",
        "akw",
        "simo-wong",
        "nmb",
        "rk4",
    ] {
        assert!(out.lines().any(|l| l.starts_with(key)), "methods lacks {key}");
    }
    // Every domain's methods, each under the subcommand that takes them.
    for (section, key) in [
        ("liemid many --rotation", "exact"),
        ("liemid many --rotation", "variational"),
        ("liemid beam --drift", "variational"),
        ("liemid spins --method", "split4"),
        ("liemid beam --method", "liemid-mts"),
        ("liemid multibody --method", "liemid8"),
    ] {
        let at = out.find(section).unwrap_or_else(|| panic!("methods lacks {section}"));
        assert!(out[at..].lines().any(|l| l.starts_with(key)), "{section} lacks {key}");
    }
    let o = liemid().arg("problems").output().unwrap();
    for p in ["fast-top", "slow-top", "free-body"] {
        assert!(stdout(&o).contains(p));
    }
    // And every domain's problems.
    let problems = stdout(&o);
    for (section, name) in [
        ("liemid many --model", "dipoles"),
        ("liemid spins --problem", "skyrmion"),
        ("liemid beam --problem", "right-angle-cantilever"),
        ("liemid multibody --problem", "closed-loop"),
    ] {
        let at = problems
            .find(section)
            .unwrap_or_else(|| panic!("problems lacks {section}"));
        assert!(
            problems[at..].lines().any(|l| l.starts_with(name)),
            "{section} lacks {name}"
        );
    }
    for sub in [
        &["--help"][..],
        &["run", "--help"],
        &["converge", "--help"],
        &["methods", "--help"],
    ] {
        let o = liemid().args(sub).output().unwrap();
        assert!(o.status.success() && stdout(&o).contains("Usage"), "{sub:?}");
    }
    let o = liemid().arg("frobnicate").output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn work_precision_reports_errors_times_and_torque_counts() {
    let dir = scratch("work-precision");
    let o = run_in(
        &dir,
        &[
            "work-precision",
            "--methods",
            "liemid-ea,rk4,dop853",
            "--max-points",
            "2",
            "--budget",
            "0.05",
            "--json",
            "-",
            "--plot",
            "wp.svg",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let study = json(&stdout(&o));
    assert_eq!(study["problem"], "fast-top");
    assert_eq!(study["repetitions"], 5);
    let methods = study["methods"].as_array().unwrap();
    assert_eq!(methods.len(), 3);
    for m in methods {
        let points = m["points"].as_array().unwrap();
        assert_eq!(points.len(), 2, "{}", m["name"]);
        for p in points {
            for key in [
                "attitude_error",
                "momentum_error",
                "seconds",
                "torque_evaluations",
                "max_energy_error",
            ] {
                assert!(p[key].as_f64().unwrap() > 0.0, "{} {key}", m["name"]);
            }
            let knob = if m["name"] == "dop853" { "tolerance" } else { "step" };
            assert!(p[knob].as_f64().is_some(), "{} lacks {knob}", m["name"]);
        }
        // Halving the step (or tightening the tolerance) reduces the error.
        assert!(points[1]["attitude_error"].as_f64() < points[0]["attitude_error"].as_f64());
    }
    // EA makes one torque evaluation per step (plus the first); RK4 four.
    let ea = &methods[0]["points"][0];
    let steps = liemid::step_count(0.0, 0.8, ea["step"].as_f64().unwrap()).unwrap();
    assert_eq!(ea["torque_evaluations"].as_u64().unwrap(), steps + 1);
    let rk4 = &methods[1]["points"][0];
    let steps = liemid::step_count(0.0, 0.8, rk4["step"].as_f64().unwrap()).unwrap();
    assert_eq!(rk4["torque_evaluations"].as_u64().unwrap(), 4 * steps);
    assert_eq!(study["targets"].as_array().unwrap().len(), 3);
    assert!(dir.join("wp.svg").exists());
    let o = run_in(&dir, &["work-precision", "--repetitions", "3"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn many_with_the_exact_rotation_keeps_energy_to_round_off_for_any_thread_count() {
    // Torque-free asymmetric rotors: the exact rotation is the flow itself, so the energy is
    // kept to round-off where the midpoint rotation's error is the step's; the totals file
    // is byte for byte the same on 1 and 3 threads.
    let dir = scratch("many-exact");
    let mut totals = Vec::new();
    for threads in ["1", "3"] {
        let file = format!("totals-{threads}.csv");
        let o = run_in(
            &dir,
            &[
                "many",
                "--model",
                "torque-free",
                "--rotation",
                "exact",
                "--bodies",
                "600",
                "--t-end",
                "0.2",
                "--step",
                "0.01",
                "--threads",
                threads,
                "--json",
                "-",
                "--out",
                &file,
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let s = json(&stdout(&o));
        assert_eq!(s["rotation"], "exact");
        assert!(s["max_relative_energy_error"].as_f64().unwrap() < 1e-14, "{s}");
        totals.push(std::fs::read(dir.join(file)).unwrap());
    }
    assert_eq!(totals[0], totals[1], "totals differ between 1 and 3 threads");
    let o = run_in(
        &dir,
        &[
            "many",
            "--model",
            "torque-free",
            "--bodies",
            "600",
            "--t-end",
            "0.2",
            "--step",
            "0.01",
            "--json",
            "-",
        ],
    );
    let s = json(&stdout(&o));
    assert_eq!(s["rotation"], "midpoint");
    assert!(s["max_relative_energy_error"].as_f64().unwrap() > 1e-12, "{s}");
    let scenario = write(
        &dir,
        "bad.toml",
        "[system]\nmodel = \"torque-free\"\n[integrator]\nrotation = \"spline\"\n",
    );
    let o = run_in(&dir, &["many", "--scenario", scenario.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("rotation") && stderr(&o).contains("midpoint, exact"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn many_reports_throughput_and_conservation() {
    let dir = scratch("many");
    let o = run_in(
        &dir,
        &[
            "many",
            "--model",
            "dipoles",
            "--bodies",
            "64",
            "--density",
            "0.5",
            "--t-end",
            "0.05",
            "--threads",
            "2",
            "--json",
            "-",
            "--out",
            "totals.csv",
            "--every",
            "5",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    assert_eq!(s["bodies"], 64);
    assert_eq!(s["steps"], 50);
    assert_eq!(s["threads"], 2);
    assert!(s["body_steps_per_second"].as_f64().unwrap() > 0.0);
    assert!(s["bytes_per_body"].as_u64().unwrap() <= 256);
    // 64 dipoles at this density live in open space (box below twice the cutoff): all
    // pairs, so total linear and angular momentum are kept to round-off.
    for key in ["linear_momentum_change", "angular_momentum_change"] {
        for v in s[key].as_array().unwrap() {
            assert!(v.as_f64().unwrap().abs() < 1e-11, "{key}: {v}");
        }
    }
    let text = std::fs::read_to_string(dir.join("totals.csv")).unwrap();
    assert_eq!(text.lines().count(), 1 + 50 / 5 + 1);
    let o = run_in(
        &dir,
        &["many", "--model", "torque-free", "--bodies", "1000", "--t-end", "0.01"],
    );
    assert!(
        o.status.success() && stdout(&o).contains("body-steps/s"),
        "{}",
        stderr(&o)
    );
    let o = run_in(&dir, &["many", "--step=-1"]);
    assert_eq!(o.status.code(), Some(2));
    // The dipole switch from the command line: the default smooth switch against a plain
    // truncation (switch start = cutoff) in a periodic box of 216 bodies; the truncated
    // energy jumps as pairs cross the cutoff.
    let energy_error = |extra: &[&str]| {
        let mut args = vec!["many", "--model", "dipoles", "--bodies", "216", "--t-end", "0.2"];
        args.extend_from_slice(&["--every", "1", "--json", "-", "--cutoff", "2.5"]);
        args.extend_from_slice(extra);
        let o = run_in(&dir, &args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        json(&stdout(&o))["max_relative_energy_error"].as_f64().unwrap()
    };
    let (switched, truncated) = (energy_error(&[]), energy_error(&["--switch-start", "2.5"]));
    assert!(
        truncated > 10.0 * switched,
        "switched {switched:e}, truncated {truncated:e}"
    );
    for (args, expected) in [
        (&["many", "--cutoff", "2"][..], "apply to the dipoles model only"),
        (
            &["many", "--model", "dipoles", "--switch-start", "3.5"],
            "`switch_start` = 3.5",
        ),
        (
            &["many", "--model", "dipoles", "--bodies", "50", "--switch-start", "2"],
            "needs a cutoff",
        ),
    ] {
        let o = run_in(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(expected), "{args:?}: {}", stderr(&o));
    }
    // The scenario-file form, with a command-line override.
    let example = examples().join("dipolar_fluid.toml");
    let o = run_in(
        &dir,
        &[
            "many",
            "--scenario",
            example.to_str().unwrap(),
            "--t-end",
            "0.01",
            "--json",
            "-",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    assert_eq!(
        (s["model"].as_str(), s["bodies"].as_u64(), s["steps"].as_u64()),
        (Some("dipoles"), Some(1000), Some(10))
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("dipolar_fluid_totals.csv"))
            .unwrap()
            .lines()
            .count(),
        3
    );
    let bad = write(&dir, "bad_many.toml", "[system]\nmodel = \"gas\"\n");
    let o = run_in(&dir, &["many", "--scenario", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("bad_many.toml: [system] model: unknown model"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn spins_runs_the_contract_scenario_and_writes_its_outputs() {
    let dir = scratch("spins");
    // The scenario contract, from a .npy start, with every output.
    let start: Vec<f64> = (0..16 * 16)
        .flat_map(|i| {
            let a = 0.1 * (i as f64).sin();
            [a, 0.05 * (i as f64).cos(), 1.0]
        })
        .collect();
    std::fs::write(
        dir.join("start.npy"),
        liemid_cli::shared::npy::matrix_bytes(256, 3, &start),
    )
    .unwrap();
    let scenario = write(
        &dir,
        "spins.toml",
        "[lattice]\nkind = \"square\"\nsize = [16, 16]\nperiodic = true\n\
         [hamiltonian]\nexchange = 1.0\nanisotropy = 0.1\nanisotropy_axis = [0.0, 0.0, 1.0]\nfield = [0.0, 0.0, 0.0]\nmu_s = 1.0\n\
         [dynamics]\ndamping = 0.0\nmethod = \"split\"\nstep = 1e-2\nt_end = 1.0\n\
         [initial]\nfile = \"start.npy\"\n",
    );
    let o = run_in(
        &dir,
        &[
            "spins",
            scenario.to_str().unwrap(),
            "--final",
            "final.npy",
            "--json",
            "-",
            "--out",
            "ts.csv",
            "--snapshot",
            "snap.png",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    assert_eq!(s["steps"], 100);
    assert_eq!(s["spins"], 256);
    for key in [
        "max_relative_energy_error",
        "max_norm_error",
        "sz_total_change",
        "spin_steps_per_second",
    ] {
        assert!(s[key].as_f64().is_some(), "{key} missing: {s}");
    }
    assert!(s["max_norm_error"].as_f64().unwrap() < 1e-14);
    assert!(s["sz_total_change"].as_f64().unwrap() < 1e-12);
    let last = liemid_cli::shared::npy::read_matrix(&dir.join("final.npy"), 3).unwrap();
    assert_eq!(last.len(), 256);
    assert!(last
        .iter()
        .all(|r| ((r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt() - 1.0).abs() < 1e-14));
    let text = std::fs::read_to_string(dir.join("ts.csv")).unwrap();
    assert_eq!(text.lines().next(), Some("t,energy,mx,my,mz"));
    assert_eq!(text.lines().count(), 1 + 1 + 100 / 10);
    assert!(std::fs::metadata(dir.join("snap.png")).unwrap().len() > 1000);
    // Every thread count gives the same final spins, byte for byte.
    let o = run_in(
        &dir,
        &[
            "spins",
            scenario.to_str().unwrap(),
            "--threads",
            "1",
            "--final",
            "one.npy",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(dir.join("one.npy")).unwrap(),
        std::fs::read(dir.join("final.npy")).unwrap()
    );
    // Methods as JSON.
    let o = run_in(&dir, &["methods", "--spins", "--json"]);
    let list = json(&stdout(&o));
    let names: Vec<&str> = list
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"split") && names.contains(&"midpoint") && names.contains(&"rk4"),
        "{names:?}"
    );
    assert!(list.as_array().unwrap().iter().all(|m| m["order"].as_u64().is_some()));
}

#[test]
fn spins_input_errors_name_the_key_and_exit_2() {
    let dir = scratch("spins-errors");
    for (text, expected) in [
        ("[lattice]\nkind = \"hex\"\nsize = [4, 4]\n", "[lattice] kind"),
        ("[lattice]\nkind = \"square\"\nsize = [4]\n", "two sizes"),
        (
            "[lattice]\nkind = \"square\"\nsize = [4, 4]\n[dynamics]\nmethod = \"leapfrog\"\n",
            "unknown spin method",
        ),
        (
            "[lattice]\nkind = \"square\"\nsize = [4, 4]\n[hamiltonian]\nmu_s = -1.0\n",
            "mu_s",
        ),
        (
            "[lattice]\nkind = \"square\"\nsize = [4, 4]\n[initial]\nfile = \"missing.npy\"\n",
            "[initial] file",
        ),
        (
            "[lattice]\nkind = \"square\"\nsize = [4, 4]\n[body]\ninertia = [1, 2, 3]\n",
            "liemid run",
        ),
    ] {
        let f = write(&dir, "bad.toml", text);
        let o = run_in(&dir, &["spins", f.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{text}: {}", stderr(&o));
        assert!(stderr(&o).contains(expected), "{text}: {}", stderr(&o));
        assert_eq!(stderr(&o).trim().lines().count(), 1, "{}", stderr(&o));
    }
    let o = run_in(&dir, &["spins", "--problem", "nope"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("square-64"));
    for (text, expected) in [
        (
            "[lattice]\nkind = \"square\"\nsize = [4, 4]\n[hamiltonian]\ndmi = 0.3\ndmi_kind = \"spiral\"\n",
            "[hamiltonian] dmi_kind",
        ),
        (
            "[lattice]\nkind = \"chain\"\nsize = [8]\n[initial]\nkind = \"skyrmion\"\n",
            "square lattice",
        ),
    ] {
        let f = write(&dir, "bad.toml", text);
        let o = run_in(&dir, &["spins", f.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{text}: {}", stderr(&o));
        assert!(stderr(&o).contains(expected), "{text}: {}", stderr(&o));
    }
}

#[test]
fn spins_runs_the_skyrmion_problem_and_a_dmi_scenario_keeping_the_charge() {
    let dir = scratch("spins-skyrmion");
    let o = run_in(
        &dir,
        &["spins", "--problem", "skyrmion", "--t-end", "0.5", "--json", "-"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    let q = s["topological_charge"].as_array().unwrap();
    assert!(q.iter().all(|q| (q.as_f64().unwrap() + 1.0).abs() < 1e-6), "{s}");
    assert_eq!(s["dmi"], true);
    // The same Hamiltonian from a scenario file, its own relaxed skyrmion, and the listing.
    let scenario = write(
        &dir,
        "sk.toml",
        "[lattice]\nkind = \"square\"\nsize = [32, 32]\nperiodic = true\n\
         [hamiltonian]\nexchange = 1.0\ndmi = 0.3\ndmi_kind = \"interfacial\"\nfield = [0.0, 0.0, 1.75]\n\
         [dynamics]\nstep = 1e-2\nt_end = 0.2\n[initial]\nkind = \"skyrmion\"\nradius = 6.0\n",
    );
    let o = run_in(&dir, &["spins", scenario.to_str().unwrap(), "--json", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    let q = s["topological_charge"].as_array().unwrap();
    assert!(q.iter().all(|q| (q.as_f64().unwrap() + 1.0).abs() < 1e-6), "{s}");
    let o = run_in(&dir, &["problems"]);
    assert!(stdout(&o).contains("skyrmion"));
}

#[test]
fn many_writes_an_extended_xyz_trajectory_and_the_radial_distribution() {
    let dir = scratch("many-xyz");
    let o = run_in(
        &dir,
        &[
            "many",
            "--model",
            "dipoles",
            "--bodies",
            "216",
            "--t-end",
            "0.05",
            "--trajectory",
            "fluid.xyz",
            "--trajectory-every",
            "10",
            "--rdf",
            "rdf",
            "--json",
            "-",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = json(&stdout(&o));
    assert_eq!(s["trajectory_frames"], 6);
    assert!(s["polar_order"].as_f64().unwrap() <= 1.0 && s["nematic_order"].as_f64().unwrap() <= 1.0);
    let text = std::fs::read_to_string(dir.join("fluid.xyz")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 6 * (2 + 216));
    assert_eq!(lines[0], "216");
    assert!(lines[1].starts_with("Lattice=\"") && lines[1].contains("Properties=species:S:1:pos:R:3:orientation:R:4"));
    assert!(lines[1].contains("pbc=\"T T T\""));
    // Every body line: a species and 16 numbers, the quaternion of unit length.
    for line in &lines[2..218] {
        let f: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(f.len(), 17);
        let q: Vec<f64> = f[4..8].iter().map(|x| x.parse().unwrap()).collect();
        assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-14);
    }
    assert!(!dir.join("fluid.xyz.partial").exists());
    let rdf_text = std::fs::read_to_string(dir.join("rdf.csv")).unwrap();
    assert_eq!(rdf_text.lines().next(), Some("r,g"));
    let rdf: Vec<Vec<f64>> = rdf_text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rdf.len(), 100);
    // No two WCA spheres come closer than about their diameter.
    assert!(rdf.iter().filter(|r| r[0] < 0.8).all(|r| r[1] == 0.0));
    assert!(std::fs::metadata(dir.join("rdf.png")).unwrap().len() > 1000);
    let o = run_in(
        &dir,
        &[
            "many", "--model", "dipoles", "--bodies", "30000", "--rdf", "big", "--t-end", "0.001",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--rdf"), "{}", stderr(&o));
}

#[test]
fn many_with_a_thermostat_is_the_same_on_any_thread_count() {
    let dir = scratch("many-langevin");
    let mut totals = Vec::new();
    for threads in ["1", "3"] {
        let file = format!("totals-{threads}.csv");
        let o = run_in(
            &dir,
            &[
                "many",
                "--model",
                "dipoles",
                "--bodies",
                "729",
                "--t-end",
                "0.04",
                "--temperature",
                "1.2",
                "--friction",
                "2",
                "--threads",
                threads,
                "--out",
                &file,
                "--json",
                "-",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let s = json(&stdout(&o));
        assert_eq!(s["thermostat"]["temperature"], 1.2);
        assert!(s["kinetic_temperature"].as_array().unwrap().len() == 2);
        totals.push(std::fs::read(dir.join(file)).unwrap());
    }
    assert_eq!(totals[0], totals[1]);
    let o = run_in(&dir, &["many", "--friction", "1"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn many_observes_at_every_multiple_of_either_interval_while_it_advances_in_blocks() {
    // `liemid many` takes its steps in blocks that end where something is observed: the
    // totals every 7 steps and the trajectory every 5 land on their steps, and the last
    // step is observed once by both, on 1 and 2 threads alike.
    let dir = scratch("many-blocks");
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let (totals, frames) = (format!("totals{threads}.csv"), format!("fluid{threads}.xyz"));
        let o = run_in(
            &dir,
            &[
                "many",
                "--model",
                "dipoles",
                "--bodies",
                "300",
                "--t-end",
                "0.05",
                "--every",
                "7",
                "--out",
                &totals,
                "--trajectory",
                &frames,
                "--trajectory-every",
                "5",
                "--threads",
                threads,
                "--json",
                "-",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let s = json(&stdout(&o));
        assert_eq!(s["steps"], 50);
        assert_eq!(s["trajectory_frames"], 11, "steps 0, 5, ..., 50");
        let rows = std::fs::read_to_string(dir.join(&totals)).unwrap();
        let t: Vec<f64> = rows
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().parse().unwrap())
            .collect();
        let expected: Vec<f64> = [0, 7, 14, 21, 28, 35, 42, 49, 50]
            .iter()
            .map(|&k| k as f64 * 1e-3)
            .collect();
        assert_eq!(t.len(), expected.len(), "{t:?}");
        for (a, b) in t.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-12, "{t:?}");
        }
        outputs.push((rows, std::fs::read_to_string(dir.join(&frames)).unwrap()));
    }
    assert!(outputs[0] == outputs[1], "1 and 2 threads wrote different files");
}

/// `--json` means the same in every subcommand: no value or `-` for standard output, FILE
/// for a file (the text summary then still printed); a scenario file given after it is
/// refused rather than replaced.
#[test]
fn json_takes_a_file_or_standard_output_in_every_subcommand() {
    let dir = scratch("json-flag");
    let o = run_in(&dir, &["run", "--t-end", "0.01", "--no-output", "--json", "run.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("steps"), "{}", stdout(&o));
    let summary = json(&std::fs::read_to_string(dir.join("run.json")).unwrap());
    assert_eq!(summary["steps"], 100);
    let o = run_in(&dir, &["run", "--t-end", "0.01", "--no-output", "--json", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(json(&stdout(&o))["steps"], 100);
    let o = run_in(&dir, &["spins", "--problem", "chain-64", "--t-end", "0.1", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(json(&stdout(&o)).get("method").is_some(), "{}", stdout(&o));
    let scenario = dir.join("top.toml");
    std::fs::copy(examples().join("fast_top.toml"), &scenario).unwrap();
    let before = std::fs::read(&scenario).unwrap();
    let o = run_in(&dir, &["run", "--json", "top.toml"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("looks like a scenario"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&scenario).unwrap(), before);
}
