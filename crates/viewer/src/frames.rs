//! The lean wire (issue 19): what one connection sends of the surface and
//! the image, given what it already sent.
//!
//! - Surface: only the nodes that moved by more than [`POS_EPS`] or whose
//!   compression changed by more than [`COMP_EPS`] since this connection last
//!   sent them ([`FrameKind::SurfaceDelta`]); the first frame holds every node.
//!   Every node the page holds is therefore within those bounds of the truth.
//! - Image: the first frame (and any change of size) as a PNG of the pixels
//!   ([`FrameKind::ImagePng`]), the next ones as a PNG of the byte-wise
//!   difference from the frame this connection last sent, modulo 256
//!   ([`FrameKind::ImageDelta`]): lossless, and mostly zeros while the probe
//!   holds still (a held probe changes ~5 % of the pixels between frames).
//!   Both carry the simulated time of the physics state they show.
//!
//! The transport is a WebSocket (reliable, in order), so the page's copy is
//! always the one kept here.

use super::protocol::{FrameHeader, FrameKind};
use echothigh_runtime::live::{ImageInfo, LiveSnapshot};

/// Smallest node displacement sent (m): 20 µm, a twentieth of a pixel of
/// the page's 3D view (a 0.3 m thigh over ~700 px is ~0.4 mm per pixel).
pub const POS_EPS: f32 = 2e-5;

/// Smallest change of a node's compression sent (fraction of the
/// asymptote): half a step of the page's 8-bit colour ramp.
pub const COMP_EPS: f32 = 1.0 / 512.0;

/// What one connection last sent, to send only what changed.
#[derive(Debug, Default)]
pub struct WireState {
    positions: Vec<[f32; 3]>,
    compression: Vec<f32>,
    image: Vec<u8>,
    image_size: (u32, u32),
    last_frame: Option<u64>,
    delta: Vec<u8>,
    changed: Vec<u32>,
}

/// `x` if finite, else 0 (the page never receives NaN).
fn finite(x: f32) -> f32 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// `|d| ≤ eps`; false for NaN (a node never sent always differs).
fn within(d: f32, eps: f32) -> bool {
    d.abs() <= eps
}

impl WireState {
    /// The surface delta of `snap` against what was sent, or `None` when no
    /// node changed beyond the thresholds. The frame: header (`a` = changed
    /// nodes, `b` = all nodes), then `a` u32 node indices, `3a` f32
    /// positions (m) and `a` f32 compressions.
    pub fn surface(&mut self, snap: &LiveSnapshot) -> Option<Vec<u8>> {
        let n = snap.positions.len().min(snap.compression.len());
        if self.positions.len() != n {
            // First frame, or a new mesh: everything, against NaN so that
            // every node differs.
            self.positions = vec![[f32::NAN; 3]; n];
            self.compression = vec![f32::NAN; n];
        }
        self.changed.clear();
        for i in 0..n {
            let p = snap.positions[i].map(finite);
            let c = finite(snap.compression[i]);
            let q = self.positions[i];
            let moved = (0..3).any(|k| !within(p[k] - q[k], POS_EPS));
            if moved || !within(c - self.compression[i], COMP_EPS) {
                self.positions[i] = p;
                self.compression[i] = c;
                self.changed.push(i as u32);
            }
        }
        if self.changed.is_empty() {
            return None;
        }
        let a = self.changed.len();
        let mut out = Vec::with_capacity(super::protocol::FRAME_HEADER_LEN + 20 * a);
        FrameHeader {
            kind: FrameKind::SurfaceDelta,
            a: a as u32,
            b: n as u32,
        }
        .write(&mut out);
        for &i in &self.changed {
            out.extend_from_slice(&i.to_le_bytes());
        }
        for &i in &self.changed {
            for c in self.positions[i as usize] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        for &i in &self.changed {
            out.extend_from_slice(&self.compression[i as usize].to_le_bytes());
        }
        Some(out)
    }

    /// The image frame for `pixels` (as described by `info`), or `None` if
    /// this connection already has that frame, it is malformed, or it is
    /// frame 0 (the image slot before the imaging thread's first render:
    /// black, which a page would show until the next frame). The frame:
    /// header (`a` = width, `b` = height), the f64 time (s), then a PNG.
    pub fn image(&mut self, info: ImageInfo, pixels: &[u8]) -> Option<Vec<u8>> {
        let n = info.width as usize * info.height as usize;
        if n == 0 || info.frame == 0 || pixels.len() < n || self.last_frame == Some(info.frame) {
            return None;
        }
        let pixels = &pixels[..n];
        let key = self.image_size != (info.width, info.height) || self.image.len() != n;
        let kind = if key {
            self.image.clear();
            self.image.extend_from_slice(pixels);
            FrameKind::ImagePng
        } else {
            self.delta.clear();
            self.delta.extend(
                pixels
                    .iter()
                    .zip(&self.image)
                    .map(|(new, old)| new.wrapping_sub(*old)),
            );
            self.image.copy_from_slice(pixels);
            FrameKind::ImageDelta
        };
        let body = if key { &self.image } else { &self.delta };
        let mut out = Vec::with_capacity(super::protocol::FRAME_HEADER_LEN + 8 + n / 2);
        FrameHeader {
            kind,
            a: info.width,
            b: info.height,
        }
        .write(&mut out);
        let time = if info.time.is_finite() {
            info.time
        } else {
            0.0
        };
        out.extend_from_slice(&time.to_le_bytes());
        if let Err(e) = encode_png(info.width, info.height, body, &mut out) {
            tracing::error!("encoding an image frame: {e}");
            // The page's copy is unknown now: start again from a key frame.
            self.image_size = (0, 0);
            self.last_frame = None;
            return None;
        }
        self.image_size = (info.width, info.height);
        self.last_frame = Some(info.frame);
        Some(out)
    }
}

/// Appends an 8-bit grayscale PNG of `pixels` (`width × height`) to `out`.
/// Fast deflate with the `Sub` filter: 0.4 ms for a 256 × 384 frame here,
/// 62 % of its raw size (the default level with `Paeth`: 7 ms, 55 %).
pub fn encode_png(
    width: u32,
    height: u32,
    pixels: &[u8],
    out: &mut Vec<u8>,
) -> Result<(), png::EncodingError> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::FilterType::Sub);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(pixels)?;
    writer.finish()
}

