//! Per-step cost of every rotation method on the fast top, against the floor any Lie-group
//! method pays: a bare Lie-Euler step `R ← R exp(hΩ)` with one torque evaluation.
//!
//! Every measurement is a run of [`STEPS`] steps of `h = 1e-4` from the initial state
//! (`t ∈ [0, 0.1]`, the spec's short run), so that all methods, the floor included, are
//! timed on the same physical states. Stepping one state for as long as criterion samples
//! (millions of steps) would not: explicit Lie-Euler is unstable on the fast top and its
//! state is NaN by step 10,000, and timing arithmetic on NaN says nothing about the
//! floor. Criterion reports the time of a run; its throughput line gives steps per second.
//!
//! `cargo bench -p liemid --bench step`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use liemid::{problems, so3, RigidBodySystem, RigidState, RotationIntegrator, RotationMethod};

/// Steps per timed run.
const STEPS: u64 = 1000;

/// The floor: one torque evaluation and one exponential per step (explicit Lie-Euler).
fn lie_euler_step<S: RigidBodySystem>(system: &S, state: &mut RigidState, h: f64) {
    let omega = system.inertia().apply_inverse(state.pi);
    let torque = system.torque(&state.rotation, state.t);
    state.pi += (state.pi.cross(omega) + torque) * h;
    state.rotation = state.rotation * so3::exp(omega * h);
    state.t += h;
}

fn per_step(c: &mut Criterion) {
    let top = problems::fast_top();
    let h = 1e-4;
    let mut group = c.benchmark_group("fast top, 1000 steps");
    group.throughput(Throughput::Elements(STEPS));
    group.bench_function("lie-euler floor", |b| {
        b.iter(|| {
            let mut s = top.initial;
            for _ in 0..STEPS {
                lie_euler_step(black_box(&top.system), &mut s, black_box(h));
            }
            assert!(s.pi.is_finite(), "the floor left the physical regime");
            s
        })
    });
    for method in RotationMethod::ALL {
        group.bench_function(method.key(), |b| {
            let mut integrator = method.integrator();
            b.iter(|| {
                let mut s = top.initial;
                for _ in 0..STEPS {
                    integrator.step(black_box(&top.system), &mut s, black_box(h)).unwrap();
                }
                s
            })
        });
    }
    group.finish();
}

criterion_group!(benches, per_step);
criterion_main!(benches);
