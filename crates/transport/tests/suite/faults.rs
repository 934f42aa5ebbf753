//! The link under the hostile conditions (20 % loss, 5 ms jitter,
//! duplication) at 1 kHz, on a virtual clock: what comes out is in
//! sequence order, fresh, finite, and as much as the loss allows.

use echothigh_transport::{in_process_pair, FaultConfig, Link, Message, ProbeMsg};

#[test]
fn lossy_jittery_duplicating_link_delivers_latest_in_order() {
    let faults = FaultConfig {
        latency: 0.001,
        jitter: 0.005,
        loss: 0.2,
        duplicate: 0.1,
        seed: 42,
    };
    let (mut haptic, mut physics) = in_process_pair(1, faults, FaultConfig::default());
    let n = 2000u32; // 2 s at 1 kHz
    let mut last_seq = None;
    let mut delivered = 0u64;
    let mut max_age: f64 = 0.0;
    for i in 0..n {
        let now = f64::from(i) * 1e-3;
        let p = ProbeMsg::new(now, [0.0, 0.1, now], [1.0, 0.0, 0.0, 0.0], 0);
        haptic.send(Message::Probe(p), now).unwrap();
        while let Some(m) = physics.recv(now).unwrap() {
            let Message::Probe(p) = m else {
                panic!("unexpected {m:?}")
            };
            assert!(!matches!(last_seq, Some(l) if p.header.seq <= l));
            assert!(p.position.iter().all(|x| x.is_finite()));
            last_seq = Some(p.header.seq);
            max_age = max_age.max(now - p.header.t_send);
            delivered += 1;
        }
    }
    let h = haptic.stats();
    let r = physics.stats();
    assert_eq!(h.sent, u64::from(n));
    let in_flight = haptic.in_flight() as u64;
    assert_eq!(
        h.transmitted + h.fault_lost + in_flight,
        h.sent + h.fault_duplicated
    );
    // Delay is latency + U(0, jitter), read at 1 ms granularity.
    assert!(max_age <= 0.001 + 0.005 + 0.001 + 1e-12, "{max_age}");
    // Jitter reorders, duplication repeats: the filter dropped both kinds.
    assert!(r.stale > 50, "{r:?}");
    assert!(r.duplicate + r.stale + r.overwritten > 0);
    // Every datagram that reached the receiver is accounted for: accepted,
    // stale, duplicate, or overwritten in the single slot before a read.
    assert_eq!(delivered, r.received);
    assert_eq!(
        r.received + r.stale + r.duplicate + r.overwritten,
        h.transmitted
    );
    // The latest still gets through often: more than a quarter of the ticks.
    assert!(delivered > 500, "{delivered}");
    assert!(!physics.peer_silent(f64::from(n) * 1e-3, 0.05));
}
