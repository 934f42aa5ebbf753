//! Helpers shared by the integration tests: a loopback session and waiting
//! for datagrams (loopback delivery is immediate on Linux, but the tests
//! must not depend on it).

#![allow(dead_code)]

use echothigh_transport::{
    connect, FaultConfig, Link, ListenConfig, Message, SessionToken, UdpEndpoint, UdpServer,
};
use std::net::SocketAddr;
use std::time::{Duration, Instant};

/// A loopback listen configuration on a free port.
pub fn loopback() -> ListenConfig {
    ListenConfig {
        addr: "127.0.0.1:0".parse().unwrap(),
        allow_remote: false,
    }
}

/// A 16-digit token whose last digits are `n` (test tokens).
pub fn token(n: u64) -> SessionToken {
    format!("{n:016x}").parse().unwrap()
}

/// A connected (server, client) pair over loopback UDP.
pub fn session(
    token: &SessionToken,
    server_faults: FaultConfig,
    client_faults: FaultConfig,
) -> (UdpEndpoint, UdpEndpoint) {
    let server = UdpServer::bind(&loopback()).unwrap();
    let addr: SocketAddr = server.local_addr().unwrap();
    let t = *token;
    let accept = std::thread::spawn(move || {
        server.accept(&t, server_faults, 100.0, Duration::from_secs(5), 0.0)
    });
    let (client, welcome) =
        connect(addr, token, client_faults, Duration::from_secs(5), 0.0).unwrap();
    assert_eq!(welcome.physics_rate, 100.0);
    let server = accept.join().unwrap().unwrap();
    (server, client)
}

/// Receives on `link` at virtual time `now`, retrying on the wall clock for
/// up to one second.
pub fn recv_wait<L: Link + ?Sized>(link: &mut L, now: f64) -> Option<Message> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(1) {
        if let Some(m) = link.recv(now).unwrap() {
            return Some(m);
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    None
}
