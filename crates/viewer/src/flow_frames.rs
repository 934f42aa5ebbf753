//! The Doppler part of the lean wire (issue 17): the colour overlay added
//! to an image frame ([`FrameKind::ImageJpegFlow`]) and the spectral lines
//! ([`FrameKind::Spectral`]).
//!
//! The overlay is one code a pixel, 0 where the frame has no colour, so
//! its PNG is mostly runs of zeros: a colour box over a vein adds a few KB
//! to a frame (measured in the browser test's bytes per second). The
//! spectral lines are 8-bit magnitudes, 64 a line at 200 lines/s: 13 KB/s.

use super::frames::encode_png;
use super::protocol::{FrameHeader, FrameKind, FRAME_HEADER_LEN};
use echothigh_runtime::live_doppler::{SpectralLines, SPECTRAL_ROWS};

/// `image` (a frame of [`super::frames::WireState::image`]: header, f64
/// time, JPEG) with the overlay `codes` (`width × height`) of the same
/// frame appended: the flow kind of the same frame, the image PNG's length
/// before it. `None` (the frame to be sent as it is) when `codes` is not
/// the image's size or the frame is not an image frame.
pub fn with_overlay(image: &[u8], codes: &[u8]) -> Option<Vec<u8>> {
    let (h, body) = FrameHeader::parse(image)?;
    let kind = match h.kind {
        FrameKind::ImageJpeg => FrameKind::ImageJpegFlow,
        _ => return None,
    };
    if codes.len() != h.a as usize * h.b as usize || codes.is_empty() {
        return None;
    }
    let (time, jpeg) = body.split_at(8);
    let mut out = Vec::with_capacity(image.len() + 4 + codes.len() / 8);
    FrameHeader { kind, ..h }.write(&mut out);
    out.extend_from_slice(time);
    out.extend_from_slice(&(jpeg.len() as u32).to_le_bytes());
    out.extend_from_slice(jpeg);
    if let Err(e) = encode_png(h.a, h.b, codes, &mut out) {
        tracing::error!("encoding a colour overlay: {e}");
        return None;
    }
    Some(out)
}

/// The frame of `lines` ([`FrameKind::Spectral`]), or `None` when it holds none.
pub fn spectral_frame(lines: &SpectralLines) -> Option<Vec<u8>> {
    if lines.count == 0 || lines.data.len() != lines.count * SPECTRAL_ROWS {
        return None;
    }
    let mut out = Vec::with_capacity(FRAME_HEADER_LEN + 24 + lines.data.len());
    FrameHeader {
        kind: FrameKind::Spectral,
        a: lines.count as u32,
        b: SPECTRAL_ROWS as u32,
    }
    .write(&mut out);
    let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
    out.extend_from_slice(&lines.first.to_le_bytes());
    out.extend_from_slice(&finite(lines.time).to_le_bytes());
    out.extend_from_slice(&finite(lines.interval).to_le_bytes());
    out.extend_from_slice(&lines.data);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::WireState;
    use echothigh_runtime::live::ImageInfo;

    fn decode(png_bytes: &[u8]) -> Vec<u8> {
        let mut r = png::Decoder::new(png_bytes).read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size()];
        r.next_frame(&mut buf).unwrap();
        buf
    }

    /// An image with its overlay: the page's parse gets back the image
    /// frame's JPEG byte for byte and the overlay codes exactly; every frame
    /// becomes `ImageJpegFlow`; an overlay of the wrong size is refused (the
    /// frame then goes without it).
    #[test]
    fn the_overlay_rides_with_its_frame() {
        let (w, h) = (64u32, 48u32);
        let img: Vec<u8> = (0..w * h).map(|k| (k % 200) as u8).collect();
        let mut codes = vec![0u8; (w * h) as usize];
        for (k, c) in codes.iter_mut().enumerate().skip(700).take(300) {
            *c = 1 + (k % 255) as u8;
        }
        let mut wire = WireState::default();
        for (frame, kind) in [(1, FrameKind::ImageJpegFlow), (2, FrameKind::ImageJpegFlow)] {
            let info = ImageInfo {
                width: w,
                height: h,
                frame,
                time: 0.25 * frame as f64,
            };
            let plain = wire.image(info, &img).unwrap();
            let flow = with_overlay(&plain, &codes).unwrap();
            let (hd, body) = FrameHeader::parse(&flow).unwrap();
            assert_eq!((hd.kind, hd.a, hd.b), (kind, w, h));
            assert_eq!(f64::from_le_bytes(body[..8].try_into().unwrap()), info.time);
            let l = u32::from_le_bytes(body[8..12].try_into().unwrap()) as usize;
            assert_eq!(&body[12..12 + l], &plain[FRAME_HEADER_LEN + 8..]);
            assert_eq!(decode(&body[12 + l..]), codes);
            assert!(with_overlay(&plain, &codes[1..]).is_none());
        }
    }

    /// Spectral lines: header sizes, first line, times and magnitudes as
    /// copied; nothing to send for no lines.
    #[test]
    fn spectral_lines_frame() {
        let lines = SpectralLines {
            first: 1234,
            count: 3,
            data: (0..3 * SPECTRAL_ROWS).map(|k| k as u8).collect(),
            time: 6.17,
            interval: 0.005,
        };
        let f = spectral_frame(&lines).unwrap();
        let (hd, body) = FrameHeader::parse(&f).unwrap();
        assert_eq!(
            (hd.kind, hd.a, hd.b),
            (FrameKind::Spectral, 3, SPECTRAL_ROWS as u32)
        );
        assert_eq!(u64::from_le_bytes(body[..8].try_into().unwrap()), 1234);
        assert_eq!(f64::from_le_bytes(body[8..16].try_into().unwrap()), 6.17);
        assert_eq!(f64::from_le_bytes(body[16..24].try_into().unwrap()), 0.005);
        assert_eq!(&body[24..], &lines.data[..]);
        let none = SpectralLines::default();
        assert!(spectral_frame(&none).is_none());
    }
}
