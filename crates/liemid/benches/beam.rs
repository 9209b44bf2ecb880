//! Element-steps per second of the explicit beam splitting on a 10⁴-element tower frame,
//! on 1 and 2 threads (results are identical; only the time differs).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use liemid::beam::{problems, BeamMethod};

fn bench(c: &mut Criterion) {
    let problem = problems::tower(25, 50).expect("the tower builds");
    let system = problem.system().expect("the tower builds");
    let h = system.stability(0).default_step(BeamMethod::Splitting);
    let elements = system.elements() as u64;
    let mut group = c.benchmark_group("beam");
    group.throughput(Throughput::Elements(elements * 10));
    group.sample_size(20);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        let mut s = system.clone();
        group.bench_function(
            format!("tower {elements} elements, 10 steps, {threads} thread(s)"),
            |b| {
                b.iter(|| {
                    pool.install(|| {
                        for _ in 0..10 {
                            s.step(h).expect("stable");
                        }
                    });
                });
            },
        );
    }
    // The element kernel alone: forces of every element, no gather, no rotation.
    let s = system.clone();
    let mut force = vec![liemid::Vec3::ZERO; s.bodies.len()];
    let mut torque = force.clone();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
    group.throughput(Throughput::Elements(elements));
    group.bench_function("internal forces only, 1 thread", |b| {
        b.iter(|| {
            pool.install(|| {
                s.structure
                    .internal_forces(&s.bodies.position, &s.bodies.rotation, &mut force, &mut torque)
            })
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
