//! Encoding and decoding of datagrams, without allocation.
//!
//! A datagram is a message's bytes (its `#[repr(C)]` struct, header first)
//! followed by a [`MAC_LEN`]-byte tag ([`crate::auth`]). [`seal`] checks
//! the message's values ([`crate::limits`]), encodes it and appends the
//! tag; [`open`] checks, in order: size (at least a header, then exactly
//! the kind's size plus the tag), magic, version, kind, session id, tag,
//! and the values. Each failure is a distinct [`DecodeError`]; no input
//! panics. [`decode_any`] does the same without session and tag (to read a
//! Welcome before its key is known, and for fuzzing).

use crate::auth::{DatagramKey, MAC_LEN};
use crate::limits::{check, ValueError};
use crate::message::{
    ByeMsg, DatagramBuf, Header, HelloMsg, Kind, Message, ProbeMsg, SampleMsg, WelcomeMsg, MAGIC,
    VERSION,
};
use bytemuck::{pod_read_unaligned, AnyBitPattern};

const HEADER_SIZE: usize = std::mem::size_of::<Header>();

/// Why a message could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum EncodeError {
    /// A field is non-finite or outside its bound.
    #[error("refusing to send: {0}")]
    InvalidValue(#[from] ValueError),
}

/// Why a datagram was rejected.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum DecodeError {
    /// Too short for a header, or not the size of its kind plus the tag.
    #[error("wrong datagram size: {len} bytes, expected {expected}")]
    WrongSize {
        /// Received length (bytes).
        len: usize,
        /// Expected length (bytes): the header size if `len` is shorter,
        /// else the kind's size plus the tag.
        expected: usize,
    },
    /// The first four bytes are not `b"ETHG"`.
    #[error("bad magic {found:#010x}, expected {:#010x} (\"ETHG\")", MAGIC)]
    BadMagic {
        /// The magic found.
        found: u32,
    },
    /// A version this crate does not speak.
    #[error("unsupported wire version {found}, this build speaks {}", VERSION)]
    UnsupportedVersion {
        /// The version found.
        found: u16,
    },
    /// A kind code outside [`Kind`].
    #[error("unknown message kind {found}")]
    UnknownKind {
        /// The kind code found.
        found: u16,
    },
    /// The header names another session.
    #[error("datagram of another session ({found:#x})")]
    WrongSession {
        /// The session id found.
        found: u64,
    },
    /// The tag does not verify under this session's key (forged, altered,
    /// or tagged with another key: a wrong token in a Hello).
    #[error("datagram tag does not verify")]
    BadMac,
    /// A field is non-finite or outside its bound.
    #[error("{0}")]
    InvalidValue(#[from] ValueError),
}

/// Checks `msg`'s values and writes its bytes into `buf` (header magic,
/// version and kind set from the variant; session, sequence and send time
/// as they are); returns the number of bytes written (the kind's size), no
/// tag. Allocates nothing.
pub fn encode(msg: &Message, buf: &mut DatagramBuf) -> Result<usize, EncodeError> {
    check(msg)?;
    let bytes = msg.as_bytes();
    let n = bytes.len();
    buf[..n].copy_from_slice(bytes);
    let header = Header {
        magic: MAGIC,
        version: VERSION,
        kind: msg.kind() as u16,
        ..*msg.header()
    };
    buf[..HEADER_SIZE].copy_from_slice(bytemuck::bytes_of(&header));
    Ok(n)
}

/// [`encode`] and append the tag of the encoded bytes under `key`; returns
/// the datagram's length. Allocates nothing.
pub fn seal(msg: &Message, key: &DatagramKey, buf: &mut DatagramBuf) -> Result<usize, EncodeError> {
    let n = encode(msg, buf)?;
    let tag = key.tag(&buf[..n]);
    buf[n..n + MAC_LEN].copy_from_slice(&tag);
    Ok(n + MAC_LEN)
}

/// Structure of a datagram: its header and kind, size checked.
fn frame(bytes: &[u8]) -> Result<(Header, Kind), DecodeError> {
    if bytes.len() < HEADER_SIZE {
        return Err(DecodeError::WrongSize {
            len: bytes.len(),
            expected: HEADER_SIZE,
        });
    }
    let header: Header = pod_read_unaligned(&bytes[..HEADER_SIZE]);
    if header.magic != MAGIC {
        return Err(DecodeError::BadMagic {
            found: header.magic,
        });
    }
    if header.version != VERSION {
        return Err(DecodeError::UnsupportedVersion {
            found: header.version,
        });
    }
    let kind =
        Kind::from_code(header.kind).ok_or(DecodeError::UnknownKind { found: header.kind })?;
    if bytes.len() != kind.size() + MAC_LEN {
        return Err(DecodeError::WrongSize {
            len: bytes.len(),
            expected: kind.size() + MAC_LEN,
        });
    }
    Ok((header, kind))
}

