//! Per-step cost of every rotation method on the fast top, against the floor any Lie-group
//! method pays: a bare Lie-Euler step `R ← R exp(hΩ)` with one torque evaluation.
//!
//! Every measurement is a run of [`STEPS`] steps of `h = 1e-4` from the initial state
//! (`t ∈ [0, 0.1]`, the short run of docs/theory/rigid.md §8), so that all methods, the floor included, are
//! timed on the same physical states. Stepping one state for as long as criterion samples
//! (millions of steps) would not: explicit Lie-Euler is unstable on the fast top and its
//! state is NaN by step 10,000, and timing arithmetic on NaN says nothing about the
//! floor. Criterion reports the time of a run; its throughput line gives steps per second.
//!
//! A second group takes EA apart: the same step written out from the public midpoint API,
//! then with the Newton iterations of the second solve, and of both, replaced by the
//! solver's predictor. Those variants are not methods (their increments are not converged);
//! they show what the Newton iterations cost in time, against the rest of the step.
//!
//! `cargo bench -p liemid --bench step`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use liemid::{
    rigid::midpoint, rigid::problems, so3, HeavyTop, RigidBodySystem, RigidState, RotationIntegrator, RotationMethod,
    Vec3,
};

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

/// The exact torque-free flow alone, 1000 calls of `h = 1e-4` from the fast top's state:
/// the symmetric closed form (the top itself) and the elliptic asymmetric case (the same
/// momentum on a body with moments (1, 2, 3) times the top's scale).
fn free_flow(c: &mut Criterion) {
    let top = problems::fast_top();
    let h = 1e-4;
    let mut group = c.benchmark_group("exact free flow, 1000 calls");
    group.throughput(Throughput::Elements(STEPS));
    let symmetric = liemid::FreeFlow::new(top.system.inertia()).unwrap();
    let asymmetric = liemid::FreeFlow::new(&liemid::Inertia::principal([0.02, 0.03, 0.045]).unwrap()).unwrap();
    for (name, flow) in [("symmetric", symmetric), ("asymmetric", asymmetric)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let (mut p, mut r) = (top.initial.pi + Vec3::new(0.05, 0.02, 0.0), top.initial.rotation);
                for _ in 0..STEPS {
                    (p, r) = flow.flow(p, &r, black_box(h));
                }
                (p, r)
            })
        });
    }
    group.finish();
}

/// How an ablated EA step finds its increments (a const parameter, so that each variant is
/// compiled on its own, as EA is):
/// - `SOLVED`: both midpoint solves to round-off (EA itself, written out);
/// - `SECOND_PREDICTED`: the second solve's Newton iterations replaced by the predictor;
/// - `BOTH_PREDICTED`: both solves replaced by the predictor.
const SOLVED: u8 = 0;
const SECOND_PREDICTED: u8 = 1;
const BOTH_PREDICTED: u8 = 2;

/// The midpoint solver's predictor `h I⁻¹ (P + ½ P × h I⁻¹ P)`, without Newton's iterations.
fn predictor<S: RigidBodySystem>(system: &S, p: Vec3, h: f64) -> Vec3 {
    let inertia = system.inertia();
    let psi0 = inertia.apply_inverse(p) * h;
    inertia.apply_inverse(p + p.cross(psi0) * 0.5) * h
}

/// One EA step from the public API, the start torque carried in `torque`.
#[inline(always)]
fn ablated_ea<S: RigidBodySystem, const HOW: u8>(system: &S, s: &mut RigidState, torque: &mut Vec3, h: f64) {
    let hh = 0.5 * h;
    let inertia = system.inertia();
    let p = s.pi + *torque * hh;
    let psi1 = if HOW == BOTH_PREDICTED {
        predictor(system, p, hh)
    } else {
        midpoint::solve(inertia, p, hh).unwrap().0
    };
    let inc1 = so3::Increment::new(psi1);
    let pi_half = inc1.inverse_apply(p);
    let psi2 = if HOW == SOLVED {
        midpoint::solve(inertia, pi_half, hh).unwrap().0
    } else {
        predictor(system, pi_half, hh)
    };
    let inc2 = so3::Increment::new(psi2);
    let rotation = inc2.rotate(&inc1.rotate(&s.rotation));
    let t1 = s.t + h;
    let torque1 = system.torque(&rotation, t1);
    *s = RigidState::new(t1, inc2.inverse_apply(pi_half) + torque1 * hh, rotation);
    *torque = torque1;
}

fn bench_ablated<const HOW: u8>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    top: &problems::RigidProblem<HeavyTop>,
    h: f64,
) {
    group.bench_function(name, |b| {
        b.iter(|| {
            let mut s = top.initial;
            let mut torque = top.system.torque(&s.rotation, s.t);
            for _ in 0..STEPS {
                ablated_ea::<_, HOW>(black_box(&top.system), &mut s, &mut torque, black_box(h));
            }
            s
        })
    });
}

fn ea_ablation(c: &mut Criterion) {
    let top = problems::fast_top();
    let h = 1e-4;
    let mut group = c.benchmark_group("EA ablation, 1000 steps");
    group.throughput(Throughput::Elements(STEPS));
    bench_ablated::<SOLVED>(&mut group, "ea written out", &top, h);
    bench_ablated::<SECOND_PREDICTED>(&mut group, "ea, second solve = predictor", &top, h);
    bench_ablated::<BOTH_PREDICTED>(&mut group, "ea, both solves = predictor", &top, h);
    group.finish();
}

criterion_group!(benches, per_step, free_flow, ea_ablation);
criterion_main!(benches);
