//! `advance` and `set_force` allocate nothing: a counting global allocator
//! (this test binary only; one test function, so single-threaded).

use echothigh_device::{
    DeviceConfig, ExamConfig, ExamScript, HandConfig, HapticDevice, ReplayDevice, SimulatedDevice,
    SimulatedHand, Vec3,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Counting is on only on the test's own thread, so the test harness's
    /// other threads (output capture, timers) do not pollute the count.
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTING.with(Cell::get) {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn advance_does_not_allocate() {
    let config = DeviceConfig::default();
    let scale = config.force_scale();
    let script = ExamScript::new(ExamConfig::default()).unwrap();
    let hand = SimulatedHand::scripted(HandConfig::default(), script).unwrap();
    let mut device = SimulatedDevice::with_hand(config, hand).unwrap();
    let mut replay = ReplayDevice::from_reader(
        "t,x,y,z\n0,0,0.1,0.15\n1,0,0.06,0.15\n2,0,0.06,0.17\n".as_bytes(),
        config,
    )
    .unwrap();
    let mut devices: [&mut dyn HapticDevice; 2] = [&mut device, &mut replay];

    // Sanity: the counter sees an allocation on this thread.
    COUNTING.with(|c| c.set(true));
    let probe = ALLOCATIONS.load(Ordering::SeqCst);
    drop(std::hint::black_box(vec![0u8; 16]));
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst) - probe, 1);
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    // The whole default exam (~10 s at 1 kHz) against a linear tissue, through
    // the trait object as the haptic loop will call it, with NaN and
    // over-limit forces thrown in.
    for tick in 0..11_000u32 {
        for d in devices.iter_mut() {
            let depth = (0.072 - d.position().y).max(0.0);
            let mut f = scale.tissue_to_device(Vec3::new(0.0, 800.0 * depth, 0.0));
            if tick % 1000 == 7 {
                f.x = f64::NAN;
            }
            if tick % 1000 == 11 {
                f.y = 1e3;
            }
            d.set_force(f);
            d.advance(1e-3);
        }
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    COUNTING.with(|c| c.set(false));
    assert_eq!(
        after - before,
        0,
        "advance allocated {} times",
        after - before
    );
    assert!(device.exam_status().unwrap().phase == echothigh_device::ExamPhase::Done);
    assert_eq!(device.faults().non_finite, 11);
    assert!(replay.finished());
}
