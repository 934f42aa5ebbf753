//! The WebSocket link to the Inverse Service and the exchange thread that
//! owns it.
//!
//! The service answers every message with exactly one state frame (its 3.5
//! protocol: "one response per message", the cadence set by the client), so
//! each round trip is a blocking send and read. That is I/O the 1 kHz tick
//! must never do: the exchange thread makes the round trips at
//! `haply.rate` and meets the tick only through [`crate::servo`]'s triple
//! buffers, as DHD's servo thread does.
//!
//! **Why not the crate's `HaplyDevice`.** The backend uses the `haply`
//! crate's message types ([`super::wire`]) but its own blocking
//! `tungstenite` socket, for reasons read in `haply` 1.3.1's source (not
//! measured): its listener task (`InverseWebSocketClient::listen`) handles
//! only `Some(Ok(Text))` from `reader.next()` and loops again on `None` or an
//! error, so after the service closes the socket the loop keeps polling a
//! finished stream instead of reporting the loss; it keeps no link between a
//! command and the state frame that answers it, which a lockstep watchdog
//! needs; and every frame goes through `tokio::sync::Mutex`es shared with
//! that listener. A plain socket with a read timeout reports a dead service
//! as an error on the next round trip (tested against the emulator).

use super::wire::{self, CommandFrame, Inventory, Reading};
use crate::servo::{ServoSide, ServoState, FAULT_LOST};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// An open session with the service, after its inventory frame.
pub struct Link {
    socket: WebSocket<TcpStream>,
}

/// Why a round trip failed.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkError {
    /// The socket failed or the service did not answer in time.
    Io(String),
    /// The service answered something unreadable.
    Protocol(String),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "{e}"),
            LinkError::Protocol(e) => write!(f, "unexpected reply: {e}"),
        }
    }
}

/// `host:port` of a `ws://` address (port 80 if absent, as for any WebSocket).
fn authority(url: &str) -> Result<(String, u16), String> {
    let uri: tungstenite::http::Uri = url.parse().map_err(|e| format!("not an address: {e}"))?;
    let host = uri.host().ok_or("no host in the address")?.to_string();
    Ok((host, uri.port_u16().unwrap_or(80)))
}

impl Link {
    /// Connects (TCP, then the WebSocket handshake), each step bounded by
    /// `connect_timeout` s, and reads the inventory frame. Reads later wait
    /// at most `reply_timeout` s.
    pub fn connect(
        url: &str,
        connect_timeout: f64,
        reply_timeout: f64,
    ) -> Result<(Link, Inventory), String> {
        let (host, port) = authority(url)?;
        let timeout = Duration::from_secs_f64(connect_timeout);
        let addrs: Vec<_> = (host.as_str(), port)
            .to_socket_addrs()
            .map_err(|e| format!("cannot resolve {host}: {e}"))?
            .collect();
        let mut last = format!("{host} has no address");
        let stream = addrs
            .iter()
            .find_map(|a| match TcpStream::connect_timeout(a, timeout) {
                Ok(s) => Some(s),
                Err(e) => {
                    last = format!("{a}: {e}");
                    None
                }
            })
            .ok_or(last)?;
        let io = |e: std::io::Error| e.to_string();
        stream.set_nodelay(true).map_err(io)?;
        stream.set_read_timeout(Some(timeout)).map_err(io)?;
        stream.set_write_timeout(Some(timeout)).map_err(io)?;
        let (socket, _) = tungstenite::client(url, stream)
            .map_err(|e| format!("WebSocket handshake failed: {e}"))?;
        let mut link = Link { socket };
        let first = link
            .receive()
            .map_err(|e| format!("no inventory frame: {e}"))?;
        let reply = Duration::from_secs_f64(reply_timeout);
        let stream = link.socket.get_mut();
        stream.set_read_timeout(Some(reply)).map_err(io)?;
        stream.set_write_timeout(Some(reply)).map_err(io)?;
        let inventory = wire::inventory(&first)?;
        Ok((link, inventory))
    }

    /// Reads until a text frame arrives (pings are answered by tungstenite).
    fn receive(&mut self) -> Result<String, LinkError> {
        loop {
            match self.socket.read() {
                Ok(Message::Text(t)) => return Ok(t.as_str().to_owned()),
                Ok(Message::Close(_)) => {
                    return Err(LinkError::Io("the service closed the connection".into()))
                }
                Ok(_) => continue,
                Err(e) => return Err(LinkError::Io(e.to_string())),
            }
        }
    }

    /// One round trip: sends `text`, returns the state frame answering it.
    pub fn round_trip(&mut self, text: String) -> Result<String, LinkError> {
        self.socket
            .send(Message::Text(text.into()))
            .map_err(|e| LinkError::Io(e.to_string()))?;
        self.receive()
    }

    /// Closes the session politely (best effort: the service may be gone).
    pub fn close(mut self) {
        if self.socket.close(None).is_ok() {
            // Drain until the service's close reply or the read timeout.
            let deadline = Instant::now() + Duration::from_millis(100);
            while Instant::now() < deadline && self.socket.read().is_ok() {}
        }
    }
}

/// The exchange thread's loop (see the module docs).
pub struct Exchange {
    /// The open session.
    pub link: Link,
    /// The tick's counterpart.
    pub side: ServoSide,
    /// The Inverse3 driven.
    pub device: String,
    /// The VerseGrip read for orientation and buttons, if any.
    pub grip: Option<String>,
    /// Round-trip period.
    pub period: Duration,
}

impl Exchange {
    /// Round trips until the stop flag (the last frame commands zero force,
    /// then the session is closed) or until the service or the device is
    /// lost (the fault is published, and the device's force is zeroed if
    /// the service still answers).
    pub fn run(self) {
        let Exchange {
            mut link,
            mut side,
            device,
            grip,
            period,
        } = self;
        let mut frame = CommandFrame::new(&device);
        let mut state = ServoState::default();
        let mut next = Instant::now();
        loop {
            let stopping = side.stopping();
            let force = side.force_to_apply();
            let outcome = link.round_trip(frame.encode(force)).and_then(|t| {
                wire::reading(&t, &device, grip.as_deref()).map_err(LinkError::Protocol)
            });
            state.ticks += 1;
            match outcome {
                Ok(Some(r)) => apply(&mut state, &r),
                Ok(None) => {
                    // The Inverse3 left the service's list: unplugged or powered off.
                    state.fault = FAULT_LOST;
                    let _ = link.round_trip(frame.encode([0.0; 3]));
                }
                Err(_) => state.fault = FAULT_LOST,
            }
            side.publish(state);
            if stopping || state.fault != 0 {
                link.close();
                return;
            }
            next += period;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
    }
}

fn apply(state: &mut ServoState, r: &Reading) {
    state.position = r.position;
    state.velocity = r.velocity;
    if let Some(m) = r.rotation {
        state.rotation = m;
    }
    state.buttons = r.buttons;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn authority_reads_host_and_port() {
        assert_eq!(
            authority("ws://localhost:10001").unwrap(),
            ("localhost".to_string(), 10001)
        );
        assert_eq!(authority("ws://127.0.0.1/").unwrap().1, 80);
        assert!(authority("ws://").is_err());
    }
}
