//! The server end to end, over a real socket, against the runtime's test
//! double: hello, state pushes, binary frames, commands, refusals that keep
//! the connection up, the exam flow, cross-origin refusal, static files.

use super::super::exam::sink::MemorySink;
use super::super::exam::{ExamPlan, ExamSession};
use super::super::fake::{fake_image_level, FakeLive};
use super::super::protocol::{Envelope, FrameHeader, FrameKind, ServerMessage, ViewState};
use super::super::server::loopback_host;
use super::super::{check_bind, check_rate, serve_on, ServerConfig};
use axum::http::{header, HeaderMap};
use echothigh_runtime::live::{LiveCommand, LiveControl, VeinState};
use futures_util::{SinkExt, StreamExt};
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::{client::IntoClientRequest, Message};

pub(super) type Client =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// Starts a server on a free loopback port; returns its address.
pub(super) async fn start(fake: Arc<FakeLive>) -> std::net::SocketAddr {
    start_with(fake, ServerConfig::default().idle_timeout).await
}

/// [`start`] with connections closed after `idle_timeout` without input.
async fn start_with(fake: Arc<FakeLive>, idle_timeout: Duration) -> std::net::SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let config = ServerConfig {
        state_rate: 100.0,
        allow_remote: false,
        idle_timeout,
        home_case: None,
    };
    tokio::spawn(serve_on(
        listener,
        fake,
        config,
        practice(),
        std::future::pending(),
    ));
    addr
}

/// The anonymous practice session of `echothigh view` (fixed order).
fn practice() -> ExamSession {
    ExamSession::new(
        ExamPlan::practice(1).unwrap(),
        Box::new(MemorySink::default()),
        true,
    )
}

