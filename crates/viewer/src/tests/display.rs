//! The image reduced to the page's display box (issue 19,
//! [`crate::display_fit`]) over a real socket, against the runtime's test
//! double: frames fit the box the page names, keep their level and their
//! overlay's codes, cost fewer bytes, and a box out of range is refused
//! naming the field.

use super::super::fake::FakeLive;
use super::super::fake_doppler::DISC_CODE;
use super::super::protocol::{FrameHeader, FrameKind};
use super::doppler::next_frame;
use super::server::{connect, decode_jpeg, decode_png, next, next_error, send, start, Client};
use std::sync::Arc;
use tokio_tungstenite::tungstenite::Message;

/// The next image frame (plain or with its overlay) of `width × height`.
async fn frame_of(ws: &mut Client, width: u32, height: u32) -> Vec<u8> {
    for _ in 0..1000 {
        if let Message::Binary(b) = next(ws).await {
            if FrameHeader::parse(&b).is_some_and(|(h, _)| {
                matches!(h.kind, FrameKind::ImageJpeg | FrameKind::ImageJpegFlow)
                    && (h.a, h.b) == (width, height)
            }) {
                return b.to_vec();
            }
        }
    }
    panic!("no {width} × {height} image frame in 1000 messages");
}

/// A 512 × 864 frame (the default grid) for a page whose image box is a
/// 1280 × 800 page's, 232 × 348 device pixels: 206 × 348, the height
/// binding. The double's frames are uniform noise over 0..=255 (mean
/// 127.5, spread 73.9); a reduced frame keeps the mean within 3 levels (the
/// mean of 71 688 pixels varies by at most 73.9 / √71 688 = 0.28 level even
/// without the filter's averaging, and JPEG's quantization of the block
/// means is unbiased: 3 is ten times the sampling error) and costs at most
/// 0.3 of the full frame's bytes (its pixels are 0.162 of them, and the
/// filter's averaging makes them more compressible, not less).
#[tokio::test]
async fn frames_fit_the_page_box_and_keep_their_level() {
    let fake = Arc::new(FakeLive::new());
    fake.speckled_images(512, 864);
    let mut ws = connect(start(fake).await).await;
    let full = frame_of(&mut ws, 512, 864).await;
    send(&mut ws, r#"{"type":"image_size","width":232,"height":348}"#).await;
    let small = frame_of(&mut ws, 206, 348).await;
    let (_, body) = FrameHeader::parse(&small).unwrap();
    let px = decode_jpeg(&body[8..]);
    assert_eq!(px.len(), 206 * 348);
    let mean = px.iter().map(|&x| f64::from(x)).sum::<f64>() / px.len() as f64;
    assert!((mean - 127.5).abs() < 3.0, "mean level {mean:.2}");
    assert!(
        (small.len() as f64) < 0.3 * full.len() as f64,
        "{} bytes reduced against {} full",
        small.len(),
        full.len()
    );
    // A box larger than the frame: the frame as rendered, never enlarged.
    send(
        &mut ws,
        r#"{"type":"image_size","width":1600,"height":2000}"#,
    )
    .await;
    frame_of(&mut ws, 512, 864).await;
}

/// Colour mode: the overlay is reduced with its image, by the nearest
/// code: the double's disc (radius a quarter of the height, centred)
/// keeps its code inside and 0 outside, one pixel of the reduced grid
/// from its edge either way (nearest sampling moves an edge by at most
/// half a reduced pixel).
#[tokio::test]
async fn the_overlay_is_reduced_with_its_codes_intact() {
    let fake = Arc::new(FakeLive::new());
    fake.speckled_images(128, 96);
    let mut ws = connect(start(fake).await).await;
    send(&mut ws, r#"{"type":"doppler_mode","mode":"color"}"#).await;
    let first = next_frame(&mut ws, &[FrameKind::ImageJpegFlow]).await;
    let (h, _) = FrameHeader::parse(&first).unwrap();
    let (bw, bh) = (h.a / 2, h.b / 2);
    send(
        &mut ws,
        &format!(r#"{{"type":"image_size","width":{bw},"height":{bh}}}"#),
    )
    .await;
    let f = frame_of(&mut ws, bw, bh).await;
    let (h, body) = FrameHeader::parse(&f).unwrap();
    assert_eq!(h.kind, FrameKind::ImageJpegFlow);
    let l = u32::from_le_bytes(body[8..12].try_into().unwrap()) as usize;
    let codes = decode_png(&body[12 + l..]);
    let (w, ht) = (h.a as usize, h.b as usize);
    assert_eq!(codes.len(), w * ht);
    assert_eq!(decode_jpeg(&body[12..12 + l]).len(), w * ht);
    let (mut inside, mut outside) = (0, 0);
    for (k, &c) in codes.iter().enumerate() {
        let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        let d = (x - w as f64 / 2.0).hypot(y - ht as f64 / 2.0);
        let r = ht as f64 / 4.0;
        assert!(c == 0 || c == DISC_CODE, "pixel {k}: code {c}, a mixture");
        if d < r - 1.0 {
            assert_eq!(c, DISC_CODE, "pixel {k} inside");
            inside += 1;
        } else if d > r + 1.0 {
            assert_eq!(c, 0, "pixel {k} outside");
            outside += 1;
        }
    }
    assert!(inside > 0 && outside > 0);
}

/// A box out of 16..=8192 device pixels, or not a whole number, is refused
/// naming the field; the connection stays up and keeps its frames.
#[tokio::test]
async fn a_box_out_of_range_is_refused_naming_the_field() {
    let fake = Arc::new(FakeLive::new());
    let mut ws = connect(start(fake).await).await;
    send(&mut ws, r#"{"type":"image_size","width":0,"height":300}"#).await;
    let e = next_error(&mut ws).await;
    assert!(e.contains("`width` 0"), "{e}");
    send(
        &mut ws,
        r#"{"type":"image_size","width":300,"height":9000}"#,
    )
    .await;
    let e = next_error(&mut ws).await;
    assert!(e.contains("`height` 9000"), "{e}");
    send(
        &mut ws,
        r#"{"type":"image_size","width":30.5,"height":300}"#,
    )
    .await;
    let e = next_error(&mut ws).await;
    assert!(e.contains("image_size"), "{e}");
    next_frame(&mut ws, &[FrameKind::ImageJpeg]).await;
}
