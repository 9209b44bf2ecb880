//! The structure of the joint-space reference `liemid multibody --method dop853`, measured:
//! DOP853 with the command's configuration (`liemid_app::dop853!`) over `t = 1` on the
//! double pendulum, as a map of its canonical coordinates `(q, p = M(q) q̇)`; the defect
//! `max |Jᵀ Ω J − Ω|` of its Jacobian at three tolerances. DOP853 is not a symplectic
//! method: its defect is its local error's, about the tolerance, not the rounding
//! (`crates/liemid/tests/multibody/symplectic.rs` measures the fixed-step RK4 the same way).

use std::cell::RefCell;

use liemid::multibody::{problems, JointSpaceModel};
use liemid_app::dop853;
use ode_solvers::{DVector, System};

/// `y' = [q̇; ABA(q, q̇)]` of the model.
struct Rhs<'a>(&'a RefCell<JointSpaceModel>);

impl System<f64, DVector<f64>> for Rhs<'_> {
    fn system(&self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) {
        self.0
            .borrow_mut()
            .derivative(t, y.as_slice(), dy.as_mut_slice())
            .unwrap();
    }
}

/// `(q, p) ↦ (q, q̇ = M(q)⁻¹ p) ↦` DOP853 over `t_end` at `rtol` `↦ (q⁺, M(q⁺) q̇⁺)`.
fn flow(model: &RefCell<JointSpaceModel>, y: [f64; 4], t_end: f64, rtol: f64) -> [f64; 4] {
    let mass = |q: &[f64]| {
        let mut m = [0.0; 4];
        model.borrow_mut().mass_matrix(q, &mut m).unwrap();
        m
    };
    let m = mass(&y[..2]);
    let det = m[0] * m[3] - m[1] * m[2];
    let qdot = [(m[3] * y[2] - m[1] * y[3]) / det, (m[0] * y[3] - m[2] * y[2]) / det];
    let start = DVector::from_vec(vec![y[0], y[1], qdot[0], qdot[1]]);
    let mut solver = dop853!(Rhs(model), 0.0, t_end, t_end, start, rtol);
    solver.integrate().unwrap();
    let end = solver.y_out().last().unwrap().clone();
    let m = mass(&end.as_slice()[..2]);
    [
        end[0],
        end[1],
        m[0] * end[2] + m[1] * end[3],
        m[2] * end[2] + m[3] * end[3],
    ]
}

/// `max |Jᵀ Ω J − Ω|` (`Ω` the canonical form of `T*ℝ²`, entries of size 1) of `map` at
/// `y`, `J` by central differences at `2e` and `e`, extrapolated.
fn canonical_defect(map: &dyn Fn([f64; 4]) -> [f64; 4], y: [f64; 4], e: f64) -> f64 {
    let mut j = [[0.0; 4]; 4];
    for k in 0..4 {
        let central = |e: f64| {
            let (mut plus, mut minus) = (y, y);
            plus[k] += e;
            minus[k] -= e;
            let (a, b) = (map(plus), map(minus));
            std::array::from_fn::<f64, 4, _>(|i| (a[i] - b[i]) / (2.0 * e))
        };
        let (coarse, fine) = (central(2.0 * e), central(e));
        for i in 0..4 {
            j[i][k] = (4.0 * fine[i] - coarse[i]) / 3.0;
        }
    }
    // ω(u, v) = u_q · v_p − v_q · u_p, of the images and of the basis.
    let omega = |a: usize, b: usize, f: &dyn Fn(usize, usize) -> f64| {
        (0..2)
            .map(|i| f(i, a) * f(i + 2, b) - f(i, b) * f(i + 2, a))
            .sum::<f64>()
    };
    let image = |i: usize, k: usize| j[i][k];
    let basis = |i: usize, k: usize| f64::from(u8::from(i == k));
    let mut worst: f64 = 0.0;
    for a in 0..4 {
        for b in 0..4 {
            worst = worst.max((omega(a, b, &image) - omega(a, b, &basis)).abs());
        }
    }
    worst
}

#[test]
fn dop853_in_joint_coordinates_is_not_symplectic_measured() {
    let model = RefCell::new(JointSpaceModel::new(&problems::double_pendulum()).unwrap());
    // The model's start (1.0, 0.5) rad, moving: q̇ = (0.3, −0.7) rad/s.
    let (q, v) = ([1.0, 0.5], [0.3, -0.7]);
    let mut m = [0.0; 4];
    model.borrow_mut().mass_matrix(&q, &mut m).unwrap();
    let y = [q[0], q[1], m[0] * v[0] + m[1] * v[1], m[2] * v[0] + m[3] * v[1]];
    let t_end = 1.0;
    println!("dop853 over t = {t_end}: rtol, defect with e = 1e-4, with e = 1e-5");
    let mut defects = Vec::new();
    for rtol in [1e-6, 1e-9, 1e-12] {
        // Two difference steps: the adaptive step sequence moves with the state, so a
        // defect that did not depend on the step would not be the differences' artefact.
        let d = [1e-4, 1e-5].map(|e| canonical_defect(&|y| flow(&model, y, t_end, rtol), y, e));
        println!("{rtol:e}  {:.2e}  {:.2e}", d[0], d[1]);
        defects.push(d);
    }
    // At rtol 1e-6 the defect is far above the differences' resolution (about 1e-11 with
    // e = 1e-4 and 1e-10 with 1e-5, u/e) and the same with either step: not symplectic.
    let loose = defects[0];
    assert!(loose[0] > 1e-8, "dop853 at rtol 1e-6: defect {loose:?}");
    assert!(
        (loose[0] / loose[1] - 1.0).abs() < 0.1,
        "dop853 at rtol 1e-6: {loose:?}"
    );
    // Tighter tolerances, smaller defects.
    assert!(defects[1][0] < 0.1 * loose[0], "{defects:?}");
}