pub(super) async fn connect(addr: std::net::SocketAddr) -> Client {
    let (ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap();
    ws
}

/// Next message of the connection (fails the test after 5 s), without
/// acknowledging it.
pub(super) async fn next_raw(ws: &mut Client) -> Message {
    tokio::time::timeout(Duration::from_secs(5), ws.next())
        .await
        .expect("no message within 5 s")
        .expect("connection closed")
        .expect("socket error")
}

/// Next message of the connection; a state or an image is acknowledged at
/// once, as a page that keeps up does (flow control).
pub(super) async fn next(ws: &mut Client) -> Message {
    let m = next_raw(ws).await;
    acknowledge(ws, &m).await;
    m
}

/// Acknowledges `m` if it is a state or an image, as a page that keeps up
/// does (flow control).
pub(super) async fn acknowledge(ws: &mut Client, m: &Message) {
    if let Message::Binary(b) = m {
        if matches!(
            FrameHeader::parse(b),
            Some((h, _)) if matches!(
                h.kind,
                FrameKind::ImageJpeg | FrameKind::ImageJpegFlow
            )
        ) {
            send(ws, r#"{"type":"image_ack"}"#).await;
        }
    }
    if let Message::Text(t) = m {
        if let Ok(Envelope {
            body: ServerMessage::State(s),
            ..
        }) = serde_json::from_str::<Envelope>(t.as_str())
        {
            send(ws, &format!(r#"{{"type":"ack","seq":{}}}"#, s.seq)).await;
        }
    }
}

/// Next JSON message satisfying `pred`, skipping others.
pub(super) async fn next_json(
    ws: &mut Client,
    mut pred: impl FnMut(&ServerMessage) -> bool,
) -> ServerMessage {
    for _ in 0..500 {
        if let Message::Text(t) = next(ws).await {
            let env: Envelope = serde_json::from_str(t.as_str()).unwrap();
            assert_eq!(env.v, super::super::protocol::PROTOCOL_VERSION);
            if pred(&env.body) {
                return env.body;
            }
        }
    }
    panic!("no matching message in 500");
}

pub(super) async fn next_state(
    ws: &mut Client,
    mut pred: impl FnMut(&ViewState) -> bool,
) -> ViewState {
    match next_json(ws, |m| matches!(m, ServerMessage::State(s) if pred(s))).await {
        ServerMessage::State(s) => s,
        _ => unreachable!(),
    }
}

pub(super) async fn send(ws: &mut Client, text: &str) {
    ws.send(Message::text(text)).await.unwrap();
}

pub(super) async fn next_error(ws: &mut Client) -> String {
    match next_json(ws, |m| matches!(m, ServerMessage::Error { .. })).await {
        ServerMessage::Error { message } => message,
        _ => unreachable!(),
    }
}

fn norm(f: [f64; 3]) -> f64 {
    f.iter().map(|c| c * c).sum::<f64>().sqrt()
}

#[tokio::test]
async fn hello_then_state_surface_and_image_frames() {
    let fake = Arc::new(FakeLive::new());
    let nodes = fake.mesh().rest.len();
    let mut ws = connect(start(fake).await).await;
    match serde_json::from_str::<Envelope>(next(&mut ws).await.to_text().unwrap())
        .unwrap()
        .body
    {
        ServerMessage::Hello {
            mesh, state_rate, ..
        } => {
            assert_eq!(mesh.rest.len(), nodes);
            assert!(!mesh.triangles.is_empty());
            assert_eq!(state_rate, 100.0);
        }
        other => panic!("first message {other:?}"),
    }
    // The first surface frame holds every node; the images are JPEGs of the
    // double's frames, each uniform at `fake_image_level(frame)`: a flat
    // 8 × 8 block is its DC coefficient alone, quantized at quality 80 by a
    // step of 6 (16 · 0.4) on 8 × the mean, so within 6/16 < 0.5 level of
    // the mean, plus the decoder's rounding: within 1 level.
    let (mut surface, mut images) = (false, 0);
    let mut last_frame = 0u32;
    for _ in 0..200 {
        if let Message::Binary(b) = next(&mut ws).await {
            let (h, body) = FrameHeader::parse(&b).expect("bad frame");
            match h.kind {
                FrameKind::SurfaceDelta if !surface => {
                    assert_eq!((h.a as usize, h.b as usize), (nodes, nodes));
                    surface = true;
                }
                FrameKind::SurfaceDelta => assert!(h.a <= h.b),
                FrameKind::ImageJpeg => {
                    assert_eq!((h.a, h.b), (32, 24));
                    let img = decode_jpeg(&body[8..]);
                    assert_eq!(img.len(), 32 * 24);
                    // The frame it shows: a later one than the last image.
                    let frame = (last_frame + 1..last_frame + 400)
                        .find(|&f| {
                            let l = fake_image_level(f);
                            img.iter().all(|&p| p.abs_diff(l) <= 1)
                        })
                        .expect("an image that is none of the next frames");
                    last_frame = frame;
                    images += 1;
                }
                other => panic!("the server sent a {other:?} frame"),
            }
        }
        if surface && images >= 4 {
            break;
        }
    }
    assert!(surface && images >= 4, "surface {surface}, {images} images");
    let s = next_state(&mut ws, |_| true).await;
    assert_eq!(s.vein, Some(VeinState::Healthy));
    assert!(!s.exam.is_some_and(|e| e.open));
}

#[tokio::test]
async fn bad_messages_get_errors_and_the_connection_stays_up() {
    let fake = Arc::new(FakeLive::new());
    let mut ws = connect(start(fake.clone()).await).await;
    let bad = [
        "\u{1}\u{2}garbage",
        r#"{"type":"probe","theta":"x","z":0,"depth":0,"tilt":0}"#,
        r#"{"type":"probe","theta":0,"z":0,"depth":0.5,"tilt":0}"#,
        r#"{"type":"set_latency","seconds":0.1,"extra":1}"#,
        // Off the 0.3 m thigh: refused at decoding, with the runtime's limits.
        r#"{"type":"probe","theta":0,"z":0.9,"depth":0.01,"tilt":0}"#,
    ];
    for text in bad {
        send(&mut ws, text).await;
        let message = next_error(&mut ws).await;
        assert!(!message.is_empty(), "{text}");
    }
    ws.send(Message::binary(vec![0u8, 159, 146, 150]))
        .await
        .unwrap();
    assert!(next_error(&mut ws).await.contains("binary"));
    // Still up: a good press raises the force.
    send(
        &mut ws,
        r#"{"type":"probe","theta":0.2,"z":0.01,"depth":0.015,"tilt":0}"#,
    )
    .await;
    let s = next_state(&mut ws, |s| norm(s.status.physics_force) > 1.0).await;
    assert!(norm(s.status.rendered_force) > 1.0);
    let live: Vec<_> = fake
        .commands()
        .into_iter()
        .filter(|c| matches!(c, LiveCommand::Probe { .. }))
        .collect();
    assert_eq!(
        live.len(),
        1,
        "only the in-range probe reaches the runtime: {live:?}"
    );
}

#[tokio::test]
async fn controls_reach_the_runtime() {
    let fake = Arc::new(FakeLive::new());
    let mut ws = connect(start(fake.clone()).await).await;
    send(&mut ws, r#"{"type":"set_vein","vein":"chronic"}"#).await;
    send(&mut ws, r#"{"type":"set_mode","mode":"direct"}"#).await;
    send(&mut ws, r#"{"type":"set_physics_rate","hz":50}"#).await;
    send(&mut ws, r#"{"type":"set_latency","seconds":0.04}"#).await;
    let s = next_state(&mut ws, |s| s.status.latency_setting > 0.0).await;
    assert_eq!(s.vein, Some(VeinState::Chronic));
    assert_eq!(
        s.status.mode,
        Some(echothigh_runtime::live::CouplingMode::Direct)
    );
    assert_eq!(
        (s.status.physics_rate_setting, s.status.latency_setting),
        (50.0, 0.04)
    );
}

/// Issue 14, end to end against the double: a case is loaded into the
/// runtime, its truth stays on the server, the observer thread detects the
/// trainee's presses from the live state (the double's section reading: a
/// healthy vein closes by 8 N, the popliteal thrombus keeps ≥ 0.9 of its
/// lumen, the artery deforms from 10 N), the calls are scored on finish and
/// the truth revealed, and the sink got every record as it happened.
#[tokio::test]
async fn exam_loads_a_case_detects_presses_and_reveals_on_finish() {
    let fake = Arc::new(FakeLive::new());
    let sink = MemorySink::default();
    let plan = ExamPlan {
        trainee: Some("ada".into()),
        protocol: echothigh_exam::Protocol::TwoPoint,
        cases: vec![echothigh_cases::builtin("popliteal-acute").unwrap()],
    };
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let session = ExamSession::new(plan, Box::new(sink.clone()), false);
    let config = ServerConfig {
        state_rate: 100.0,
        ..ServerConfig::default()
    };
    tokio::spawn(serve_on(
        listener,
        fake.clone(),
        config,
        session,
        std::future::pending(),
    ));
    let mut ws = connect(addr).await;
    send(
        &mut ws,
        r#"{"type":"exam_call","site":"cfv","finding":"normal"}"#,
    )
    .await;
    assert!(next_error(&mut ws).await.contains("no case is open"));
    send(&mut ws, r#"{"type":"exam_start"}"#).await;
    // The case's leg has its own rest shape: a new `hello` with its mesh
    // comes, and the open case's status (sent once, when it changed).
    let (mut hello, mut open) = (false, None);
    while !(hello && open.is_some()) {
        match next_json(&mut ws, |m| !matches!(m, ServerMessage::Error { .. })).await {
            ServerMessage::Hello { .. } => hello = true,
            ServerMessage::State(s) if s.exam.as_ref().is_some_and(|e| e.open) => open = Some(s),
            _ => {}
        }
    }
    let s = open.unwrap();
    let e = s.exam.unwrap();
    assert_eq!((e.case_number, e.cases_total, s.vein), (1, 1, None));
    assert!(e.last.is_none(), "no truth while the case is open");
    let names: Vec<&str> = e.sites.iter().map(|x| x.name.as_str()).collect();
    assert_eq!(names, ["cfv", "popliteal"]);
    assert_eq!(fake.case_name().as_deref(), Some("popliteal-acute"));
    send(&mut ws, r#"{"type":"set_vein","vein":"healthy"}"#).await;
    assert!(next_error(&mut ws).await.contains("the case's"));

    // Press each site, then release: 12 N at the CFV (closes), 20 N at the
    // popliteal (stays open, the artery deforms).
    for (k, (site, depth)) in [(&e.sites[0], 0.015), (&e.sites[1], 0.02)]
        .into_iter()
        .enumerate()
    {
        let z = crate::fake::z_of(&fake, site.s);
        let probe = format!(r#"{{"type":"probe","theta":0,"z":{z},"depth":{depth},"tilt":0}}"#);
        send(&mut ws, &probe).await;
        next_state(&mut ws, |s| s.status.rendered_force[1] > 10.0).await;
        // A few observer samples (50 Hz) at the peak.
        tokio::time::sleep(Duration::from_millis(200)).await;
        send(&mut ws, r#"{"type":"lift"}"#).await;
        let s = next_state(&mut ws, |s| {
            s.exam.as_ref().is_some_and(|e| e.presses == k as u32 + 1)
        })
        .await;
        assert!(s.exam.unwrap().sites[k].done, "site {} covered", site.name);
    }
    send(
        &mut ws,
        r#"{"type":"exam_call","site":"cfv","finding":"normal"}"#,
    )
    .await;
    send(
        &mut ws,
        r#"{"type":"exam_call","site":"popliteal","finding":"acute_dvt"}"#,
    )
    .await;
    send(&mut ws, r#"{"type":"exam_finish"}"#).await;
    let s = next_state(&mut ws, |s| {
        s.exam.as_ref().is_some_and(|e| e.last.is_some())
    })
    .await;
    let e = s.exam.unwrap();
    let last = e.last.unwrap();
    assert_eq!(last.diagnosis, "acute_dvt");
    assert_eq!((last.score.calls_correct, last.score.calls_total), (2, 2));
    assert_eq!(last.score.coverage, 1.0);
    assert!(last
        .truth
        .iter()
        .any(|t| t.vein == "pv" && t.kind == "acute_occlusive"));
    {
        let cases = sink.cases.lock().unwrap();
        let log = cases[0].1.lock().unwrap();
        assert_eq!((log.events.len(), log.calls.len()), (2, 2));
        assert_eq!(log.score.as_ref(), Some(&last.score));
    }
    // Leaving the exam puts the practice leg back (the server's home case,
    // here the scenario's own leg): a new `hello` with its mesh, and the
    // vein control is the page's again.
    send(&mut ws, r#"{"type":"exam_stop"}"#).await;
    let mut hello = false;
    while !hello {
        hello = matches!(
            next_json(&mut ws, |m| !matches!(m, ServerMessage::Error { .. })).await,
            ServerMessage::Hello { .. }
        );
    }
    assert_eq!(fake.case_name(), None);
    next_state(&mut ws, |s| s.vein.is_some()).await;
}

#[tokio::test]
async fn cross_origin_websocket_is_refused() {
    let addr = start(Arc::new(FakeLive::new())).await;
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    req.headers_mut()
        .insert("origin", "http://evil.example".parse().unwrap());
    assert!(tokio_tungstenite::connect_async(req).await.is_err());
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    req.headers_mut()
        .insert("origin", format!("http://{addr}").parse().unwrap());
    assert!(tokio_tungstenite::connect_async(req).await.is_ok());
}

/// DNS rebinding (issue 20, item 8): a page on evil.example whose name now
/// resolves to 127.0.0.1 sends `Host: evil.example:port` with a matching
/// `Origin`; the server refuses it (403) on the WebSocket and the page.
#[tokio::test]
async fn dns_rebinding_host_is_refused() {
    let addr = start(Arc::new(FakeLive::new())).await;
    let port = addr.port();
    let evil = format!("evil.example:{port}");
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    req.headers_mut().insert("host", evil.parse().unwrap());
    req.headers_mut()
        .insert("origin", format!("http://{evil}").parse().unwrap());
    match tokio_tungstenite::connect_async(req).await {
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => assert_eq!(r.status(), 403),
        other => panic!(
            "rebinding WebSocket not refused with 403: {:?}",
            other.map(|_| ())
        ),
    }
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!("GET / HTTP/1.1\r\nHost: {evil}\r\nConnection: close\r\n\r\n");
    s.write_all(req.as_bytes()).await.unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).await.unwrap();
    assert!(String::from_utf8_lossy(&out).starts_with("HTTP/1.1 403"));
    for ok in ["localhost:8080", "127.0.0.1", "127.1.2.3:9", "[::1]:8080"] {
        let mut h = HeaderMap::new();
        h.insert(header::HOST, ok.parse().unwrap());
        assert!(loopback_host(&h), "{ok} is loopback");
    }
    for bad in [
        "evil.example",
        "localhost.evil.example:80",
        "10.0.0.1:8080",
        "[::2]:1",
    ] {
        let mut h = HeaderMap::new();
        h.insert(header::HOST, bad.parse().unwrap());
        assert!(!loopback_host(&h), "{bad} is not loopback");
    }
}

async fn http_get(addr: std::net::SocketAddr, path: &str) -> String {
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    s.write_all(req.as_bytes()).await.unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).await.unwrap();
    String::from_utf8_lossy(&out).into_owned()
}

#[tokio::test]
async fn serves_the_embedded_page() {
    let addr = start(Arc::new(FakeLive::new())).await;
    let page = http_get(addr, "/").await;
    assert!(page.starts_with("HTTP/1.1 200"), "{page}");
    assert!(page.to_lowercase().contains("content-type: text/html"));
    assert!(page.contains("app.js"));
    let js = http_get(addr, "/vendor/three.module.min.js").await;
    assert!(js.starts_with("HTTP/1.1 200") && js.contains("text/javascript"));
    assert!(http_get(addr, "/secret.txt")
        .await
        .starts_with("HTTP/1.1 404"));
}

#[test]
fn binds_only_loopback_unless_allowed() {
    assert!(check_bind("127.0.0.1".parse().unwrap(), false).is_ok());
    assert!(check_bind("::1".parse().unwrap(), false).is_ok());
    let err = check_bind("0.0.0.0".parse().unwrap(), false).unwrap_err();
    assert!(err.to_string().contains("--allow-remote"));
    assert!(check_bind("192.168.1.4".parse().unwrap(), false).is_err());
    assert!(check_bind("0.0.0.0".parse().unwrap(), true).is_ok());
    assert!(check_rate(40.0).is_ok());
    assert!(
        check_rate(0.0).is_err() && check_rate(f64::NAN).is_err() && check_rate(500.0).is_err()
    );
}

/// Not a check: serves the page against the runtime's test double so the
/// page and the browser test can be worked on without the physics.
/// `ECHOTHIGH_VIEW_DEV_PORT=8090 cargo test -p echothigh serve_test_double -- --ignored`
/// (stops after `ECHOTHIGH_VIEW_DEV_SECONDS`, default 600).
#[tokio::test]
#[ignore = "development server, runs until its timeout"]
async fn serve_test_double() {
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let port = env("ECHOTHIGH_VIEW_DEV_PORT", 8090) as u16;
    let seconds = env("ECHOTHIGH_VIEW_DEV_SECONDS", 600);
    let listener = tokio::net::TcpListener::bind(("127.0.0.1", port))
        .await
        .unwrap();
    println!(
        "echothigh viewer: http://{}/",
        listener.local_addr().unwrap()
    );
    let stop = tokio::time::sleep(Duration::from_secs(seconds));
    serve_on(
        listener,
        Arc::new(FakeLive::new()),
        ServerConfig::default(),
        practice(),
        stop,
    )
    .await
    .unwrap();
}

/// Issue 16: a mode change (a restart of the simulation's threads, here held
/// open by the double until released) runs off the async executor: another
/// page keeps receiving states meanwhile. Had it run on the executor (a
/// single thread in `#[tokio::test]`), no state could reach the second page
/// until the double gave up waiting ([`super::super::fake::GATE_WAIT`]),
/// which the double reports.
#[tokio::test]
async fn a_restart_does_not_stall_the_other_pages() {
    let fake = Arc::new(FakeLive::new());
    let addr = start(fake.clone()).await;
    let mut changer = connect(addr).await;
    let mut watcher = connect(addr).await;
    next_state(&mut watcher, |_| true).await;
    let release = fake.hold_next_mode_change();
    send(&mut changer, r#"{"type":"set_mode","mode":"direct"}"#).await;
    // Wait until the command is inside the double, held at the gate.
    let t = tokio::time::Instant::now();
    while !fake.gate_taken() {
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "the command never arrived"
        );
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let mut seen = 0;
    let mut last_time = -1.0;
    while seen < 5 {
        let s = next_state(&mut watcher, |_| true).await;
        assert!(s.status.time > last_time, "a stale state was repeated");
        last_time = s.status.time;
        seen += 1;
    }
    assert!(!fake.gate_timed_out(), "the restart blocked the executor");
    release.send(()).unwrap();
    let s = next_state(&mut changer, |s| {
        s.status.mode == Some(echothigh_runtime::live::CouplingMode::Direct)
    })
    .await;
    assert_eq!(
        s.status.mode,
        Some(echothigh_runtime::live::CouplingMode::Direct)
    );
    assert!(!fake.gate_timed_out());
}

/// Issue 20: a connection that sends nothing (not even the pong a browser
/// returns to the server's pings) is closed after the idle timeout, both a
/// WebSocket and a bare HTTP keep-alive connection; a page that answers
/// stays. The imaging is asked for only while a page is connected.
#[tokio::test]
async fn idle_connections_are_closed_and_live_ones_kept() {
    let fake = Arc::new(FakeLive::new());
    let timeout = Duration::from_millis(600);
    let addr = start_with(fake.clone(), timeout).await;
    // A page that never reads: tungstenite answers pings only when read.
    let mut silent = connect(addr).await;
    // A page that reads (and so answers every ping with a pong).
    let mut live = connect(addr).await;
    // A bare TCP connection after one HTTP request, left open.
    let mut http = tokio::net::TcpStream::connect(addr).await.unwrap();
    http.write_all(b"GET /style.css HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        .await
        .unwrap();
    wait_watchers(&fake, 2).await;
    let start = tokio::time::Instant::now();
    // Several timeouts long, reading the live page all the while.
    while start.elapsed() < 4 * timeout {
        next(&mut live).await;
    }
    // The live page is still served.
    next_state(&mut live, |_| true).await;
    // The silent page was closed: draining its buffered frames ends in a
    // close or an error, within the test's 5 s bound.
    let closed = tokio::time::timeout(Duration::from_secs(5), async {
        loop {
            match silent.next().await {
                None | Some(Err(_)) | Some(Ok(Message::Close(_))) => return,
                Some(Ok(_)) => {}
            }
        }
    })
    .await;
    assert!(closed.is_ok(), "the silent WebSocket was not closed");
    // The HTTP connection was answered, then closed: reading to the end
    // returns (EOF or reset) instead of waiting forever.
    let mut body = Vec::new();
    let read = tokio::time::timeout(Duration::from_secs(5), http.read_to_end(&mut body)).await;
    assert!(read.is_ok(), "the idle HTTP connection was not closed");
    assert!(String::from_utf8_lossy(&body).starts_with("HTTP/1.1 200"));
    // The closed page no longer counts as looking.
    drop(live);
    wait_watchers(&fake, 0).await;
}

/// Waits (at most 5 s) until `n` pages look at the double.
async fn wait_watchers(fake: &FakeLive, n: usize) {
    let t = tokio::time::Instant::now();
    while fake.watchers() != n {
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "{} pages look, expected {n}",
            fake.watchers()
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

/// An 8-bit grayscale PNG's pixels.
/// The gray pixels of a JPEG image frame's body.
pub(super) fn decode_jpeg(jpeg: &[u8]) -> Vec<u8> {
    let mut d = jpeg_decoder::Decoder::new(jpeg);
    let px = d.decode().expect("a JPEG the decoder reads");
    let info = d.info().unwrap();
    assert_eq!(info.pixel_format, jpeg_decoder::PixelFormat::L8);
    px
}

pub(super) fn decode_png(png_bytes: &[u8]) -> Vec<u8> {
    let mut reader = png::Decoder::new(png_bytes).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    buf.truncate(info.buffer_size());
    buf
}

/// Flow control (issue 19): a page that does not acknowledge gets
/// `CREDIT` states and one image, then nothing, though the server ticks at
/// 100 Hz (0.5 s is fifty ticks, and the double has a new image at every
/// tick); one acknowledgement frees one more, the newest.
#[tokio::test]
async fn an_unacknowledged_page_gets_no_backlog() {
    use super::super::protocol::CREDIT;
    let fake = Arc::new(FakeLive::new());
    let mut ws = connect(start(fake).await).await;
    let (mut states, mut images) = (Vec::new(), 0);
    let deadline = tokio::time::Instant::now() + Duration::from_millis(500);
    while let Ok(Some(Ok(m))) = tokio::time::timeout_at(deadline, ws.next()).await {
        if let Message::Binary(b) = &m {
            let kind = FrameHeader::parse(b).unwrap().0.kind;
            images += usize::from(kind == FrameKind::ImageJpeg);
        }
        if let Message::Text(t) = m {
            if let ServerMessage::State(s) =
                serde_json::from_str::<Envelope>(t.as_str()).unwrap().body
            {
                states.push(s);
            }
        }
    }
    assert_eq!(
        states.len() as u64,
        CREDIT,
        "states sent without acknowledgement"
    );
    assert_eq!(
        states.iter().map(|s| s.seq).collect::<Vec<_>>(),
        (1..=CREDIT).collect::<Vec<_>>()
    );
    assert_eq!(images, 1, "images sent without acknowledgement");
    // An acknowledgement of a state never sent frees nothing beyond.
    send(&mut ws, r#"{"type":"ack","seq":99}"#).await;
    let next = next_state(&mut ws, |_| true).await;
    assert_eq!(next.seq, CREDIT + 1);
    assert!(
        next.status.time > states[states.len() - 1].status.time,
        "not the newest state"
    );
}

/// Issue 19, one owner of the probe: the first tab drives, a second one
/// observes (it receives the states, its commands are refused and never
/// reach the runtime); when the first closes, the second may take control.
#[tokio::test]
async fn a_second_tab_observes_until_the_first_closes() {
    let fake = Arc::new(FakeLive::new());
    let addr = start(fake.clone()).await;
    let mut first = connect(addr).await;
    assert!(!next_state(&mut first, |_| true).await.observer);
    let mut second = connect(addr).await;
    assert!(next_state(&mut second, |_| true).await.observer);
    let press = r#"{"type":"probe","theta":0.1,"z":0.0,"depth":0.01,"tilt":0}"#;
    send(&mut second, press).await;
    assert!(next_error(&mut second).await.contains("observes"));
    send(&mut second, r#"{"type":"take_control"}"#).await;
    assert!(next_error(&mut second).await.contains("observes"));
    send(&mut second, r#"{"type":"exam_start"}"#).await;
    assert!(next_error(&mut second).await.contains("observes"));
    assert!(fake.commands().is_empty(), "{:?}", fake.commands());
    send(&mut first, press).await;
    next_state(&mut second, |s| norm(s.status.physics_force) > 1.0).await;
    assert_eq!(fake.commands().len(), 1);
    // The driver leaves: the observer takes control and drives.
    first.close(None).await.unwrap();
    drop(first);
    let t = tokio::time::Instant::now();
    loop {
        send(&mut second, r#"{"type":"take_control"}"#).await;
        if !next_state(&mut second, |_| true).await.observer {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(5), "never took control");
    }
    send(&mut second, r#"{"type":"lift"}"#).await;
    next_state(&mut second, |s| norm(s.status.physics_force) == 0.0).await;
    assert_eq!(fake.commands().len(), 2);
}
