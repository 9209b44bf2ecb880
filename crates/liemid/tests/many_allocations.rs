//! Many-body stepping allocates nothing once warm: a global counting allocator (all
//! threads) watches steps of a dipolar fluid with its cell list and of torque-free rotors
//! (midpoint, exact and variational free rotation).

use liemid::many::problems;

#[path = "common/counting.rs"]
mod counting;

#[global_allocator]
static GLOBAL: counting::Counting = counting::Counting;

#[test]
fn many_body_steps_allocate_nothing_once_warm() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let (mut fluid, dipoles) = problems::dipolar_fluid(1000, 0.3, 1).unwrap();
    let (mut rotors, free) = problems::torque_free_ensemble(1000, 1);
    let mut exact_rotors = rotors.clone();
    exact_rotors
        .set_free_rotation(liemid::many::FreeRotation::Exact)
        .unwrap();
    let mut variational_rotors = rotors.clone();
    variational_rotors
        .set_free_rotation(liemid::many::FreeRotation::Variational)
        .unwrap();
    pool.install(|| {
        for _ in 0..3 {
            fluid.step(&dipoles, 1e-3).unwrap();
            rotors.step(&free, 1e-3).unwrap();
            exact_rotors.step(&free, 1e-3).unwrap();
            variational_rotors.step(&free, 1e-3).unwrap();
        }
    });
    let before = counting::allocations();
    assert!(before > 0, "the counter saw the set-up allocate");
    pool.install(|| {
        for _ in 0..10 {
            fluid.step(&dipoles, 1e-3).unwrap();
            rotors.step(&free, 1e-3).unwrap();
            exact_rotors.step(&free, 1e-3).unwrap();
            variational_rotors.step(&free, 1e-3).unwrap();
        }
    });
    let during = counting::allocations() - before;
    assert_eq!(during, 0, "{during} allocations in 40 many-body steps");
    // `advance` by a team of threads: what forming the team costs (rayon's broadcast) once
    // per call, nothing per step.
    let allocations_of = |fluid: &mut liemid::many::Bodies, steps: u64| {
        let before = counting::allocations();
        pool.install(|| fluid.advance(&dipoles, 1e-3, steps).unwrap());
        counting::allocations() - before
    };
    let (few, many) = (allocations_of(&mut fluid, 2), allocations_of(&mut fluid, 20));
    assert_eq!(few, many, "advance allocated per step: {few} in 2 steps, {many} in 20");
}
