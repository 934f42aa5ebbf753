//! The physics step with contact and the haptic queries allocate nothing
//! after warm-up (a counting global allocator; one test, single-threaded).

use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{ModelConfig, ThighModel, Vec3};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn contact_step_and_queries_do_not_allocate() {
    let config = ModelConfig::default();
    let top = config.thigh.semi_axis_y;
    let mut model = ThighModel::new(&config).unwrap();
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    let pose = |d: f64| Probe::exam_pose(Vec3::new(0.001 * d.sin(), top - d, 0.0));
    // Warm-up: out of contact, then pressing.
    for i in 0..10 {
        pc.step(&mut model, &pose(0.004 - 0.001 * i as f64), 0.01);
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let mut touched = 0;
    for i in 0..40 {
        // Approach from 3 mm above to 8 mm deep and back: both query paths.
        let d = -0.003 + 0.011 * (1.0 - ((i as f64 - 20.0) / 20.0).abs());
        let s = pc.step(&mut model, &pose(d), 0.01);
        touched += s.sample.in_contact as usize;
    }
    let after = ALLOCATIONS.load(Ordering::Relaxed);
    assert!(
        touched > 10 && touched < 40,
        "both paths exercised: {touched}"
    );
    assert_eq!(after - before, 0, "allocations during 40 contact steps");
}
