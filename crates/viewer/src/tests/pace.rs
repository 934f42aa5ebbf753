//! The images' pace over a real socket (issue 19, [`crate::image_pace`]),
//! against the runtime's test double, whose frames are new at every read
//! and whose force follows the commanded depth at once: a still probe gets
//! [`STILL_RATE`] frames a second, a pressing one a frame for each press,
//! and the frames answering a press draw on the budget's reserve.

use super::super::fake::FakeLive;
use super::super::image_pace::STILL_RATE;
use super::super::protocol::{FrameHeader, FrameKind};
use super::server::{acknowledge, connect, next_raw, send, start, Client};
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::Message;

fn is_image(m: &Message) -> bool {
    matches!(m, Message::Binary(b) if FrameHeader::parse(b).is_some_and(|(h, _)| matches!(h.kind, FrameKind::ImageJpeg | FrameKind::ImageJpegFlow)))
}

/// Images received over `span`, sending a press alternating between 4 and
/// 8 mm every `press` (none if `None`). Only the read is cut short at a
/// press (a socket's read is cancel-safe); every message read is
/// acknowledged.
async fn images_over(ws: &mut Client, span: Duration, press: Option<Duration>) -> usize {
    let end = Instant::now() + span;
    let mut at = press.map(|p| Instant::now() + p);
    let (mut images, mut deep) = (0, false);
    loop {
        let now = Instant::now();
        if now >= end {
            return images;
        }
        if let Some(t) = at.filter(|&t| t <= now) {
            deep = !deep;
            let depth = if deep { 0.008 } else { 0.004 };
            send(
                ws,
                &format!(r#"{{"type":"probe","theta":0,"z":0,"depth":{depth},"tilt":0}}"#),
            )
            .await;
            at = press.map(|p| t + p);
            continue;
        }
        let until = at.map_or(end, |t| t.min(end));
        if let Ok(m) = tokio::time::timeout_at(until, next_raw(ws)).await {
            acknowledge(ws, &m).await;
            if is_image(&m) {
                images += 1;
            }
        }
    }
}

/// Held still for 2 s, at most `STILL_RATE` frames a second (and one more
/// for the window's edges); pressed every 50 ms for 2 s (40 presses, each
/// moving the double's force by 1–2 N, over `MOVING_FORCE`), a frame for
/// most presses: at least 25, against the 11 a still probe may get
/// (the margin leaves a loaded machine a third of the presses).
#[tokio::test]
async fn a_still_probe_gets_few_frames_and_a_pressing_one_many() {
    let fake = Arc::new(FakeLive::new());
    // Frames as new as any state: none is too old to answer a press.
    fake.image_time(f64::MAX);
    let mut ws = connect(start(fake).await).await;
    send(
        &mut ws,
        r#"{"type":"probe","theta":0,"z":0,"depth":0.004,"tilt":0}"#,
    )
    .await;
    // The first frames, then the press settles (the double has no dynamics).
    images_over(&mut ws, Duration::from_millis(500), None).await;
    let still = images_over(&mut ws, Duration::from_secs(2), None).await;
    let bound = (2.0 * STILL_RATE) as usize + 1;
    assert!(
        still <= bound,
        "{still} frames in 2 s of a still probe (≤ {bound})"
    );
    assert!(
        still >= 2,
        "{still} frames in 2 s of a still probe: the still frames stopped"
    );
    let pressing = images_over(
        &mut ws,
        Duration::from_secs(2),
        Some(Duration::from_millis(50)),
    )
    .await;
    assert!(
        pressing >= 25,
        "{pressing} frames over 40 presses in 2 s (still: {still})"
    );
}

/// On a budget the images keep empty (uniform noise, 200 × 200, in colour
/// mode, where every frame is due: ~30 KB a frame, ~12 a second at 360
/// KB/s), the frames answering a press draw on the reserve: in the 300 ms
/// after a press, ~(0.3 · 360 + 80) / 30 ≈ 6 frames, against ~(0.3 · 360) /
/// 30 ≈ 3.6 in 300 ms without one. Over three windows of each, alternated,
/// at least 4 more answering (expected ~7; a loaded machine's slower
/// acknowledgements take from both sides).
#[tokio::test]
async fn the_frames_answering_a_press_draw_on_the_reserve() {
    let fake = Arc::new(FakeLive::new());
    // Frames as new as any state: none is too old to answer a press.
    fake.image_time(f64::MAX);
    fake.speckled_images(200, 200);
    let mut ws = connect(start(fake).await).await;
    send(&mut ws, r#"{"type":"doppler_mode","mode":"color"}"#).await;
    let (mut answering, mut others) = (0, 0);
    for k in 0..3 {
        // Past any earlier press's window, with the bucket drained by the
        // colour frames.
        images_over(&mut ws, Duration::from_millis(1000), None).await;
        others += images_over(&mut ws, Duration::from_millis(300), None).await;
        images_over(&mut ws, Duration::from_millis(1000), None).await;
        let depth = if k % 2 == 0 { 0.012 } else { 0.002 };
        send(
            &mut ws,
            &format!(r#"{{"type":"probe","theta":0.3,"z":0,"depth":{depth},"tilt":0}}"#),
        )
        .await;
        answering += images_over(&mut ws, Duration::from_millis(300), None).await;
    }
    eprintln!("answering {answering}, others {others}");
    assert!(
        answering >= others + 4,
        "{answering} frames answering three presses, {others} in three other windows"
    );
}

/// A frame of a physics state older than the newest the connection had
/// when the page's probe command came cannot show its effect: none is sent
/// in the command's answer window (`RESPONSE_WINDOW`, 0.3 s; one may have
/// been on its way already), and the
/// frames resume after it (every frame here is that old: the double's
/// imaging is frozen at t = 0 while its states advance).
#[tokio::test]
async fn frames_older_than_the_command_are_not_sent_in_its_answer() {
    let fake = Arc::new(FakeLive::new());
    fake.image_time(0.0);
    let mut ws = connect(start(fake).await).await;
    // Colour mode: every frame is due (none held back as a still one).
    send(&mut ws, r#"{"type":"doppler_mode","mode":"color"}"#).await;
    // States pass t = 0 (the double's advance 10 ms a snapshot); frames flow.
    assert!(images_over(&mut ws, Duration::from_millis(500), None).await >= 1);
    send(
        &mut ws,
        r#"{"type":"probe","theta":0,"z":0,"depth":0.006,"tilt":0}"#,
    )
    .await;
    // One frame may have been on its way when the command came; without
    // the skip, every poll (5 ms) would send one as soon as acknowledged
    // (measured: 25 in this window; 2 in B-mode, where the still frames go
    // at 5 a second).
    let within = images_over(&mut ws, Duration::from_millis(250), None).await;
    assert!(
        within <= 1,
        "{within} frames older than the command sent in its answer window"
    );
    tokio::time::sleep(Duration::from_millis(100)).await;
    let after = images_over(&mut ws, Duration::from_millis(500), None).await;
    assert!(
        after >= 1,
        "the frames did not resume after the answer window"
    );
}
