//! Body-steps per second of the multibody step (RATTLE with EA's rotation): a 1000-link
//! ball-joint chain (one system, O(bodies) constraint solve), and an ensemble of 1000
//! independent 10-link chains on 1 and 2 threads (bitwise the same results; only the time
//! differs). Throughput is in body-steps.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use liemid::multibody::{problems, MultibodyEnsemble, MultibodyMethod, MultibodySystem};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("multibody");
    group.sample_size(10);

    let chain = problems::chain(1000);
    let mut system = MultibodySystem::new(&chain, MultibodyMethod::Liemid).expect("the chain builds");
    let mut state = chain.initial_state().expect("the chain starts");
    group.throughput(Throughput::Elements(1000 * 10));
    group.bench_function("chain-1000, 10 steps of 1e-4", |b| {
        b.iter(|| {
            for _ in 0..10 {
                system.step(&mut state, 1e-4).expect("the step converges");
            }
        });
    });

    let ten = problems::chain(10);
    for threads in [1, 2] {
        let mut ensemble = MultibodyEnsemble::new(&ten, MultibodyMethod::Liemid, 1000, |k, s| {
            let last = s.len() - 1;
            s.p[last].x += 1e-4 * k as f64;
        })
        .expect("the ensemble builds");
        group.throughput(Throughput::Elements(10 * 1000 * 10));
        group.bench_function(format!("1000 chain-10s, 10 steps of 1e-4, {threads} thread(s)"), |b| {
            b.iter(|| ensemble.advance(1e-4, 10, threads).expect("the steps converge"));
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
