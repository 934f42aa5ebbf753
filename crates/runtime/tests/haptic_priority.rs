//! The haptic thread runs at real-time priority where permitted (issue 19:
//! "the simulation keeps its rates under load: real-time priority ... where
//! permitted"), and the live state says truly what it got: the kernel's
//! scheduling policy of the `haptic-loop` thread (`/proc/self/task/*/stat`,
//! field 41: 1 = SCHED_FIFO, 0 = SCHED_OTHER) matches the reported
//! priority. Linux only (the `/proc` interface).

#![cfg(target_os = "linux")]

use echothigh_runtime::live::{HapticPriority, LiveControl, LiveSnapshot};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::time::{Duration, Instant};

/// The scheduling policy of the thread named `name` (proc(5): field 41 of
/// `stat`, counted after the parenthesised command name).
fn policy_of(name: &str) -> Option<u32> {
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let dir = e.ok()?.path();
        let comm = std::fs::read_to_string(dir.join("comm")).ok()?;
        if comm.trim() != name {
            continue;
        }
        let stat = std::fs::read_to_string(dir.join("stat")).ok()?;
        let after = &stat[stat.rfind(')')? + 2..];
        // Fields from 3 (state) on: policy is field 41, the 39th here.
        return after.split_whitespace().nth(38)?.parse().ok();
    }
    None
}

/// Starts the live system with `scenario` and returns the reported
/// priority and the kernel's policy of its haptic thread.
fn priority_of(scenario: Scenario) -> (HapticPriority, u32) {
    let system = LiveSystem::start(scenario).unwrap();
    let mut snap = LiveSnapshot::default();
    let end = Instant::now() + Duration::from_secs(10);
    // The thread sets its priority as it starts: wait for the report.
    while Instant::now() < end {
        system.snapshot(&mut snap);
        if snap.status.haptic_priority != HapticPriority::Normal && snap.status.haptic_rate > 0.0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let reported = snap.status.haptic_priority;
    let policy = policy_of("haptic-loop").expect("the haptic-loop thread");
    system.shutdown().unwrap();
    (reported, policy)
}

/// One test, the two systems one after the other: the thread is found by
/// its name, which a second live system in the same process would share.
#[test]
fn the_reported_priority_is_the_kernels() {
    let (reported, policy) = priority_of(Scenario::default());
    eprintln!("haptic loop: reported {reported:?}, kernel policy {policy}");
    match reported {
        HapticPriority::Realtime => assert_eq!(policy, 1, "reported real-time, not SCHED_FIFO"),
        HapticPriority::Raised | HapticPriority::Normal => {
            assert_eq!(policy, 0, "reported {reported:?}, the kernel says {policy}")
        }
    }
    // Without `[haptics.runner] realtime_priority` the loop stays
    // time-shared, and says so.
    let mut s = Scenario::default();
    s.haptics.runner.realtime_priority = false;
    let (reported, policy) = priority_of(s);
    eprintln!("not asked: reported {reported:?}, kernel policy {policy}");
    assert_ne!(reported, HapticPriority::Realtime);
    assert_eq!(policy, 0, "not asked for, at policy {policy}");
}
