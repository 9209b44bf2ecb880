//! Body-steps per second of the multibody step (RATTLE with EA's rotation): a 1000-link
//! ball-joint chain (one system, O(bodies) constraint solve), an ensemble of 1000
//! independent 10-link chains on 1 and 2 threads (bitwise the same results; only the time
//! differs), and the small systems whose cost is the fixed part of a step (the spacecraft
//! and the double pendulum, by the base step and its compositions). Throughput is in
//! body-steps.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use liemid::multibody::{problems, MultibodyEnsemble, MultibodyMethod, Simulation};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("multibody");
    group.sample_size(10);

    let chain = problems::chain(1000);
    let mut system = Simulation::new(&chain, MultibodyMethod::Liemid).expect("the chain builds");
    let mut state = chain.initial_state().expect("the chain starts");
    group.throughput(Throughput::Elements(1000 * 10));
    group.bench_function("chain-1000, 10 steps of 1e-4", |b| {
        b.iter(|| {
            for _ in 0..10 {
                system.step(&mut state, 1e-4).expect("the step converges");
            }
        });
    });

    for (name, model, method, h) in [
        ("spacecraft", problems::spacecraft(), MultibodyMethod::Liemid, 1e-4),
        ("spacecraft", problems::spacecraft(), MultibodyMethod::Liemid6, 2.5e-3),
        (
            "double-pendulum",
            problems::double_pendulum(),
            MultibodyMethod::Liemid,
            1e-4,
        ),
        (
            "double-pendulum",
            problems::double_pendulum(),
            MultibodyMethod::Liemid4,
            1e-2,
        ),
    ] {
        let mut system = Simulation::new(&model, method).expect("the model builds");
        let mut state = model.initial_state().expect("the model starts");
        let bodies = state.len() as u64;
        group.throughput(Throughput::Elements(bodies * 100));
        group.bench_function(format!("{name}, {}, 100 steps of {h:e}", method.name()), |b| {
            b.iter(|| {
                for _ in 0..100 {
                    system.step(&mut state, h).expect("the step converges");
                }
            });
        });
    }

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
