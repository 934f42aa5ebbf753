//! The live system's imaging thread (issue 16/19): it renders only while a
//! page looks, idles otherwise, reports its achieved rate (issue 19), and
//! stops and is joined on shutdown. Real
//! threads on the real clock; only frame counters are asserted, each wait
//! bounded generously (60 s) so a loaded machine slows the test, not fails it.

use echothigh_runtime::live::{LiveControl, LiveSnapshot, IMAGING_RATE_SETTING};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::time::{Duration, Instant};

fn frame(system: &LiveSystem) -> u64 {
    let mut pixels = Vec::new();
    system.image(&mut pixels).frame
}

fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "timed out: {what}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn the_image_is_rendered_only_while_a_page_looks_and_the_thread_joins() {
    let system = LiveSystem::start(Scenario::default()).unwrap();
    // Nobody looks: not one frame. 0.5 s is ten frame periods (50 ms at 20
    // frames/s), so a thread that rendered for nobody would have counted
    // some.
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(frame(&system), 0, "frames rendered with no page open");

    system.page_opened();
    wait_until("a first frame for the page", || frame(&system) >= 3);
    // Its achieved rate is reported once a window of ≥ 1 s has passed. The
    // schedule never bursts to catch up (a late frame starts its period
    // then), so a window of span T ≥ 1 s holds at most R T + 1 frames (R
    // the schedule's rate): the rate is at most R + 1/T ≤ R + 1 frames/s.
    let mut snap = LiveSnapshot::default();
    let rate = |snap: &mut LiveSnapshot| {
        system.snapshot(snap);
        snap.status.imaging_rate
    };
    wait_until("the imaging rate", || rate(&mut snap) > 0.0);
    let hz = rate(&mut snap);
    assert!(
        hz > 0.0 && hz <= IMAGING_RATE_SETTING + 1.0,
        "imaging at {hz} frames/s, scheduled {IMAGING_RATE_SETTING}"
    );

    system.page_closed();
    // The frame under way may finish; then the counter stays put.
    let mut last = frame(&system);
    wait_until("the imaging to idle", || {
        std::thread::sleep(Duration::from_millis(200));
        let now = frame(&system);
        std::mem::replace(&mut last, now) == now
    });
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(
        frame(&system),
        last,
        "frames rendered after the page closed"
    );
    // Idle, it says so: no rate.
    wait_until("the idle imaging rate", || rate(&mut snap) == 0.0);

    system.snapshot(&mut snap);
    assert_eq!(snap.fault, None);
    // Joined, with no error; a second shutdown has nothing left to stop.
    system.shutdown().unwrap();
    system.shutdown().unwrap();
}

/// Frames rendered over `span`, calling `hurry_image` every 5 ms if `hurry`.
fn frames_over(system: &LiveSystem, span: Duration, hurry: bool) -> u64 {
    let (start, first) = (Instant::now(), system.image_frame());
    while start.elapsed() < span {
        if hurry {
            system.hurry_image();
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    system.image_frame() - first
}

/// A front end hurrying the frames (issue 19: the frames answering a
/// command) gets them as fast as they render, at most one every 25 ms;
/// left alone the thread keeps its schedule. Over 2 s: the schedule gives
/// 2 R + 1 frames at most; hurried, the thread renders back to back when a
/// frame costs more than 25 ms, else every 25 ms (≤ 81 frames). Asserted:
/// hurried ≤ 81 and, when the unhurried frames kept the schedule (≥ 0.9 of
/// 2 R), hurried ≥ 1.2 of them, which a frame rendering in under 41 ms
/// gives (2 s / 41 ms = 48.8 ≥ 1.2 × 40). A machine that renders a frame in
/// 41–50 ms would fail it; this test profile renders one in under 25 ms
/// (measured: 39 frames on schedule, 80 hurried).
#[test]
fn hurried_frames_come_faster_than_the_schedule_and_never_burst() {
    let system = LiveSystem::start(Scenario::default()).unwrap();
    system.page_opened();
    wait_until("a first frame", || system.image_frame() >= 2);
    let span = Duration::from_secs(2);
    let scheduled = frames_over(&system, span, false);
    let hurried = frames_over(&system, span, true);
    eprintln!("frames in 2 s: {scheduled} on schedule, {hurried} hurried");
    let r = IMAGING_RATE_SETTING;
    assert!(
        scheduled as f64 <= 2.0 * r + 1.0,
        "{scheduled} frames on schedule"
    );
    assert!(
        hurried <= 81,
        "{hurried} hurried frames in 2 s: more than one every 25 ms"
    );
    if scheduled as f64 >= 0.9 * 2.0 * r {
        assert!(
            hurried as f64 >= 1.2 * scheduled as f64,
            "{hurried} hurried frames against {scheduled} on schedule"
        );
    }
    system.page_closed();
    system.shutdown().unwrap();
}