fn parse(bytes: &[u8], kind: Kind) -> Result<Message, DecodeError> {
    let msg = match kind {
        Kind::Probe => Message::Probe(read::<ProbeMsg>(bytes)),
        Kind::Sample => Message::Sample(read::<SampleMsg>(bytes)),
        Kind::Hello => Message::Hello(read::<HelloMsg>(bytes)),
        Kind::Welcome => Message::Welcome(read::<WelcomeMsg>(bytes)),
        Kind::Bye => Message::Bye(read::<ByeMsg>(bytes)),
    };
    check(&msg)?;
    Ok(msg)
}

/// Decodes a datagram checking its structure and values but neither its
/// session nor its tag.
pub fn decode_any(bytes: &[u8]) -> Result<Message, DecodeError> {
    let (_, kind) = frame(bytes)?;
    parse(bytes, kind)
}

/// Decodes a datagram of session `session` tagged under `key`: structure,
/// session id, tag (constant-time), then values.
pub fn open(bytes: &[u8], key: &DatagramKey, session: u64) -> Result<Message, DecodeError> {
    let (header, kind) = frame(bytes)?;
    if header.session != session {
        return Err(DecodeError::WrongSession {
            found: header.session,
        });
    }
    let n = kind.size();
    if !key.verify(&bytes[..n], &bytes[n..]) {
        return Err(DecodeError::BadMac);
    }
    parse(bytes, kind)
}

