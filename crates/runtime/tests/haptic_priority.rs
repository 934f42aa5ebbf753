//! The haptic thread runs at real-time priority where permitted (issue 19:
//! "the simulation keeps its rates under load: real-time priority ... where
//! permitted"), and the live state says truly what it got: the kernel's
//! scheduling policy of the `haptic-loop` thread (`/proc/self/task/*/stat`,
//! field 41: 1 = SCHED_FIFO, 0 = SCHED_OTHER) matches the reported
//! priority. The physics thread runs FIFO too, below the haptic loop
//! (`PHYSICS_FIFO_PRIORITY`), so a busy browser cannot starve the model and
//! the tick still preempts it. The imaging thread stays time-shared, at
//! nice `IMAGING_NICE` where it may be raised (field 19). Linux only (the
//! `/proc` interface).

#![cfg(target_os = "linux")]

use echothigh_runtime::live::{HapticPriority, LiveControl, LiveSnapshot};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::time::{Duration, Instant};

/// The real-time priority and the scheduling policy of the thread named
/// `name` (proc(5): fields 40 and 41 of `stat`, counted after the
/// parenthesised command name).
fn sched_of(name: &str) -> Option<(u32, u32)> {
    let f = stat_of(name)?;
    // Fields from 3 (state) on: rt_priority is field 40, the 38th here.
    Some((f.get(37)?.parse().ok()?, f.get(38)?.parse().ok()?))
}

/// The nice value of the thread named `name` (proc(5): field 19).
fn nice_of(name: &str) -> Option<i32> {
    stat_of(name)?.get(16)?.parse().ok()
}

/// The fields of `/proc/self/task/*/stat` from field 3 (state) on, of the
/// newest thread named `name`. (An unnamed thread takes its creator's
/// name: the rayon pool that the first imaging thread starts for its beam
/// tables is named "imaging" too, and outlives that live system; the newest
/// of the name is the running system's imaging thread, or a pool thread it
/// started, with its nice value.)
fn stat_of(name: &str) -> Option<Vec<String>> {
    let mut newest: Option<(u64, Vec<String>)> = None;
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let dir = e.ok()?.path();
        let comm = std::fs::read_to_string(dir.join("comm")).ok()?;
        if comm.trim() != name {
            continue;
        }
        let tid: u64 = dir.file_name()?.to_str()?.parse().ok()?;
        let stat = std::fs::read_to_string(dir.join("stat")).ok()?;
        let after = &stat[stat.rfind(')')? + 2..];
        if newest.as_ref().is_none_or(|(t, _)| tid > *t) {
            newest = Some((tid, after.split_whitespace().map(str::to_owned).collect()));
        }
    }
    newest.map(|(_, f)| f)
}

/// What the kernel says of the haptic and the physics thread.
struct Threads {
    reported: HapticPriority,
    haptic: (u32, u32),
    physics: (u32, u32),
    /// The imaging thread's (policy, nice).
    imaging: (u32, i32),
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
    // The imaging thread sets its nice value as it starts.
    let imaging = loop {
        let i = (
            sched_of("imaging").expect("the imaging thread").1,
            nice_of("imaging").expect("its nice value"),
        );
        if i.1 != 0 || Instant::now() > end {
            break i;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    system.shutdown().unwrap();
    Threads {
        reported,
        haptic,
        physics,
        imaging,
    }
}

/// One test, the two systems one after the other: the thread is found by
/// its name, which a second live system in the same process would share.
#[test]
fn the_reported_priority_is_the_kernels() {
    let t = priority_of(Scenario::default());
    let (reported, policy) = (t.reported, t.haptic.1);
    eprintln!(
        "haptic loop: reported {reported:?}, kernel (rt_priority, policy) {:?}; physics {:?}; imaging (policy, nice) {:?}",
        t.haptic, t.physics, t.imaging
    );
    // The imaging thread is never real-time.
    assert_eq!(t.imaging.0, 0, "imaging at policy {}", t.imaging.0);
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
            // The privilege that grants FIFO grants a lower nice value.
            assert_eq!(t.imaging.1, echothigh_runtime::live_system::IMAGING_NICE);
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
    assert_eq!(t.imaging, (0, 0), "imaging not asked for");
}
