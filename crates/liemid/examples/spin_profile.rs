//! Time one spin method on issue 17's 64×64 lattice: `cargo run --release -p liemid
//! --example spin_profile -- split 2000 1` (method key, steps, threads, and optionally the side of a larger square lattice).

use liemid::spin::{problems, SpinIntegrator, SpinMethod};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let method = SpinMethod::from_key(args.get(1).map_or("split", String::as_str)).expect("a spin method key");
    let steps: usize = args.get(2).map_or(2000, |s| s.parse().expect("a step count"));
    let mut p = problems::square_64();
    if let Some(side) = args.get(4) {
        // A larger periodic square lattice with the same parameters.
        let side: usize = side.parse().expect("a lattice side");
        p.system.lattice =
            liemid::spin::Lattice::new(liemid::spin::LatticeKind::Square, &[side, side], true).expect("a lattice");
        p.spins = problems::near_z(side * side, 0.3, 1);
    }
    let mut spins = p.spins.clone();
    let mut integ = SpinIntegrator::new(method);
    let threads: usize = args.get(3).map_or(1, |s| s.parse().expect("a thread count"));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a pool");
    let start = std::time::Instant::now();
    pool.install(|| {
        // In runs of 100 steps, as `liemid spins` observes them.
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(100);
            integ
                .advance(&p.system, &mut spins, done as f64 * p.step, p.step, n as u64)
                .unwrap();
            done += n;
        }
    });
    let s = start.elapsed().as_secs_f64();
    println!(
        "{}: {steps} steps of {} spins in {s:.3} s: {:.3e} spin-steps/s",
        method.key(),
        spins.len(),
        (steps * spins.len()) as f64 / s
    );
}
