//! Decoder fuzzing: random bytes, truncated, oversized and mutated
//! datagrams never panic, and every bad datagram that reaches an endpoint is
//! counted (malformed or wrong token), never delivered.

mod common;

use common::session;
use echothigh_transport::{
    decode, encode, ByeMsg, DatagramBuf, DecodeError, FaultConfig, Header, HelloMsg, Kind, Link,
    Message, ProbeMsg, SampleMsg, WelcomeMsg, MAX_MESSAGE_SIZE,
};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::net::UdpSocket;
use std::time::{Duration, Instant};

const TOKEN: u64 = 0x5eed;

fn valid_messages() -> Vec<Message> {
    let h = Header {
        token: TOKEN,
        seq: 3,
        t_send: 0.5,
        ..Header::default()
    };
    vec![
        Message::Probe(ProbeMsg {
            header: h,
            ..ProbeMsg::new(0.4, [0.0, 0.1, 0.0], [1.0, 0.0, 0.0, 0.0], 0)
        }),
        Message::Sample(SampleMsg {
            header: h,
            stiffness: 500.0,
            ..SampleMsg::default()
        }),
        Message::Hello(HelloMsg {
            header: h,
            nonce: 1,
        }),
        Message::Welcome(WelcomeMsg {
            header: h,
            nonce: 1,
            physics_rate: 100.0,
        }),
        Message::Bye(ByeMsg {
            header: h,
            ..ByeMsg::new(0)
        }),
    ]
}

fn encoded(i: usize) -> Vec<u8> {
    let msgs = valid_messages();
    let mut buf: DatagramBuf = [0; MAX_MESSAGE_SIZE];
    let n = encode(&msgs[i % msgs.len()], &mut buf);
    buf[..n].to_vec()
}

proptest! {
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = decode(&bytes, TOKEN);
    }

    #[test]
    fn truncated_or_oversized_is_wrong_size(i in 0usize..5, cut in 0usize..200, extra in 1usize..200) {
        let good = encoded(i);
        let short = &good[..cut.min(good.len() - 1)];
        let short_ok = matches!(decode(short, TOKEN), Err(DecodeError::WrongSize { .. }));
        prop_assert!(short_ok, "truncated datagram not rejected for its size");
        let mut long = good.clone();
        long.resize(good.len() + extra, 0);
        let long_ok = matches!(decode(&long, TOKEN), Err(DecodeError::WrongSize { .. }));
        prop_assert!(long_ok, "oversized datagram not rejected for its size");
    }

    #[test]
    fn mutated_messages_decode_or_fail_typed(i in 0usize..5, at in 0usize..160, byte in any::<u8>()) {
        let mut bytes = encoded(i);
        let at = at % bytes.len();
        bytes[at] = byte;
        match decode(&bytes, TOKEN) {
            Ok(m) => {
                // Whatever decodes is a well-formed message of the right size.
                prop_assert_eq!(m.kind().size(), bytes.len());
            }
            Err(DecodeError::WrongSize { len, .. }) => prop_assert_eq!(len, bytes.len()),
            Err(_) => {}
        }
    }
}

/// A datagram that must be rejected: random, truncated, oversized, or with
/// a corrupted header.
fn bad_datagram(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let good = encoded(rng.gen_range(0..5));
    match rng.gen_range(0..5) {
        0 => {
            let len = rng.gen_range(0..400);
            // Random bytes; force a bad magic so it cannot decode by chance.
            let mut v: Vec<u8> = (0..len).map(|_| rng.gen()).collect();
            if v.len() >= 4 {
                v[0] = b'X';
            }
            v
        }
        1 => good[..rng.gen_range(0..good.len())].to_vec(),
        2 => {
            let mut v = good.clone();
            v.resize(good.len() + rng.gen_range(1..300), rng.gen());
            v
        }
        3 => {
            let mut v = good.clone();
            v[rng.gen_range(0..8)] ^= 1 << rng.gen_range(0..8); // magic, version or kind
            v
        }
        _ => {
            let mut v = good.clone();
            v[8] ^= 0x40; // token
            v
        }
    }
}

#[test]
fn every_bad_datagram_reaching_an_endpoint_is_counted() {
    let (mut server, client) = session(TOKEN, FaultConfig::default(), FaultConfig::default());
    // The server only hears the client's address: send from it.
    let client_addr = client.transport().local_addr().unwrap();
    let server_addr = server.transport().local_addr().unwrap();
    drop(client);
    let raw = UdpSocket::bind(client_addr).unwrap();
    raw.connect(server_addr).unwrap();
    // Handshake datagrams still in flight (the client resends its Hello
    // every 20 ms until it hears the Welcome; on a loaded machine one may
    // arrive late) are legitimate: drain them and count from here.
    let drain_until = Instant::now() + Duration::from_millis(100);
    while Instant::now() < drain_until {
        let _ = server.recv(1.0).unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    let base = server.stats();

    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let n = 2000u64;
    let mut sent = 0u64;
    while sent < n {
        for _ in 0..50 {
            raw.send(&bad_datagram(&mut rng)).unwrap();
            sent += 1;
        }
        let target = sent;
        let start = Instant::now();
        loop {
            assert!(
                server.recv(1.0).unwrap().is_none(),
                "a bad datagram was delivered"
            );
            let s = server.stats();
            if s.malformed + s.wrong_token >= base.malformed + base.wrong_token + target
                || start.elapsed() > Duration::from_secs(2)
            {
                break;
            }
            std::thread::sleep(Duration::from_micros(100));
        }
    }
    let s = server.stats();
    assert_eq!(
        s.malformed + s.wrong_token - base.malformed - base.wrong_token,
        n,
        "{s:?}"
    );
    assert!(s.wrong_token > base.wrong_token && s.malformed > base.malformed);
    assert_eq!(s.received, base.received, "a bad datagram was accepted");
    // The link still works afterwards.
    let mut good = valid_messages()[0];
    good.header_mut().seq = 10_000;
    let mut buf: DatagramBuf = [0; MAX_MESSAGE_SIZE];
    let len = encode(&good, &mut buf);
    raw.send(&buf[..len]).unwrap();
    assert!(matches!(
        common::recv_wait(&mut server, 2.0),
        Some(Message::Probe(_))
    ));
    assert_eq!(good.kind(), Kind::Probe);
}
