//! Spin stepping allocates nothing per step once warm (a counting global allocator, all
//! threads): none at all on one thread, and on a team of threads one hand-off per
//! `advance` call (rayon's broadcast), whatever the number of steps it takes.

use liemid::spin::{problems, DmiKind, SpinIntegrator, SpinMethod};

#[path = "common/counting.rs"]
mod counting;

#[global_allocator]
static GLOBAL: counting::Counting = counting::Counting;

#[test]
fn spin_steps_allocate_nothing_once_warm() {
    let mut p = problems::square_64();
    let damped = {
        let mut s = p.system.clone();
        s.damping = 0.1;
        s
    };
    let dmi = p.system.clone().with_dmi(0.3, DmiKind::Interfacial).unwrap();
    let dmi_damped = damped.clone().with_dmi(0.3, DmiKind::Bulk).unwrap();
    // Undamped, then damped (the splitting's damped flows keep their constants on the stack),
    // then with DMI (its bond constants too).
    for (threads, system) in [
        (1, p.system.clone()),
        (2, p.system.clone()),
        (1, damped.clone()),
        (2, damped),
        (1, dmi.clone()),
        (2, dmi),
        (1, dmi_damped.clone()),
        (2, dmi_damped),
    ] {
        p.system = system;
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut integrators: Vec<SpinIntegrator> = SpinMethod::ALL.iter().map(|&m| SpinIntegrator::new(m)).collect();
        let mut spins: Vec<_> = SpinMethod::ALL.iter().map(|_| p.spins.clone()).collect();
        let mut calls = |steps: u64| {
            pool.install(|| {
                for (integ, s) in integrators.iter_mut().zip(spins.iter_mut()) {
                    integ.advance(&p.system, s, 0.0, 1e-2, steps).unwrap();
                }
            })
        };
        calls(2);
        let before = counting::allocations();
        calls(5);
        let during = counting::allocations() - before;
        // The four splitting methods hand their steps to the team once per call.
        let allowed = if threads == 1 { 0 } else { 4 };
        assert!(
            during <= allowed,
            "{threads} threads: {during} allocations in 8 calls of 5 steps"
        );
    }
}
