//! Helpers shared by the integration tests: error norms, observed orders, references and a
//! torque-counting wrapper.
#![allow(dead_code)]

use liemid::{integrate_to, Mat3, RigidBodySystem, RigidState, RotationIntegrator, RungeKutta4Quaternion, Vec3};

/// Least-squares slope of `log(err)` against `log(h)` (the library's `observed_order`).
pub fn observed_order(hs: &[f64], errs: &[f64]) -> f64 {
    liemid::observed_order(hs, errs).expect("at least two distinct steps")
}

/// `h0, h0/2, …` (`n` steps).
pub fn halvings(h0: f64, n: usize) -> Vec<f64> {
    (0..n).map(|k| h0 / f64::from(1u32 << k)).collect()
}

/// Momentum error `|Π − Π_ref| / |Π_ref|` and attitude error `‖R − R_ref‖_F`.
pub fn errors(state: &RigidState, reference: &RigidState) -> (f64, f64) {
    (
        (state.pi - reference.pi).norm() / reference.pi.norm(),
        (state.rotation - reference.rotation).norm_frobenius(),
    )
}

/// A reference solution: RK4 on quaternions at the small step `h`.
pub fn reference<S: RigidBodySystem>(system: &S, initial: RigidState, t_end: f64, h: f64) -> RigidState {
    integrate_to(&mut RungeKutta4Quaternion::new(), system, initial, t_end, h)
        .unwrap()
        .state
}

/// The end state of `method` from `initial` to `t_end` with step `h`.
pub fn run<M: RotationIntegrator, S: RigidBodySystem>(
    method: &mut M,
    system: &S,
    initial: RigidState,
    t_end: f64,
    h: f64,
) -> RigidState {
    integrate_to(method, system, initial, t_end, h).unwrap().state
}

/// The shipped reference of the fast top at `t`, from `tests/data/fast_top_reference.json`
/// (adaptive 8th-order Runge-Kutta, rtol 1e-13).
pub fn shipped_fast_top_reference(t: f64) -> RigidState {
    let text = include_str!("../data/fast_top_reference.json");
    let json: serde_json::Value = serde_json::from_str(text).unwrap();
    let state = json["states"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| (s["t"].as_f64().unwrap() - t).abs() < 1e-12)
        .expect("a shipped state at t");
    let v = |key: &str| -> Vec<f64> {
        state[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let pi = v("body_angular_momentum");
    let r: [f64; 9] = v("rotation_matrix_row_major").try_into().unwrap();
    RigidState::new(t, Vec3::new(pi[0], pi[1], pi[2]), Mat3::from_row_major(r))
}
