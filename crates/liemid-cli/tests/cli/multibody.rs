//! End-to-end tests of `liemid multibody`: the JSON summary's keys and what they promise
//! (constraints at round-off, momenta kept on the free spacecraft), the joint-space
//! reference (RK4 and DOP853) against the maximal-coordinate composition, the example
//! models, the `--view` page, and refusals (exit 2, one line, nothing written).

use crate::common;
use common::{examples, json, run_in, scratch, stderr, stdout};
use std::path::Path;

fn summary(dir: &Path, args: &[&str]) -> serde_json::Value {
    let o = run_in(dir, &[&["multibody"], args, &["--json", "-"]].concat());
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    json(&stdout(&o))
}

fn xpos(s: &serde_json::Value) -> Vec<f64> {
    s["final"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|b| b["xpos"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()))
        .collect()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn summary_keys_and_constraints() {
    let dir = scratch("mb-summary");
    let s = summary(&dir, &["--problem", "double-pendulum", "--t-end", "1"]);
    for key in [
        "steps",
        "max_relative_energy_error",
        "max_position_constraint_violation",
        "max_velocity_constraint_violation",
        "max_momentum_change",
        "final",
        "joints",
    ] {
        assert!(s.get(key).is_some(), "no {key} in {s}");
    }
    assert_eq!(s["steps"], 1000);
    assert!(s["max_position_constraint_violation"].as_f64().unwrap() <= 1e-12);
    assert!(s["max_velocity_constraint_violation"].as_f64().unwrap() <= 1e-12);
    // Gravity and a joint to the world: the momenta are not conserved, so not reported.
    assert!(s["max_momentum_change"].is_null());
    let body = &s["final"][1];
    assert!(body["name"].is_string());
    let q: Vec<f64> = body["xquat"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-14);
    assert_eq!(s["joints"].as_array().unwrap().len(), 2);
    // Second order: the energy error falls 4x per halving of the step (bounded, not drifting).
    let coarse = summary(
        &dir,
        &["--problem", "double-pendulum", "--t-end", "1", "--step", "2e-3"],
    );
    let ratio =
        coarse["max_relative_energy_error"].as_f64().unwrap() / s["max_relative_energy_error"].as_f64().unwrap();
    assert!((3.5..4.5).contains(&ratio), "energy error ratio {ratio}");
}

#[test]
fn spacecraft_momenta_in_the_summary() {
    let dir = scratch("mb-spacecraft");
    let s = summary(&dir, &["--problem", "spacecraft", "--t-end", "1"]);
    let m = &s["max_momentum_change"];
    assert!(m.is_object(), "{s}");
    // The hub spins at 20 rad/s: |L| is of order 10^1-10^3 in the model's units; round-off
    // over 1000 steps stays below 1e-10 absolute.
    assert!(
        m["linear"].as_f64().unwrap() < 1e-10 && m["angular"].as_f64().unwrap() < 1e-10,
        "{m}"
    );
}

#[test]
fn joint_space_references_agree_with_the_composition() {
    let dir = scratch("mb-reference");
    let base = ["--problem", "test-chain", "--t-end", "0.5"];
    let dop = summary(&dir, &[&base[..], &["--method", "dop853", "--rtol", "1e-13"]].concat());
    let loose = summary(&dir, &[&base[..], &["--method", "dop853", "--rtol", "1e-10"]].concat());
    let l8 = summary(&dir, &[&base[..], &["--method", "liemid8", "--step", "1e-3"]].concat());
    let rk4 = summary(&dir, &[&base[..], &["--method", "rk4", "--step", "1e-4"]].concat());
    let (x, xl, x8, xr) = (xpos(&dop), xpos(&loose), xpos(&l8), xpos(&rk4));
    println!(
        "dop853 1e-10 vs 1e-13: {:.2e}; liemid8 h=1e-3: {:.2e}; rk4 h=1e-4: {:.2e}; dop853 steps {}",
        max_diff(&xl, &x),
        max_diff(&x8, &x),
        max_diff(&xr, &x),
        dop["steps"]
    );
    // Two independent formulations (maximal coordinates with constraints, joint coordinates
    // with the articulated-body algorithm) meet at the reference's accuracy.
    assert!(max_diff(&x8, &x) < 1e-10);
    assert!(max_diff(&xr, &x) < 1e-9);
    assert!(max_diff(&xl, &x) < 1e-8);
    assert!(dop["max_relative_energy_error"].as_f64().unwrap() < 1e-11);
    assert!(dop["evaluations"].as_u64().unwrap() > 12 * dop["steps"].as_u64().unwrap());
}

#[test]
fn example_models_load_and_name_what_they_ignore() {
    let dir = scratch("mb-examples");
    for file in [
        "double_pendulum.xml",
        "double_pendulum.urdf",
        "chain_10.xml",
        "arm.xml",
        "arm_scene.xml",
        "four_bar.xml",
        "arm.urdf",
    ] {
        let path = examples().join("multibody").join(file);
        let o = run_in(
            &dir,
            &["multibody", path.to_str().unwrap(), "--t-end", "0.05", "--json", "-"],
        );
        assert!(o.status.success(), "{file}: {}", stderr(&o));
        let s = json(&stdout(&o));
        assert!(
            s["max_position_constraint_violation"].as_f64().unwrap() < 1e-12,
            "{file}"
        );
        if file.starts_with("arm") && file.ends_with(".xml") {
            // Written as a published robot model is: its actuators are simulated (not among
            // what is ignored), its sensor is named.
            let err = stderr(&o);
            assert!(err.contains("ignored") && err.contains("sensor"), "{err}");
            let ignored = err.split("ignored:").nth(1).unwrap_or_default();
            assert!(!ignored.contains("actuator"), "{err}");
        }
    }
}

#[test]
fn view_page() {
    let dir = scratch("mb-view");
    let o = run_in(
        &dir,
        &[
            "multibody",
            "--problem",
            "closed-loop",
            "--t-end",
            "0.5",
            "--view",
            "m.html",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("view: m.html (51 frames of 500 steps)"),
        "{}",
        stdout(&o)
    );
    let html = std::fs::read_to_string(dir.join("m.html")).unwrap();
    assert!(html.contains("\"articulated\"") && html.contains("51 frames of 500 steps"));
    // A wrong page path is refused before the run, like every output.
    std::fs::create_dir_all(dir.join("a-dir")).unwrap();
    let model = examples().join("multibody").join("double_pendulum.xml");
    let model = model.to_str().unwrap();
    for wrong in ["a-dir", "/dev/null", model] {
        let o = run_in(&dir, &["multibody", model, "--view", wrong]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "--view {wrong}: {err}");
        assert!(err.contains("--view") && err.trim().lines().count() == 1, "{err}");
    }
}

#[test]
fn refusals_write_nothing() {
    let dir = scratch("mb-refusals");
    let bad_mass = r#"<mujoco><worldbody><body name="a"><joint type="hinge" axis="0 1 0"/>
<inertial pos="0 0 0" mass="-1" diaginertia="1 1 1"/></body></worldbody></mujoco>"#;
    std::fs::write(dir.join("bad.xml"), bad_mass).unwrap();
    let cycle = r#"<robot name="r"><link name="a"/><link name="b"/>
<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
<joint name="j2" type="revolute"><parent link="b"/><child link="a"/><axis xyz="0 0 1"/></joint></robot>"#;
    std::fs::write(dir.join("cycle.urdf"), cycle).unwrap();
    for (file, words) in [("bad.xml", ["mass", "bad.xml:2"]), ("cycle.urdf", ["cycle", "a"])] {
        let o = run_in(&dir, &["multibody", file, "--out", "t.csv", "--json", "s.json"]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{file}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        for w in words {
            assert!(err.contains(w), "{file}: no {w} in {err}");
        }
        assert!(!dir.join("t.csv").exists() && !dir.join("s.json").exists());
    }
    for args in [
        &["--problem", "chain-10", "--rtol", "1e-9"][..],
        &["--problem", "chain-10", "--method", "dop853", "--rtol", "2"],
        &["--problem", "nope"],
        &["--problem", "chain-10", "--method", "euler"],
    ] {
        let o = run_in(&dir, &[&["multibody"], args].concat());
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    let o = run_in(&dir, &["problems"]);
    assert!(stdout(&o).contains("chain-1000") && stdout(&o).contains("spacecraft"));
}

#[test]
fn a_stiff_damper_runs_and_a_composition_against_it_names_the_step() {
    // The shoulder's child turns with I = 1e-4 + 0.1 * 0.1^2 = 1.1e-3 kg m^2 about the
    // axis; damping 20 gives x = h d / (2 I) = 1 at h = 2 I / d = 1.1e-4 s. (No armature:
    // an armature of 0.1, now kept exactly, would make I = 0.1011 and the damper mild.)
    let dir = scratch("mb-damper");
    let model = r#"<mujoco model="damped">
  <worldbody>
    <body name="arm">
      <joint name="shoulder" axis="0 1 0" damping="20"/>
      <inertial pos="0.1 0 0" mass="0.1" diaginertia="1e-4 1e-4 1e-4"/>
      <body name="tip" pos="0.2 0 0">
        <joint name="wrist" axis="0 1 0" damping="0.001"/>
        <inertial pos="0.05 0 0" mass="0.01" diaginertia="1e-6 1e-6 1e-6"/>
      </body>
    </body>
  </worldbody>
  <keyframe><key qpos="0.3 0.1"/></keyframe>
</mujoco>"#;
    std::fs::write(dir.join("damped.xml"), model).unwrap();
    // The implicit end half-kick holds liemid at x = 9 and 90.
    let coarse = summary(&dir, &["damped.xml", "--step", "1e-2", "--t-end", "1"]);
    let fine = summary(&dir, &["damped.xml", "--step", "1e-4", "--t-end", "1"]);
    assert!(coarse["max_position_constraint_violation"].as_f64().unwrap() < 1e-12);
    assert!(max_diff(&xpos(&coarse), &xpos(&fine)) < 1e-2);
    // liemid4's negative sub-step at x > 1 cannot: refused before the first step (exit 2,
    // nothing written), one line naming the joint and the largest step that holds it (the
    // row's own constrained response: 1.69e-4, above the pessimistic 2 I / d = 1.1e-4).
    let o = run_in(
        &dir,
        &[
            "multibody",
            "damped.xml",
            "--method",
            "liemid4",
            "--step",
            "1e-3",
            "--t-end",
            "1",
            "--json",
            "s.json",
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let error: Vec<&str> = err.lines().filter(|l| l.starts_with("liemid: error")).collect();
    assert_eq!(error.len(), 1, "{err}");
    assert!(
        error[0].contains("joint `shoulder`") && error[0].contains("damping 20") && error[0].contains("1.690e-4"),
        "{err}"
    );
    assert!(!dir.join("s.json").exists());
    summary(
        &dir,
        &["damped.xml", "--method", "liemid4", "--step", "1e-4", "--t-end", "1"],
    );
    // With an armature of 0.1 on the shoulder (kept exactly by the liemid methods, as by
    // joint-space RK4), I = 0.1011 and the same damper holds at h = 1e-3 in every method.
    std::fs::write(
        dir.join("armature.xml"),
        model.replace(r#"damping="20"/>"#, r#"damping="20" armature="0.1"/>"#),
    )
    .unwrap();
    for method in ["liemid4", "rk4"] {
        summary(
            &dir,
            &["armature.xml", "--step", "1e-3", "--t-end", "1", "--method", method],
        );
    }
}

#[test]
fn the_joint_space_methods_say_they_drop_joint_limits() {
    let dir = scratch("mb-limits");
    let arm = examples().join("multibody").join("arm.xml");
    let arm = arm.to_str().unwrap();
    for (method, said) in [("rk4", true), ("dop853", true), ("liemid", false)] {
        let o = run_in(
            &dir,
            &["multibody", arm, "--method", method, "--t-end", "0.01", "--json", "-"],
        );
        assert!(o.status.success(), "{method}: {}", stderr(&o));
        assert_eq!(stderr(&o).contains("joint limits"), said, "{method}: {}", stderr(&o));
    }
}

#[test]
fn the_variational_drift_is_a_choice_of_the_liemid_methods() {
    let dir = scratch("mb-drift");
    let midpoint = summary(&dir, &["--problem", "chain-10", "--t-end", "0.1"]);
    let variational = summary(
        &dir,
        &["--problem", "chain-10", "--t-end", "0.1", "--drift", "variational"],
    );
    assert_eq!(midpoint["drift"], "midpoint");
    assert_eq!(variational["drift"], "variational");
    // Both second order: at h = 1e-3 the two runs agree to the size of their errors, not to
    // round-off, and both keep the constraints.
    let d = max_diff(&xpos(&midpoint), &xpos(&variational));
    assert!(d > 1e-12 && d < 1e-4, "the drifts differ by {d:e}");
    assert!(variational["max_position_constraint_violation"].as_f64().unwrap() < 1e-12);
    for (args, said) in [
        (&["multibody", "--drift", "cayley"][..], "--drift: unknown drift"),
        (
            &["multibody", "--method", "rk4", "--drift", "variational"][..],
            "--drift chooses",
        ),
    ] {
        let o = run_in(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(said), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn no_output_replaces_a_file_the_model_includes() {
    // `arm_scene.xml` includes `arm.xml`: --out or --view onto either is refused, and both
    // files are left as they were.
    let dir = scratch("mb-include-out");
    for name in ["arm_scene.xml", "arm.xml"] {
        std::fs::copy(examples().join("multibody").join(name), dir.join(name)).unwrap();
    }
    for flag in ["--out", "--view"] {
        for target in ["arm.xml", "arm_scene.xml"] {
            let before = std::fs::read(dir.join(target)).unwrap();
            let o = run_in(&dir, &["multibody", "arm_scene.xml", "--t-end", "0.01", flag, target]);
            assert_eq!(o.status.code(), Some(2), "{flag} {target}: {}", stderr(&o));
            assert!(stderr(&o).contains("is the input"), "{flag} {target}: {}", stderr(&o));
            assert_eq!(
                std::fs::read(dir.join(target)).unwrap(),
                before,
                "{flag} {target} changed"
            );
        }
    }
}

#[test]
fn a_start_of_infinite_energy_is_refused_and_a_run_beyond_the_step_bound_too() {
    let dir = scratch("mb-bounds");
    let fast = r#"<mujoco model="fast"><option gravity="0 0 0"/><worldbody>
<body name="b"><freejoint/><inertial pos="0 0 0" mass="1" diaginertia="1 2 2.5"/></body>
</worldbody><keyframe><key qpos="0 0 0 1 0 0 0" qvel="1e308 0 0 0 0 0"/></keyframe></mujoco>"#;
    std::fs::write(dir.join("fast.xml"), fast).unwrap();
    let o = run_in(&dir, &["multibody", "fast.xml", "--t-end", "0.01", "--out", "fast.npy"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("energy is inf"), "{}", stderr(&o));
    assert!(!dir.join("fast.npy").exists() && !dir.join("fast.npy.partial").exists());
    // --t-end 1e9 at the default step: 1e12 steps, refused before the first.
    let o = run_in(&dir, &["multibody", "--t-end", "1e9", "--out", "long.npy"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("more than the default bound"), "{}", stderr(&o));
    assert!(!dir.join("long.npy.partial").exists());
    // A zero keyframe quaternion is refused before any output file exists.
    let zero = fast.replace(
        r#"qpos="0 0 0 1 0 0 0" qvel="1e308 0 0 0 0 0""#,
        r#"qpos="0 0 0 0 0 0 0""#,
    );
    std::fs::write(dir.join("zero.xml"), zero).unwrap();
    let o = run_in(&dir, &["multibody", "zero.xml", "--out", "zero.npy"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!dir.join("zero.npy").exists() && !dir.join("zero.npy.partial").exists());
}

#[test]
fn the_dop853_summary_gives_its_tolerance_not_a_step() {
    // It used to print "of h = NaN": DOP853 has no fixed step.
    let dir = scratch("mb-dop853-summary");
    let o = run_in(&dir, &["multibody", "--method", "dop853", "--t-end", "0.1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(!out.contains("NaN"), "{out}");
    assert!(out.contains("accepted") && out.contains("at rtol 1e-12"), "{out}");
}
