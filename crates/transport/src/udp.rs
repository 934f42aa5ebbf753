//! The UDP link of the two-process deployment (paper §2: "connected via the
//! local network by socket connections"), with authenticated datagrams
//! ([`crate::auth`]).
//!
//! Handshake (the token never on the wire):
//! 1. client → server: Hello `{nonce_c}`, tagged with the token's hello key
//!    (resent every 20 ms until answered);
//! 2. server → client: Welcome `{nonce_c, nonce_s, physics_rate}` in the new
//!    session (id and keys derived from the token and both nonces), tagged
//!    with the server→client key; a repeated Hello gets the same Welcome;
//! 3. client → server: the Hello again, now in the session and tagged with
//!    the client→server key, which proves the client derived the keys. The
//!    server commits to that client (connects its socket to it) only then:
//!    a replayed Hello gets a Welcome nobody can use, never the server.
//!
//! A Hello whose tag shows a wrong token is counted, logged at most once a
//! second (with the count since the last line), and answered with a
//! rejecting Bye at most once per second per source address and
//! [`MAX_REJECTIONS_PER_S`] per second over all sources. The handshake runs
//! on the wall clock; the established [`UdpEndpoint`] is non-blocking and
//! works on the caller's clock like any [`crate::Link`].

use crate::auth::{DatagramKey, SessionKeys};
use crate::codec::{decode_any, open, seal, DecodeError};
use crate::fault::FaultConfig;
use crate::link::{count_decode_error, Endpoint, LinkError, Transport};
use crate::message::{
    bye_reason, ByeMsg, DatagramBuf, Header, HelloMsg, Message, WelcomeMsg, MAX_DATAGRAM_SIZE,
};
use crate::reject::RejectLimiter;
use crate::sequence::LinkStats;
use crate::token::SessionToken;
use std::io::ErrorKind;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

pub use crate::reject::MAX_REJECTIONS_PER_S;

/// Interval between Hello retransmissions.
const HELLO_INTERVAL: Duration = Duration::from_millis(20);
/// Read timeout used while handshaking.
const HANDSHAKE_POLL: Duration = Duration::from_millis(5);
/// Receive buffer: larger than any datagram, so oversized ones show.
const RECV_BUF: usize = 2 * MAX_DATAGRAM_SIZE;
/// Clients half-way through the handshake that the server remembers.
const PENDING: usize = 4;

/// A connected, non-blocking UDP socket that tags what it sends and checks
/// the tag of what it receives.
pub struct UdpTransport {
    socket: UdpSocket,
    peer: SocketAddr,
    tx_key: DatagramKey,
    rx_key: DatagramKey,
}

/// A UDP [`crate::Link`].
pub type UdpEndpoint = Endpoint<UdpTransport>;

fn io(context: &'static str) -> impl FnOnce(std::io::Error) -> LinkError {
    move |source| LinkError::Io { context, source }
}

/// Errors a UDP socket reports for a peer that went away (ICMP port
/// unreachable) or that the OS refused transiently: survivable.
fn transient(kind: ErrorKind) -> bool {
    matches!(
        kind,
        ErrorKind::ConnectionRefused | ErrorKind::ConnectionReset | ErrorKind::Interrupted
    )
}

fn waiting(kind: ErrorKind) -> bool {
    matches!(kind, ErrorKind::WouldBlock | ErrorKind::TimedOut) || transient(kind)
}

impl UdpTransport {
    /// The peer's address.
    pub fn peer(&self) -> SocketAddr {
        self.peer
    }

    /// The local address.
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.socket
            .local_addr()
            .map_err(io("reading the local address"))
    }
}

impl Transport for UdpTransport {
    fn transmit(&mut self, msg: &Message, stats: &mut LinkStats) -> Result<(), LinkError> {
        let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
        let n = seal(msg, &self.tx_key, &mut buf)?;
        match self.socket.send(&buf[..n]) {
            Ok(_) => Ok(()),
            Err(e) if transient(e.kind()) || e.kind() == ErrorKind::WouldBlock => {
                stats.io_errors += 1;
                Ok(())
            }
            Err(e) => Err(io("sending a datagram")(e)),
        }
    }

