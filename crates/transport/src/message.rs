//! The wire format: fixed-size `#[repr(C)]` messages, each starting with a
//! common [`Header`].
//!
//! The physics–haptics exchange of the paper's Fig. 1 (§2): the haptic side
//! sends the probe pose ([`ProbeMsg`]); the physics answers with the distance
//! `D`, its gradient `∇D` and the local stiffness `k` ([`SampleMsg`], the
//! inputs of the model manager, §4), plus the contact force and solver
//! statistics. [`HelloMsg`] / [`WelcomeMsg`] form the handshake, [`ByeMsg`]
//! a clean shutdown.
//!
//! Byte order: the structs are written as their in-memory bytes
//! (`bytemuck`), and the crate refuses to compile on big-endian targets, so
//! the wire format is little-endian. Every struct is padding-free (asserted by
//! `bytemuck::Pod`'s derive), so the encoded size of a kind is its
//! `size_of`.

use bytemuck::{Pod, Zeroable};

/// The four magic bytes `b"ETHG"` at the start of every datagram.
pub const MAGIC: u32 = u32::from_le_bytes(*b"ETHG");
/// The wire-format version this crate speaks.
pub const VERSION: u16 = 1;
/// Size of the largest message (bytes); a buffer of this size holds any
/// encoded message.
pub const MAX_MESSAGE_SIZE: usize = std::mem::size_of::<SampleMsg>();
/// A buffer able to hold any encoded message.
pub type DatagramBuf = [u8; MAX_MESSAGE_SIZE];

/// Header common to every message (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Header {
    /// [`MAGIC`].
    pub magic: u32,
    /// [`VERSION`].
    pub version: u16,
    /// The message kind, one of [`Kind`] as `u16`.
    pub kind: u16,
    /// Session token agreed in the handshake (see [`crate::SessionToken`]).
    pub token: u64,
    /// Sender's sequence number, strictly increasing per sender (all kinds).
    pub seq: u64,
    /// Time the message was sent, on the sender's clock (s).
    pub t_send: f64,
}

/// Message kinds as carried in [`Header::kind`].
#[repr(u16)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// [`ProbeMsg`].
    Probe = 1,
    /// [`SampleMsg`].
    Sample = 2,
    /// [`HelloMsg`].
    Hello = 3,
    /// [`WelcomeMsg`].
    Welcome = 4,
    /// [`ByeMsg`].
    Bye = 5,
}

impl Kind {
    /// The kind with this wire code, if any.
    pub fn from_code(code: u16) -> Option<Kind> {
        match code {
            1 => Some(Kind::Probe),
            2 => Some(Kind::Sample),
            3 => Some(Kind::Hello),
            4 => Some(Kind::Welcome),
            5 => Some(Kind::Bye),
            _ => None,
        }
    }

    /// Encoded size of a message of this kind (bytes).
    pub fn size(self) -> usize {
        match self {
            Kind::Probe => std::mem::size_of::<ProbeMsg>(),
            Kind::Sample => std::mem::size_of::<SampleMsg>(),
            Kind::Hello => std::mem::size_of::<HelloMsg>(),
            Kind::Welcome => std::mem::size_of::<WelcomeMsg>(),
            Kind::Bye => std::mem::size_of::<ByeMsg>(),
        }
    }
}

/// Probe pose, haptic → physics (paper §2: "It receives the actual position
/// of the virtual echographic probe").
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ProbeMsg {
    /// Common header.
    pub header: Header,
    /// Time the device was sampled, haptic clock (s).
    pub t_device: f64,
    /// Probe reference point (face centre), thigh frame (m).
    pub position: [f64; 3],
    /// Probe orientation, unit quaternion `(w, x, y, z)`, thigh frame.
    pub orientation: [f64; 4],
    /// Application flags (bit field, free for the caller).
    pub flags: u32,
    /// Explicit padding, zero.
    pub _pad: u32,
}

/// One physics sample, physics → haptic: the model manager's inputs
/// `(D, ∇D, k)` of paper §4 at the probe point `p`, plus the contact force
/// (Eq. 2 summed over the nodes) and solver statistics (Eq. 1).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SampleMsg {
    /// Common header.
    pub header: Header,
    /// Physics time of the sample (s).
    pub t_sample: f64,
    /// Sequence number of the [`ProbeMsg`] this sample answers.
    pub probe_seq: u64,
    /// Probe reference point the sample was taken at, thigh frame (m).
    pub p: [f64; 3],
    /// Signed distance `D` (m), positive outside, `−|F·n|/k` in contact.
    pub distance: f64,
    /// Gradient `∇D` with respect to `p` (unit).
    pub gradient: [f64; 3],
    /// Local stiffness `k` (N/m).
    pub stiffness: f64,
    /// Net contact force on the probe, thigh frame (N).
    pub force: [f64; 3],
    /// 1 when the probe touches the tissue, 0 otherwise.
    pub in_contact: u32,
    /// Newton iterations of the last physics step.
    pub newton_iterations: u32,
    /// CG iterations of the last physics step (all Newton iterations).
    pub cg_iterations: u32,
    /// Asymptote-limiter activations of the last physics step.
    pub limited: u32,
    /// Physics rate achieved (Hz).
    pub physics_rate: f64,
}

