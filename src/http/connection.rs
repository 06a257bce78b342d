//! Connections: the accept loop, and how long a connection may wait for
//! its client. A response waiting for the client to take it holds memory
//! (a 5.9 MB step 300 times over held 1.7 GB): a write that makes no
//! progress for the stall limit fails, and the connection closes.

use std::future::Future;
use std::io;
use std::pin::{Pin, pin};
use std::task::{Context, Poll, ready};
use std::time::Duration;

use axum::Router;
use axum::serve::Listener;
use hyper::server::conn::http1;
use hyper_util::rt::TokioIo;
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::watch;
use tokio::time::Sleep;

/// Headers the HTTP layer reads before it answers 431 itself, with no
/// body: well past the service's own limit (`super::MAX_HEADERS`), which
/// answers in the error body.
pub const HEADERS_READ: usize = 1000;

/// Serves `app` on `listener` (HTTP/1.1) until `stopped` turns true, then
/// lets each connection finish the request it is answering.
pub async fn serve(
    mut listener: StallLimitedListener,
    app: Router,
    mut stopped: watch::Receiver<bool>,
) {
    // Each connection holds a receiver; all are gone when all have closed.
    let (open, open_receiver) = watch::channel(());
    loop {
        let (io, _) = tokio::select! {
            accepted = Listener::accept(&mut listener) => accepted,
            _ = stopped.wait_for(|stop| *stop) => break,
        };
        let service = TowerToHyperService::new(app.clone());
        let mut stop = stopped.clone();
        let connection_open = open_receiver.clone();
        tokio::spawn(async move {
            let mut http = http1::Builder::new();
            http.max_headers(HEADERS_READ);
            let mut connection = pin!(http.serve_connection(TokioIo::new(io), service));
            let mut stopping = false;
            loop {
                tokio::select! {
                    served = connection.as_mut() => {
                        if let Err(e) = served {
                            tracing::debug!("connection ended: {e}");
                        }
                        break;
                    }
                    _ = stop.wait_for(|stop| *stop), if !stopping => {
                        stopping = true;
                        connection.as_mut().graceful_shutdown();
                    }
                }
            }
            drop(connection_open);
        });
    }
    drop(open_receiver);
    drop(listener);
    open.closed().await;
}

/// A TCP listener whose connections fail a write stalled past `limit`.
pub struct StallLimitedListener {
    pub listener: TcpListener,
    pub limit: Duration,
}

impl Listener for StallLimitedListener {
    type Io = StallLimited<TcpStream>;
    type Addr = std::net::SocketAddr;

    async fn accept(&mut self) -> (Self::Io, Self::Addr) {
        let (stream, addr) = Listener::accept(&mut self.listener).await;
        (
            StallLimited {
                inner: stream,
                limit: self.limit,
                stall: None,
            },
            addr,
        )
    }

    fn local_addr(&self) -> io::Result<Self::Addr> {
        Listener::local_addr(&self.listener)
    }
}

/// A stream whose writes (and flushes) fail once one has waited `limit`
/// for the peer without progress.
pub struct StallLimited<S> {
    inner: S,
    limit: Duration,
    /// Started when a write first waits; cleared when one progresses.
    stall: Option<Pin<Box<Sleep>>>,
}

impl<S> StallLimited<S> {
    /// `polled` is a write's or flush's outcome: a wait starts the stall
    /// timer (or runs on it), progress clears it.
    fn limit_stall<T>(
        &mut self,
        cx: &mut Context<'_>,
        polled: Poll<io::Result<T>>,
    ) -> Poll<io::Result<T>> {
        if polled.is_ready() {
            self.stall = None;
            return polled;
        }
        let limit = self.limit;
        let stall = self
            .stall
            .get_or_insert_with(|| Box::pin(tokio::time::sleep(limit)));
        ready!(stall.as_mut().poll(cx));
        self.stall = None;
        Poll::Ready(Err(io::Error::new(
            io::ErrorKind::TimedOut,
            format!("the client took nothing for {} s", limit.as_secs_f64()),
        )))
    }
}

impl<S: AsyncRead + Unpin> AsyncRead for StallLimited<S> {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_read(cx, buf)
    }
}

impl<S: AsyncWrite + Unpin> AsyncWrite for StallLimited<S> {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        let polled = Pin::new(&mut this.inner).poll_write(cx, buf);
        this.limit_stall(cx, polled)
    }

    fn poll_write_vectored(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        let polled = Pin::new(&mut this.inner).poll_write_vectored(cx, bufs);
        this.limit_stall(cx, polled)
    }

    fn is_write_vectored(&self) -> bool {
        self.inner.is_write_vectored()
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        let polled = Pin::new(&mut this.inner).poll_flush(cx);
        this.limit_stall(cx, polled)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_shutdown(cx)
    }
}
