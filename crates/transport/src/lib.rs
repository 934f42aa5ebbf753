//! The link between the physical model and the haptic loop (paper §2,
//! Fig. 1: "connected via the local network by socket connections"), for
//! both deployments of echothigh: two threads of one process
//! ([`in_process_pair`]) or two processes over UDP ([`UdpServer`],
//! [`connect`]).
//!
//! - [`message`]: fixed-size `#[repr(C)]` messages with a common header
//!   (magic, version, kind, session id, sequence, send time); "no contact"
//!   is [`contact_state::NO_SURFACE`] with a finite sentinel distance.
//! - [`codec`]: [`seal`] / [`open`] without allocation, typed
//!   [`EncodeError`] / [`DecodeError`]s; [`limits`]: the bounds every value
//!   is checked against on both sides.
//! - [`auth`]: per-session keys derived in the handshake (HKDF-SHA256) and
//!   a 128-bit HMAC-SHA256 tag on every UDP datagram; the [`SessionToken`]
//!   never goes on the wire.
//! - [`Link`]: send with fault injection, receive through a
//!   [`SequenceFilter`] (latest wins: reordered, duplicated and replayed
//!   datagrams are dropped, and sequence jumps beyond [`MAX_SEQ_JUMP`]),
//!   [`LinkStats`] counters of every rejection by reason, peer-silence
//!   detection.
//! - [`FaultConfig`] / [`DelayLine`]: latency, jitter, loss, duplication on
//!   the caller's clock (deterministic with a virtual clock).
//! - [`EchoResponder`] / [`round_trip`]: request/response for latency
//!   benchmarks.
//!
//! ```
//! use echothigh_transport::{in_process_pair, FaultConfig, Link, Message, ProbeMsg};
//! let (mut haptic, mut physics) = in_process_pair(7, FaultConfig::default(), FaultConfig::default());
//! let probe = ProbeMsg::new(0.0, [0.0, 0.08, 0.0], [1.0, 0.0, 0.0, 0.0], 0);
//! haptic.send(Message::Probe(probe), 0.0).unwrap();
//! let got = physics.recv(0.0).unwrap().unwrap();
//! assert!(matches!(got, Message::Probe(p) if p.position[1] == 0.08));
//! ```
//!
//! Byte order: messages go on the wire as their in-memory bytes, so the
//! wire format is little-endian and big-endian targets are refused at
//! compile time.

#![warn(missing_docs)]

#[cfg(not(target_endian = "little"))]
compile_error!("echothigh-transport writes messages as native bytes: little-endian targets only");

pub mod auth;
pub mod codec;
pub mod echo;
pub mod fault;
pub mod limits;
pub mod link;
pub mod memory;
pub mod message;
mod reject;
pub mod sequence;
pub mod token;
pub mod udp;

pub use auth::{DatagramKey, SessionKeys, MAC_LEN};
pub use codec::{decode_any, encode, open, seal, DecodeError, EncodeError};
pub use echo::{echo_sample, measure_round_trips, round_trip, EchoResponder, RoundTripReport};
pub use fault::{ConfigError, DelayLine, FaultConfig, DEFAULT_DELAY_CAPACITY};
pub use limits::ValueError;
pub use link::{Endpoint, Link, LinkError, Transport};
pub use memory::{in_process_pair, InProcessEndpoint, MemoryTransport};
pub use message::{
    bye_reason, contact_state, wire_query, ByeMsg, DatagramBuf, Header, HelloMsg, Kind, Message,
    ProbeMsg, SampleMsg, WelcomeMsg, MAGIC, MAX_DATAGRAM_SIZE, MAX_MESSAGE_SIZE,
    NO_SURFACE_DISTANCE, VERSION,
};
pub use sequence::{LinkStats, SeqVerdict, SequenceFilter, MAX_SEQ_JUMP};
pub use token::{SessionToken, TokenSource, MAX_TOKEN_DIGITS, MIN_TOKEN_DIGITS, TOKEN_ENV};
pub use udp::{connect, ListenConfig, UdpEndpoint, UdpServer, UdpTransport, MAX_REJECTIONS_PER_S};
