//! Symplecticity of the multibody step, measured: the smallest model that decides it, one
//! free body (a `freejoint`, no gravity, no rows), stepped by RATTLE with EA's rotation and
//! its compositions, as a map of `(c, p, R, Π)`; its defect in the canonical symplectic form
//! of `T*(ℝ³ × SO(3))` (`tests/common/cotangent.rs`) at two steps. With no constraint the
//! step is EA's torque-free pair of midpoint half steps and a free translation, so it keeps
//! the form only as well as EA's drift does: the defect falls as `h^(p+1)`, a measured
//! counterexample to symplecticity for every model (a method is symplectic only if it is so
//! on every model).
//!
//! The joint-space reference `rk4` is measured on the double pendulum in its canonical
//! coordinates `(q, p = M(q) q̇)`: `Jᵀ Ω J = Ω` for the Jacobian `J` of one step (DOP853 at a
//! tolerance is measured the same way in the command's tests, `dop853_structure.rs`, where
//! its configuration lives).

use crate::cotangent::{defect, Body};
use liemid::multibody::{mjcf, problems, Drift, JointSpaceModel, Model, MultibodyMethod, MultibodyState, Simulation};
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

/// One step of `h` of the joint-space RK4 on the double pendulum in canonical coordinates:
/// `(q, p) ↦ (q, q̇ = M(q)⁻¹ p) ↦ RK4 ↦ (q⁺, M(q⁺) q̇⁺)`.
fn rk4_canonical(model: &mut JointSpaceModel, y: [f64; 4], h: f64) -> [f64; 4] {
    let mut m = [0.0; 4];
    let (mut q, p) = ([y[0], y[1]], [y[2], y[3]]);
    model.mass_matrix(&q, &mut m).unwrap();
    let det = m[0] * m[3] - m[1] * m[2];
    let mut v = [(m[3] * p[0] - m[1] * p[1]) / det, (m[0] * p[1] - m[2] * p[0]) / det];
    model.rk4_step(&mut q, &mut v, h).unwrap();
    model.mass_matrix(&q, &mut m).unwrap();
    [q[0], q[1], m[0] * v[0] + m[1] * v[1], m[2] * v[0] + m[3] * v[1]]
}

/// `max |Jᵀ Ω J − Ω|` (`Ω` the canonical form of `T*ℝ²`, entries of size 1) of `map` at
/// `y`, `J` by central differences at `2e` and `e = 10⁻⁴`, extrapolated (resolution about
/// 1e-11 here).
fn canonical_defect(map: &mut dyn FnMut([f64; 4]) -> [f64; 4], y: [f64; 4]) -> f64 {
    let mut j = [[0.0; 4]; 4];
    for k in 0..4 {
        let mut central = |e: f64| {
            let (mut plus, mut minus) = (y, y);
            plus[k] += e;
            minus[k] -= e;
            let (a, b) = (map(plus), map(minus));
            std::array::from_fn::<f64, 4, _>(|i| (a[i] - b[i]) / (2.0 * e))
        };
        let (coarse, fine) = (central(2e-4), central(1e-4));
        for i in 0..4 {
            j[i][k] = (4.0 * fine[i] - coarse[i]) / 3.0;
        }
    }
    // ω(u, v) = u_q · v_p − v_q · u_p.
    let omega = |a: usize, b: usize, f: &dyn Fn(usize, usize) -> f64| {
        (0..2)
            .map(|i| f(i, a) * f(i + 2, b) - f(i, b) * f(i + 2, a))
            .sum::<f64>()
    };
    let (image, identity) = (
        |i: usize, k: usize| j[i][k],
        |i: usize, k: usize| f64::from(u8::from(i == k)),
    );
    let mut worst: f64 = 0.0;
    for a in 0..4 {
        for b in 0..4 {
            worst = worst.max((omega(a, b, &image) - omega(a, b, &identity)).abs());
        }
    }
    worst
}

#[test]
fn the_joint_space_rk4_is_not_symplectic_measured() {
    let mut model = JointSpaceModel::new(&problems::double_pendulum()).unwrap();
    // The model's start (1.0, 0.5) rad, moving: q̇ = (0.3, −0.7) rad/s.
    let (q, v) = ([1.0, 0.5], [0.3, -0.7]);
    let mut m = [0.0; 4];
    model.mass_matrix(&q, &mut m).unwrap();
    let y = [q[0], q[1], m[0] * v[0] + m[1] * v[1], m[2] * v[0] + m[3] * v[1]];
    // The pendulum's fastest normal mode near 6 rad/s: h = 0.04 turns it by 0.24 rad.
    let d = [0.04, 0.02, 0.01].map(|h| canonical_defect(&mut |y| rk4_canonical(&mut model, y, h), y));
    let orders = [(d[0] / d[1]).log2(), (d[1] / d[2]).log2()];
    println!(
        "rk4 (joint space): defect {:.2e}, {:.2e}, {:.2e} at h = 0.04, 0.02, 0.01; orders {:.2}, {:.2}",
        d[0], d[1], d[2], orders[0], orders[1]
    );
    // Not symplectic: the defect of a fourth-order method falls as h⁵, far above the
    // resolution.
    assert!(d[2] > 1e-9, "rk4: defect {d:?} at the resolution");
    assert!(
        (orders[1] - 5.0).abs() < 0.3,
        "rk4: the defect falls at order {orders:?}"
    );
}
