//! The UDP link of the two-process deployment (paper §2: "connected via the
//! local network by socket connections").
//!
//! Server: [`UdpServer::bind`] (loopback only unless `allow_remote`), then
//! [`UdpServer::accept`] waits for a [`HelloMsg`] carrying the session token,
//! answers with a [`WelcomeMsg`] and connects the socket to that client.
//! A Hello with another token is counted and answered with a rejecting
//! [`ByeMsg`]. Client: [`connect`] sends Hellos every 20 ms until the
//! Welcome arrives or the timeout passes. The handshake runs on the wall
//! clock; the established [`UdpEndpoint`] is non-blocking and works on the
//! caller's clock like any [`crate::Link`].

use crate::codec::{decode, decode_any, encode};
use crate::fault::FaultConfig;
use crate::link::{count_decode_error, Endpoint, LinkError, Transport};
use crate::message::{
    bye_reason, ByeMsg, DatagramBuf, HelloMsg, Message, WelcomeMsg, MAX_MESSAGE_SIZE,
};
use crate::sequence::LinkStats;
use crate::Header;
use std::io::ErrorKind;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

/// Interval between Hello retransmissions.
const HELLO_INTERVAL: Duration = Duration::from_millis(20);
/// Read timeout used while handshaking.
const HANDSHAKE_POLL: Duration = Duration::from_millis(5);
/// Receive buffer: larger than any message, so oversized datagrams show.
const RECV_BUF: usize = 2 * MAX_MESSAGE_SIZE;

/// A connected, non-blocking UDP socket.
pub struct UdpTransport {
    socket: UdpSocket,
    peer: SocketAddr,
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
        let mut buf: DatagramBuf = [0; MAX_MESSAGE_SIZE];
        let n = encode(msg, &mut buf);
        match self.socket.send(&buf[..n]) {
            Ok(_) => Ok(()),
            Err(e) if transient(e.kind()) || e.kind() == ErrorKind::WouldBlock => {
                stats.io_errors += 1;
                Ok(())
            }
            Err(e) => Err(io("sending a datagram")(e)),
        }
    }

    fn receive(&mut self, token: u64, stats: &mut LinkStats) -> Result<Option<Message>, LinkError> {
        let mut buf = [0u8; RECV_BUF];
        loop {
            match self.socket.recv(&mut buf) {
                Ok(n) => match decode(&buf[..n], token) {
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

    /// Waits up to `timeout` (wall clock) for a Hello with `token`, answers
    /// with a Welcome announcing `physics_rate` (Hz), and returns the
    /// endpoint connected to that client, injecting `faults` on what it
    /// sends. `now` (s, caller's clock) stamps the Welcome and marks the
    /// client heard.
    pub fn accept(
        self,
        token: u64,
        faults: FaultConfig,
        physics_rate: f64,
        timeout: Duration,
        now: f64,
    ) -> Result<UdpEndpoint, LinkError> {
        let socket = self.socket;
        socket
            .set_read_timeout(Some(HANDSHAKE_POLL))
            .map_err(io("setting the read timeout"))?;
        let start = Instant::now();
        let mut stats = LinkStats::default();
        let mut buf = [0u8; RECV_BUF];
        while start.elapsed() < timeout {
            let (n, from) = match socket.recv_from(&mut buf) {
                Ok(r) => r,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    continue
                }
                Err(e) if transient(e.kind()) => continue,
                Err(e) => return Err(io("waiting for a client")(e)),
            };
            let hello = match decode_any(&buf[..n]) {
                Ok(Message::Hello(h)) => h,
                Ok(_) => continue,
                Err(e) => {
                    count_decode_error(e, &mut stats);
                    continue;
                }
            };
            if hello.header.token != token {
                stats.wrong_token += 1;
                tracing::warn!(%from, "refused a client with a wrong session token");
                reject(&socket, &hello, from);
                continue;
            }
            socket
                .connect(from)
                .map_err(io("connecting to the client"))?;
            socket
                .set_nonblocking(true)
                .map_err(io("making the socket non-blocking"))?;
            let transport = UdpTransport { socket, peer: from };
            let mut endpoint = Endpoint::new(transport, token, faults);
            endpoint.merge_stats(&stats);
            // The Hello arrived now, on the caller's clock: `now` was read
            // before the wait, and a client that starts later than the peer
            // timeout after the server must not be taken as already silent.
            let now = now + start.elapsed().as_secs_f64();
            endpoint.mark_heard(hello.header.seq, now);
            let welcome = WelcomeMsg {
                header: Header::default(),
                nonce: hello.nonce,
                physics_rate,
            };
            endpoint.set_welcome(welcome);
            endpoint.send_direct(Message::Welcome(welcome), now)?;
            tracing::info!(client = %from, "client accepted");
            return Ok(endpoint);
        }
        Err(LinkError::AcceptTimeout {
            waited: timeout,
            wrong_token: stats.wrong_token,
        })
    }
}

/// Best-effort rejecting Bye to a client with the wrong token (same size as
/// its Hello: no amplification).
fn reject(socket: &UdpSocket, hello: &HelloMsg, to: SocketAddr) {
    let mut bye = ByeMsg::new(bye_reason::REJECTED);
    bye.header.token = hello.header.token;
    let mut buf: DatagramBuf = [0; MAX_MESSAGE_SIZE];
    let n = encode(&Message::Bye(bye), &mut buf);
    if let Err(e) = socket.send_to(&buf[..n], to) {
        tracing::debug!(%to, error = %e, "could not send the rejection");
    }
}

/// Client side: binds an ephemeral port (loopback for a loopback server),
/// handshakes with the server at `server` presenting `token`, and returns
/// the endpoint (injecting `faults` on what it sends) and the server's
/// Welcome. Fails with [`LinkError::HandshakeTimeout`] after `timeout`
/// (wall clock) or [`LinkError::Rejected`] on a wrong token. `now` (s,
/// caller's clock) stamps the Hellos and marks the server heard.
pub fn connect(
    server: SocketAddr,
    token: u64,
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
    let transport = UdpTransport {
        socket,
        peer: server,
    };
    let mut endpoint = Endpoint::new(transport, token, faults);
    let start = Instant::now();
    let mut last_hello: Option<Instant> = None;
    let mut buf = [0u8; RECV_BUF];
    while start.elapsed() < timeout {
        if !matches!(last_hello, Some(t) if t.elapsed() < HELLO_INTERVAL) {
            let hello = HelloMsg {
                header: Header::default(),
                nonce,
            };
            endpoint.send_direct(Message::Hello(hello), now)?;
            last_hello = Some(Instant::now());
        }
        let n = match endpoint.transport().socket.recv(&mut buf) {
            Ok(n) => n,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => continue,
            Err(e) if transient(e.kind()) => continue,
            Err(e) => return Err(io("waiting for the Welcome")(e)),
        };
        match decode(&buf[..n], token) {
            Ok(Message::Welcome(w)) if w.nonce == nonce => {
                endpoint
                    .transport()
                    .socket
                    .set_nonblocking(true)
                    .map_err(io("making the socket non-blocking"))?;
                endpoint.mark_heard(w.header.seq, now);
                return Ok((endpoint, w));
            }
            Ok(Message::Bye(b)) if b.reason == bye_reason::REJECTED => {
                return Err(LinkError::Rejected { addr: server });
            }
            Ok(_) => {}
            Err(e) => {
                let mut stats = LinkStats::default();
                count_decode_error(e, &mut stats);
                endpoint.merge_stats(&stats);
            }
        }
    }
    Err(LinkError::HandshakeTimeout {
        addr: server,
        waited: timeout,
    })
}
