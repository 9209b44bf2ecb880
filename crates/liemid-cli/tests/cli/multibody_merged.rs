//! `liemid multibody` on the humanoid example (several hinges per body, merged into
//! universal and ball joints): it loads and runs, its constraints stay at round-off, the
//! maximal-coordinate step converges at order 2 to the joint-space reference (DOP853),
//! the motors are listed as not simulated; and a body whose joints cannot be merged is
//! refused with exit 2 in one line naming the body and its joints.

use crate::common;
use common::{examples, json, run_in, scratch, stderr, stdout};

fn xpos(s: &serde_json::Value) -> Vec<f64> {
    s["final"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|b| b["xpos"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()))
        .collect()
}

#[test]
fn humanoid_runs_and_converges_to_the_joint_space_reference() {
    let dir = scratch("mb-humanoid");
    let file = examples().join("multibody/humanoid.xml");
    let file = file.to_str().unwrap();
    let run = |extra: &[&str]| {
        let o = run_in(
            &dir,
            &[&["multibody", file, "--t-end", "0.1", "--json", "-"], extra].concat(),
        );
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        json(&stdout(&o))
    };
    let reference = xpos(&run(&["--method", "dop853", "--rtol", "1e-12"]));
    let mut errors = Vec::new();
    for h in ["1e-3", "5e-4"] {
        let s = run(&["--step", h]);
        assert_eq!(s["final"].as_array().unwrap().len(), 16);
        assert!(s["max_position_constraint_violation"].as_f64().unwrap() <= 1e-12, "{s}");
        assert!(s["max_velocity_constraint_violation"].as_f64().unwrap() <= 1e-12, "{s}");
        let ignored: Vec<&str> = s["ignored"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        // Motors on merged hinges have no coordinate of their own: named, not simulated.
        assert!(
            ignored.contains(&"actuators on merged hinges (not simulated)"),
            "{ignored:?}"
        );
        let x = xpos(&s);
        errors.push(x.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max));
    }
    // Measured: 5.0e-7 and 1.24e-7 m (ratio 4.0, second order).
    let ratio = errors[0] / errors[1];
    assert!(errors[0] < 1e-6 && (3.6..4.4).contains(&ratio), "{errors:?}");
}

#[test]
fn unmergeable_joints_are_refused_in_one_line() {
    let dir = scratch("mb-unmergeable");
    let text = r#"<mujoco><worldbody><body name="carriage">
<joint name="spin" axis="0 0 1"/><joint name="travel" type="slide" axis="0 0 1"/>
<geom size="0.1"/></body></worldbody></mujoco>"#;
    std::fs::write(dir.join("cyl.xml"), text).unwrap();
    let o = run_in(&dir, &["multibody", "cyl.xml", "--out", "t.csv"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    for w in ["cyl.xml:1", "body `carriage`", "`spin` (hinge)", "`travel` (slide)"] {
        assert!(err.contains(w), "no {w} in {err}");
    }
    assert!(!dir.join("t.csv").exists());
}
