//! The UDP link over loopback: handshake, token, bind policy, exchange,
//! faults, peer silence, round trips.

use crate::common;

use common::{loopback, recv_wait, session, token};
use echothigh_transport::{
    bye_reason, connect, decode_any, round_trip, seal, DatagramBuf, DatagramKey, EchoResponder,
    FaultConfig, Header, HelloMsg, Link, LinkError, ListenConfig, Message, ProbeMsg, SampleMsg,
    UdpServer, MAX_DATAGRAM_SIZE, MAX_REJECTIONS_PER_S,
};
use std::net::UdpSocket;
use std::time::{Duration, Instant};

fn probe(t: f64) -> Message {
    Message::Probe(ProbeMsg::new(t, [0.01, 0.08, t], [1.0, 0.0, 0.0, 0.0], 0))
}

#[test]
fn handshake_then_both_directions() {
    let (mut server, mut client) = session(
        &token(0xfeed),
        FaultConfig::default(),
        FaultConfig::default(),
    );
    let seq = client.send(probe(0.25), 1.0).unwrap();
    let got = recv_wait(&mut server, 1.0).unwrap();
    match got {
        Message::Probe(p) => {
            assert_eq!(p.header.seq, seq);
            assert_eq!(p.header.session, server.session());
            assert_eq!(server.session(), client.session());
            assert_eq!(p.header.t_send, 1.0);
            assert_eq!(p.position, [0.01, 0.08, 0.25]);
        }
        other => panic!("expected a probe, got {other:?}"),
    }
    let sample = SampleMsg {
        probe_seq: seq,
        stiffness: 640.0,
        contact: echothigh_transport::contact_state::TOUCHING,
        ..SampleMsg::default()
    };
    server.send(Message::Sample(sample), 1.01).unwrap();
    match recv_wait(&mut client, 1.02).unwrap() {
        Message::Sample(s) => {
            assert_eq!(s.probe_seq, seq);
            assert_eq!(s.stiffness, 640.0);
        }
        other => panic!("expected a sample, got {other:?}"),
    }
    assert_eq!(client.last_heard(), Some(1.02));
    assert_eq!(server.stats().malformed, 0);
}

#[test]
fn wrong_token_is_rejected_and_the_right_client_still_gets_in() {
    let server = UdpServer::bind(&loopback()).unwrap();
    let addr = server.local_addr().unwrap();
    let accept = std::thread::spawn(move || {
        server.accept(
            &token(7),
            FaultConfig::default(),
            100.0,
            Duration::from_secs(5),
            0.0,
        )
    });
    let err = connect(
        addr,
        &token(8),
        FaultConfig::default(),
        Duration::from_secs(2),
        0.0,
    )
    .err()
    .expect("a wrong token must not connect");
    assert!(matches!(err, LinkError::Rejected { .. }), "{err}");
    assert!(err.to_string().contains("session token"));
    let (_client, _) = connect(
        addr,
        &token(7),
        FaultConfig::default(),
        Duration::from_secs(2),
        0.0,
    )
    .unwrap();
    let server = accept.join().unwrap().unwrap();
    assert!(server.stats().wrong_token >= 1);
}

#[test]
fn accept_times_out_with_a_clear_error() {
    let server = UdpServer::bind(&loopback()).unwrap();
    let err = server
        .accept(
            &token(1),
            FaultConfig::default(),
            100.0,
            Duration::from_millis(50),
            0.0,
        )
        .err()
        .unwrap();
    assert!(matches!(err, LinkError::AcceptTimeout { .. }), "{err}");
}

#[test]
fn connect_to_nobody_times_out_naming_the_address() {
    // A bound socket that never answers.
    let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
    let addr = silent.local_addr().unwrap();
    let err = connect(
        addr,
        &token(1),
        FaultConfig::default(),
        Duration::from_millis(100),
        0.0,
    )
    .err()
    .unwrap();
    assert!(matches!(err, LinkError::HandshakeTimeout { .. }), "{err}");
    assert!(err.to_string().contains(&addr.to_string()));
}

#[test]
fn non_loopback_bind_is_refused_without_allow_remote() {
    let mut config = ListenConfig {
        addr: "0.0.0.0:0".parse().unwrap(),
        allow_remote: false,
    };
    let err = UdpServer::bind(&config).err().unwrap();
    assert!(matches!(err, LinkError::RemoteNotAllowed { .. }));
    assert!(err.to_string().contains("--allow-remote"));
    config.allow_remote = true;
    assert!(UdpServer::bind(&config).is_ok());
}

#[test]
fn peer_silence_is_detected_after_the_server_goes_away() {
    let (mut server, mut client) =
        session(&token(3), FaultConfig::default(), FaultConfig::default());
    server
        .send(Message::Sample(SampleMsg::default()), 1.0)
        .unwrap();
    assert!(recv_wait(&mut client, 1.0).is_some());
    assert!(!client.peer_silent(1.1, 0.25));
    drop(server); // killed: no Bye
    for i in 0..5 {
        let now = 1.1 + 0.1 * f64::from(i);
        client.send(probe(now), now).unwrap(); // ICMP refusals are survived
        assert!(client.recv(now).unwrap().is_none());
    }
    assert!(client.peer_silent(1.5, 0.25));
    assert!(!client.peer_closed());
}

#[test]
fn clean_shutdown_is_reported_as_peer_closed() {
    let (mut server, mut client) =
        session(&token(3), FaultConfig::default(), FaultConfig::default());
    server.close(2.0).unwrap();
    assert!(matches!(recv_wait(&mut client, 2.0), Some(Message::Bye(_))));
    assert!(client.peer_closed());
    assert!(client.peer_silent(2.0, 10.0));
}

