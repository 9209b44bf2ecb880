//! Symplecticity of the multibody step, measured: the smallest model that decides it, one
//! free body (a `freejoint`, no gravity, no rows), stepped by RATTLE with EA's rotation and
//! its compositions, as a map of `(c, p, R, Π)`; its defect in the canonical symplectic form
//! of `T*(ℝ³ × SO(3))` (`tests/common/cotangent.rs`) at two steps. With no constraint the
//! step is EA's torque-free pair of midpoint half steps and a free translation, so it keeps
//! the form only as well as EA's drift does: the defect falls as `h^(p+1)`, a measured
//! counterexample to symplecticity for every model (a method is symplectic only if it is so
//! on every model).

use crate::cotangent::{defect, Body};
use liemid::multibody::{mjcf, Drift, Model, MultibodyMethod, MultibodyState, Simulation};
use liemid::{so3, Vec3};

fn free_body() -> (Model, [Body; 1]) {
    let text = r#"<mujoco model="free"><option gravity="0 0 0"/><worldbody>
        <body name="b"><freejoint/><inertial pos="0 0 0" mass="2" diaginertia="1 2 2.5"/></body>
        </worldbody></mujoco>"#;
    let model = mjcf::parse(text, "free.xml").unwrap().model;
    let start = [Body {
        x: Vec3::new(0.1, -0.2, 0.3),
        p: Vec3::new(0.4, 0.1, -0.2),
        r: so3::exp(Vec3::new(0.3, -0.2, 0.5)),
        pi: Vec3::new(0.9, -1.1, 1.3) * (2.0 / Vec3::new(0.9, -1.1, 1.3).norm()),
    }];
    (model, start)
}

/// The defects at `h0` and `h0/2` of `method` with `drift` on the free body.
fn defects(model: &Model, start: &[Body], method: MultibodyMethod, drift: Drift, h0: f64) -> Vec<f64> {
    [h0, h0 / 2.0]
        .iter()
        .map(|&h| {
            let map = |s: &[Body]| -> Vec<Body> {
                let mut sim = Simulation::new(model, method).unwrap();
                sim.integrator.set_drift(drift);
                let mut state = MultibodyState {
                    t: 0.0,
                    c: vec![s[0].x],
                    p: vec![s[0].p],
                    rotation: vec![s[0].r],
                    pi: vec![s[0].pi],
                };
                sim.step(&mut state, h).unwrap();
                vec![Body {
                    x: state.c[0],
                    p: state.p[0],
                    r: state.rotation[0],
                    pi: state.pi[0],
                }]
            };
            defect(&map, start, true)
        })
        .collect()
}

#[test]
fn with_the_variational_drift_the_step_keeps_the_symplectic_form() {
    let (model, start) = free_body();
    for method in MultibodyMethod::ALL {
        let h0 = [0.2, 0.4, 0.8, 1.2][method.order() as usize / 2 - 1];
        let d = defects(&model, &start, method, Drift::Variational, h0);
        println!("{} variational drift: defects {:.2e}, {:.2e}", method.key(), d[0], d[1]);
        // The differences resolve about 1e-11 here (liemid8's, at h = 1.2: 9.5e-12).
        assert!(d.iter().all(|&x| x < 2e-11), "{}: defect {d:?}", method.key());
    }
}

#[test]
fn rattle_with_eas_rotation_is_not_symplectic_on_a_free_body() {
    let (model, start) = free_body();
    println!("method      h0    defect h0   defect h0/2  order");
    for method in MultibodyMethod::ALL {
        let h0 = match method.order() {
            0..=2 => 0.2,
            3..=4 => 0.4,
            5..=6 => 0.8,
            _ => 1.2,
        };
        let d = defects(&model, &start, method, Drift::Midpoint, h0);
        let order = (d[0] / d[1]).log2();
        println!(
            "{:<11} {h0:<5} {:<11.2e} {:<12.2e} {order:.2}",
            method.key(),
            d[0],
            d[1]
        );
        assert!(d[0] > 1e-9, "{}: defect {d:?} is at the resolution", method.key());
        assert!(
            (order - f64::from(method.order() + 1)).abs() < 0.6,
            "{}: the defect falls at order {order}",
            method.key()
        );
    }
}