fn read<T: AnyBitPattern>(bytes: &[u8]) -> T {
    pod_read_unaligned(&bytes[..std::mem::size_of::<T>()])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::auth::SessionKeys;
    use crate::message::contact_state;
    use crate::token::SessionToken;

    const SESSION: u64 = 0xDEAD_BEEF_0123_4567;

    fn key() -> DatagramKey {
        let t: SessionToken = "0123456789abcdef".parse().unwrap();
        SessionKeys::derive(&t, 1, 2).client_to_server
    }

    fn every_message() -> Vec<Message> {
        let h = Header {
            session: SESSION,
            seq: 42,
            t_send: 1.25,
            ..Header::default()
        };
        vec![
            Message::Probe(ProbeMsg {
                header: h,
                ..ProbeMsg::new(0.5, [0.01, 0.07, -0.02], [1.0, 0.0, 0.0, 0.0], 3)
            }),
            Message::Sample(SampleMsg {
                header: h,
                t_sample: 0.49,
                probe_seq: 41,
                p: [0.01, 0.069, -0.02],
                distance: -0.003,
                gradient: [0.0, 1.0, 0.0],
                stiffness: 650.0,
                force: [0.0, 1.95, 0.1],
                contact: contact_state::TOUCHING,
                newton_iterations: 3,
                cg_iterations: 57,
                limited: 1,
                physics_rate: 101.5,
            }),
            Message::Hello(HelloMsg {
                header: h,
                nonce: 77,
                _reserved: 0,
            }),
            Message::Welcome(WelcomeMsg {
                header: h,
                nonce: 77,
                server_nonce: 78,
                physics_rate: 100.0,
            }),
            Message::Bye(ByeMsg {
                header: h,
                ..ByeMsg::new(crate::bye_reason::REJECTED)
            }),
        ]
    }

    fn sealed(msg: &Message) -> Vec<u8> {
        let mut buf = [0u8; crate::MAX_DATAGRAM_SIZE];
        let n = seal(msg, &key(), &mut buf).unwrap();
        buf[..n].to_vec()
    }

    #[test]
    fn every_message_round_trips() {
        for msg in every_message() {
            let bytes = sealed(&msg);
            assert_eq!(bytes.len(), msg.kind().size() + MAC_LEN);
            let back = open(&bytes, &key(), SESSION).unwrap();
            let mut expected = msg;
            let h = expected.header_mut();
            h.magic = MAGIC;
            h.version = VERSION;
            h.kind = msg.kind() as u16;
            assert_eq!(back, expected);
        }
    }

    #[test]
    fn each_fault_is_its_own_error() {
        let msg = every_message()[0];
        let good = sealed(&msg);
        let n = good.len();
        let k = key();
        assert_eq!(
            open(&good[..10], &k, SESSION),
            Err(DecodeError::WrongSize {
                len: 10,
                expected: 32
            })
        );
        assert_eq!(
            open(&good[..n - 1], &k, SESSION),
            Err(DecodeError::WrongSize {
                len: n - 1,
                expected: n
            })
        );
        let mut bad = good.clone();
        bad[0] = b'X';
        assert!(matches!(
            open(&bad, &k, SESSION),
            Err(DecodeError::BadMagic { .. })
        ));
        let mut bad = good.clone();
        bad[4] = 9;
        assert_eq!(
            open(&bad, &k, SESSION),
            Err(DecodeError::UnsupportedVersion { found: 9 })
        );
        let mut bad = good.clone();
        bad[6] = 200;
        assert_eq!(
            open(&bad, &k, SESSION),
            Err(DecodeError::UnknownKind { found: 200 })
        );
        assert_eq!(
            open(&good, &k, SESSION ^ 1),
            Err(DecodeError::WrongSession { found: SESSION })
        );
        // Any flipped bit of the message or the tag fails the tag.
        for byte in [16, 40, 60, n - 1] {
            let mut bad = good.clone();
            bad[byte] ^= 0x10;
            assert_eq!(open(&bad, &k, SESSION), Err(DecodeError::BadMac), "{byte}");
        }
        let t: SessionToken = "0123456789abcdef".parse().unwrap();
        let other = SessionKeys::derive(&t, 1, 2).server_to_client;
        assert_eq!(open(&good, &other, SESSION), Err(DecodeError::BadMac));
        assert!(decode_any(&good).is_ok());
    }

    #[test]
    fn absurd_values_are_refused_both_ways() {
        let mut msg = every_message()[0];
        if let Message::Probe(p) = &mut msg {
            p.position[1] = 1e300;
        }
        let mut buf = [0u8; crate::MAX_DATAGRAM_SIZE];
        let e = seal(&msg, &key(), &mut buf).unwrap_err();
        assert!(e.to_string().contains("position"), "{e}");
        // A peer that tags an absurd value anyway (position[1] sits at
        // 32 (header) + 8 (t_device) + 8) is refused after the tag check.
        let mut bytes = sealed(&every_message()[0]);
        let n = Kind::Probe.size();
        bytes[48..56].copy_from_slice(&f64::NAN.to_le_bytes());
        let tag = key().tag(&bytes[..n]);
        bytes[n..].copy_from_slice(&tag);
        assert!(matches!(
            open(&bytes, &key(), SESSION),
            Err(DecodeError::InvalidValue(ValueError {
                field: "position",
                ..
            }))
        ));
    }

    /// The physics' "no surface near the probe" is `D = +∞`: sent raw it is
    /// refused (the limits want every field finite), so it travels as
    /// [`crate::wire_query`]'s finite sentinel with its own contact state and
    /// arrives as exactly that pair.
    #[test]
    fn no_contact_crosses_the_wire_as_its_sentinel() {
        let Message::Sample(base) = every_message()[1] else {
            unreachable!("every_message()[1] is a Sample")
        };
        let mut buf = [0u8; crate::MAX_DATAGRAM_SIZE];
        let raw = Message::Sample(SampleMsg {
            distance: f64::INFINITY,
            contact: contact_state::SEPARATED,
            ..base
        });
        let e = seal(&raw, &key(), &mut buf).unwrap_err();
        assert!(e.to_string().contains("distance"), "{e}");

        let (distance, contact) = crate::wire_query(f64::INFINITY, false);
        let msg = Message::Sample(SampleMsg {
            distance,
            contact,
            ..base
        });
        let Message::Sample(back) = open(&sealed(&msg), &key(), SESSION).unwrap() else {
            panic!("a Sample came back as another kind")
        };
        assert_eq!(back.contact, contact_state::NO_SURFACE);
        assert_eq!(back.distance, crate::NO_SURFACE_DISTANCE);
    }

    #[test]
    fn decode_accepts_unaligned_buffers() {
        let bytes = sealed(&every_message()[1]);
        let mut shifted = vec![0u8; bytes.len() + 1];
        shifted[1..].copy_from_slice(&bytes);
        assert!(open(&shifted[1..], &key(), SESSION).is_ok());
    }
}
