//! Spin stepping allocates nothing once warm (a counting global allocator, all threads).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use liemid::spin::{problems, SpinIntegrator, SpinMethod};

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
fn spin_steps_allocate_nothing_once_warm() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let p = problems::square_64();
    let mut integrators: Vec<SpinIntegrator> = SpinMethod::ALL.iter().map(|&m| SpinIntegrator::new(m)).collect();
    let mut spins: Vec<_> = SpinMethod::ALL.iter().map(|_| p.spins.clone()).collect();
    let mut steps = |count: usize| {
        pool.install(|| {
            for (integ, s) in integrators.iter_mut().zip(spins.iter_mut()) {
                for k in 0..count {
                    integ.step(&p.system, s, k as f64 * 1e-2, 1e-2).unwrap();
                }
            }
        })
    };
    steps(2);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    assert!(before > 0, "the counter saw the set-up allocate");
    steps(5);
    let during = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert_eq!(during, 0, "{during} allocations in 40 spin steps");
}
