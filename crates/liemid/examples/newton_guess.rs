//! Why the midpoint solver starts Newton from its third-order predictor rather than warm
//! from an earlier increment: runs LIEMID[EA] on the fast top and reports, over the run,
//! the largest relative distance from each candidate guess to the converged `Ψ`.
//!
//! `cargo run --release -p liemid --example newton_guess`
use liemid::{rigid::midpoint, rigid::problems, so3, RigidBodySystem, Vec3};

fn main() {
    let top = problems::fast_top();
    let system = &top.system;
    let inertia = system.inertia();
    for h in [1e-4f64, 1e-3] {
        let hh = 0.5 * h;
        let (mut r, mut pi) = (top.initial.rotation, top.initial.pi);
        let mut torque = system.torque(&r, 0.0);
        let mut previous: Option<Vec3> = None;
        let (mut predictor, mut last_step, mut first_half) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..(0.8 / h).round() as usize {
            let p = pi + torque * hh;
            let psi0 = inertia.apply_inverse(p) * hh;
            let guess = inertia.apply_inverse(p + p.cross(psi0) * 0.5) * hh;
            let (psi1, _) = midpoint::solve(inertia, p, hh).expect("converges");
            predictor = predictor.max((guess - psi1).norm() / psi1.norm());
            if let Some(previous) = previous {
                last_step = last_step.max((previous - psi1).norm() / psi1.norm());
            }
            let inc1 = so3::Increment::new(psi1);
            let pi_half = inc1.inverse_apply(p);
            let (psi2, _) = midpoint::solve(inertia, pi_half, hh).expect("converges");
            first_half = first_half.max((psi1 - psi2).norm() / psi2.norm());
            previous = Some(psi2);
            let inc2 = so3::Increment::new(psi2);
            r = inc2.rotate(&inc1.rotate(&r));
            torque = system.torque(&r, 0.0);
            pi = inc2.inverse_apply(pi_half) + torque * hh;
        }
        println!(
            "h = {h:e}: largest relative error of the Newton guess: predictor {predictor:.1e}, \
             previous step's increment {last_step:.1e}, the step's first increment (for its second solve) {first_half:.1e}"
        );
    }
}
