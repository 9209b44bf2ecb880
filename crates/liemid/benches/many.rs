//! Throughput of the many-body splitting integrator, in body-steps per second, with 1 and 2
//! threads, against the memory-bandwidth floor of copying the state arrays once, and the
//! exact free rotation against the midpoint rotation.
//!
//! `cargo bench -p liemid --bench many`

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use liemid::many::problems;
use liemid::many::{Bodies, FreeRotation, CHUNK};
use rayon::prelude::*;

/// Copy every state array of `b` into `into`: the least any step must move through memory.
/// With `parallel`, each array is split in chunks over the threads of the current pool.
fn copy_state(b: &Bodies, into: &mut Bodies, parallel: bool) {
    fn copy<T: Copy + Send + Sync>(from: &[T], to: &mut [T], parallel: bool) {
        if parallel {
            to.par_chunks_mut(CHUNK)
                .zip(from.par_chunks(CHUNK))
                .for_each(|(to, from)| to.copy_from_slice(from));
        } else {
            to.copy_from_slice(from);
        }
    }
    copy(&b.mass, &mut into.mass, parallel);
    copy(&b.inertia, &mut into.inertia, parallel);
    copy(&b.free, &mut into.free, parallel);
    copy(&b.position, &mut into.position, parallel);
    copy(&b.momentum, &mut into.momentum, parallel);
    copy(&b.rotation, &mut into.rotation, parallel);
    copy(&b.pi, &mut into.pi, parallel);
    copy(&b.force, &mut into.force, parallel);
    copy(&b.torque, &mut into.torque, parallel);
}

fn throughput(c: &mut Criterion) {
    let mut group = c.benchmark_group("many");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for n in [100usize, 10_000, 1_000_000] {
        group.throughput(Throughput::Elements(n as u64));
        let (bodies, free) = problems::torque_free_ensemble(n, 1);
        let mut copy = bodies.clone();
        group.bench_with_input(BenchmarkId::new("copy floor, 1 thread", n), &n, |b, _| {
            b.iter(|| copy_state(&bodies, &mut copy, false))
        });
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            if threads == 2 {
                group.bench_with_input(BenchmarkId::new("copy floor, 2 threads", n), &n, |b, _| {
                    b.iter(|| pool.install(|| copy_state(&bodies, &mut copy, true)))
                });
            }
            let mut state = bodies.clone();
            group.bench_with_input(
                BenchmarkId::new(format!("torque-free, {threads} threads"), n),
                &n,
                |b, _| b.iter(|| pool.install(|| state.step(&free, 1e-3).unwrap())),
            );
        }
    }
    // The exact and variational free rotations against the midpoint rotation, 1 thread:
    // asymmetric rotors (the elliptic flow) and heavy tops (symmetric, closed form).
    for n in [10_000usize] {
        group.throughput(Throughput::Elements(n as u64));
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let (rotors, free) = problems::torque_free_ensemble(n, 1);
        let (tops, gravity) = problems::top_ensemble(n, 1);
        for kind in FreeRotation::ALL {
            let mut state = rotors.clone();
            state.set_free_rotation(kind).unwrap();
            group.bench_with_input(
                BenchmarkId::new(format!("torque-free asymmetric, {} rotation, 1 thread", kind.key()), n),
                &n,
                |b, _| b.iter(|| pool.install(|| state.step(&free, 1e-3).unwrap())),
            );
            let mut state = tops.clone();
            state.set_free_rotation(kind).unwrap();
            group.bench_with_input(
                BenchmarkId::new(format!("symmetric tops, {} rotation, 1 thread", kind.key()), n),
                &n,
                |b, _| b.iter(|| pool.install(|| state.step(&gravity, 1e-4).unwrap())),
            );
        }
    }
    for n in [1000usize, 10_000] {
        group.throughput(Throughput::Elements(n as u64));
        let (bodies, dipoles) = problems::dipolar_fluid(n, 0.3, 1).unwrap();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut state = bodies.clone();
            group.throughput(Throughput::Elements(n as u64));
            group.bench_with_input(
                BenchmarkId::new(format!("dipoles, step, {threads} threads"), n),
                &n,
                |b, _| b.iter(|| pool.install(|| state.step(&dipoles, 1e-3).unwrap())),
            );
            // Ten steps by a team of threads (`Bodies::advance`), as `liemid many` takes them
            // between two samples of the totals.
            group.throughput(Throughput::Elements(10 * n as u64));
            group.bench_with_input(
                BenchmarkId::new(format!("dipoles, advance 10, {threads} threads"), n),
                &n,
                |b, _| b.iter(|| pool.install(|| state.advance(&dipoles, 1e-3, 10).unwrap())),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, throughput);
criterion_main!(benches);
