//! The paper's fast Lagrangian top: the error of every rotation method at t = 0.8 for
//! step sizes halved from 2e-3, against a reference computed here with RK4 at h = 1e-6.
//!
//! Run with `cargo run --release --example fast_top`.

use liemid::{integrate_to, rigid::problems, RotationIntegrator, RotationMethod, RungeKutta4Quaternion};

fn main() -> Result<(), liemid::Error> {
    let top = problems::fast_top();
    let reference = integrate_to(
        &mut RungeKutta4Quaternion::new(),
        &top.system,
        top.initial,
        top.t_end,
        1e-6,
    )?
    .state;
    println!("fast top to t = {}; reference: RK4 at h = 1e-6", top.t_end);
    println!("{:<12} {:>10} {:>12} {:>12}", "method", "h", "momentum", "attitude");
    for method in RotationMethod::PAPER {
        for k in 0..5 {
            let h = 2e-3 / f64::from(1 << k);
            let mut integrator = method.integrator();
            let end = match integrate_to(&mut integrator, &top.system, top.initial, top.t_end, h) {
                Ok(s) => s.state,
                Err(e) => {
                    println!("{:<12} {h:>10.3e} failed: {e}", integrator.name());
                    continue;
                }
            };
            let dp = (end.pi - reference.pi).norm() / reference.pi.norm();
            let dr = (end.rotation - reference.rotation).norm_frobenius();
            println!("{:<12} {h:>10.3e} {dp:>12.3e} {dr:>12.3e}", integrator.name());
        }
    }
    Ok(())
}
