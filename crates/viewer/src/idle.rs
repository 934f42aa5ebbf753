//! Closing idle connections (issue 20: without it, idle or half-open
//! connections pile up until the descriptor limit).
//!
//! Every accepted TCP stream is wrapped in an [`IdleStream`] that fails its
//! pending read with [`std::io::ErrorKind::TimedOut`] once nothing has been
//! read from the peer for the timeout. That one rule covers both protocols
//! the server speaks on the stream:
//! - HTTP keep-alive: hyper waits in a read for the next request; the error
//!   closes the connection;
//! - WebSocket (the upgraded stream is this same stream): the session waits
//!   in a read for the page's next message, and it pings the page every
//!   third of the timeout, so a live page (whose browser answers each ping
//!   with a pong, and which acknowledges every frame) is never idle.
//!
//! Hand-written (60 lines) because no crate of the offline registry offers a
//! read-idle timeout for a tokio stream (`tokio-io-timeout` would).

use std::future::Future;
use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::time::{Instant, Sleep};

/// Default idle timeout of a connection (s): long enough for a page in a
/// background tab (browsers throttle its timers to one wake-up a minute at
/// worst, but still answer pings at once, in the network stack).
pub const DEFAULT_IDLE_TIMEOUT: Duration = Duration::from_secs(60);

/// A listener whose connections close after `timeout` without input.
pub struct IdleListener {
    inner: TcpListener,
    timeout: Duration,
}

impl IdleListener {
    /// Wraps `inner`; its connections time out after `timeout` without input.
    pub fn new(inner: TcpListener, timeout: Duration) -> Self {
        Self { inner, timeout }
    }
}

impl axum::serve::Listener for IdleListener {
    type Io = IdleStream;
    type Addr = std::net::SocketAddr;

    async fn accept(&mut self) -> (Self::Io, Self::Addr) {
        let (stream, addr) = axum::serve::Listener::accept(&mut self.inner).await;
        if let Err(e) = stream.set_nodelay(true) {
            tracing::debug!("TCP_NODELAY on {addr}: {e}");
        }
        (IdleStream::new(stream, self.timeout), addr)
    }

    fn local_addr(&self) -> io::Result<Self::Addr> {
        self.inner.local_addr()
    }
}

/// A TCP stream whose reads fail once it has been idle (no byte read) for
/// its timeout.
pub struct IdleStream {
    inner: TcpStream,
    timeout: Duration,
    deadline: Pin<Box<Sleep>>,
}

impl IdleStream {
    fn new(inner: TcpStream, timeout: Duration) -> Self {
        Self {
            inner,
            timeout,
            deadline: Box::pin(tokio::time::sleep(timeout)),
        }
    }
}

impl AsyncRead for IdleStream {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        match Pin::new(&mut self.inner).poll_read(cx, buf) {
            Poll::Ready(r) => {
                if buf.filled().len() > before {
                    let next = Instant::now() + self.timeout;
                    self.deadline.as_mut().reset(next);
                }
                Poll::Ready(r)
            }
            Poll::Pending => match self.deadline.as_mut().poll(cx) {
                Poll::Ready(()) => Poll::Ready(Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    format!("no input for {:?}: connection closed", self.timeout),
                ))),
                Poll::Pending => Poll::Pending,
            },
        }
    }
}

impl AsyncWrite for IdleStream {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.inner).poll_write(cx, buf)
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }
}
