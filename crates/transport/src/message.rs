//! The wire format: fixed-size `#[repr(C)]` messages, each starting with a
//! common [`Header`].
//!
//! The physics–haptics exchange of the paper's Fig. 1 (§2): the haptic side
//! sends the probe pose ([`ProbeMsg`]); the physics answers with the distance
//! `D`, its gradient `∇D` and the local stiffness `k` ([`SampleMsg`], the
//! inputs of the model manager, §4), plus the contact force and solver
//! statistics. [`HelloMsg`] / [`WelcomeMsg`] form the handshake, [`ByeMsg`]
//! a clean shutdown. On UDP every message is followed by a
//! [`crate::MAC_LEN`]-byte tag ([`crate::auth`]); the session token itself
//! is never sent.
//!
//! "No contact" on the wire: [`SampleMsg::contact`] says which of three
//! states the physics is in ([`contact_state`]): touching (`D < 0` or 0),
//! separated (`D > 0`, the distance to the surface), or no surface found
//! near the probe, where the physics' own `D = +∞` is sent as the finite
//! sentinel [`NO_SURFACE_DISTANCE`] (1 m, farther than any probe–skin
//! distance that matters: a local model placed 1 m away renders no force
//! within the device's workspace). Use [`wire_query`] to fill both. No
//! field of any message may be non-finite or outside the limits of
//! [`crate::limits`]: the encoder refuses such a message and the decoder
//! drops such a datagram.
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
pub const VERSION: u16 = 2;
/// Size of the largest message (bytes), without its tag.
pub const MAX_MESSAGE_SIZE: usize = std::mem::size_of::<SampleMsg>();
/// Size of the largest datagram: the largest message and its tag (bytes).
pub const MAX_DATAGRAM_SIZE: usize = MAX_MESSAGE_SIZE + crate::auth::MAC_LEN;
/// A buffer able to hold any datagram (message and tag).
pub type DatagramBuf = [u8; MAX_DATAGRAM_SIZE];

/// Distance sent when the physics found no surface near the probe (its
/// `D = +∞`), m, with [`contact_state::NO_SURFACE`].
pub const NO_SURFACE_DISTANCE: f64 = 1.0;

/// Values of [`SampleMsg::contact`].
pub mod contact_state {
    /// The probe is outside the tissue; `distance` is `D > 0`.
    pub const SEPARATED: u32 = 0;
    /// The probe touches the tissue; `distance` is `D = −|F·n|/k ≤ 0`.
    pub const TOUCHING: u32 = 1;
    /// No surface near the probe; `distance` is
    /// [`super::NO_SURFACE_DISTANCE`].
    pub const NO_SURFACE: u32 = 2;
}

/// The wire form `(distance, contact)` of the physics' `D` (m) and contact
/// flag: `D = +∞` (or beyond [`crate::limits::MAX_DISTANCE`]) outside
/// contact becomes [`NO_SURFACE_DISTANCE`] with
/// [`contact_state::NO_SURFACE`]. A NaN stays NaN (the encoder refuses it).
pub fn wire_query(distance: f64, in_contact: bool) -> (f64, u32) {
    if in_contact {
        (distance, contact_state::TOUCHING)
    } else if distance > crate::limits::MAX_DISTANCE {
        (NO_SURFACE_DISTANCE, contact_state::NO_SURFACE)
    } else {
        (distance, contact_state::SEPARATED)
    }
}

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
    /// Public session id derived in the handshake (0 in a Hello); not a
    /// secret: the tag authenticates, the id tells sessions apart.
    pub session: u64,
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
    /// One of [`contact_state`]: touching, separated, or no surface.
    pub contact: u32,
    /// Newton iterations of the last physics step.
    pub newton_iterations: u32,
    /// CG iterations of the last physics step (all Newton iterations).
    pub cg_iterations: u32,
    /// Asymptote-limiter activations of the last physics step.
    pub limited: u32,
    /// Physics rate achieved (Hz).
    pub physics_rate: f64,
}

/// Handshake request, client → server, tagged with the token's hello key
/// (session 0); after the Welcome, sent once more tagged with the session
/// key to confirm the session.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HelloMsg {
    /// Common header.
    pub header: Header,
    /// Client nonce (random), echoed by the [`WelcomeMsg`].
    pub nonce: u64,
    /// Reserved, zero: makes a Hello as long as a rejecting Bye (no
    /// amplification).
    pub _reserved: u64,
}

/// Handshake answer, server → client, tagged with the new session's key.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WelcomeMsg {
    /// Common header; `session` is the new session's id.
    pub header: Header,
    /// The client's nonce, echoed.
    pub nonce: u64,
    /// Server nonce (random): with the client's and the token, the session
    /// keys.
    pub server_nonce: u64,
    /// Physics rate the server is configured for (Hz).
    pub physics_rate: f64,
}

/// Reasons carried by a [`ByeMsg`].
pub mod bye_reason {
    /// Clean shutdown.
    pub const SHUTDOWN: u32 = 0;
    /// The server rejected the client's session token (unauthenticated:
    /// the server cannot tag it with a key the client would accept; the
    /// client believes it only if it echoes its Hello's nonce).
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
    /// A rejection echoes the refused Hello's nonce; 0 otherwise.
    pub nonce: u64,
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
            nonce: 0,
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

    /// The header, mutable (the link stamps session, sequence and send time).
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

impl SampleMsg {
    /// True when [`Self::contact`] is [`contact_state::TOUCHING`].
    pub fn in_contact(&self) -> bool {
        self.contact == contact_state::TOUCHING
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
        assert_eq!(Kind::Hello.size(), 48);
        assert_eq!(Kind::Welcome.size(), 56);
        assert_eq!(Kind::Bye.size(), 48);
        assert_eq!(Kind::Hello.size(), Kind::Bye.size(), "no amplification");
        assert_eq!(MAX_MESSAGE_SIZE, 160);
        assert_eq!(MAX_DATAGRAM_SIZE, 176);
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
    fn no_contact_is_a_finite_sentinel_with_its_own_state() {
        assert_eq!(
            wire_query(f64::INFINITY, false),
            (NO_SURFACE_DISTANCE, contact_state::NO_SURFACE)
        );
        assert_eq!(wire_query(0.02, false), (0.02, contact_state::SEPARATED));
        assert_eq!(wire_query(-0.003, true), (-0.003, contact_state::TOUCHING));
        assert!(wire_query(f64::NAN, false).0.is_nan());
    }

    #[test]
    fn magic_reads_as_ascii_on_the_wire() {
        assert_eq!(&MAGIC.to_le_bytes(), b"ETHG");
    }
}
