//! An emulator of Haply's Inverse Service (3.5): a local WebSocket server
//! speaking the service's JSON frames, in the `haply` crate's own message
//! types, for one emulated Inverse3 and an optional wireless VerseGrip.
//!
//! Protocol, as the service documents it: on connecting, the client gets an
//! inventory frame (every device with `config`, `state` and `status`); from
//! then on the server answers **each** client message with exactly one state
//! frame. A `set_cursor_force` command sets the motor force (N, device
//! frame), held until the next command (zero-order hold). Plain HTTP
//! `GET /version` and `GET /devices` on the same port answer as the
//! service's REST interface does (3.5 serves both on port 10001).
//!
//! The Inverse3 is an [`Arm`] (0.2 kg, 2 N·s/m, as the DHD emulator's)
//! integrated to the wall-clock time of each message. **Not the real
//! service:** when a session's socket closes, this emulator releases the
//! motors (zero force) and counts whether the client had left a non-zero
//! force commanded ([`InverseService::closed_with_force`]), so tests can
//! check that echothigh zeroes the force itself before leaving.
//!
//! Unlike the HD and DHD emulators this one is used in-process (a Rust
//! API, not C functions): [`InverseService::start`] binds a free loopback
//! port; the test controls (hand, grip, unplug, kill) are methods.

mod session;

use crate::arm::Arm;
use crate::lock;
use std::net::{SocketAddr, TcpListener};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// The emulated Inverse3's `device_id`.
pub const DEVICE_ID: &str = "049D";
/// The emulated VerseGrip's `device_id`.
pub const GRIP_ID: &str = "2A1F";

/// The emulated hardware and what the tests read back.
#[derive(Debug, Clone)]
pub(crate) struct Hardware {
    pub arm: Arm,
    /// The Inverse3 is listed (false after [`InverseService::unplug`]).
    pub present: bool,
    /// The VerseGrip: orientation `[w, x, y, z]` and buttons (bit 0 = a).
    pub grip: Option<([f64; 4], u32)>,
    /// Last commanded force (N) and when (s, [`crate::now`]).
    pub last_force: ([f64; 3], f64),
    /// Largest force magnitude applied (N).
    pub max_applied: f64,
    /// Time the arm was last integrated to (s).
    pub integrated_to: Option<f64>,
    /// Command messages answered.
    pub frames: u64,
    /// Sessions that closed while their last command was a non-zero force.
    pub closed_with_force: u32,
}

impl Hardware {
    fn new() -> Self {
        Hardware {
            arm: Arm::new(0.2, 2.0),
            present: true,
            grip: Some(([1.0, 0.0, 0.0, 0.0], 0)),
            last_force: ([0.0; 3], 0.0),
            max_applied: 0.0,
            integrated_to: None,
            frames: 0,
            closed_with_force: 0,
        }
    }

    /// Integrates the arm to now with the force held since the last message.
    pub fn integrate(&mut self) {
        let now = crate::now();
        if let Some(t) = self.integrated_to {
            self.arm.advance(now - t);
        }
        self.integrated_to = Some(now);
    }
}

pub(crate) struct Shared {
    pub hw: Mutex<Hardware>,
    /// Set by [`InverseService::kill`]: every session drops its socket at once.
    pub killed: AtomicBool,
}

/// A running emulated service; stops (and joins its threads) when dropped.
pub struct InverseService {
    addr: SocketAddr,
    shared: Arc<Shared>,
    accept: Option<JoinHandle<()>>,
}

impl InverseService {
    /// Starts the service on a free loopback port.
    pub fn start() -> std::io::Result<InverseService> {
        let listener = TcpListener::bind("127.0.0.1:0")?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let shared = Arc::new(Shared {
            hw: Mutex::new(Hardware::new()),
            killed: AtomicBool::new(false),
        });
        let s = Arc::clone(&shared);
        let accept = std::thread::Builder::new()
            .name("inverse-emu-accept".into())
            .spawn(move || accept_loop(listener, s))?;
        Ok(InverseService {
            addr,
            shared,
            accept: Some(accept),
        })
    }

    /// The simulation channel's address, `ws://127.0.0.1:PORT`.
    pub fn url(&self) -> String {
        format!("ws://{}", self.addr)
    }

    /// The REST interface's base address, `http://127.0.0.1:PORT`.
    pub fn http_url(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// The emulated hand pulls the cursor to `target` (m, device frame) with
    /// stiffness `k` (N/m) and damping `c` (N·s/m); `None` lets go.
    pub fn set_hand(&self, target: Option<[f64; 3]>, k: f64, c: f64) {
        lock(&self.shared.hw).arm.hand = target.map(|t| (t, k, c));
    }

    /// The VerseGrip's orientation `[w, x, y, z]` (normalised by the reader);
    /// `None` detaches the grip (the service stops listing it).
    pub fn set_grip(&self, orientation: Option<[f64; 4]>) {
        let mut hw = lock(&self.shared.hw);
        let buttons = hw.grip.map_or(0, |g| g.1);
        hw.grip = orientation.map(|q| (q, buttons));
    }

    /// The grip's buttons (bit 0 = a, 1 = b, 2 = c).
    pub fn set_buttons(&self, mask: u32) {
        if let Some(g) = lock(&self.shared.hw).grip.as_mut() {
            g.1 = mask;
        }
    }

    /// The Inverse3 disappears (unplugged): the motors stop and the state
    /// frames no longer list it; the sessions stay open.
    pub fn unplug(&self) {
        let mut hw = lock(&self.shared.hw);
        hw.present = false;
        hw.arm.motor = [0.0; 3];
    }

    /// The service dies: every session's socket is dropped without a close
    /// frame and no new connection is accepted.
    pub fn kill(&self) {
        self.shared.killed.store(true, Ordering::Release);
    }

    /// Last commanded force (N, device frame) and the emulator time (s) it came at.
    pub fn last_force(&self) -> ([f64; 3], f64) {
        lock(&self.shared.hw).last_force
    }

    /// Force the motors apply now (N, device frame).
    pub fn applied_force(&self) -> [f64; 3] {
        lock(&self.shared.hw).arm.motor
    }

    /// Largest force magnitude applied so far (N).
    pub fn max_applied_force(&self) -> f64 {
        lock(&self.shared.hw).max_applied
    }

    /// Cursor position (m, device frame), integrated to now.
    pub fn position(&self) -> [f64; 3] {
        let mut hw = lock(&self.shared.hw);
        hw.integrate();
        hw.arm.position
    }

    /// Command messages answered so far.
    pub fn frames(&self) -> u64 {
        lock(&self.shared.hw).frames
    }

    /// Sessions that ended with a non-zero force still commanded.
    pub fn closed_with_force(&self) -> u32 {
        lock(&self.shared.hw).closed_with_force
    }
}

impl Drop for InverseService {
    fn drop(&mut self) {
        self.kill();
        if let Some(t) = self.accept.take() {
            let _ = t.join();
        }
    }
}

/// Accepts connections until killed, one session thread each; joins them.
fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    let mut sessions: Vec<JoinHandle<()>> = Vec::new();
    while !shared.killed.load(Ordering::Acquire) {
        match listener.accept() {
            Ok((stream, _)) => {
                let s = Arc::clone(&shared);
                if let Ok(h) = std::thread::Builder::new()
                    .name("inverse-emu-session".into())
                    .spawn(move || session::serve(stream, s))
                {
                    sessions.push(h);
                }
            }
            Err(_) => std::thread::sleep(Duration::from_millis(2)),
        }
    }
    drop(listener);
    for h in sessions {
        let _ = h.join();
    }
}
