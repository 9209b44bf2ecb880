//! Throughput of the spin integrators on issue 17's 64×64 square lattice (J = 1 meV,
//! K = 0.1 meV, h = 0.01 ps), in spin-steps per second, on 1 and 2 threads: each sample is
//! one `advance` of 100 steps (how `liemid spins` runs between observations).
//!
//! `docs/spins.md` sets the per-spin-step cost of `split`, `split4`, `split8` and `rk4`
//! beside the operations they need (485, 2030, 6670 and about 210 per site and step).
//! Criterion measures wall time: on a loaded machine compare methods within one run.
//!
//! `cargo bench -p liemid --bench spin`

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use liemid::spin::{problems, SpinIntegrator, SpinMethod};

fn throughput(c: &mut Criterion) {
    let mut group = c.benchmark_group("spin");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let p = problems::square_64();
    let n = p.spins.len();
    group.throughput(Throughput::Elements(100 * n as u64));
    for method in SpinMethod::ALL {
        for threads in [1, 2] {
            if threads == 2 && !matches!(method, SpinMethod::Splitting | SpinMethod::Midpoint) {
                continue;
            }
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut spins = p.spins.clone();
            let mut integ = SpinIntegrator::new(method);
            group.bench_with_input(
                BenchmarkId::new(format!("{}, {threads} threads", method.key()), n),
                &n,
                |b, _| b.iter(|| pool.install(|| integ.advance(&p.system, &mut spins, 0.0, p.step, 100).unwrap())),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, throughput);
criterion_main!(benches);
