//! The UDP link over loopback: handshake, token, bind policy, exchange,
//! faults, peer silence, round trips.

mod common;

use common::{loopback, recv_wait, session};
use echothigh_transport::{
    connect, encode, round_trip, DatagramBuf, EchoResponder, FaultConfig, Header, HelloMsg, Link,
    LinkError, ListenConfig, Message, ProbeMsg, SampleMsg, UdpServer, MAX_MESSAGE_SIZE,
};
use std::net::UdpSocket;
use std::time::{Duration, Instant};

fn probe(t: f64) -> Message {
    Message::Probe(ProbeMsg::new(t, [0.01, 0.08, t], [1.0, 0.0, 0.0, 0.0], 0))
}

#[test]
fn handshake_then_both_directions() {
    let (mut server, mut client) = session(0xfeed, FaultConfig::default(), FaultConfig::default());
    let seq = client.send(probe(0.25), 1.0).unwrap();
    let got = recv_wait(&mut server, 1.0).unwrap();
    match got {
        Message::Probe(p) => {
            assert_eq!(p.header.seq, seq);
            assert_eq!(p.header.token, 0xfeed);
            assert_eq!(p.header.t_send, 1.0);
            assert_eq!(p.position, [0.01, 0.08, 0.25]);
        }
        other => panic!("expected a probe, got {other:?}"),
    }
    let sample = SampleMsg {
        probe_seq: seq,
        stiffness: 640.0,
        in_contact: 1,
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
            7,
            FaultConfig::default(),
            100.0,
            Duration::from_secs(5),
            0.0,
        )
    });
    let err = connect(addr, 8, FaultConfig::default(), Duration::from_secs(2), 0.0)
        .err()
        .expect("a wrong token must not connect");
    assert!(matches!(err, LinkError::Rejected { .. }), "{err}");
    assert!(err.to_string().contains("session token"));
    let (_client, _) =
        connect(addr, 7, FaultConfig::default(), Duration::from_secs(2), 0.0).unwrap();
    let server = accept.join().unwrap().unwrap();
    assert!(server.stats().wrong_token >= 1);
}

#[test]
fn accept_times_out_with_a_clear_error() {
    let server = UdpServer::bind(&loopback()).unwrap();
    let err = server
        .accept(
            1,
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
        1,
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
    let (mut server, mut client) = session(3, FaultConfig::default(), FaultConfig::default());
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
    let (mut server, mut client) = session(3, FaultConfig::default(), FaultConfig::default());
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
    let (mut server, mut client) = session(4, FaultConfig::default(), faults);
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

#[test]
fn repeated_hello_after_the_handshake_gets_a_fresh_welcome() {
    let (mut server, client) = session(11, FaultConfig::default(), FaultConfig::default());
    // Pretend the Welcome was lost: a Hello comes again from the client's
    // address (the server socket is connected to it, so only it gets in).
    let client_addr = client.transport().local_addr().unwrap();
    let hello = Message::Hello(HelloMsg {
        header: Header {
            token: 11,
            seq: 1000,
            ..Header::default()
        },
        nonce: 99,
    });
    let mut buf: DatagramBuf = [0; MAX_MESSAGE_SIZE];
    let n = encode(&hello, &mut buf);
    assert_eq!(server.transport().peer(), client_addr);
    drop(client);
    let resend = UdpSocket::bind(client_addr).unwrap();
    resend
        .connect(server.transport().local_addr().unwrap())
        .unwrap();
    resend.send(&buf[..n]).unwrap();
    assert!(
        recv_wait(&mut server, 0.5).is_none(),
        "a Hello is answered, not delivered"
    );
    resend
        .set_read_timeout(Some(Duration::from_secs(1)))
        .unwrap();
    let mut back = [0u8; 256];
    let m = resend.recv(&mut back).unwrap();
    match echothigh_transport::decode(&back[..m], 11).unwrap() {
        Message::Welcome(w) => assert_eq!(w.nonce, 99),
        other => panic!("expected a Welcome, got {other:?}"),
    }
}

#[test]
fn echo_round_trips_over_loopback() {
    let (server, mut client) = session(5, FaultConfig::default(), FaultConfig::default());
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