/// Bytes per second one connection may be sent (state, surface and image
/// together): the budget of issue 19 is 400 KB/s per tab; 10 % is left for
/// the WebSocket framing and the pings, which this count does not see.
pub const BYTES_PER_SECOND: f64 = 360_000.0;

/// Burst allowance of [`ByteBudget`] (bytes): about half a key frame.
pub const BURST_BYTES: f64 = 40_000.0;

/// A token bucket of bytes: a message may go while the balance is positive,
/// and its size is then taken from it (the balance may go below zero by one
/// message). Over any span `T`, what it lets through is at most
/// `rate · T + burst + the largest message`.
#[derive(Debug, Clone, Copy)]
pub struct ByteBudget {
    rate: f64,
    burst: f64,
    tokens: f64,
    last: f64,
}

impl ByteBudget {
    /// A full bucket at time `now` (s).
    pub fn new(rate: f64, burst: f64, now: f64) -> Self {
        Self {
            rate,
            burst,
            tokens: burst,
            last: now,
        }
    }

    /// Refills for the time since the last call (`now` in s, monotonic).
    pub fn refill(&mut self, now: f64) {
        let dt = (now - self.last).max(0.0);
        self.tokens = (self.tokens + self.rate * dt).min(self.burst);
        self.last = now;
    }

    /// Whether a message may go now.
    pub fn allows(&self) -> bool {
        self.tokens > 0.0
    }