    fn receive(
        &mut self,
        session: u64,
        stats: &mut LinkStats,
    ) -> Result<Option<Message>, LinkError> {
        let mut buf = [0u8; RECV_BUF];
        loop {
            match self.socket.recv(&mut buf) {
                Ok(n) => match open(&buf[..n], &self.rx_key, session) {
                    Ok(msg) => return Ok(Some(msg)),
                    Err(e) => count_decode_error(e, stats),
                },
                Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(None),
                Err(e) if transient(e.kind()) => stats.io_errors += 1,
                Err(e) => return Err(io("receiving a datagram")(e)),
            }
        }
    }
}

/// Where and how a physics server listens.
#[derive(Clone, Copy, Debug)]
pub struct ListenConfig {
    /// Listen address; port 0 picks a free port.
    pub addr: SocketAddr,
    /// Accept a non-loopback listen address (clients from other hosts).
    pub allow_remote: bool,
}

/// A bound server socket waiting for its client.
pub struct UdpServer {
    socket: UdpSocket,
}

/// A client that sent a good Hello and got a Welcome, not yet confirmed.
struct Pending {
    from: SocketAddr,
    nonce: u64,
    keys: SessionKeys,
    welcome: Message,
}

impl UdpServer {
    /// Binds the listen socket; a non-loopback address without
    /// `allow_remote` is refused with [`LinkError::RemoteNotAllowed`].
    pub fn bind(config: &ListenConfig) -> Result<Self, LinkError> {
        if !config.addr.ip().is_loopback() && !config.allow_remote {
            return Err(LinkError::RemoteNotAllowed { addr: config.addr });
        }
        let socket = UdpSocket::bind(config.addr).map_err(io("binding the listen address"))?;
        Ok(UdpServer { socket })
    }

    /// The bound address (with the port chosen if 0 was asked).
    pub fn local_addr(&self) -> Result<SocketAddr, LinkError> {
        self.socket
            .local_addr()
            .map_err(io("reading the local address"))
    }

    /// Waits up to `timeout` (wall clock) for a client holding `token`
    /// (the handshake of the module docs), announcing `physics_rate` (Hz),
    /// and returns the endpoint connected to it, injecting `faults` on what
    /// it sends. `now` (s) is the caller's clock at the call; the wall time
    /// spent waiting is added to it to stamp the Welcome and to mark the
    /// client heard (so a client arriving late is not taken for silent).
    pub fn accept(
        self,
        token: &SessionToken,
        faults: FaultConfig,
        physics_rate: f64,
        timeout: Duration,
        now: f64,
    ) -> Result<UdpEndpoint, LinkError> {
        let socket = self.socket;
        socket
            .set_read_timeout(Some(HANDSHAKE_POLL))
            .map_err(io("setting the read timeout"))?;
        let hello_key = DatagramKey::hello(token);
        let start = Instant::now();
        let clock = |start: Instant| now + start.elapsed().as_secs_f64();
        let mut stats = LinkStats::default();
        let mut limiter = RejectLimiter::new();
        let mut pending: [Option<Pending>; PENDING] = Default::default();
        let mut next_slot = 0;
        let mut buf = [0u8; RECV_BUF];
        while start.elapsed() < timeout {
            let (n, from) = match socket.recv_from(&mut buf) {
                Ok(r) => r,
                Err(e) if waiting(e.kind()) => continue,
                Err(e) => return Err(io("waiting for a client")(e)),
            };
            let bytes = &buf[..n];
            // A pending client's confirmation (or, if that was lost, its
            // first message) in its new session.
            let confirmed = pending.iter().position(|p| {
                matches!(p, Some(p) if p.from == from
                    && open(bytes, &p.keys.client_to_server, p.keys.session_id).is_ok())
            });
            if let Some(i) = confirmed {
                let p = pending[i].take().expect("matched as Some");
                let seq = open(bytes, &p.keys.client_to_server, p.keys.session_id)
                    .map(|m| m.seq())
                    .unwrap_or(0);
                return commit(socket, p, seq, faults, &stats, clock(start));
            }
            match open(bytes, &hello_key, 0) {
                Ok(Message::Hello(h)) => {
                    let known = pending
                        .iter()
                        .flatten()
                        .find(|p| p.from == from && p.nonce == h.nonce);
                    let welcome = match known {
                        Some(p) => (p.welcome, p.keys.server_to_client.clone()),
                        None => {
                            let server_nonce: u64 = rand::random();
                            let keys = SessionKeys::derive(token, h.nonce, server_nonce);
                            let p = welcome_for(from, h.nonce, server_nonce, keys, physics_rate);
                            let w = (p.welcome, p.keys.server_to_client.clone());
                            pending[next_slot] = Some(p);
                            next_slot = (next_slot + 1) % PENDING;
                            w
                        }
                    };
                    let mut msg = welcome.0;
                    msg.header_mut().t_send = clock(start);
                    send_sealed(&socket, &msg, &welcome.1, from);
                }
                Ok(_) => {}
                Err(DecodeError::BadMac) => match decode_any(bytes) {
                    // A well-formed Hello under another token's key.
                    Ok(Message::Hello(h)) => {
                        stats.wrong_token += 1;
                        if limiter.refused(from, Instant::now()) {
                            stats.rejections_sent += 1;
                            send_sealed(&socket, &rejection(h.nonce), &hello_key, from);
                        } else {
                            stats.rejections_suppressed += 1;
                        }
                    }
                    _ => stats.bad_mac += 1,
                },
                Err(e) => count_decode_error(e, &mut stats),
            }
        }
        Err(LinkError::AcceptTimeout {
            waited: timeout,
            wrong_token: stats.wrong_token,
        })
    }
}

