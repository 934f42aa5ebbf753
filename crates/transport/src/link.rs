//! The [`Link`]: one end of the physics–haptics connection (paper Fig. 1),
//! over any [`Transport`] (UDP socket or in-process buffer), with the same
//! sequence stamping, fault injection, sequence filter, statistics and peer
//! silence detection.
//!
//! All times are on the caller's clock (s), so a virtual clock works.
//! Receiving is "latest wins": call [`Link::recv`] until it returns `None`
//! and keep the last message of each kind; stale, duplicated, replayed and
//! implausibly far-ahead datagrams never come out ([`SequenceFilter`]), nor
//! do handshake messages once the session is up. Sending checks the
//! message's values first ([`crate::limits`]) on either transport.

use crate::codec::{DecodeError, EncodeError};
use crate::fault::{DelayLine, FaultConfig, DEFAULT_DELAY_CAPACITY};
use crate::limits::check;
use crate::message::{bye_reason, ByeMsg, Message};
use crate::sequence::{LinkStats, SequenceFilter};
use std::net::SocketAddr;
use std::time::Duration;

/// Errors of the link layer.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// A socket operation failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: &'static str,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// A non-loopback listen address without `allow_remote`.
    #[error(
        "refusing to listen on non-loopback address {addr}: pass --allow-remote \
         (allow_remote) to accept clients from other hosts"
    )]
    RemoteNotAllowed {
        /// The refused address.
        addr: SocketAddr,
    },
    /// The client got no answer to its Hello.
    #[error(
        "no Welcome from the physics server at {addr} within {waited:?}: \
         is it running and listening there?"
    )]
    HandshakeTimeout {
        /// Server address.
        addr: SocketAddr,
        /// How long the client tried.
        waited: Duration,
    },
    /// The server answered the Hello with a rejection.
    #[error(
        "the physics server at {addr} rejected the session token (check --token / ECHOTHIGH_TOKEN)"
    )]
    Rejected {
        /// Server address.
        addr: SocketAddr,
    },
    /// No client with the right token arrived.
    #[error("no client presented the session token within {waited:?} ({wrong_token} Hello(s) with a wrong token)")]
    AcceptTimeout {
        /// How long the server waited.
        waited: Duration,
        /// Hellos refused for their token meanwhile.
        wrong_token: u64,
    },
    /// No answer to a round-trip request.
    #[error("no answer to probe {seq} within {waited:?}")]
    RoundTripTimeout {
        /// Sequence of the unanswered probe.
        seq: u64,
        /// How long the caller waited.
        waited: Duration,
    },
    /// A session token that does not parse or is too short.
    #[error("invalid session token {text:?}: {reason}")]
    BadToken {
        /// The offending text (at most 80 characters of it).
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A message that may not be sent (a non-finite or absurd value).
    #[error(transparent)]
    Encode(#[from] EncodeError),
    /// The endpoint was closed with [`Link::close`].
    #[error("the link is closed")]
    Closed,
}

/// Moves single messages, without faults, ordering or statistics of its own
/// beyond the datagrams it rejects.
pub trait Transport {
    /// Puts one message on the wire now.
    fn transmit(&mut self, msg: &Message, stats: &mut LinkStats) -> Result<(), LinkError>;
    /// Takes the next valid message of session `session` off the wire, if
    /// any, without blocking. Datagrams that fail to decode (structure,
    /// session, tag, values) are counted in `stats` by reason and skipped.
    fn receive(
        &mut self,
        session: u64,
        stats: &mut LinkStats,
    ) -> Result<Option<Message>, LinkError>;
}

/// Counts a decode failure in `stats`, by reason.
pub(crate) fn count_decode_error(e: DecodeError, stats: &mut LinkStats) {
    match e {
        DecodeError::WrongSession { .. } => stats.wrong_session += 1,
        DecodeError::BadMac => stats.bad_mac += 1,
        DecodeError::InvalidValue(_) => stats.bad_value += 1,
        DecodeError::WrongSize { .. }
        | DecodeError::BadMagic { .. }
        | DecodeError::UnsupportedVersion { .. }
        | DecodeError::UnknownKind { .. } => stats.malformed += 1,
    }
}

/// One end of the connection, object-safe so that the runtime can hold a
/// `Box<dyn Link>` for either deployment.
pub trait Link: Send {
    /// Stamps `msg` (session, next sequence number, `t_send = now`), checks
    /// its values ([`LinkError::Encode`] names a non-finite or absurd field;
    /// nothing is sent then) and sends it through the fault injector;
    /// returns the sequence number given. Messages already due are released
    /// (so a fault-free link sends now).
    fn send(&mut self, msg: Message, now: f64) -> Result<u64, LinkError>;
    /// Releases the delayed messages due at `now` (s) to the transport.
    fn poll(&mut self, now: f64) -> Result<(), LinkError>;
    /// The next accepted message (newer than any accepted before), if any;
    /// polls the delay line first. Never blocks.
    fn recv(&mut self, now: f64) -> Result<Option<Message>, LinkError>;
    /// Counters.
    fn stats(&self) -> LinkStats;
    /// When the peer was last heard (s, caller's clock), if ever.
    fn last_heard(&self) -> Option<f64>;
    /// True if nothing was heard for more than `timeout` (s) before `now`,
    /// or ever, or the peer said Bye.
    fn peer_silent(&self, now: f64, timeout: f64) -> bool;
    /// True once the peer said Bye.
    fn peer_closed(&self) -> bool;
    /// Sends a Bye now (bypassing the faults), drops what is in flight and
    /// refuses further sends. Idempotent.
    fn close(&mut self, now: f64) -> Result<(), LinkError>;
}

/// A [`Link`] over transport `T`.
pub struct Endpoint<T: Transport> {
    transport: T,
    session: u64,
    next_seq: u64,
    delay: DelayLine<Message>,
    filter: SequenceFilter,
    stats: LinkStats,
    last_heard: Option<f64>,
    peer_closed: bool,
    closed: bool,
}

impl<T: Transport> Endpoint<T> {
    /// An endpoint of session `session` over `transport`, injecting
    /// `faults` on what it sends (validate them first). Allocates its delay
    /// line.
    pub fn new(transport: T, session: u64, faults: FaultConfig) -> Self {
        Endpoint {
            transport,
            session,
            next_seq: 0,
            delay: DelayLine::new(faults, DEFAULT_DELAY_CAPACITY),
            filter: SequenceFilter::new(),
            stats: LinkStats::default(),
            last_heard: None,
            peer_closed: false,
            closed: false,
        }
    }

    /// The underlying transport.
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// The session id.
    pub fn session(&self) -> u64 {
        self.session
    }

    /// Sets the session id (the client learns it from the Welcome).
    pub(crate) fn set_session(&mut self, session: u64) {
        self.session = session;
    }

    /// The underlying transport, mutable (the handshake sets its keys).
    pub(crate) fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    /// Messages in the delay line.
    pub fn in_flight(&self) -> usize {
        self.delay.len()
    }

    /// Adds the rejection counters gathered before the endpoint existed
    /// (handshake).
    pub(crate) fn merge_stats(&mut self, s: &LinkStats) {
        self.stats.malformed += s.malformed;
        self.stats.bad_value += s.bad_value;
        self.stats.bad_mac += s.bad_mac;
        self.stats.wrong_session += s.wrong_session;
        self.stats.wrong_token += s.wrong_token;
        self.stats.rejections_sent += s.rejections_sent;
        self.stats.rejections_suppressed += s.rejections_suppressed;
        self.stats.io_errors += s.io_errors;
    }

    /// Skips one sequence number (the server's Welcome used 0).
    pub(crate) fn skip_sequence(&mut self) {
        self.next_seq += 1;
    }

    /// Marks the peer heard at `now` (the handshake answer).
    pub(crate) fn mark_heard(&mut self, seq: u64, now: f64) {
        self.filter.check(seq);
        self.last_heard = Some(now);
    }

    fn stamp(&mut self, msg: &mut Message, now: f64) -> u64 {
        let seq = self.next_seq;
        self.next_seq += 1;
        let h = msg.header_mut();
        h.session = self.session;
        h.seq = seq;
        h.t_send = now;
        seq
    }

    /// Stamps and transmits `msg` now, without faults (handshake, Bye).
    pub(crate) fn send_direct(&mut self, mut msg: Message, now: f64) -> Result<u64, LinkError> {
        msg.header_mut().t_send = now;
        check(&msg).map_err(EncodeError::from)?;
        let seq = self.stamp(&mut msg, now);
        self.transport.transmit(&msg, &mut self.stats)?;
        self.stats.sent += 1;
        self.stats.transmitted += 1;
        Ok(seq)
    }
}

impl<T: Transport + Send> Link for Endpoint<T> {
    fn send(&mut self, mut msg: Message, now: f64) -> Result<u64, LinkError> {
        if self.closed {
            return Err(LinkError::Closed);
        }
        msg.header_mut().t_send = now;
        check(&msg).map_err(EncodeError::from)?;
        let seq = self.stamp(&mut msg, now);
        self.stats.sent += 1;
        self.delay.push(msg, now, &mut self.stats);
        self.poll(now)?;
        Ok(seq)
    }

    fn poll(&mut self, now: f64) -> Result<(), LinkError> {
        while let Some((_, msg)) = self.delay.pop_due(now) {
            self.transport.transmit(&msg, &mut self.stats)?;
            self.stats.transmitted += 1;
        }
        Ok(())
    }

    fn recv(&mut self, now: f64) -> Result<Option<Message>, LinkError> {
        if !self.closed {
            self.poll(now)?;
        }
        while let Some(msg) = self.transport.receive(self.session, &mut self.stats)? {
            if !self.filter.accept(msg.seq(), &mut self.stats) {
                continue;
            }
            self.stats.received += 1;
            self.last_heard = Some(now);
            match msg {
                Message::Bye(_) => self.peer_closed = true,
                // The session is up: a late handshake message (the
                // client's confirmation sent twice) is heard, not delivered.
                Message::Hello(_) | Message::Welcome(_) => continue,
                _ => {}
            }
            return Ok(Some(msg));
        }
        Ok(None)
    }

    fn stats(&self) -> LinkStats {
        self.stats
    }

    fn last_heard(&self) -> Option<f64> {
        self.last_heard
    }

    fn peer_silent(&self, now: f64, timeout: f64) -> bool {
        self.peer_closed || !matches!(self.last_heard, Some(t) if now - t <= timeout)
    }

    fn peer_closed(&self) -> bool {
        self.peer_closed
    }

    fn close(&mut self, now: f64) -> Result<(), LinkError> {
        if self.closed {
            return Ok(());
        }
        self.closed = true;
        self.delay.clear();
        self.send_direct(Message::Bye(ByeMsg::new(bye_reason::SHUTDOWN)), now)?;
        Ok(())
    }
}