#[test]
fn duplicated_datagrams_are_delivered_once() {
    let faults = FaultConfig {
        duplicate: 1.0,
        ..FaultConfig::default()
    };
    let (mut server, mut client) = session(&token(4), FaultConfig::default(), faults);
    for i in 0..20 {
        let now = f64::from(i) * 1e-3;
        let seq = client.send(probe(now), now).unwrap();
        assert_eq!(recv_wait(&mut server, now).unwrap().seq(), seq);
    }
    // Drain: every second copy must be dropped as a duplicate.
    let start = Instant::now();
    while server.stats().duplicate < 20 && start.elapsed() < Duration::from_secs(1) {
        assert!(server.recv(1.0).unwrap().is_none());
    }
    assert_eq!(server.stats().duplicate, 20);
    assert_eq!(server.stats().received, 20);
}

/// 300 wrong-token Hellos from one source within a second (issue 20: one
/// reply and one log line each) get one rejecting reply; every one is
/// counted; the right client still gets in.
#[test]
fn wrong_token_hellos_get_one_reply_per_second_and_are_counted() {
    let server = UdpServer::bind(&loopback()).unwrap();
    let addr = server.local_addr().unwrap();
    let accept = std::thread::spawn(move || {
        server.accept(
            &token(7),
            FaultConfig::default(),
            100.0,
            Duration::from_secs(10),
            0.0,
        )
    });
    let attacker = UdpSocket::bind("127.0.0.1:0").unwrap();
    attacker.connect(addr).unwrap();
    let wrong = DatagramKey::hello(&token(8));
    let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
    let n = 300u64;
    let start = Instant::now();
    for i in 0..n {
        let hello = Message::Hello(HelloMsg {
            header: Header {
                seq: i,
                ..Header::default()
            },
            nonce: 1000 + i,
            _reserved: 0,
        });
        let len = seal(&hello, &wrong, &mut buf).unwrap();
        attacker.send(&buf[..len]).unwrap();
        // Paced (300 in ~0.1 s) so that the socket's receive buffer, not
        // the server, is never what drops them.
        std::thread::sleep(Duration::from_micros(300));
    }
    // The replies: 1 within the first second from this one source.
    attacker
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let mut replies = 0;
    let mut back = [0u8; 256];
    while let Ok(m) = attacker.recv(&mut back) {
        match decode_any(&back[..m]).unwrap() {
            Message::Bye(b) => {
                assert_eq!(b.reason, bye_reason::REJECTED);
                assert!(
                    (1000..1000 + n).contains(&b.nonce),
                    "echoes a Hello's nonce"
                );
            }
            other => panic!("expected a rejection, got {other:?}"),
        }
        replies += 1;
    }
    let within_a_second = start.elapsed() < Duration::from_secs(1);
    let (_client, _) = connect(
        addr,
        &token(7),
        FaultConfig::default(),
        Duration::from_secs(2),
        0.0,
    )
    .unwrap();
    let server = accept.join().unwrap().unwrap();
    let s = server.stats();
    assert_eq!(s.wrong_token, n, "{s:?}");
    assert_eq!(s.rejections_sent + s.rejections_suppressed, n);
    if within_a_second {
        // All sent and read within one second: one reply, at most.
        assert_eq!(replies, 1);
        assert_eq!(s.rejections_sent, 1);
    }
    assert!(s.rejections_sent <= u64::from(MAX_REJECTIONS_PER_S) * 2);
}

#[test]
fn echo_round_trips_over_loopback() {
    let (server, mut client) = session(&token(5), FaultConfig::default(), FaultConfig::default());
    let responder = EchoResponder::spawn(server);
    let clock = Instant::now();
    let mut rtts = Vec::new();
    for i in 0..100 {
        let p = ProbeMsg::new(f64::from(i), [0.0; 3], [1.0, 0.0, 0.0, 0.0], 0);
        rtts.push(round_trip(&mut client, p, clock, Duration::from_secs(2)).unwrap());
    }
    client.close(clock.elapsed().as_secs_f64()).unwrap();
    let stats = responder.stop().unwrap();
    assert!(stats.received >= 100);
    assert!(rtts.iter().all(|&r| r > 0.0 && r < 2.0));
}

/// Issue 20, item 1: the server reads its clock before the accept wait; a
/// client that arrives later than the peer timeout must not be taken as
/// already silent. The Hello is heard at the caller's clock plus the wait
/// (`now` + elapsed), so 3 s after a wait that began at t = 0 the session
/// is fresh for a 2 s peer timeout (here 2.6 s after). Fails when `accept` records `now` alone
/// (last heard 0 s, silent at 2.6 s).
#[test]
fn a_client_arriving_after_the_peer_timeout_is_not_silent() {
    let server = UdpServer::bind(&loopback()).unwrap();
    let addr = server.local_addr().unwrap();
    let t = token(0x1a7e);
    let accept = std::thread::spawn(move || {
        let started = Instant::now();
        let link = server.accept(
            &t,
            FaultConfig::default(),
            100.0,
            Duration::from_secs(20),
            0.0,
        );
        (link, started.elapsed().as_secs_f64())
    });
    std::thread::sleep(Duration::from_millis(2600));
    let _client = connect(
        addr,
        &t,
        FaultConfig::default(),
        Duration::from_secs(5),
        0.0,
    )
    .unwrap();
    let (link, waited) = accept.join().unwrap();
    let link = link.unwrap();
    assert!(waited > 2.5, "the accept returned after {waited} s");
    // The caller's clock when accept returned: 0 + the wait.
    assert!(
        !link.peer_silent(waited, 2.0),
        "a client heard {waited:.2} s into the accept is taken as silent"
    );
}
