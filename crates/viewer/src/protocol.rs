//! The viewer's WebSocket protocol, version [`PROTOCOL_VERSION`].
//!
//! Server → page:
//! - text frames: one JSON [`Envelope`] (`{"v": 1, "type": "...", ...}`), typed
//!   by the serde tag `type`: [`ServerMessage::Hello`] once per connection
//!   (mesh topology), [`ServerMessage::State`] at the push rate,
//!   [`ServerMessage::Error`] when a page message is refused;
//! - binary frames: a 16-byte [`FrameHeader`] then a payload, little-endian:
//!   [`FrameKind::Image`] (8-bit grayscale echographic frame, `a × b` =
//!   width × height, row-major, axial rows) and [`FrameKind::Surface`] (`a` =
//!   node count; `3a` f32 positions in m, then `a` f32 compressions in 0..1).
//!
//! The image frames go on a second socket, `/ws/image?token=T`, once the
//! page's worker opens it with the token of its hello
//! ([`crate::image_link`]); it carries only image frames one way and
//! `image_ack` the other.
//!
//! Page → server: text frames holding one JSON object, either a
//! [`LiveCommand`] (forwarded to the runtime) or a [`ViewerCommand`] (exam
//! mode, handled by the server). [`decode_client`] refuses anything else —
//! wrong types, unknown fields, non-finite or out-of-range numbers, binary
//! frames, oversized text — with a [`ProtocolError`] naming the field; the
//! connection stays up.
//!
//! Units: SI (m, N, s, Hz), thigh frame (z along the axis, y anterior).

use echothigh_exam::Finding;
use echothigh_runtime::live::{LiveCommand, LiveMesh, LiveSnapshot, LiveStatus, VeinState};
use echothigh_runtime::live_device::LiveDeviceStatus;
use echothigh_runtime::live_doppler::{DopplerCommand, DopplerStatus, DOPPLER_COMMAND_TYPES};
use serde::{Deserialize, Serialize};

/// Version carried by every JSON envelope and binary frame header: 2 since
/// the image frames became JPEG (a page of version 1 says it is stale).
pub const PROTOCOL_VERSION: u32 = 2;

/// Largest accepted page message (bytes). Commands are a few dozen bytes.
pub const MAX_CLIENT_MESSAGE: usize = 4096;

pub use echothigh_runtime::live::{
    CommandError, CommandLimits, DEPTH_RANGE, LATENCY_RANGE, MAX_TILT, MIN_PHYSICS_RATE,
    THETA_RANGE,
};

/// A server → page JSON message with its protocol version.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Envelope {
    /// Protocol version, [`PROTOCOL_VERSION`].
    pub v: u32,
    /// The message, tagged by `type`.
    #[serde(flatten)]
    pub body: ServerMessage,
}

impl Envelope {
    /// Wraps `body` with the current protocol version.
    pub fn new(body: ServerMessage) -> Self {
        Self {
            v: PROTOCOL_VERSION,
            body,
        }
    }
}

/// Server → page JSON messages.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
#[allow(clippy::large_enum_variant)] // sent one at a time, never stored in bulk
pub enum ServerMessage {
    /// First message of a connection.
    Hello {
        /// Surface mesh topology and rest positions (m).
        mesh: LiveMesh,
        /// Rate at which state is pushed (Hz).
        state_rate: f64,
        /// The image's field of view (m), for the depth scale drawn on it.
        #[serde(default)]
        image: echothigh_runtime::live::ImageGeometry,
        /// The token (hex) with which the page's worker may open the image
        /// socket, `/ws/image?token=…` ([`crate::image_link`]): the images
        /// then go there.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        image_link: Option<String>,
    },
    /// Latest live state (the surface geometry follows as a binary frame).
    State(ViewState),
    /// A page message was refused; the connection stays up.
    Error {
        /// What was wrong, naming the field.
        message: String,
    },
}

/// A live state as the page shows it: the runtime's scalar state, flattened
/// (its fields sit at the top level of the JSON message, next to `vein` and
/// `exam`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewState {
    /// Time, probe, forces, rates and settings, with every number finite.
    #[serde(flatten)]
    pub status: LiveStatus,
    /// Vein state; `None` while an exam question hides it.
    pub vein: Option<VeinState>,
    /// The exam session, when it changed since this connection's last
    /// state ([`ExamStatus::rev`]); absent otherwise (the page keeps the
    /// last one it got).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exam: Option<ExamStatus>,
    /// This tab only observes: another one drives the probe and the exam
    /// (issue 19: two tabs fought over the probe).
    pub observer: bool,
    /// Number of this state on its connection (1, 2, …): the page
    /// acknowledges it ([`ViewerCommand::Ack`]) once drawn.
    pub seq: u64,
    /// When the server sent this state: Unix time (ms). On one machine the
    /// page's clock is the server's, so a command's lag splits into the
    /// server's part (sent − command) and the delivery's (arrival − sent).
    #[serde(default)]
    pub sent_ms: f64,
    /// A thread of the simulation stopped, in plain words (`None`: all run).
    pub fault: Option<String>,
    /// The real haptic device driving the probe (issue 15): its clutch, its
    /// force (N, device units) next to the tissue force, its workspace in
    /// the thigh frame, whether it still answers; `None` while the page's
    /// mouse drives.
    pub haptic_device: Option<LiveDeviceStatus>,
    /// The Doppler mode, scales, gate and manoeuvres (issue 17); absent
    /// when the live system has no flow model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doppler: Option<DopplerStatus>,
}

