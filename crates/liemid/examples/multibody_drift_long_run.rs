//! chain-10 over long runs with both drifts of the multibody step: the relative energy
//! error of RATTLE with EA's midpoint rotation and with the variational rotation (LIEMID[EAV]'s,
//! docs/theory/rigid.md §9), its largest value over the first and over the last tenth of the
//! run (sampled every 100 steps), the largest position-constraint violation, and the time
//! per step. The numbers in docs/multibody.md ("Structure") come from this program.
//!
//! Run with `cargo run --release --example multibody_drift_long_run [steps] [h]`
//! (default 10⁷ steps of 1e-3 s).

use std::time::Instant;

use liemid::multibody::{problems, Drift, MultibodyMethod, Simulation};

fn main() -> Result<(), liemid::Error> {
    let mut args = std::env::args().skip(1);
    let steps: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(10_000_000);
    let h: f64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1e-3);
    let model = problems::chain(10);
    println!("chain-10, {steps} steps of {h:e}: max |E - E0|/|E0| over the first and last tenth");
    println!(
        "{:<12} {:>12} {:>12} {:>14} {:>10}",
        "drift", "first", "last", "max violation", "us/step"
    );
    for drift in Drift::ALL {
        let Simulation { system, mut integrator } = Simulation::new(&model, MultibodyMethod::Liemid)?;
        integrator.set_drift(drift);
        let mut state = model.initial_state()?;
        let e0 = system.energy(&state);
        let (mut first, mut last) = (0.0f64, 0.0f64);
        let tenth = steps / 10;
        let started = Instant::now();
        let run = integrator.integrate(&system, &mut state, h * steps as f64, h, |k, s, _, _| {
            if k % 100 == 0 {
                let e = ((system.energy(s) - e0) / e0).abs();
                if k <= tenth {
                    first = first.max(e);
                }
                if k >= steps - tenth {
                    last = last.max(e);
                }
            }
            Ok(())
        })?;
        let micros = started.elapsed().as_secs_f64() / steps as f64 * 1e6;
        println!(
            "{:<12} {first:>12.3e} {last:>12.3e} {:>14.1e} {micros:>10.2}",
            drift.key(),
            run.max_position_violation
        );
    }
    Ok(())
}