/// The pending state and Welcome for a client's Hello.
fn welcome_for(
    from: SocketAddr,
    nonce: u64,
    server_nonce: u64,
    keys: SessionKeys,
    physics_rate: f64,
) -> Pending {
    let welcome = Message::Welcome(WelcomeMsg {
        header: Header {
            session: keys.session_id,
            seq: 0,
            ..Header::default()
        },
        nonce,
        server_nonce,
        physics_rate,
    });
    Pending {
        from,
        nonce,
        keys,
        welcome,
    }
}

/// Seals `msg` under `key` and sends it to `to`, best effort (a lost
/// Welcome is resent on the next Hello).
fn send_sealed(socket: &UdpSocket, msg: &Message, key: &DatagramKey, to: SocketAddr) {
    let mut buf: DatagramBuf = [0; MAX_DATAGRAM_SIZE];
    match seal(msg, key, &mut buf) {
        Ok(n) => {
            if let Err(e) = socket.send_to(&buf[..n], to) {
                tracing::debug!(%to, error = %e, "could not send a handshake datagram");
            }
        }
        Err(e) => tracing::warn!(error = %e, "handshake datagram not sent"),
    }
}

/// Connects the socket to the confirmed client and builds the endpoint.
fn commit(
    socket: UdpSocket,
    p: Pending,
    seq: u64,
    faults: FaultConfig,
    stats: &LinkStats,
    now: f64,
) -> Result<UdpEndpoint, LinkError> {
    socket
        .connect(p.from)
        .map_err(io("connecting to the client"))?;
    socket
        .set_nonblocking(true)
        .map_err(io("making the socket non-blocking"))?;
    let transport = UdpTransport {
        socket,
        peer: p.from,
        tx_key: p.keys.server_to_client,
        rx_key: p.keys.client_to_server,
    };
    let mut endpoint = Endpoint::new(transport, p.keys.session_id, faults);
    endpoint.skip_sequence(); // the Welcome was sequence 0
    endpoint.merge_stats(stats);
    endpoint.mark_heard(seq, now);
    tracing::info!(client = %p.from, "client accepted");
    Ok(endpoint)
}

