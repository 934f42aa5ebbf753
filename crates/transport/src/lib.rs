//! The link between the physical model and the haptic loop (paper §2,
//! Fig. 1: "connected via the local network by socket connections"), for
//! both deployments of echothigh: two threads of one process
//! ([`in_process_pair`]) or two processes over UDP ([`UdpServer`],
//! [`connect`]).
//!
//! - [`message`]: fixed-size `#[repr(C)]` messages with a common header
//!   (magic, version, kind, session token, sequence, send time);
//!   [`encode`] / [`decode`] without allocation, typed [`DecodeError`]s.
//! - [`Link`]: send with fault injection, receive through a
//!   [`SequenceFilter`] (latest wins: reordered and duplicated datagrams
//!   are dropped), [`LinkStats`] counters, peer-silence detection.
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

pub mod codec;
pub mod echo;
pub mod fault;
pub mod link;
pub mod memory;
pub mod message;
pub mod sequence;
pub mod token;
pub mod udp;

pub use codec::{decode, decode_any, encode, DecodeError};
pub use echo::{echo_sample, measure_round_trips, round_trip, EchoResponder, RoundTripReport};
pub use fault::{ConfigError, DelayLine, FaultConfig, DEFAULT_DELAY_CAPACITY};
pub use link::{Endpoint, Link, LinkError, Transport};
pub use memory::{in_process_pair, InProcessEndpoint, MemoryTransport};
pub use message::{
    bye_reason, ByeMsg, DatagramBuf, Header, HelloMsg, Kind, Message, ProbeMsg, SampleMsg,
    WelcomeMsg, MAGIC, MAX_MESSAGE_SIZE, VERSION,
};
pub use sequence::{LinkStats, SeqVerdict, SequenceFilter};
pub use token::{SessionToken, TokenSource, TOKEN_ENV};
pub use udp::{connect, ListenConfig, UdpEndpoint, UdpServer, UdpTransport};
