//! Many-body stepping allocates nothing once warm: a global counting allocator (all
//! threads) watches steps of a dipolar fluid with its cell list and of torque-free rotors
//! (midpoint and exact free rotation).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use liemid::problems;

struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn many_body_steps_allocate_nothing_once_warm() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let (mut fluid, dipoles) = problems::dipolar_fluid(1000, 0.3, 1).unwrap();
    let (mut rotors, free) = problems::torque_free_ensemble(1000, 1);
    let mut exact_rotors = rotors.clone();
    exact_rotors
        .set_free_rotation(liemid::many::FreeRotation::Exact)
        .unwrap();
    pool.install(|| {
        for _ in 0..3 {
            fluid.step(&dipoles, 1e-3).unwrap();
            rotors.step(&free, 1e-3).unwrap();
            exact_rotors.step(&free, 1e-3).unwrap();
        }
    });
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    assert!(before > 0, "the counter saw the set-up allocate");
    pool.install(|| {
        for _ in 0..10 {
            fluid.step(&dipoles, 1e-3).unwrap();
            rotors.step(&free, 1e-3).unwrap();
            exact_rotors.step(&free, 1e-3).unwrap();
        }
    });
    let during = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert_eq!(during, 0, "{during} allocations in 30 many-body steps");
}
