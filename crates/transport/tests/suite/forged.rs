//! Forged datagrams against a live UDP session (issue 20, item 7), from
//! the position of an attacker on the path: the client talks to the server
//! through a relay on loopback that records every datagram and can inject
//! its own, which the server sees as coming from its client. Cases: the
//! maximum sequence, an absurd pose, a replay of captured datagrams, a
//! wrong tag, a datagram of another session, a forged Bye, 2000 random bad
//! datagrams. After each, the real client must still be in control: its
//! next probe is the one the server delivers, the server's sample reaches
//! it, and every forged datagram is counted by reason, none delivered.

use crate::common;

use common::{recv_wait, token};
use echothigh_transport::{
    connect, in_process_pair, Endpoint, FaultConfig, Link, LinkError, LinkStats, MemoryTransport,
    Message, ProbeMsg, SampleMsg, Transport, UdpEndpoint, UdpServer, MAX_SEQ_JUMP,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A loopback relay between one client and one server.
struct Relay {
    socket: UdpSocket,
    addr: SocketAddr,
    server: SocketAddr,
    client: Arc<Mutex<Option<SocketAddr>>>,
    /// Client → server datagrams seen.
    captured: Arc<Mutex<Vec<Vec<u8>>>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl Relay {
    fn start(server: SocketAddr) -> Relay {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        socket
            .set_read_timeout(Some(Duration::from_millis(5)))
            .unwrap();
        let addr = socket.local_addr().unwrap();
        let (client, captured, stop) = (
            Arc::new(Mutex::new(None)),
            Arc::new(Mutex::new(Vec::new())),
            Arc::new(AtomicBool::new(false)),
        );
        let (s, c, cap, st) = (
            socket.try_clone().unwrap(),
            Arc::clone(&client),
            Arc::clone(&captured),
            Arc::clone(&stop),
        );
        let handle = std::thread::spawn(move || {
            let mut buf = [0u8; 2048];
            while !st.load(Ordering::Relaxed) {
                let Ok((n, from)) = s.recv_from(&mut buf) else {
                    continue;
                };
                if from == server {
                    if let Some(to) = *c.lock().unwrap() {
                        let _ = s.send_to(&buf[..n], to);
                    }
                } else {
                    *c.lock().unwrap() = Some(from);
                    cap.lock().unwrap().push(buf[..n].to_vec());
                    let _ = s.send_to(&buf[..n], server);
                }
            }
        });
        Relay {
            socket,
            addr,
            server,
            client,
            captured,
            stop,
            handle: Some(handle),
        }
    }

    /// Sends `bytes` to the server as if from the client.
    fn to_server(&self, bytes: &[u8]) {
        self.socket.send_to(bytes, self.server).unwrap();
    }

    /// Sends `bytes` to the client as if from the server.
    fn to_client(&self, bytes: &[u8]) {
        let to = self.client.lock().unwrap().expect("client seen");
        self.socket.send_to(bytes, to).unwrap();
    }

    /// The last captured client → server datagram of `len` bytes.
    fn last_of_len(&self, len: usize) -> Vec<u8> {
        let cap = self.captured.lock().unwrap();
        cap.iter().rev().find(|d| d.len() == len).unwrap().clone()
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// A session through a relay: (server, client, relay).
fn relayed_session(n: u64) -> (UdpEndpoint, UdpEndpoint, Relay) {
    let server = UdpServer::bind(&common::loopback()).unwrap();
    let relay = Relay::start(server.local_addr().unwrap());
    let t = token(n);
    let accept = std::thread::spawn(move || {
        server.accept(
            &t,
            FaultConfig::default(),
            100.0,
            Duration::from_secs(5),
            0.0,
        )
    });
    let (client, _) = connect(
        relay.addr,
        &token(n),
        FaultConfig::default(),
        Duration::from_secs(5),
        0.0,
    )
    .unwrap();
    (accept.join().unwrap().unwrap(), client, relay)
}

fn probe(x: f64) -> Message {
    Message::Probe(ProbeMsg::new(x, [x, 0.08, 0.0], [1.0, 0.0, 0.0, 0.0], 0))
}

/// Waits until `link`'s rejections reach `target` (wall clock, 2 s),
/// asserting nothing is delivered meanwhile.
fn drain_until_rejected(link: &mut UdpEndpoint, target: u64, now: f64) {
    let start = Instant::now();
    while link.stats().rejected() < target && start.elapsed() < Duration::from_secs(2) {
        let got = link.recv(now).unwrap();
        assert!(got.is_none(), "a forged datagram was delivered: {got:?}");
        std::thread::sleep(Duration::from_micros(200));
    }
    assert_eq!(link.stats().rejected(), target, "{:?}", link.stats());
}

/// The real client sends a probe at `x` and gets the server's answer.
fn client_in_control(server: &mut UdpEndpoint, client: &mut UdpEndpoint, x: f64, now: f64) {
    let seq = client.send(probe(x), now).unwrap();
    match recv_wait(server, now) {
        Some(Message::Probe(p)) => {
            assert_eq!(p.header.seq, seq);
            assert_eq!(p.position[0], x, "the server follows the real client");
        }
        other => panic!("expected the client's probe, got {other:?}"),
    }
    let answer = SampleMsg {
        probe_seq: seq,
        stiffness: 700.0,
        ..SampleMsg::default()
    };
    server.send(Message::Sample(answer), now).unwrap();
    match recv_wait(client, now) {
        Some(Message::Sample(s)) => assert_eq!(s.probe_seq, seq),
        other => panic!("expected the server's sample, got {other:?}"),
    }
    assert!(!server.peer_closed() && !client.peer_closed());
    assert!(!server.peer_silent(now, 1.0) && !client.peer_silent(now, 1.0));
}

fn set_f64(d: &mut [u8], at: usize, v: f64) {
    d[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

fn set_u64(d: &mut [u8], at: usize, v: u64) {
    d[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn forged_datagrams_leave_the_real_client_in_control() {
    let (mut server, mut client, relay) = relayed_session(0x1234_5678);
    let (mut other_server, mut other_client, other_relay) = relayed_session(0x1234_5678);
    assert_ne!(
        server.session(),
        other_server.session(),
        "fresh keys per session"
    );
    client_in_control(&mut server, &mut client, 0.001, 1.0);
    client_in_control(&mut other_server, &mut other_client, 0.5, 1.0);
    let probe_len = echothigh_transport::Kind::Probe.size() + echothigh_transport::MAC_LEN;
    let sample_len = echothigh_transport::Kind::Sample.size() + echothigh_transport::MAC_LEN;
    let captured = relay.last_of_len(probe_len);
    let base = server.stats();
    let mut expected = base.rejected();

    // 1. Sequence 2⁶⁴−1 (header: magic 4, version 2, kind 2, session 8, seq 8).
    let mut d = captured.clone();
    set_u64(&mut d, 16, u64::MAX);
    relay.to_server(&d);
    expected += 1;
    drain_until_rejected(&mut server, expected, 1.1);
    assert_eq!(server.stats().bad_mac, base.bad_mac + 1);
    client_in_control(&mut server, &mut client, 0.002, 1.1);

    // 2. An absurd pose: position[1] = 1e300 (32 header + 8 t_device + 8).
    let mut d = captured.clone();
    set_f64(&mut d, 48, 1e300);
    relay.to_server(&d);
    expected += 1;
    drain_until_rejected(&mut server, expected, 1.2);
    assert_eq!(server.stats().bad_mac, base.bad_mac + 2);
    client_in_control(&mut server, &mut client, 0.003, 1.2);
    // The real client cannot send one either.
    let absurd = ProbeMsg::new(1.2, [0.0, 1e300, 0.0], [1.0, 0.0, 0.0, 0.0], 0);
    let e = client.send(Message::Probe(absurd), 1.2).unwrap_err();
    assert!(
        matches!(e, LinkError::Encode(_)) && e.to_string().contains("position"),
        "{e}"
    );

    // 3. Replays of every captured, correctly tagged probe.
    let before = server.stats();
    let all: Vec<Vec<u8>> = relay
        .captured
        .lock()
        .unwrap()
        .iter()
        .filter(|d| d.len() == probe_len)
        .cloned()
        .collect();
    assert!(all.len() >= 3);
    for d in &all {
        relay.to_server(d);
    }
    expected += all.len() as u64;
    drain_until_rejected(&mut server, expected, 1.3);
    let after = server.stats();
    assert_eq!(
        after.duplicate + after.stale - before.duplicate - before.stale,
        all.len() as u64,
        "replays are refused by sequence"
    );
    client_in_control(&mut server, &mut client, 0.004, 1.3);

    // 4. A wrong tag (one bit of the tag flipped).
    let mut d = captured.clone();
    let last = d.len() - 1;
    d[last] ^= 1;
    relay.to_server(&d);
    expected += 1;
    drain_until_rejected(&mut server, expected, 1.4);
    assert_eq!(server.stats().bad_mac, base.bad_mac + 3);
    client_in_control(&mut server, &mut client, 0.005, 1.4);

    // 5. A datagram of another session, tagged with that session's key,
    //    with a sequence far ahead.
    let foreign = other_relay.last_of_len(probe_len);
    relay.to_server(&foreign);
    expected += 1;
    drain_until_rejected(&mut server, expected, 1.5);
    assert_eq!(server.stats().wrong_session, base.wrong_session + 1);
    client_in_control(&mut server, &mut client, 0.006, 1.5);

    // 6. A forged Bye (a probe datagram relabelled: kind 5, Bye's size).
    let mut d = captured[..echothigh_transport::Kind::Bye.size()].to_vec();
    d[6] = 5;
    d.extend_from_slice(&[0u8; 16]);
    relay.to_server(&d);
    expected += 1;
    drain_until_rejected(&mut server, expected, 1.6);
    assert!(
        !server.peer_closed(),
        "a forged Bye does not end the session"
    );
    client_in_control(&mut server, &mut client, 0.007, 1.6);

    // 7. Towards the client: a sample with sequence 2⁶⁴−1 and a replay.
    let cbase = client.stats().rejected();
    let mut d = vec![0u8; sample_len];
    d[..4].copy_from_slice(b"ETHG");
    d[4] = 2;
    d[6] = 2;
    set_u64(&mut d, 8, client.session());
    set_u64(&mut d, 16, u64::MAX);
    relay.to_client(&d);
    drain_until_rejected(&mut client, cbase + 1, 1.7);
    assert_eq!(client.stats().bad_mac, 1);
    client_in_control(&mut server, &mut client, 0.008, 1.7);

    // 8. 2000 random bad datagrams: random bytes, truncations, mutations.
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let n = 2000u64;
    for i in 0..n {
        let d = match rng.gen_range(0..3) {
            0 => (0..rng.gen_range(0..300)).map(|_| rng.gen()).collect(),
            1 => captured[..rng.gen_range(0..captured.len())].to_vec(),
            _ => {
                let mut d = captured.clone();
                let at = rng.gen_range(0..d.len());
                d[at] ^= rng.gen_range(1..=255u8);
                d
            }
        };
        relay.to_server(&d);
        if i % 50 == 49 {
            expected += 50;
            drain_until_rejected(&mut server, expected, 1.8);
        }
    }
    client_in_control(&mut server, &mut client, 0.009, 1.8);

    let s = server.stats();
    let delta = |f: fn(&LinkStats) -> u64| f(&s) - f(&base);
    assert!(delta(|s| s.bad_mac) > 4, "{s:?}");
    assert!(delta(|s| s.malformed) > 0, "{s:?}");
    assert_eq!(delta(|s| s.received), 8, "only the real client's probes");
    drop(other_client);
    drop(other_server);
}

/// The sequence bound on a link whose datagrams carry no tag (in-process,
/// or a peer holding the key): 2⁶⁴−1 and any jump beyond `MAX_SEQ_JUMP` are
/// refused and counted, and the real sender goes on.
#[test]
fn far_ahead_sequences_cannot_freeze_a_link() {
    let (mut raw, other) = MemoryTransport::pair();
    let mut physics = Endpoint::new(other, 7, FaultConfig::default());
    let (mut haptic, _unused) = in_process_pair(7, FaultConfig::default(), FaultConfig::default());
    let mut stats = LinkStats::default();
    let mut send = |seq: u64, x: f64, physics: &mut Endpoint<MemoryTransport>| {
        let mut m = probe(x);
        let h = m.header_mut();
        h.session = 7;
        h.seq = seq;
        raw.transmit(&m, &mut stats).unwrap();
        physics.recv(0.0).unwrap()
    };
    assert!(send(1, 0.01, &mut physics).is_some());
    assert!(send(u64::MAX, 9.0, &mut physics).is_none());
    assert!(send(2 + MAX_SEQ_JUMP, 9.0, &mut physics).is_none());
    assert_eq!(physics.stats().seq_jump, 2);
    match send(2, 0.02, &mut physics) {
        Some(Message::Probe(p)) => assert_eq!(p.position[0], 0.02),
        other => panic!("the real sender was frozen out: {other:?}"),
    }
    // Sending checks values on the in-process link too.
    let e = haptic.send(probe(f64::NAN), 0.0).unwrap_err();
    assert!(e.to_string().contains("t_device"), "{e}");
}