impl ViewState {
    /// The scalar state of `snap`, sanitized ([`LiveStatus::sanitized`]: a
    /// non-finite value becomes 0, so the page never sees NaN); `vein` and
    /// `exam` come from the server.
    pub fn from_snapshot(
        snap: &LiveSnapshot,
        vein: Option<VeinState>,
        exam: Option<ExamStatus>,
    ) -> Self {
        Self {
            status: snap.status.sanitized(),
            vein,
            exam,
            observer: false,
            seq: 0,
            sent_ms: 0.0,
            fault: snap.fault.clone(),
            haptic_device: snap.haptic_device.as_ref().map(|d| d.sanitized()),
            doppler: None,
        }
    }
}

pub use crate::exam_status::{CaseFeedback, ExamStatus, SiteStatus, TruthSegment};

/// The viewer's own page → server commands (exam mode).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
#[allow(clippy::enum_variant_names)] // the wire names are `exam_*`
pub enum ViewerCommand {
    /// Open the session's next case (exam mode turns on): its truth stays
    /// on the server, the live system loads its leg and thrombi.
    ExamStart,
    /// Call a finding at a site of the protocol.
    ExamCall {
        /// The site's name (`cfv`, `fv-mid`, `popliteal`, `fv@190mm`).
        site: String,
        /// The finding (`normal`, `acute_dvt`, `chronic_post_thrombotic`,
        /// `indeterminate`).
        finding: Finding,
    },
    /// Call the spectral Doppler at a Doppler site (`cfv`, `popliteal`):
    /// the flow pattern and whether a calf squeeze augments it.
    ExamDoppler {
        /// The Doppler site's name.
        site: String,
        /// `phasic`, `continuous` or `absent`.
        flow: echothigh_exam::FlowPattern,
        /// The flow augments on a calf squeeze.
        augments: bool,
    },
    /// Finish the open case: score it and reveal its truth.
    ExamFinish,
    /// Leave exam mode (an open case is dropped unscored).
    ExamStop,
    /// The page has decoded and shown the last image frame it received
    /// (flow control of the images: the next one is sent only then, so
    /// that a page slow to decode never queues images).
    ImageAck,
    /// The box the page draws the image in (device pixels): frames are
    /// sent reduced to fit it ([`crate::display_fit`]), never enlarged.
    ImageSize {
        /// Width ([`crate::display_fit::MIN_DISPLAY`]..=[`crate::display_fit::MAX_DISPLAY`]).
        width: u32,
        /// Height (same range).
        height: u32,
    },
    /// An observer tab asks to drive the probe; granted only when no other
    /// tab drives it (the driving tab closed).
    TakeControl,
    /// The page has drawn the state numbered `seq` (flow control: the
    /// server sends a new state only when at most [`CREDIT`] − 1 are unacknowledged).
    Ack {
        /// [`ViewState::seq`] of the drawn state.
        seq: u64,
    },
}

/// States a connection may have unacknowledged. With 2 (one taken by the
/// page, one on its way) a page held ~60 ms by a long task stalled the
/// stream: the state showing a command's effect waited for an
/// acknowledgement, and the page took 16 of the 40 states/s. With 4 the
/// states sent during such a task (25 ms apart) wait in the socket and are
/// taken in one burst; the newest is at most one push old. The queue is at
/// most 4 states (~2.5 KB), never a backlog (the issue 19 backlog was
/// seconds of unacknowledged frames).
pub const CREDIT: u64 = 4;

/// A decoded, validated page message.
#[derive(Debug, Clone, PartialEq)]
pub enum ClientMessage {
    /// Forward to the runtime.
    Live(LiveCommand),
    /// Handled by the viewer server.
    Viewer(ViewerCommand),
    /// Forwarded to the runtime's flow model (issue 17).
    Doppler(DopplerCommand),
}