    /// Takes a sent message's `bytes` from the balance.
    pub fn spend(&mut self, bytes: usize) {
        self.tokens -= bytes as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::FRAME_HEADER_LEN;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Applies a surface delta frame to the page's copy.
    fn apply_surface(frame: &[u8], pos: &mut Vec<[f32; 3]>, comp: &mut Vec<f32>) {
        let (h, body) = FrameHeader::parse(frame).unwrap();
        assert_eq!(h.kind, FrameKind::SurfaceDelta);
        let (a, n) = (h.a as usize, h.b as usize);
        pos.resize(n, [0.0; 3]);
        comp.resize(n, 0.0);
        let f = |k: usize| f32::from_le_bytes(body[4 * k..4 * k + 4].try_into().unwrap());
        for j in 0..a {
            let i = u32::from_le_bytes(body[4 * j..4 * j + 4].try_into().unwrap()) as usize;
            pos[i] = [f(a + 3 * j), f(a + 3 * j + 1), f(a + 3 * j + 2)];
            comp[i] = f(4 * a + j);
        }
    }

    /// The page's copy of every node stays within the thresholds of the
    /// truth through a random walk in which most nodes hold still; nodes that
    /// did not move are not sent again.
    #[test]
    fn the_page_surface_stays_within_the_thresholds() {
        let mut rng = ChaCha8Rng::seed_from_u64(19);
        let n = 500;
        let mut snap = LiveSnapshot {
            positions: (0..n).map(|i| [i as f32 * 1e-3, 0.07, 0.0]).collect(),
            compression: vec![0.0; n],
            ..Default::default()
        };
        let mut wire = WireState::default();
        let (mut pos, mut comp) = (Vec::new(), Vec::new());
        let mut sent_nodes = 0;
        for step in 0..200 {
            // ~5 % of the nodes move by up to 50 µm, some by sub-threshold steps.
            for i in 0..n {
                if rng.gen_bool(0.05) {
                    let d: f32 = rng.gen_range(-5e-5..5e-5);
                    snap.positions[i][1] += d;
                    snap.compression[i] = (snap.compression[i] + d * 20.0).clamp(0.0, 1.0);
                }
            }
            if let Some(frame) = wire.surface(&snap) {
                sent_nodes += FrameHeader::parse(&frame).unwrap().0.a as usize;
                apply_surface(&frame, &mut pos, &mut comp);
            }
            for i in 0..n {
                for (p, t) in pos[i].iter().zip(snap.positions[i]) {
                    assert!((p - t).abs() <= POS_EPS, "step {step}");
                }
                assert!(
                    (comp[i] - snap.compression[i]).abs() <= COMP_EPS,
                    "step {step}"
                );
            }
        }
        // The first frame is every node; then about 5 % a step at most.
        assert!(sent_nodes < n + 200 * n / 10, "{sent_nodes} nodes sent");
        // Nothing moved: nothing to send.
        assert!(wire.surface(&snap).is_none());
    }

    /// Frame 0 is the image slot before the imaging thread's first render
    /// (black): it is never sent, and the first rendered frame still goes
    /// out as the key frame.
    #[test]
    fn the_slot_before_the_first_render_is_not_sent() {
        let (w, h) = (16u32, 8u32);
        let black = vec![0u8; (w * h) as usize];
        let mut wire = WireState::default();
        let at = |frame| ImageInfo {
            width: w,
            height: h,
            frame,
            time: 0.0,
        };
        assert!(wire.image(at(0), &black).is_none());
        let f = wire.image(at(1), &black).expect("the first render");
        assert_eq!(FrameHeader::parse(&f).unwrap().0.kind, FrameKind::ImagePng);
    }

    /// Key frame then deltas rebuild every frame exactly; a held image with
    /// a few changed pixels costs a small fraction of a key frame.
    #[test]
    fn image_deltas_rebuild_the_frames_exactly() {
        let mut rng = ChaCha8Rng::seed_from_u64(20);
        let (w, h) = (256u32, 384u32);
        let mut img: Vec<u8> = (0..w * h).map(|_| rng.gen()).collect();
        let mut wire = WireState::default();
        let mut page: Vec<u8> = Vec::new();
        let decode = |png_bytes: &[u8]| {
            let mut r = png::Decoder::new(png_bytes).read_info().unwrap();
            let mut buf = vec![0; r.output_buffer_size()];
            r.next_frame(&mut buf).unwrap();
            buf
        };
        let mut sizes = Vec::new();
        for frame in 1..=6u64 {
            // 5 % of the pixels change (a held probe, measured 4.9 %).
            for _ in 0..(w * h / 20) {
                let k = rng.gen_range(0..img.len());
                img[k] = rng.gen();
            }
            let info = ImageInfo {
                width: w,
                height: h,
                frame,
                time: frame as f64 * 0.05,
            };
            let f = wire.image(info, &img).unwrap();
            assert!(wire.image(info, &img).is_none(), "the same frame twice");
            let (hd, body) = FrameHeader::parse(&f).unwrap();
            assert_eq!(f64::from_le_bytes(body[..8].try_into().unwrap()), info.time);
            let pixels = decode(&body[8..]);
            if frame == 1 {
                assert_eq!(hd.kind, FrameKind::ImagePng);
                page = pixels;
            } else {
                assert_eq!(hd.kind, FrameKind::ImageDelta);
                for (p, d) in page.iter_mut().zip(pixels) {
                    *p = p.wrapping_add(d);
                }
            }
            assert_eq!(page, img, "frame {frame}");
            sizes.push(f.len() - FRAME_HEADER_LEN);
        }
        // Random bytes do not compress (key ≈ raw); a delta with 5 % of its
        // bytes non-zero holds ~0.05 · 98 KB of random bytes plus run codes.
        assert!(sizes[1..].iter().all(|&s| 4 * s < sizes[0]), "{sizes:?}");
    }

    /// The bucket's bound: over any run of offers, bytes let through ≤
    /// rate · T + burst + one message.
    #[test]
    fn the_byte_budget_bounds_the_rate() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut b = ByteBudget::new(BYTES_PER_SECOND, BURST_BYTES, 0.0);
        let (mut t, mut sent, mut largest) = (0.0, 0.0, 0usize);
        for _ in 0..20_000 {
            t += rng.gen_range(0.0..0.02);
            b.refill(t);
            let size = rng.gen_range(100..70_000);
            if b.allows() {
                b.spend(size);
                sent += size as f64;
                largest = largest.max(size);
            }
        }
        assert!(sent <= BYTES_PER_SECOND * t + BURST_BYTES + largest as f64);
        // And it does let through most of its rate when offered more.
        assert!(sent > 0.9 * BYTES_PER_SECOND * t, "{} B/s", sent / t);
    }
}
