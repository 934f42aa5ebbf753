//! Codec properties (proptest), repeatable at any size: arbitrary bytes
//! never panic either decoder; every in-bounds message round-trips through
//! `seal` / `open`; any value out of bounds is refused by the encoder and,
//! tagged anyway, by the decoder; any change to a sealed datagram is
//! refused.
//!
//! The number of cases per property is `ECHOTHIGH_FUZZ_CASES` (default
//! 256), e.g. a long run:
//! `ECHOTHIGH_FUZZ_CASES=200000 cargo test -p echothigh-transport --release --test suite fuzz::`.

use echothigh_transport::{
    decode_any, limits, open, seal, ByeMsg, DatagramBuf, DatagramKey, DecodeError, EncodeError,
    Header, HelloMsg, Message, ProbeMsg, SampleMsg, SessionKeys, SessionToken, WelcomeMsg, MAC_LEN,
    MAX_DATAGRAM_SIZE,
};
use proptest::prelude::*;

const SESSION: u64 = 0x5eed;

fn cases() -> u32 {
    std::env::var("ECHOTHIGH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256)
}

fn key() -> DatagramKey {
    let t: SessionToken = "00112233445566778899aabbccddeeff".parse().unwrap();
    SessionKeys::derive(&t, 11, 22).client_to_server
}

fn header(seq: u64, t: f64) -> Header {
    Header {
        session: SESSION,
        seq,
        t_send: t,
        ..Header::default()
    }
}

/// Any `f64` bit pattern, NaN and infinities included, half the time; else
/// a value in `[-bound, bound]`.
fn value(bound: f64) -> impl Strategy<Value = f64> {
    prop_oneof![any::<u64>().prop_map(f64::from_bits), -bound..=bound]
}

fn in_bounds(bound: f64) -> impl Strategy<Value = f64> {
    -bound..=bound
}

/// Messages of every kind; `v` draws each `f64`.
fn messages(wild: bool) -> impl Strategy<Value = Message> {
    let f = move |b: f64| -> BoxedStrategy<f64> {
        if wild {
            value(b).boxed()
        } else {
            in_bounds(b).boxed()
        }
    };
    let probe = (
        any::<u64>(),
        f(limits::MAX_TIME),
        f(limits::MAX_TIME),
        [
            f(limits::MAX_POSITION),
            f(limits::MAX_POSITION),
            f(limits::MAX_POSITION),
        ],
        [f(1.0), f(1.0), f(1.0), f(1.0)],
        any::<u32>(),
    )
        .prop_map(|(seq, t, td, position, orientation, flags)| {
            Message::Probe(ProbeMsg {
                header: header(seq, t),
                ..ProbeMsg::new(td, position, orientation, flags)
            })
        });
    let sample = (
        (
            any::<u64>(),
            f(limits::MAX_TIME),
            f(limits::MAX_TIME),
            any::<u64>(),
        ),
        [
            f(limits::MAX_POSITION),
            f(limits::MAX_POSITION),
            f(limits::MAX_POSITION),
        ],
        (f(limits::MAX_DISTANCE), f(1.0), f(limits::MAX_STIFFNESS)),
        [
            f(limits::MAX_FORCE),
            f(limits::MAX_FORCE),
            f(limits::MAX_FORCE),
        ],
        (0u32..=2, any::<u32>(), f(1e4).prop_map(f64::abs)),
    )
        .prop_map(
            |((seq, t, ts, ps), p, (d, g, k), force, (contact, it, rate))| {
                Message::Sample(SampleMsg {
                    header: header(seq, t),
                    t_sample: ts,
                    probe_seq: ps,
                    p,
                    distance: d,
                    gradient: [0.0, g, 0.0],
                    stiffness: k,
                    force,
                    contact,
                    newton_iterations: it,
                    cg_iterations: it / 2,
                    limited: it % 3,
                    physics_rate: rate,
                })
            },
        );
    let small = (any::<u64>(), f(limits::MAX_TIME), any::<u64>(), 0u32..3).prop_map(
        |(seq, t, nonce, which)| match which {
            0 => Message::Hello(HelloMsg {
                header: header(seq, t),
                nonce,
                _reserved: 0,
            }),
            1 => Message::Welcome(WelcomeMsg {
                header: header(seq, t),
                nonce,
                server_nonce: nonce.rotate_left(7),
                physics_rate: 100.0,
            }),
            _ => Message::Bye(ByeMsg {
                header: header(seq, t),
                nonce,
                ..ByeMsg::new(1)
            }),
        },
    );
    prop_oneof![probe, sample, small]
}

/// The header fields `seal` sets from the variant.
fn as_sent(msg: &Message) -> Message {
    let mut m = *msg;
    let h = m.header_mut();
    h.magic = echothigh_transport::MAGIC;
    h.version = echothigh_transport::VERSION;
    h.kind = msg.kind() as u16;
    m
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = decode_any(&bytes);
        // Never accepted without the key's tag (2⁻¹²⁸ per case).
        prop_assert!(open(&bytes, &key(), SESSION).is_err());
    }

    #[test]
    fn in_bounds_messages_round_trip(msg in messages(false)) {
        let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
        let n = seal(&msg, &key(), &mut buf).unwrap();
        prop_assert_eq!(n, msg.kind().size() + MAC_LEN);
        prop_assert_eq!(open(&buf[..n], &key(), SESSION).unwrap(), as_sent(&msg));
    }

    #[test]
    fn out_of_bounds_values_are_refused_on_both_sides(msg in messages(true)) {
        let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
        match (limits::check(&msg), seal(&msg, &key(), &mut buf)) {
            (Ok(()), Ok(n)) => {
                prop_assert_eq!(open(&buf[..n], &key(), SESSION).unwrap(), as_sent(&msg));
            }
            (Err(e), Err(EncodeError::InvalidValue(f))) => {
                // Same field, same value bits (NaN ≠ NaN under `==`).
                prop_assert_eq!((e.field, e.value.to_bits()), (f.field, f.value.to_bits()));
                // A peer that tags the bytes anyway is refused after the tag.
                let bytes = bytemuck_bytes(&as_sent(&msg));
                let mut dg = bytes.clone();
                dg.extend_from_slice(&key().tag(&bytes));
                match open(&dg, &key(), SESSION) {
                    Err(DecodeError::InvalidValue(g)) => prop_assert_eq!(g.field, e.field),
                    other => prop_assert!(false, "tagged absurd value opened as {:?}", other),
                }
            }
            (c, s) => prop_assert!(false, "check {:?} but seal {:?}", c, s),
        }
    }

    #[test]
    fn any_change_to_a_sealed_datagram_is_refused(
        msg in messages(false),
        at in 0usize..MAX_DATAGRAM_SIZE,
        flip in 1u8..=255,
        cut in 0usize..MAX_DATAGRAM_SIZE,
    ) {
        let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
        let n = seal(&msg, &key(), &mut buf).unwrap();
        let mut bad = buf[..n].to_vec();
        bad[at % n] ^= flip;
        prop_assert!(open(&bad, &key(), SESSION).is_err());
        let short = &buf[..cut % n];
        let short_ok = matches!(open(short, &key(), SESSION), Err(DecodeError::WrongSize { .. }));
        prop_assert!(short_ok, "a truncated datagram is refused for its size");
    }
}

/// The bytes of a message as `seal` writes them, before the tag, without
/// the value check.
fn bytemuck_bytes(msg: &Message) -> Vec<u8> {
    match msg {
        Message::Probe(m) => bytemuck::bytes_of(m).to_vec(),
        Message::Sample(m) => bytemuck::bytes_of(m).to_vec(),
        Message::Hello(m) => bytemuck::bytes_of(m).to_vec(),
        Message::Welcome(m) => bytemuck::bytes_of(m).to_vec(),
        Message::Bye(m) => bytemuck::bytes_of(m).to_vec(),
    }
}