/// Why a page message was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProtocolError {
    /// More than [`MAX_CLIENT_MESSAGE`] bytes.
    #[error("message of {0} bytes exceeds the limit of {MAX_CLIENT_MESSAGE} bytes")]
    TooLong(usize),
    /// A binary frame, which pages never send.
    #[error("binary messages are not accepted; send JSON text")]
    Binary,
    /// Not JSON, not an object, or without a string `type`.
    #[error("malformed message: {0}")]
    Malformed(String),
    /// JSON of the wrong shape for its `type` (unknown type or field, wrong type).
    #[error("invalid `{kind}` message: {reason}")]
    Invalid {
        /// The message's `type`.
        kind: String,
        /// The decoder's explanation.
        reason: String,
    },
    /// A command outside its range ([`LiveCommand::validate`], the same
    /// check, and message, as the runtime's).
    #[error(transparent)]
    Command(#[from] CommandError),
}

/// Decodes one page text message and validates it against `limits` (those
/// of the live system it is for, [`echothigh_runtime::live::LiveControl::limits`]).
pub fn decode_client(text: &str, limits: &CommandLimits) -> Result<ClientMessage, ProtocolError> {
    if text.len() > MAX_CLIENT_MESSAGE {
        return Err(ProtocolError::TooLong(text.len()));
    }
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| ProtocolError::Malformed(e.to_string()))?;
    let kind = value
        .as_object()
        .ok_or_else(|| ProtocolError::Malformed("expected a JSON object".into()))?
        .get("type")
        .and_then(|t| t.as_str())
        .ok_or_else(|| ProtocolError::Malformed("missing string field `type`".into()))?
        .to_owned();
    let invalid = |e: serde_json::Error| ProtocolError::Invalid {
        kind: kind.clone(),
        reason: e.to_string(),
    };
    let (msg, known) = if DOPPLER_COMMAND_TYPES.contains(&kind.as_str()) {
        let cmd: DopplerCommand = serde_json::from_value(value.clone()).map_err(invalid)?;
        let known = serde_json::to_value(&cmd);
        (ClientMessage::Doppler(cmd), known)
    } else if kind.starts_with("exam_")
        || ["ack", "image_ack", "image_size", "take_control"].contains(&kind.as_str())
    {
        let cmd: ViewerCommand = serde_json::from_value(value.clone()).map_err(invalid)?;
        let known = serde_json::to_value(&cmd);
        (ClientMessage::Viewer(cmd), known)
    } else {
        let cmd: LiveCommand = serde_json::from_value(value.clone()).map_err(invalid)?;
        let known = serde_json::to_value(&cmd);
        (ClientMessage::Live(cmd), known)
    };
    // serde's `deny_unknown_fields` does not cover the unit variants of an
    // internally tagged enum (`{"type":"reset","now":1}` would pass): every
    // key received must also appear when the decoded message is encoded.
    let known = known.map_err(|e| ProtocolError::Malformed(e.to_string()))?;
    if let (Some(received), Some(known)) = (value.as_object(), known.as_object()) {
        if let Some(extra) = received.keys().find(|k| !known.contains_key(*k)) {
            return Err(ProtocolError::Invalid {
                kind,
                reason: format!("unknown field `{extra}`"),
            });
        }
    }
    match &msg {
        ClientMessage::Live(cmd) => cmd.validate(limits)?,
        ClientMessage::Doppler(cmd) => cmd.validate()?,
        ClientMessage::Viewer(ViewerCommand::ImageSize { width, height }) => {
            use crate::display_fit::{MAX_DISPLAY, MIN_DISPLAY};
            for (field, v) in [("width", width), ("height", height)] {
                if !(MIN_DISPLAY..=MAX_DISPLAY).contains(v) {
                    return Err(ProtocolError::Invalid {
                        kind,
                        reason: format!(
                            "`{field}` {v} is outside {MIN_DISPLAY}..={MAX_DISPLAY} device pixels"
                        ),
                    });
                }
            }
        }
        ClientMessage::Viewer(_) => {}
    }
    Ok(msg)
}

/// Kind of a binary server → page frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum FrameKind {
    /// Echographic image: `a` = width, `b` = height, then `a·b` bytes.
    Image = 1,
    /// Deformed surface: `a` = node count, `b` = 0, then `3a` f32 positions
    /// (m) and `a` f32 compressions (fraction of the asymptote, 0..1).
    Surface = 2,
    /// Echographic image as a JPEG: `a` = width, `b` = height, then the f64
    /// simulated time (s) of the state it shows, then an 8-bit gray JPEG.
    /// (Protocol 1's kinds 3 and 4, a PNG and a PNG delta, are retired.)
    ImageJpeg = 3,
    /// The surface nodes that moved: `a` = their count, `b` = all nodes,
    /// then `a` u32 indices, `3a` f32 positions (m), `a` f32 compressions.
    SurfaceDelta = 5,
    /// [`FrameKind::ImageJpeg`] with the colour overlay of the same frame
    /// (issue 17): `a` = width, `b` = height, the f64 time (s), a u32 byte
    /// length `L`, the image's JPEG (`L` bytes), then an 8-bit gray PNG of
    /// the overlay codes (0 none, else `echothigh_doppler::code_rgb`),
    /// lossless because they are codes. (Protocol 1's kind 7 is retired.)
    ImageJpegFlow = 6,
    /// PW spectral lines (issue 17): `a` = lines, `b` = rows a line, then
    /// the u64 number of the first line, its f64 time (s), the f64 time
    /// between lines (s), then `a·b` 8-bit magnitudes, line after line,
    /// each from the top of the display span (the highest frequency) down.
    Spectral = 8,
}