/// Client side: binds an ephemeral port (loopback for a loopback server),
/// handshakes with the server at `server` proving it holds `token`, and
/// returns the endpoint (injecting `faults` on what it sends) and the
/// server's Welcome. Fails with [`LinkError::HandshakeTimeout`] after
/// `timeout` (wall clock) or [`LinkError::Rejected`] on a wrong token. `now`
/// (s) is the caller's clock at the call; the wall time spent is added to
/// stamp the Hellos and mark the server heard.
pub fn connect(
    server: SocketAddr,
    token: &SessionToken,
    faults: FaultConfig,
    timeout: Duration,
    now: f64,
) -> Result<(UdpEndpoint, WelcomeMsg), LinkError> {
    let local_ip: IpAddr = match (server.ip().is_loopback(), server) {
        (true, SocketAddr::V4(_)) => Ipv4Addr::LOCALHOST.into(),
        (true, SocketAddr::V6(_)) => Ipv6Addr::LOCALHOST.into(),
        (false, SocketAddr::V4(_)) => Ipv4Addr::UNSPECIFIED.into(),
        (false, SocketAddr::V6(_)) => Ipv6Addr::UNSPECIFIED.into(),
    };
    let socket = UdpSocket::bind((local_ip, 0)).map_err(io("binding the client socket"))?;
    socket
        .connect(server)
        .map_err(io("connecting to the server"))?;
    socket
        .set_read_timeout(Some(HANDSHAKE_POLL))
        .map_err(io("setting the read timeout"))?;
    let nonce: u64 = rand::random();
    let hello_key = DatagramKey::hello(token);
    let transport = UdpTransport {
        socket,
        peer: server,
        tx_key: hello_key.clone(),
        rx_key: hello_key,
    };
    let mut endpoint = Endpoint::new(transport, 0, faults);
    let start = Instant::now();
    let clock = |start: Instant| now + start.elapsed().as_secs_f64();
    let hello = Message::Hello(HelloMsg {
        header: Header::default(),
        nonce,
        _reserved: 0,
    });
    let mut last_hello: Option<Instant> = None;
    let mut stats = LinkStats::default();
    let mut buf = [0u8; RECV_BUF];
    while start.elapsed() < timeout {
        if !matches!(last_hello, Some(t) if t.elapsed() < HELLO_INTERVAL) {
            endpoint.send_direct(hello, clock(start))?;
            last_hello = Some(Instant::now());
        }
        let n = match endpoint.transport().socket.recv(&mut buf) {
            Ok(n) => n,
            Err(e) if waiting(e.kind()) => continue,
            Err(e) => return Err(io("waiting for the Welcome")(e)),
        };
        let bytes = &buf[..n];
        match decode_any(bytes) {
            Ok(Message::Welcome(w)) if w.nonce == nonce => {
                let keys = SessionKeys::derive(token, nonce, w.server_nonce);
                if let Err(e) = open(bytes, &keys.server_to_client, keys.session_id) {
                    count_decode_error(e, &mut stats);
                    continue;
                }
                let t = endpoint.transport_mut();
                t.tx_key = keys.client_to_server;
                t.rx_key = keys.server_to_client;
                endpoint.set_session(keys.session_id);
                endpoint.mark_heard(w.header.seq, clock(start));
                endpoint.merge_stats(&stats);
                // Confirm: the Hello again, in the session, under its key.
                endpoint.send_direct(hello, clock(start))?;
                endpoint
                    .transport()
                    .socket
                    .set_nonblocking(true)
                    .map_err(io("making the socket non-blocking"))?;
                return Ok((endpoint, w));
            }
            Ok(Message::Bye(b)) if b.reason == bye_reason::REJECTED && b.nonce == nonce => {
                return Err(LinkError::Rejected { addr: server });
            }
            Ok(_) => {}
            Err(e) => count_decode_error(e, &mut stats),
        }
    }
    Err(LinkError::HandshakeTimeout {
        addr: server,
        waited: timeout,
    })
}

/// The rejecting Bye answering a wrong-token Hello (same size as the
/// Hello: no amplification). The client cannot check its tag (it is under
/// the server's token); it believes it because it echoes its Hello's nonce.
fn rejection(nonce: u64) -> Message {
    Message::Bye(ByeMsg {
        nonce,
        ..ByeMsg::new(bye_reason::REJECTED)
    })
}