/// Handshake request, client → server.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HelloMsg {
    /// Common header; `token` is the session token the client presents.
    pub header: Header,
    /// Client nonce, echoed by the [`WelcomeMsg`].
    pub nonce: u64,
}

/// Handshake answer, server → client.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WelcomeMsg {
    /// Common header; `token` echoes the session token.
    pub header: Header,
    /// The client's nonce, echoed.
    pub nonce: u64,
    /// Physics rate the server is configured for (Hz).
    pub physics_rate: f64,
}

/// Reasons carried by a [`ByeMsg`].
pub mod bye_reason {
    /// Clean shutdown.
    pub const SHUTDOWN: u32 = 0;
    /// The server rejected the client's session token.
    pub const REJECTED: u32 = 1;
}

/// Clean shutdown, either side.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ByeMsg {
    /// Common header.
    pub header: Header,
    /// One of [`bye_reason`].
    pub reason: u32,
    /// Explicit padding, zero.
    pub _pad: u32,
}

/// Any message of the wire format.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message {
    /// Probe pose, haptic → physics.
    Probe(ProbeMsg),
    /// Physics sample, physics → haptic.
    Sample(SampleMsg),
    /// Handshake request.
    Hello(HelloMsg),
    /// Handshake answer.
    Welcome(WelcomeMsg),
    /// Clean shutdown.
    Bye(ByeMsg),
}

impl ProbeMsg {
    /// A probe message with a blank header (the link stamps it on send).
    pub fn new(t_device: f64, position: [f64; 3], orientation: [f64; 4], flags: u32) -> Self {
        ProbeMsg {
            header: Header::default(),
            t_device,
            position,
            orientation,
            flags,
            _pad: 0,
        }
    }
}

impl ByeMsg {
    /// A bye message with a blank header and the given [`bye_reason`].
    pub fn new(reason: u32) -> Self {
        ByeMsg {
            header: Header::default(),
            reason,
            _pad: 0,
        }
    }
}

impl Message {
    /// The kind of this message.
    pub fn kind(&self) -> Kind {
        match self {
            Message::Probe(_) => Kind::Probe,
            Message::Sample(_) => Kind::Sample,
            Message::Hello(_) => Kind::Hello,
            Message::Welcome(_) => Kind::Welcome,
            Message::Bye(_) => Kind::Bye,
        }
    }

    /// The header.
    pub fn header(&self) -> &Header {
        match self {
            Message::Probe(m) => &m.header,
            Message::Sample(m) => &m.header,
            Message::Hello(m) => &m.header,
            Message::Welcome(m) => &m.header,
            Message::Bye(m) => &m.header,
        }
    }

    /// The header, mutable (the link stamps token, sequence and send time).
    pub fn header_mut(&mut self) -> &mut Header {
        match self {
            Message::Probe(m) => &mut m.header,
            Message::Sample(m) => &mut m.header,
            Message::Hello(m) => &mut m.header,
            Message::Welcome(m) => &mut m.header,
            Message::Bye(m) => &mut m.header,
        }
    }

    /// The sequence number of the header.
    pub fn seq(&self) -> u64 {
        self.header().seq
    }

    /// The message's bytes, as they go on the wire (header magic, version
    /// and kind not yet fixed: see [`crate::encode`]).
    pub(crate) fn as_bytes(&self) -> &[u8] {
        match self {
            Message::Probe(m) => bytemuck::bytes_of(m),
            Message::Sample(m) => bytemuck::bytes_of(m),
            Message::Hello(m) => bytemuck::bytes_of(m),
            Message::Welcome(m) => bytemuck::bytes_of(m),
            Message::Bye(m) => bytemuck::bytes_of(m),
        }
    }
}

impl From<ProbeMsg> for Message {
    fn from(m: ProbeMsg) -> Self {
        Message::Probe(m)
    }
}

impl From<SampleMsg> for Message {
    fn from(m: SampleMsg) -> Self {
        Message::Sample(m)
    }
}

impl From<ByeMsg> for Message {
    fn from(m: ByeMsg) -> Self {
        Message::Bye(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_fixed_and_aligned() {
        assert_eq!(std::mem::size_of::<Header>(), 32);
        assert_eq!(Kind::Probe.size(), 104);
        assert_eq!(Kind::Sample.size(), 160);
        assert_eq!(Kind::Hello.size(), 40);
        assert_eq!(Kind::Welcome.size(), 48);
        assert_eq!(Kind::Bye.size(), 40);
        assert_eq!(MAX_MESSAGE_SIZE, 160);
    }

    #[test]
    fn kind_codes_round_trip() {
        for k in [
            Kind::Probe,
            Kind::Sample,
            Kind::Hello,
            Kind::Welcome,
            Kind::Bye,
        ] {
            assert_eq!(Kind::from_code(k as u16), Some(k));
        }
        assert_eq!(Kind::from_code(0), None);
        assert_eq!(Kind::from_code(6), None);
    }

    #[test]
    fn magic_reads_as_ascii_on_the_wire() {
        assert_eq!(&MAGIC.to_le_bytes(), b"ETHG");
    }
}
