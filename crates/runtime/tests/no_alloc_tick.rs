//! The one haptic tick allocates nothing, run as the binary runs it: the
//! threaded deployment's `HapticTick` with its `HandoffObserver` (pose to a
//! link thread, records into the recorder's lock-free ring), while a link
//! thread (`client::exchange`) and a physics thread (`physics_loop`) run
//! the other side over the in-process link, exactly as `run_threads` wires
//! them. 100 000 ticks in `buffer` and `hold`, 20 000 in `direct` (which steps
//! the physics inside every tick), both with the haptic queries (the virtual
//! clock's tick) and without (the real-time deployments' force-only tick). The counting allocator counts this thread only, so the
//! link and physics threads may allocate without being counted (they are
//! not real-time). One test function so that nothing else runs on this
//! thread while counting.

use echothigh_device::{SimulatedDevice, SimulatedHand};
use echothigh_haptics::Vec3;
use echothigh_runtime::client::exchange;
use echothigh_runtime::haptic_side::haptic_side_for;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::physics_loop::{physics_loop, Clock};
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::recorder::RecordSink;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::tick::{HandoffObserver, HapticTick};
use echothigh_testkit::{count_allocations, CountingAllocator};
use echothigh_transport::ProbeMsg;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Ticks per mode. `direct` runs a whole physics step (a Newton solve of
/// the 1 008-node thigh, ~1.5 ms) inside every tick, so it is held to
/// 20 000 ticks (the allocation-free step itself is proven over longer runs
/// in the model crate's own no-allocation test).
fn ticks_for(mode: CouplingMode) -> u32 {
    match mode {
        CouplingMode::Direct => 20_000,
        _ => 100_000,
    }
}

/// Runs `TICKS` ticks in `mode` (in `direct`, with the haptic queries or
/// without); returns (allocations on the tick's thread, ticks with contact
/// force, peak force in N).
fn ticks_allocate(mode: CouplingMode, direct_queries: bool) -> (u64, u64, f64) {
    let mut s = Scenario::default();
    s.coupling.mode = mode;
    s.run.duration = 120.0;
    s.validate().unwrap();
    // A hand holding the probe pressed 12 mm into the top of the thigh at
    // mid-thigh, the device starting 10 mm above the skin: the ticks run
    // unpaced, so a scripted exam would be over before the 100 Hz physics
    // saw its press; a still, pressed hand keeps the contact whatever the
    // speed.
    let top = s.thigh.semi_axis_y;
    let hand = SimulatedHand::new(s.hand, Vec3::new(0.0, top - 0.012, 0.0)).unwrap();
    let mut device = SimulatedDevice::with_hand(s.device, hand).unwrap();
    device.set_state(Vec3::new(0.0, top + 0.010, 0.0), Vec3::zeros());
    let (mut sink, source) = haptic_side_for(mode, &s).unwrap();
    let direct = (mode == CouplingMode::Direct).then(|| PhysicsSide::new(&s).unwrap());
    let period = s.coupling.haptic_period();
    let mut tick = HapticTick::new(device, source, s.device.force_scale(), direct, period);
    tick.set_direct_queries(direct_queries);
    let (pose_in, mut pose_out) = triple_buffer::triple_buffer(&None::<ProbeMsg>);
    let (producer, mut consumer) = rtrb::RingBuffer::new(1 << 14);
    let mut observer = HandoffObserver::new(pose_in, RecordSink::Ring(producer, 0));
    let stop = Arc::new(AtomicBool::new(false));
    let clock = Clock::start();
    let mut threads = Vec::new();
    if mode != CouplingMode::Direct {
        let (mut haptic_end, mut physics_end) = s.in_process_link();
        let mut physics = PhysicsSide::new(&s).unwrap();
        let (st, rate) = (stop.clone(), s.coupling.physics_rate);
        threads.push(std::thread::spawn(move || {
            let mut steps = RecordSink::Discard;
            physics_loop(
                &mut physics,
                &mut physics_end,
                clock,
                &st,
                rate,
                f64::INFINITY,
                &mut steps,
            )
            .unwrap();
        }));
        let st = stop.clone();
        threads.push(std::thread::spawn(move || {
            let (mut last, mut rate) = (-1.0, 0.0);
            while !st.load(Ordering::Relaxed) {
                exchange(
                    &mut haptic_end,
                    &mut pose_out,
                    &mut sink,
                    &mut last,
                    &mut rate,
                    clock.now(),
                )
                .unwrap();
                // The recorder's drain, as its thread does.
                while consumer.pop().is_ok() {}
                std::thread::sleep(std::time::Duration::from_micros(500));
            }
        }));
    }
    let mut peak: f64 = 0.0;
    let mut contact = 0u64;
    let ((), n) = count_allocations(|| {
        for i in 0..ticks_for(mode) {
            // The loop's clock, as the binary reads it (the ticks run
            // unpaced here: the device still advances one period per tick).
            let _ = i;
            let r = tick.tick(clock.now(), &mut observer).unwrap();
            let f = r.force.norm();
            peak = peak.max(f);
            contact += u64::from(f > 1e-9);
        }
    });
    stop.store(true, Ordering::Relaxed);
    for t in threads {
        t.join().unwrap();
    }
    (n, contact, peak)
}

#[test]
fn the_tick_allocates_nothing_in_any_coupling_mode() {
    for (mode, queries) in [
        (CouplingMode::Buffer, true),
        (CouplingMode::Hold, true),
        (CouplingMode::Direct, true),
        (CouplingMode::Direct, false),
    ] {
        let (n, contact, peak) = ticks_allocate(mode, queries);
        assert_eq!(
            n,
            0,
            "{mode:?} (queries {queries}): {n} allocations in {} ticks",
            ticks_for(mode)
        );
        // The test must exercise contact (the hand presses 12 mm in); its
        // force is not the subject here.
        assert!(
            contact > 0 && peak > 1.0,
            "{mode:?} (queries {queries}): no contact (peak {peak} N)"
        );
    }
}
