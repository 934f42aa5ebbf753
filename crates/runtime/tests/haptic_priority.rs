//! The haptic thread runs at real-time priority where permitted (issue 19:
//! "the simulation keeps its rates under load: real-time priority ... where
//! permitted"), and the live state says truly what it got: the kernel's
//! scheduling policy of the `haptic-loop` thread (`/proc/self/task/*/stat`,
//! field 41: 1 = SCHED_FIFO, 0 = SCHED_OTHER) matches the reported
//! priority. The physics thread runs FIFO too, below the haptic loop
//! (`PHYSICS_FIFO_PRIORITY`), so a busy browser cannot starve the model and
//! the tick still preempts it. Linux only (the `/proc` interface).

#![cfg(target_os = "linux")]

use echothigh_runtime::live::{HapticPriority, LiveControl, LiveSnapshot};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::time::{Duration, Instant};

/// The real-time priority and the scheduling policy of the thread named
/// `name` (proc(5): fields 40 and 41 of `stat`, counted after the
/// parenthesised command name).
fn sched_of(name: &str) -> Option<(u32, u32)> {
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let dir = e.ok()?.path();
        let comm = std::fs::read_to_string(dir.join("comm")).ok()?;
        if comm.trim() != name {
            continue;
        }
        let stat = std::fs::read_to_string(dir.join("stat")).ok()?;
        let after = &stat[stat.rfind(')')? + 2..];
        // Fields from 3 (state) on: rt_priority is field 40, the 38th here.
        let mut fields = after.split_whitespace().skip(37);
        let rt = fields.next()?.parse().ok()?;
        return Some((rt, fields.next()?.parse().ok()?));
    }
    None
}

/// What the kernel says of the haptic and the physics thread.
struct Threads {
    reported: HapticPriority,
    haptic: (u32, u32),
    physics: (u32, u32),
}

/// Starts the live system with `scenario` and returns the reported
/// priority and the kernel's (rt_priority, policy) of its haptic and
/// physics threads.
fn priority_of(scenario: Scenario) -> Threads {
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
    let haptic = sched_of("haptic-loop").expect("the haptic-loop thread");
    let physics = sched_of("physics").expect("the physics thread");
    system.shutdown().unwrap();
    Threads {
        reported,
        haptic,
        physics,
    }
}

/// One test, the two systems one after the other: the thread is found by
/// its name, which a second live system in the same process would share.
#[test]
fn the_reported_priority_is_the_kernels() {
    let t = priority_of(Scenario::default());
    let (reported, policy) = (t.reported, t.haptic.1);
    eprintln!(
        "haptic loop: reported {reported:?}, kernel (rt_priority, policy) {:?}; physics {:?}",
        t.haptic, t.physics
    );
    match reported {
        HapticPriority::Realtime => {
            assert_eq!(policy, 1, "reported real-time, not SCHED_FIFO");
            // Where the haptic loop got FIFO the physics got it too, lower.
            assert_eq!(t.physics.1, 1, "physics not SCHED_FIFO: {:?}", t.physics);
            assert_eq!(
                t.physics.0,
                u32::from(echothigh_runtime::physics_loop::PHYSICS_FIFO_PRIORITY)
            );
            assert!(
                t.physics.0 < t.haptic.0,
                "physics at {} is not below the haptic loop's {}",
                t.physics.0,
                t.haptic.0
            );
        }
        HapticPriority::Raised | HapticPriority::Normal => {
            assert_eq!(policy, 0, "reported {reported:?}, the kernel says {policy}")
        }
    }
    // Without `[haptics.runner] realtime_priority` both loops stay
    // time-shared, and the haptic loop says so.
    let mut s = Scenario::default();
    s.haptics.runner.realtime_priority = false;
    let t = priority_of(s);
    eprintln!(
        "not asked: reported {:?}, kernel haptic {:?}, physics {:?}",
        t.reported, t.haptic, t.physics
    );
    assert_ne!(t.reported, HapticPriority::Realtime);
    assert_eq!(t.haptic.1, 0, "not asked for, at policy {}", t.haptic.1);
    assert_eq!(
        t.physics.1, 0,
        "physics not asked for, at policy {}",
        t.physics.1
    );
}
