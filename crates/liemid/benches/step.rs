//! Per-step cost of every rotation method on the fast top, against the floor any Lie-group
//! method pays: a bare Lie-Euler step `R ← R exp(hΩ)` with one torque evaluation.
//!
//! `cargo bench -p liemid --bench step`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use liemid::{problems, so3, RigidBodySystem, RigidState, RotationIntegrator, RotationMethod};

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
    let mut group = c.benchmark_group("fast top step");
    group.bench_function("lie-euler floor", |b| {
        let mut s = top.initial;
        b.iter(|| lie_euler_step(black_box(&top.system), &mut s, black_box(h)))
    });
    for method in RotationMethod::ALL {
        group.bench_function(method.key(), |b| {
            let mut integrator = method.integrator();
            let mut s = top.initial;
            b.iter(|| integrator.step(black_box(&top.system), &mut s, black_box(h)).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, per_step);
criterion_main!(benches);
