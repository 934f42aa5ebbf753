//! `Renderer::render_into` allocates nothing after construction.

use echothigh_imaging::*;
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
fn render_into_does_not_allocate() {
    let cfg = ImagingConfig {
        columns: 128,
        rows: 192,
        ..Default::default()
    };
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let bone = r.anatomy().unwrap().femur_top();
    let presses: Vec<SectionDeformation> = (0..5)
        .map(|k| SectionDeformation::flat_press(k as f64 * 3e-3, 0.04, 1.5e-3, bone).unwrap())
        .collect();
    let mut out = vec![0u8; cfg.columns * cfg.rows];
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for (k, d) in presses.iter().enumerate() {
        let input = FrameInput {
            deformation: d,
            probe_pressure: k as f64 * 5000.0,
            time: k as f64 * 0.1,
        };
        r.render_into(&input, &mut out).unwrap();
        r.lumens(&input).unwrap();
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert_eq!(
        after - before,
        0,
        "render_into allocated {} times",
        after - before
    );
    assert!(out.iter().any(|&p| p > 0));
}
