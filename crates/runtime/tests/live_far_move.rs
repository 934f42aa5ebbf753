//! A probe placed far from where it presses goes over the skin, not through
//! the leg (issue 12's force spikes, issue 19's transitions): pressed 12 mm
//! on the front of the thigh, then placed 12 mm deep on its back 10 cm
//! further down, the live system's simulated hand lifts, travels over the
//! lifted surface and comes down. A straight path would drive the probe
//! through the thigh (tens of newtons; 20–30 N seen in the browser's exam).

use echothigh_runtime::live::{LiveCommand, LiveControl, LiveSnapshot};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::time::{Duration, Instant};

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Samples the live state every 2 ms for `secs` (wall clock): (physics
/// force N, device position m).
fn watch(system: &LiveSystem, secs: f64) -> Vec<(f64, [f64; 3])> {
    let mut snap = LiveSnapshot::default();
    let mut out = Vec::new();
    let end = Instant::now() + Duration::from_secs_f64(secs);
    while Instant::now() < end {
        system.snapshot(&mut snap);
        out.push((norm(snap.status.physics_force), snap.status.device));
        std::thread::sleep(Duration::from_millis(2));
    }
    out
}

#[test]
fn a_far_placement_travels_over_the_skin() {
    let system = LiveSystem::start(Scenario::default()).unwrap();
    let probe = |theta, z| LiveCommand::Probe {
        theta,
        z,
        depth: 0.012,
        tilt: 0.0,
    };
    system.command(probe(0.3, 0.0)).unwrap();
    let settle = watch(&system, 3.0);
    let (f_front, _) = *settle.last().unwrap();
    assert!(f_front > 1.0, "the front press pushes: {f_front} N");
    // The destination's device position, known once it has settled there.
    system.command(probe(-2.6, -0.1)).unwrap();
    let travel = watch(&system, 5.0);
    let (f_back, dest) = *travel.last().unwrap();
    assert!(f_back > 1.0, "the back press pushes: {f_back} N");
    // While the device is more than 25 mm from its destination (lifting,
    // travelling, until the last descent), the probe never presses harder
    // than it did at the start: the force only falls as it lifts. 0.5 N
    // covers the settled force's ripple (hundredths of a newton) and the
    // first millisecond of the lift.
    let far: Vec<f64> = travel
        .iter()
        .filter(|(_, p)| norm([p[0] - dest[0], p[1] - dest[1], p[2] - dest[2]]) > 0.025)
        .map(|(f, _)| *f)
        .collect();
    assert!(far.len() > 100, "the travel took {} samples", far.len());
    let peak = far.iter().cloned().fold(0.0, f64::max);
    assert!(
        peak <= f_front + 0.5,
        "{peak:.2} N on the way, {f_front:.2} N at the start"
    );
    // And it was off the skin for part of the way.
    assert!(far.iter().any(|&f| f < 0.05), "never off the skin");
    system.shutdown().unwrap();
}
