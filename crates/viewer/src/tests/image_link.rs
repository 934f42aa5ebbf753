//! The image socket of a page's worker (issue 19, [`crate::image_link`]),
//! over real sockets against the runtime's test double: once the worker's
//! socket presents its connection's token, the images go there and not on
//! the main socket, one at a time against its acknowledgements; a token
//! opens one socket, an unknown one none; when the worker's socket closes
//! the images come back on the main socket.

use super::super::fake::FakeLive;
use super::super::protocol::{Envelope, FrameHeader, FrameKind, ServerMessage};
use super::server::{acknowledge, connect, next_raw, start, Client};
use futures_util::{SinkExt, StreamExt};
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

fn is_image(m: &Message) -> bool {
    matches!(m, Message::Binary(b) if FrameHeader::parse(b).is_some_and(|(h, _)| matches!(h.kind, FrameKind::ImageJpeg | FrameKind::ImageJpegFlow)))
}

/// The image token of the connection's hello (its first message).
async fn token(ws: &mut Client) -> String {
    let m = next_raw(ws).await;
    let Message::Text(t) = m else {
        panic!("the first message is not the hello: {m:?}")
    };
    match serde_json::from_str::<Envelope>(t.as_str()).unwrap().body {
        ServerMessage::Hello { image_link, .. } => {
            image_link.expect("a hello offers an image link")
        }
        other => panic!("the first message is not the hello: {other:?}"),
    }
}

async fn open_link(addr: std::net::SocketAddr, token: &str) -> Result<Client, String> {
    tokio_tungstenite::connect_async(format!("ws://{addr}/ws/image?token={token}"))
        .await
        .map(|(ws, _)| ws)
        .map_err(|e| e.to_string())
}

/// Reads the main socket for `span`, acknowledging what it must (states;
/// images too, as a page does); returns the images seen there.
async fn main_images(ws: &mut Client, span: Duration) -> usize {
    let end = Instant::now() + span;
    let mut images = 0;
    while let Ok(m) = tokio::time::timeout_at(end, next_raw(ws)).await {
        acknowledge(ws, &m).await;
        images += usize::from(is_image(&m));
    }
    images
}

/// The next message on the worker's socket that is not a ping (5 s at most).
async fn next_link_image(link: &mut Client) -> Message {
    loop {
        let m = tokio::time::timeout(Duration::from_secs(5), link.next())
            .await
            .expect("no image on the worker's socket within 5 s")
            .expect("the worker's socket closed")
            .expect("socket error");
        if !matches!(m, Message::Ping(_) | Message::Pong(_)) {
            return m;
        }
    }
}

#[tokio::test]
async fn images_go_to_the_worker_one_at_a_time_against_its_acknowledgements() {
    let fake = Arc::new(FakeLive::new());
    let addr = start(fake).await;
    let mut ws = connect(addr).await;
    let token = token(&mut ws).await;
    let mut link = open_link(addr, &token).await.unwrap();
    // The worker's first image; the main socket may carry images sent
    // before the worker attached (at most one: one is sent per
    // acknowledgement), none after.
    main_images(&mut ws, Duration::from_millis(300)).await;
    let first = next_link_image(&mut link).await;
    assert!(is_image(&first), "{first:?}");
    // Unacknowledged, no second image comes (the double's frames are new
    // at every read and a still probe gets 5 a second, so 1 s would see ~5).
    let main = main_images(&mut ws, Duration::from_secs(1)).await;
    assert_eq!(
        main, 0,
        "images on the main socket once the worker has its own"
    );
    let second = tokio::time::timeout(Duration::from_millis(10), link.next()).await;
    assert!(
        second.is_err() || matches!(second, Ok(Some(Ok(Message::Ping(_))))),
        "a second image before the first was acknowledged: {second:?}"
    );
    // Acknowledged on the worker's socket, the next one comes there.
    link.send(Message::Text(r#"{"type":"image_ack"}"#.into()))
        .await
        .unwrap();
    let next = next_link_image(&mut link).await;
    assert!(is_image(&next), "{next:?}");
}

#[tokio::test]
async fn a_token_opens_one_socket_and_an_unknown_one_none() {
    let fake = Arc::new(FakeLive::new());
    let addr = start(fake).await;
    let mut ws = connect(addr).await;
    let offered = token(&mut ws).await;
    let err = open_link(addr, "0123456789abcdef").await.unwrap_err();
    assert!(err.contains("404"), "{err}");
    let err = open_link(addr, "nothex").await.unwrap_err();
    assert!(err.contains("404"), "{err}");
    let _link = open_link(addr, &offered).await.unwrap();
    let err = open_link(addr, &offered).await.unwrap_err();
    assert!(err.contains("404"), "a token opened two sockets: {err}");
    // Another connection's token is its own.
    let mut other = connect(addr).await;
    assert_ne!(token(&mut other).await, offered);
}

#[tokio::test]
async fn images_come_back_on_the_main_socket_when_the_worker_closes() {
    let fake = Arc::new(FakeLive::new());
    let addr = start(fake).await;
    let mut ws = connect(addr).await;
    let token = token(&mut ws).await;
    let mut link = open_link(addr, &token).await.unwrap();
    main_images(&mut ws, Duration::from_millis(300)).await;
    // An image the worker never acknowledges, then the worker goes.
    let first = next_link_image(&mut link).await;
    assert!(is_image(&first));
    link.close(None).await.unwrap();
    drop(link);
    // A still probe's 5 images a second come on the main socket again.
    let main = main_images(&mut ws, Duration::from_secs(1)).await;
    assert!(
        main >= 2,
        "{main} images on the main socket in 1 s after the worker closed"
    );
}

/// The image socket has `/ws`'s guards: another site's page (its `Origin`),
/// or a rebound host name (`Host: evil.example`), is refused with 403 even
/// with a token on offer, which then still opens from this page.
#[tokio::test]
async fn another_sites_page_cannot_open_the_image_socket() {
    let fake = Arc::new(FakeLive::new());
    let addr = start(fake).await;
    let mut ws = connect(addr).await;
    let offered = token(&mut ws).await;
    let url = format!("ws://{addr}/ws/image?token={offered}");
    let evil = format!("evil.example:{}", addr.port());
    for (host, origin) in [
        (None, "http://evil.example".to_string()),
        (Some(evil.clone()), format!("http://{evil}")),
    ] {
        let mut req = url.as_str().into_client_request().unwrap();
        if let Some(h) = host {
            req.headers_mut().insert("host", h.parse().unwrap());
        }
        req.headers_mut().insert("origin", origin.parse().unwrap());
        match tokio_tungstenite::connect_async(req).await {
            Err(tokio_tungstenite::tungstenite::Error::Http(r)) => assert_eq!(r.status(), 403),
            other => panic!("{origin}: not refused with 403: {:?}", other.map(|_| ())),
        }
    }
    assert!(open_link(addr, &offered).await.is_ok());
}
