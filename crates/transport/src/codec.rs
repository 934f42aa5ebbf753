//! Encoding and decoding of [`Message`]s, without allocation.
//!
//! [`decode`] checks, in order: size at least a header, magic, version, kind,
//! exact size of that kind, finiteness of every `f64`, and the session
//! token. Each failure is a distinct [`DecodeError`]; no input panics.

use crate::message::{
    ByeMsg, DatagramBuf, Header, HelloMsg, Kind, Message, ProbeMsg, SampleMsg, WelcomeMsg, MAGIC,
    VERSION,
};
use bytemuck::{pod_read_unaligned, AnyBitPattern};

/// Why a datagram was rejected.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum DecodeError {
    /// Too short for a header, or not the size of its kind.
    #[error("wrong datagram size: {len} bytes, expected {expected}")]
    WrongSize {
        /// Received length (bytes).
        len: usize,
        /// Expected length (bytes): the header size if `len` is shorter, else the kind's size.
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
    /// A floating-point field is NaN or infinite.
    #[error("non-finite value in field `{field}`")]
    NonFinite {
        /// Name of the field.
        field: &'static str,
    },
    /// The session token is not this session's.
    #[error("wrong session token")]
    WrongToken,
}

/// Encodes `msg` into `buf` and returns the number of bytes written (the
/// kind's size). The header's magic, version and kind are set from the
/// variant; token, sequence and send time are taken from the message as is.
/// Allocates nothing; cannot fail (the buffer type holds any message).
pub fn encode(msg: &Message, buf: &mut DatagramBuf) -> usize {
    let bytes = msg.as_bytes();
    let n = bytes.len();
    buf[..n].copy_from_slice(bytes);
    let header = Header {
        magic: MAGIC,
        version: VERSION,
        kind: msg.kind() as u16,
        ..*msg.header()
    };
    buf[..std::mem::size_of::<Header>()].copy_from_slice(bytemuck::bytes_of(&header));
    n
}

/// Decodes a datagram, checking everything but the token (used by a server
/// to answer a client that presents the wrong token).
pub fn decode_any(bytes: &[u8]) -> Result<Message, DecodeError> {
    let header_size = std::mem::size_of::<Header>();
    if bytes.len() < header_size {
        return Err(DecodeError::WrongSize {
            len: bytes.len(),
            expected: header_size,
        });
    }
    let header: Header = pod_read_unaligned(&bytes[..header_size]);
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
    if bytes.len() != kind.size() {
        return Err(DecodeError::WrongSize {
            len: bytes.len(),
            expected: kind.size(),
        });
    }
    finite("t_send", &[header.t_send])?;
    let msg = match kind {
        Kind::Probe => {
            let m: ProbeMsg = read(bytes);
            finite("t_device", &[m.t_device])?;
            finite("position", &m.position)?;
            finite("orientation", &m.orientation)?;
            Message::Probe(m)
        }
        Kind::Sample => {
            let m: SampleMsg = read(bytes);
            finite("t_sample", &[m.t_sample])?;
            finite("p", &m.p)?;
            finite("distance", &[m.distance])?;
            finite("gradient", &m.gradient)?;
            finite("stiffness", &[m.stiffness])?;
            finite("force", &m.force)?;
            finite("physics_rate", &[m.physics_rate])?;
            Message::Sample(m)
        }
        Kind::Hello => Message::Hello(read::<HelloMsg>(bytes)),
        Kind::Welcome => {
            let m: WelcomeMsg = read(bytes);
            finite("physics_rate", &[m.physics_rate])?;
            Message::Welcome(m)
        }
        Kind::Bye => Message::Bye(read::<ByeMsg>(bytes)),
    };
    Ok(msg)
}

/// Decodes a datagram of this session: [`decode_any`] plus the token check.
pub fn decode(bytes: &[u8], token: u64) -> Result<Message, DecodeError> {
    let msg = decode_any(bytes)?;
    if msg.header().token != token {
        return Err(DecodeError::WrongToken);
    }
    Ok(msg)
}

fn read<T: AnyBitPattern>(bytes: &[u8]) -> T {
    pod_read_unaligned(&bytes[..std::mem::size_of::<T>()])
}

fn finite(field: &'static str, values: &[f64]) -> Result<(), DecodeError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(DecodeError::NonFinite { field })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(token: u64, seq: u64) -> Header {
        Header {
            token,
            seq,
            t_send: 1.25,
            ..Header::default()
        }
    }

    fn every_message() -> Vec<Message> {
        let h = header(0xDEAD_BEEF_0123_4567, 42);
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
                in_contact: 1,
                newton_iterations: 3,
                cg_iterations: 57,
                limited: 1,
                physics_rate: 101.5,
            }),
            Message::Hello(HelloMsg {
                header: h,
                nonce: 77,
            }),
            Message::Welcome(WelcomeMsg {
                header: h,
                nonce: 77,
                physics_rate: 100.0,
            }),
            Message::Bye(ByeMsg {
                header: h,
                ..ByeMsg::new(crate::bye_reason::REJECTED)
            }),
        ]
    }

    #[test]
    fn every_message_round_trips() {
        for msg in every_message() {
            let mut buf = [0u8; crate::MAX_MESSAGE_SIZE];
            let n = encode(&msg, &mut buf);
            assert_eq!(n, msg.kind().size());
            let back = decode(&buf[..n], 0xDEAD_BEEF_0123_4567).unwrap();
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
        let mut buf = [0u8; crate::MAX_MESSAGE_SIZE];
        let n = encode(&msg, &mut buf);
        let good = buf[..n].to_vec();
        let token = msg.header().token;

        assert_eq!(
            decode(&good[..10], token),
            Err(DecodeError::WrongSize {
                len: 10,
                expected: 32
            })
        );
        assert_eq!(
            decode(&good[..n - 1], token),
            Err(DecodeError::WrongSize {
                len: n - 1,
                expected: n
            })
        );
        let mut bad = good.clone();
        bad[0] = b'X';
        assert!(matches!(
            decode(&bad, token),
            Err(DecodeError::BadMagic { .. })
        ));
        let mut bad = good.clone();
        bad[4] = 9;
        assert_eq!(
            decode(&bad, token),
            Err(DecodeError::UnsupportedVersion { found: 9 })
        );
        let mut bad = good.clone();
        bad[6] = 200;
        assert_eq!(
            decode(&bad, token),
            Err(DecodeError::UnknownKind { found: 200 })
        );
        let mut bad = good.clone();
        // position[1] sits at 32 (header) + 8 (t_device) + 8.
        bad[48..56].copy_from_slice(&f64::NAN.to_le_bytes());
        assert_eq!(
            decode(&bad, token),
            Err(DecodeError::NonFinite { field: "position" })
        );
        assert_eq!(decode(&good, token ^ 1), Err(DecodeError::WrongToken));
        assert!(decode_any(&good).is_ok());
    }

    #[test]
    fn decode_accepts_unaligned_buffers() {
        let msg = every_message()[1];
        let mut buf = [0u8; crate::MAX_MESSAGE_SIZE];
        let n = encode(&msg, &mut buf);
        let mut shifted = vec![0u8; n + 1];
        shifted[1..].copy_from_slice(&buf[..n]);
        assert!(decode(&shifted[1..], msg.header().token).is_ok());
    }
}
