//! What the variational drift is worth over long runs: the relative energy error of
//! LIEMID[EA] and LIEMID[EAV] over 10⁷ steps of the fast top (h = 1e-4) and of the free
//! asymmetric body (h = 1e-2, the tennis-racket flip), its largest value over the first and
//! over the last tenth of the run (equal when the error does not drift), and the time per
//! step; then the cost of a step alone (no observer), EA and EAV alternating, the fastest of
//! seven runs of 10⁶ steps each, and their ratio. The numbers in docs/rigid.md
//! ("Structure") come from this program.
//!
//! Run with `cargo run --release --example variational_long_run [steps]`.

use std::time::Instant;

use liemid::{
    advance, integrate, rigid::problems, Diagnostics, LieMidpointAlternating, LieVariationalAlternating,
    RigidBodySystem, RigidState, RotationIntegrator,
};

/// The largest relative energy error over the first and the last tenth, sampled every 100
/// steps, and the seconds per step.
fn run<M: RotationIntegrator, S: RigidBodySystem>(
    mut method: M,
    system: &S,
    initial: RigidState,
    h: f64,
    steps: u64,
) -> Result<(f64, f64, f64), liemid::Error> {
    let e0 = Diagnostics::of(system, &initial).energy;
    let (mut first, mut last) = (0.0f64, 0.0f64);
    let tenth = steps / 10;
    let started = Instant::now();
    integrate(&mut method, system, initial, h * steps as f64, h, 100, |k, _, d| {
        let e = ((d.energy - e0) / e0).abs();
        if k <= tenth {
            first = first.max(e);
        }
        if k >= steps - tenth {
            last = last.max(e);
        }
        Ok(())
    })?;
    Ok((first, last, started.elapsed().as_secs_f64() / steps as f64))
}

fn main() -> Result<(), liemid::Error> {
    let steps: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    println!("{steps} steps; energy error max |E - E0|/|E0| over the first and last tenth");
    println!(
        "{:<12} {:<12} {:>8} {:>12} {:>12} {:>10}",
        "problem", "method", "h", "first", "last", "ns/step"
    );
    let top = problems::fast_top();
    let body = problems::free_body();
    for (name, h) in [("fast-top", 1e-4), ("free-body", 1e-2)] {
        for variational in [false, true] {
            let (first, last, seconds) = match (name, variational) {
                ("fast-top", false) => run(LieMidpointAlternating::new(), &top.system, top.initial, h, steps)?,
                ("fast-top", true) => run(LieVariationalAlternating::new(), &top.system, top.initial, h, steps)?,
                (_, false) => run(LieMidpointAlternating::new(), &body.system, body.initial, h, steps)?,
                (_, true) => run(LieVariationalAlternating::new(), &body.system, body.initial, h, steps)?,
            };
            let method = if variational { "LIEMID[EAV]" } else { "LIEMID[EA]" };
            println!(
                "{name:<12} {method:<12} {h:>8.0e} {first:>12.3e} {last:>12.3e} {:>10.1}",
                seconds * 1e9
            );
        }
    }
    // The cost alone: the fastest of seven alternating runs of 10⁶ steps of the fast top.
    let timed = |variational: bool| -> Result<f64, liemid::Error> {
        let mut state = top.initial;
        let started = Instant::now();
        if variational {
            advance(
                &mut LieVariationalAlternating::new(),
                &top.system,
                &mut state,
                100.0,
                1e-4,
            )?;
        } else {
            advance(&mut LieMidpointAlternating::new(), &top.system, &mut state, 100.0, 1e-4)?;
        }
        std::hint::black_box(state);
        Ok(started.elapsed().as_secs_f64() / 1e6 * 1e9)
    };
    let (mut ea, mut eav) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..7 {
        ea = ea.min(timed(false)?);
        eav = eav.min(timed(true)?);
    }
    println!(
        "fast top, h = 1e-4, a step alone (fastest of 7 x 10^6): EA {ea:.1} ns, EAV {eav:.1} ns, EAV/EA {:.3}",
        eav / ea
    );
    Ok(())
}
