//! The hot paths allocate nothing: encode/decode, the sequence filter, the
//! delay line, the in-process link with every fault on, and the UDP link.
//! One test function, so the counting allocator sees one thread's work.

mod common;

use echothigh_testkit::{count_allocations, CountingAllocator};
use echothigh_transport::{
    in_process_pair, open, seal, DatagramBuf, DatagramKey, DelayLine, FaultConfig, Link, LinkStats,
    Message, ProbeMsg, SampleMsg, SequenceFilter, MAX_DATAGRAM_SIZE,
};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn allocations_in(f: impl FnOnce()) -> u64 {
    count_allocations(f).1
}

fn probe(t: f64) -> Message {
    Message::Probe(ProbeMsg::new(t, [0.0, 0.08, t], [1.0, 0.0, 0.0, 0.0], 0))
}

#[test]
fn hot_paths_do_not_allocate() {
    // Codec.
    let msg = Message::Sample(SampleMsg {
        stiffness: 700.0,
        ..SampleMsg::default()
    });
    let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
    let key = DatagramKey::hello(&common::token(1));
    let n = allocations_in(|| {
        for _ in 0..1000 {
            let len = seal(&msg, &key, &mut buf).unwrap();
            assert!(open(&buf[..len], &key, 0).is_ok());
            assert!(open(&buf[..len - 1], &key, 0).is_err());
        }
    });
    assert_eq!(n, 0, "codec allocated");

    // Sequence filter and delay line.
    let faults = FaultConfig {
        latency: 0.002,
        jitter: 0.003,
        loss: 0.2,
        duplicate: 0.1,
        seed: 1,
    };
    let mut line: DelayLine<Message> = DelayLine::new(faults, 64);
    let mut filter = SequenceFilter::new();
    let mut stats = LinkStats::default();
    let n = allocations_in(|| {
        for i in 0..5000u32 {
            let now = f64::from(i) * 1e-3;
            line.push(probe(now), now, &mut stats);
            while let Some((_, m)) = line.pop_due(now) {
                filter.accept(m.seq(), &mut stats);
            }
        }
    });
    assert_eq!(n, 0, "delay line or filter allocated");

    // In-process link, every fault on, both directions.
    let (mut haptic, mut physics) = in_process_pair(9, faults, faults.with_seed(2));
    let n = allocations_in(|| {
        for i in 0..5000u32 {
            let now = f64::from(i) * 1e-3;
            haptic.send(probe(now), now).unwrap();
            physics.poll(now).unwrap();
            while let Some(m) = physics.recv(now).unwrap() {
                if let Message::Probe(p) = m {
                    let s = SampleMsg {
                        probe_seq: p.header.seq,
                        ..SampleMsg::default()
                    };
                    physics.send(Message::Sample(s), now).unwrap();
                }
            }
            while haptic.recv(now).unwrap().is_some() {}
            let _ = haptic.peer_silent(now, 0.05);
        }
    });
    assert_eq!(n, 0, "in-process link allocated");
    assert!(haptic.stats().received > 1000);

    // UDP link over loopback (set up outside the window).
    let (mut server, mut client) = common::session(&common::token(3), faults, faults.with_seed(4));
    let n = allocations_in(|| {
        for i in 0..2000u32 {
            let now = f64::from(i) * 1e-3;
            client.send(probe(now), now).unwrap();
            while let Some(m) = server.recv(now).unwrap() {
                let s = SampleMsg {
                    probe_seq: m.seq(),
                    ..SampleMsg::default()
                };
                server.send(Message::Sample(s), now).unwrap();
            }
            while client.recv(now).unwrap().is_some() {}
        }
    });
    assert_eq!(n, 0, "UDP link allocated");
    assert!(client.stats().received > 100);
}
