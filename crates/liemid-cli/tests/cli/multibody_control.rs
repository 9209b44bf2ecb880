//! `liemid multibody --ctrl` and `--ctrl-file`: a constant control and a table held
//! piecewise constant drive a wheel's motor to the closed form, the liemid methods and
//! RK4 alike; bad controls are refused (exit 2, one line naming what is wrong).

use crate::common;
use common::{json, run_in, scratch, stderr, stdout};
use std::path::Path;

/// A wheel (I_zz = 0.2) on a hinge about z, no gravity, a motor of gear 2 with
/// ctrlrange ±3 and a position servo with kp 0 (a second actuator to name).
const WHEEL: &str = "<mujoco><option gravity=\"0 0 0\" timestep=\"0.001\"/><worldbody><body name=\"wheel\">\
     <joint name=\"axle\" axis=\"0 0 1\"/><inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.5 0.5 0.2\"/>\
     </body></worldbody><actuator><motor name=\"drive\" joint=\"axle\" gear=\"2\" ctrlrange=\"-3 3\"/>\
     <position name=\"servo\" joint=\"axle\" kp=\"0\"/></actuator></mujoco>";

fn angle(dir: &Path, args: &[&str]) -> f64 {
    let o = run_in(
        dir,
        &[&["multibody", "wheel.xml", "--t-end", "0.1"], args, &["--json", "-"]].concat(),
    );
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    json(&stdout(&o))["joints"][0]["value"].as_f64().unwrap()
}

#[test]
fn a_constant_control_and_a_held_table_drive_the_motor() {
    let dir = scratch("mb-ctrl");
    std::fs::write(dir.join("wheel.xml"), WHEEL).unwrap();
    // τ = gear · clamp(u) = 2 · 1.5 on I = 0.2: q(0.1) = ½ (3/0.2) 0.1².
    let expected = 0.5 * 3.0 / 0.2 * 0.01;
    for method in ["liemid", "liemid4", "rk4"] {
        let q = angle(&dir, &["--ctrl", "1.5,0", "--method", method]);
        assert!((q - expected).abs() < 1e-12, "{method}: {q} vs {expected}");
        // Clamped to the ctrlrange: u = 10 acts as 3.
        let q = angle(&dir, &["--ctrl", "10,0", "--method", method]);
        assert!((q - 2.0 * expected).abs() < 1e-12, "{method} clamped: {q}");
    }
    // The table, columns in any order, held: u = 1 for t < 0.05, then u = −1; the wheel
    // speeds up for 0.05 s and slows again: q(0.1) = a · 0.05², a = 2/0.2.
    std::fs::write(dir.join("u.csv"), "t,servo,drive\n0,0,1\n0.05,0,-1\n").unwrap();
    let expected = 10.0 * 0.05 * 0.05;
    for method in ["liemid", "rk4"] {
        let q = angle(&dir, &["--ctrl-file", "u.csv", "--method", method]);
        assert!((q - expected).abs() < 1e-12, "{method}: {q} vs {expected}");
    }
}

#[test]
fn bad_controls_are_refused() {
    let dir = scratch("mb-ctrl-bad");
    std::fs::write(dir.join("wheel.xml"), WHEEL).unwrap();
    std::fs::write(dir.join("cols.csv"), "t,drive,brake\n0,1,0\n").unwrap();
    std::fs::write(dir.join("nan.csv"), "t,drive,servo\n0,1,nan\n").unwrap();
    std::fs::write(dir.join("back.csv"), "t,drive,servo\n0,1,0\n0,2,0\n").unwrap();
    for (args, says) in [
        (&["--ctrl", "1"][..], "ctrl has 1 entries, the model has 2 actuators"),
        (&["--ctrl", "1,nan"][..], "actuator `servo`"),
        (&["--ctrl", "1,x"][..], "value 1 `x` is not a number"),
        (&["--ctrl-file", "cols.csv"][..], "column `brake` names no actuator"),
        (&["--ctrl-file", "nan.csv"][..], "not a finite number"),
        (&["--ctrl-file", "back.csv"][..], "does not increase"),
        (&["--ctrl-file", "u.csv", "--method", "dop853"][..], "dop853"),
    ] {
        let o = run_in(&dir, &[&["multibody", "wheel.xml", "--t-end", "0.01"], args].concat());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}