/// Magic bytes opening every binary frame.
pub const FRAME_MAGIC: [u8; 4] = *b"ETHV";

/// Size of [`FrameHeader`] in bytes (a multiple of 4, so f32 payloads align).
pub const FRAME_HEADER_LEN: usize = 16;

/// The 16-byte header of a binary frame: magic, version (u8), kind (u8), two
/// reserved zero bytes, then `a` and `b` (u32, little-endian).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameHeader {
    /// Frame kind.
    pub kind: FrameKind,
    /// First size field (see [`FrameKind`]).
    pub a: u32,
    /// Second size field (see [`FrameKind`]).
    pub b: u32,
}

impl FrameHeader {
    /// Appends the header's 16 bytes to `out`.
    pub fn write(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&FRAME_MAGIC);
        out.push(PROTOCOL_VERSION as u8);
        out.push(self.kind as u8);
        out.extend_from_slice(&[0, 0]);
        out.extend_from_slice(&self.a.to_le_bytes());
        out.extend_from_slice(&self.b.to_le_bytes());
    }

    /// Parses a header and checks that the payload length matches it.
    #[allow(dead_code)] // the page parses frames in JS; this parser serves the tests
    pub fn parse(frame: &[u8]) -> Option<(FrameHeader, &[u8])> {
        let head = frame.get(..FRAME_HEADER_LEN)?;
        if head[..4] != FRAME_MAGIC || u32::from(head[4]) != PROTOCOL_VERSION {
            return None;
        }
        let kind = match head[5] {
            1 => FrameKind::Image,
            2 => FrameKind::Surface,
            3 => FrameKind::ImageJpeg,
            5 => FrameKind::SurfaceDelta,
            6 => FrameKind::ImageJpegFlow,
            8 => FrameKind::Spectral,
            _ => return None,
        };
        let a = u32::from_le_bytes(head[8..12].try_into().ok()?);
        let b = u32::from_le_bytes(head[12..16].try_into().ok()?);
        let payload = &frame[FRAME_HEADER_LEN..];
        let fits = match kind {
            FrameKind::Image => payload.len() == a as usize * b as usize,
            FrameKind::Surface => payload.len() == a as usize * 16,
            FrameKind::ImageJpeg => payload.len() > 8,
            FrameKind::SurfaceDelta => payload.len() == a as usize * 20 && a <= b,
            FrameKind::ImageJpegFlow => payload.len() > 12,
            FrameKind::Spectral => payload.len() == 24 + a as usize * b as usize,
        };
        fits.then_some((FrameHeader { kind, a, b }, payload))
    }
}

/// Encodes an image frame (`pixels` is `width × height`, row-major) into
/// `out`. A buffer shorter than `width × height` is sent as an empty 0×0 frame.
pub fn encode_image(width: u32, height: u32, pixels: &[u8], out: &mut Vec<u8>) {
    out.clear();
    let n = width as usize * height as usize;
    out.reserve(FRAME_HEADER_LEN + n);
    let (a, b, body) = match pixels.get(..n) {
        Some(body) => (width, height, body),
        None => (0, 0, &[][..]),
    };
    FrameHeader {
        kind: FrameKind::Image,
        a,
        b,
    }
    .write(out);
    out.extend_from_slice(body);
}

/// Encodes the deformed surface of `snap` into `out`. Non-finite values are
/// sent as 0 so the page never receives NaN; the node count is the shorter of
/// the positions and compressions.
pub fn encode_surface(snap: &LiveSnapshot, out: &mut Vec<u8>) {
    out.clear();
    let n = snap.positions.len().min(snap.compression.len());
    out.reserve(FRAME_HEADER_LEN + 16 * n);
    FrameHeader {
        kind: FrameKind::Surface,
        a: n as u32,
        b: 0,
    }
    .write(out);
    let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
    for p in &snap.positions[..n] {
        for c in p {
            out.extend_from_slice(&finite(*c).to_le_bytes());
        }
    }
    for c in &snap.compression[..n] {
        out.extend_from_slice(&finite(*c).to_le_bytes());
    }
}
