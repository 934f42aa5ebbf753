//! The haptic client's startup grace (fault path, `client.rs`): a physics
//! side that answers at once but sends its first sample only after the
//! peer timeout is waited for, not taken for lost. Over UDP the handshake's
//! Welcome marks the server heard, and the server steps only once the
//! client's first pose has reached it; here the physics end sends one
//! message at t = 0 (heard, not a sample, as the Welcome), then its samples
//! from 0.6 s on: past the 0.25 s peer timeout, inside the 2 s grace. Before
//! the fix the client declared the physics lost at 0.25 s with no sample
//! (seen in `app/tests/suite/faults.rs` on two busy cores).

use echothigh_runtime::client::{run_client, ClientConfig, ClientEnd, LoopParts};
use echothigh_runtime::deploy::scripted_device;
use echothigh_runtime::haptic_side::haptic_side_for;
use echothigh_runtime::physics_loop::{physics_loop, Clock};
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::recorder::RecordSink;
use echothigh_runtime::scenario::Scenario;
use echothigh_transport::{Link, Message, ProbeMsg};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

#[test]
fn a_first_sample_after_the_peer_timeout_is_waited_for() {
    let mut s = Scenario::builtin().unwrap();
    s.run.duration = 1.5;
    let peer_timeout = s.coupling.peer_timeout;
    assert!(peer_timeout < 0.6, "the delay must exceed the peer timeout");
    let (haptic_end, mut physics_end) = s.in_process_link();
    let mut physics = PhysicsSide::new(&s).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let physics_stop = Arc::new(AtomicBool::new(false));
    let ps = physics_stop.clone();
    let rate = s.coupling.physics_rate;
    let server = std::thread::spawn(move || {
        let clock = Clock::start();
        // Heard, but not a sample (stands for the handshake's Welcome).
        let hello = ProbeMsg::new(0.0, [0.0; 3], [1.0, 0.0, 0.0, 0.0], 0);
        physics_end
            .send(Message::Probe(hello), clock.now())
            .unwrap();
        std::thread::sleep(Duration::from_millis(600));
        let mut discard = RecordSink::Discard;
        physics_loop(
            &mut physics,
            &mut physics_end,
            clock,
            &ps,
            rate,
            peer_timeout,
            &mut discard,
        )
        .unwrap()
    });
    let (sink, source) = haptic_side_for(s.coupling.mode, &s).unwrap();
    let parts = LoopParts {
        device: scripted_device(&s).unwrap(),
        source,
        scale: s.device().force_scale(),
        direct_physics: None,
    };
    let config = ClientConfig {
        loop_config: &s.haptics.runner,
        duration: s.run.duration,
        peer_timeout,
        stop: stop.clone(),
        orientation: s.probe_orientation().unwrap(),
    };
    let report = run_client(
        Some(Box::new(haptic_end)),
        sink,
        parts,
        config,
        RecordSink::Discard,
    )
    .unwrap();
    physics_stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
    assert_eq!(
        report.end,
        ClientEnd::Completed,
        "lost at {:?} s with {} samples",
        report.lost_at,
        report.samples
    );
    // 0.9 s of samples at ~100 Hz: well over one.
    assert!(report.samples > 10, "{} samples", report.samples);
}
