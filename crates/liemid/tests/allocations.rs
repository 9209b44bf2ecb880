//! Stepping allocates nothing: a counting global allocator watches every method's steps.

use liemid::vector::{PhaseState, VectorIntegrator, Verlet};
use liemid::{integrate_to, rigid::problems, Composition, RotationIntegrator, RotationMethod, Scheme};

#[path = "common/thread_counting.rs"]
mod thread_counting;
use thread_counting::allocations;

#[global_allocator]
static GLOBAL: thread_counting::Counting = thread_counting::Counting;

#[test]
fn the_counter_sees_allocations() {
    let before = allocations();
    let v = std::hint::black_box(vec![1u8; 16]);
    assert!(allocations() > before && v.len() == 16);
}

#[test]
fn rotation_steps_and_the_driver_allocate_nothing() {
    let top = problems::fast_top();
    for method in RotationMethod::ALL {
        let mut integrator = method.integrator();
        let mut state = top.initial;
        integrator.step(&top.system, &mut state, 1e-4).unwrap(); // warm-up
        let before = allocations();
        for _ in 0..1000 {
            integrator.step(&top.system, &mut state, 1e-4).unwrap();
        }
        assert_eq!(allocations() - before, 0, "{} allocates per step", method.name());
        let before = allocations();
        let run = integrate_to(&mut integrator, &top.system, top.initial, 0.05, 1e-4).unwrap();
        assert_eq!(run.steps, 500);
        assert_eq!(allocations() - before, 0, "{}: the driver allocates", method.name());
    }
}

#[test]
fn vector_steps_allocate_nothing_after_the_first() {
    let kepler = liemid::vector::problems::Kepler::default();
    let mut state: PhaseState = liemid::vector::problems::Kepler::initial(0.5);
    let mut verlet = Verlet::default();
    let mut composed = Composition::new(Verlet::default(), Scheme::KAHAN_LI8, "Verlet8");
    verlet.step(&kepler, &mut state, 1e-3).unwrap(); // sizes the scratch space
    composed.step(&kepler, &mut state, 1e-3).unwrap();
    let before = allocations();
    for _ in 0..1000 {
        verlet.step(&kepler, &mut state, 1e-3).unwrap();
        composed.step(&kepler, &mut state, 1e-3).unwrap();
    }
    assert_eq!(allocations() - before, 0);
}
