//! The image stream's own socket (issue 19): a page that draws the image in
//! a worker opens a second WebSocket, `/ws/image?token=T`, with the token
//! of its connection's `hello`, and its images go there instead of on the
//! main socket. The worker's thread then receives, decodes and draws each
//! image without waiting for the page's thread, which a slow page keeps
//! busy with its layout and paint (measured in the browser test, ×2 CPU
//! throttling, idle machine: an image took 20 ms p50 / 43 ms p95 from its
//! sending to the page's handler and 34 / 103 ms from there to drawn).
//!
//! Everything else stays with the main connection: what is sent, when, and
//! within which byte budget (`server.rs`, [`crate::frames`]); the link only
//! carries the images it is handed and brings back the worker's
//! acknowledgements (`image_ack`, the same flow control as on the main
//! socket). A page without the link (no worker, or the link closed) gets
//! its images on the main socket as before.

use axum::extract::ws::{Message, WebSocket};
use std::collections::HashMap;
use std::sync::Mutex;
use std::time::Duration;
use tokio::sync::mpsc;

/// What the image socket tells its main connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LinkEvent {
    /// The worker connected: images go to it from now on.
    Attached,
    /// The worker took an image (`image_ack`).
    Ack,
    /// The worker's socket closed: images go on the main socket again.
    Detached,
}

/// The main connection's ends of a link not yet claimed by a worker.
struct Unclaimed {
    images: mpsc::Receiver<Message>,
    events: mpsc::UnboundedSender<LinkEvent>,
}

/// The links offered by the open connections, by token.
#[derive(Default)]
pub(crate) struct ImageLinks {
    unclaimed: Mutex<HashMap<u64, Unclaimed>>,
}

/// How many images may wait in a link: the main connection sends one and
/// waits for its acknowledgement, so one is enough; two leave room for
/// the image handed over as the worker detaches.
const LINK_DEPTH: usize = 2;

impl ImageLinks {
    /// Offers a link for a new connection: its token (random, for the page's
    /// `hello`) and the connection's end.
    pub(crate) fn offer(&self) -> ImageLink {
        let (image_tx, image_rx) = mpsc::channel(LINK_DEPTH);
        let (event_tx, event_rx) = mpsc::unbounded_channel();
        let token = rand::random::<u64>() | 1;
        if let Ok(mut m) = self.unclaimed.lock() {
            m.insert(
                token,
                Unclaimed {
                    images: image_rx,
                    events: event_tx,
                },
            );
        }
        ImageLink {
            token,
            images: image_tx,
            events: event_rx,
            attached: false,
        }
    }

    /// The worker's claim of `token`: the link's ends, once.
    fn claim(&self, token: u64) -> Option<Unclaimed> {
        self.unclaimed.lock().ok()?.remove(&token)
    }

    /// Withdraws an offer that no worker claimed (its connection closed).
    fn withdraw(&self, token: u64) {
        if let Ok(mut m) = self.unclaimed.lock() {
            m.remove(&token);
        }
    }

    /// Whether `token` is on offer (for the route: refuse before upgrading).
    pub(crate) fn offered(&self, token: u64) -> bool {
        self.unclaimed
            .lock()
            .map(|m| m.contains_key(&token))
            .unwrap_or(false)
    }

    /// The image socket of `token` until it or its connection closes: the
    /// images handed over are sent, `image_ack` is passed back, a ping goes
    /// every `ping` (the idle timeout counts reads). Refused (closed at once)
    /// when the token is not on offer.
    pub(crate) async fn serve(&self, mut socket: WebSocket, token: u64, ping: Duration) {
        let Some(Unclaimed { mut images, events }) = self.claim(token) else {
            let _ = socket.send(Message::Close(None)).await;
            return;
        };
        if events.send(LinkEvent::Attached).is_err() {
            return; // the connection closed meanwhile
        }
        let mut pings = tokio::time::interval(ping);
        pings.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                image = images.recv() => match image {
                    Some(m) => if socket.send(m).await.is_err() { break },
                    None => break, // the main connection closed
                },
                incoming = socket.recv() => match incoming {
                    None | Some(Err(_)) | Some(Ok(Message::Close(_))) => break,
                    Some(Ok(Message::Text(t))) if is_image_ack(t.as_str()) => {
                        if events.send(LinkEvent::Ack).is_err() { break }
                    }
                    Some(Ok(_)) => {} // nothing else is read here
                },
                _ = pings.tick() => if socket.send(Message::Ping(Default::default())).await.is_err() { break },
            }
        }
        let _ = events.send(LinkEvent::Detached);
    }
}

/// Whether a text frame is the worker's `image_ack` (the only message the
/// image socket takes; anything else is ignored, not an error to answer).
fn is_image_ack(text: &str) -> bool {
    #[derive(serde::Deserialize)]
    struct Msg<'a> {
        #[serde(rename = "type", borrow)]
        kind: &'a str,
    }
    serde_json::from_str::<Msg>(text).is_ok_and(|m| m.kind == "image_ack")
}

/// A connection's end of its image link.
pub(crate) struct ImageLink {
    /// The token its page's worker presents.
    pub token: u64,
    images: mpsc::Sender<Message>,
    events: mpsc::UnboundedReceiver<LinkEvent>,
    attached: bool,
}

impl ImageLink {
    /// The next event from the worker's socket (pending forever once the
    /// link is gone, so that a `select!` arm on it stays quiet).
    pub(crate) async fn event(&mut self) -> LinkEvent {
        match self.events.recv().await {
            Some(e) => {
                self.attached = match e {
                    LinkEvent::Attached | LinkEvent::Ack => true,
                    LinkEvent::Detached => false,
                };
                e
            }
            None => std::future::pending().await,
        }
    }

    /// Hands `image` to the worker's socket; gives it back when the link
    /// cannot take it (not attached, or full), for the main socket.
    pub(crate) fn send(&mut self, image: Message) -> Result<(), Message> {
        if !self.attached {
            return Err(image);
        }
        self.images.try_send(image).map_err(|e| match e {
            mpsc::error::TrySendError::Full(m) | mpsc::error::TrySendError::Closed(m) => m,
        })
    }

    /// Withdraws the offer from `links` if no worker claimed it.
    pub(crate) fn close(&self, links: &ImageLinks) {
        links.withdraw(self.token);
    }
}
