//! A physics step and a stiffness solve allocate nothing (counting global
//! allocator; one test function so no other thread allocates meanwhile).

mod common;

use echothigh_model::{NoExtraForce, Vec3};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steps_and_stiffness_solves_allocate_nothing() {
    let mut config = common::small_config(24, 11);
    config.tissue.gravity = [0.0, -9.81, 0.0];
    let mut m = common::model(&config);
    common::press_top(&mut m, 12.0); // strong load: Newton iterates, limiter may act
    let n = m.node_count();
    let mut rhs = vec![Vec3::zeros(); n];
    rhs[common::top_node(&m)] = Vec3::new(0.0, -1.0, 0.0);
    let mut out = vec![Vec3::zeros(); n];
    m.step(0.01, &mut NoExtraForce); // warm-up
    m.solve_stiffness(&mut NoExtraForce, &rhs, &mut out);

    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut work = 0;
    for _ in 0..20 {
        let s = m.step(0.01, &mut NoExtraForce);
        work += s.cg_iterations;
    }
    let s = m.solve_stiffness(&mut NoExtraForce, &rhs, &mut out);
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert!(work > 0 && s.iterations > 0, "the steps must do real work");
    assert_eq!(after - before, 0, "allocations during steps");
}
