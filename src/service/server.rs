//! Service: the HTTP server loop under the routes. Accepts TCP connections and serves the
//! router over HTTP/1.1 with hyper, holding every connection to limits a careless or hostile
//! client cannot stretch: at most `--max-connections` at once (more are closed on accept),
//! request headers within `--header-timeout`, no connection idle (nothing read or written)
//! beyond `--idle-timeout`, and a graceful stop on shutdown. Body read time is enforced by the
//! routes that read bodies (`--body-timeout`). Headers beyond hyper's own buffer get hyper's
//! 431, which this loop rewrites on the wire into the same problem+json as the routes' 431.
use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use std::future::Future;
use std::io;
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::Semaphore;

/// Connection limits and timeouts (flags of `ashlar serve`).
#[derive(Debug, Clone, PartialEq)]
pub struct ServerParams {
    /// Open connections at once; beyond it new ones are closed as soon as accepted. 512 keeps
    /// the process well inside the usual limit of 1024 file descriptors (the store, logs and
    /// artifact files need the rest).
    pub max_connections: usize,
    /// Time a client has to send a request's headers (from the connection's first byte, or
    /// the end of its previous request): a half-sent request holds a connection no longer.
    pub header_read_timeout: Duration,
    /// Time a client has to send a submission's body once its headers arrived. 60 s is a 16 MB
    /// body at 2 Mbit/s.
    pub body_read_timeout: Duration,
    /// A connection with nothing read or written for this long is closed (event streams send
    /// a keep-alive comment every 15 s, so an open stream is never idle).
    pub idle_timeout: Duration,
    /// Bytes of all request headers together; 431 (problem+json) beyond. Far above any
    /// browser's headers (a few KB), far below hyper's own buffer limit, whose bare 431 a
    /// client then only meets beyond [`HYPER_BUF`].
    pub max_header_bytes: usize,
    /// Request header fields; 431 beyond.
    pub max_headers: usize,
    /// Origins whose web pages may call the API from a browser (CORS), e.g.
    /// `https://app.foxglove.dev` for the "open in Foxglove" link. None by default: the
    /// service's own page is same-origin and needs none, and any other page open in a
    /// browser on the host must not be able to submit, read or delete jobs.
    pub cors_origins: Vec<String>,
    /// Bearer tokens required on `/v1/…` (`--tokens`); `None`: no authentication.
    pub tokens: Option<Arc<super::auth::Tokens>>,
    /// The key of signed short-lived URLs (with `--tokens`): `--signing-key-file`, or a
    /// random key per start.
    pub signing: Option<super::auth::SigningKey>,
}

impl Default for ServerParams {
    fn default() -> Self {
        Self {
            max_connections: 512,
            header_read_timeout: Duration::from_secs(10),
            body_read_timeout: Duration::from_secs(60),
            idle_timeout: Duration::from_secs(60),
            max_header_bytes: 32 * 1024,
            max_headers: 100,
            cors_origins: Vec::new(),
            tokens: None,
            signing: None,
        }
    }
}

/// hyper's read buffer: headers beyond it get hyper's own (bodiless) 431, which [`IdleIo`]
/// rewrites into problem+json.
pub const HYPER_BUF: usize = 256 * 1024;
/// hyper's header count limit: beyond it, hyper's own 431.
pub const HYPER_MAX_HEADERS: usize = 400;

/// Serve `app` on `listener` until `shutdown` resolves, then stop accepting, let open
/// connections finish their current request (at most 10 s more) and return.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    params: ServerParams,
    shutdown: impl Future<Output = ()>,
) -> io::Result<()> {
    let slots = Arc::new(Semaphore::new(params.max_connections));
    let refused = Arc::new(AtomicU64::new(0));
    let (stop_tx, stop_rx) = tokio::sync::watch::channel(false);
    let mut builder = http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(params.header_read_timeout)
        .max_buf_size(HYPER_BUF)
        .max_headers(HYPER_MAX_HEADERS)
        .keep_alive(true);
    let builder = Arc::new(builder);
    tokio::pin!(shutdown);
    loop {
        let stream = tokio::select! {
            _ = &mut shutdown => break,
            r = listener.accept() => match r {
                Ok((s, _)) => s,
                Err(e) => {
                    // Out of file descriptors or a connection reset before accept: wait a
                    // little instead of spinning, like axum::serve.
                    tracing::warn!(error = %e, "accepting a connection");
                    tokio::time::sleep(Duration::from_millis(100)).await;
                    continue;
                }
            },
        };
        let Ok(permit) = slots.clone().try_acquire_owned() else {
            let n = refused.fetch_add(1, Ordering::Relaxed) + 1;
            if n.is_power_of_two() {
                tracing::warn!(
                    refused = n,
                    limit = params.max_connections,
                    "connection limit reached (ashlar serve --max-connections): closing new connections"
                );
            }
            drop(stream);
            continue;
        };
        let _ = stream.set_nodelay(true);
        let io = TokioIo::new(IdleIo::new(
            stream,
            params.idle_timeout,
            params.max_header_bytes,
        ));
        let service = TowerToHyperService::new(app.clone());
        let builder = builder.clone();
        let mut stop_rx = stop_rx.clone();
        tokio::spawn(async move {
            let _permit = permit;
            let conn = builder.serve_connection(io, service);
            tokio::pin!(conn);
            let mut stopping = false;
            loop {
                tokio::select! {
                    r = conn.as_mut() => {
                        if let Err(e) = r {
                            tracing::debug!(error = %e, "connection ended with an error");
                        }
                        break;
                    }
                    _ = stop_rx.changed(), if !stopping => {
                        stopping = true;
                        conn.as_mut().graceful_shutdown();
                    }
                }
            }
        });
    }
    drop(listener);
    let _ = stop_tx.send(true);
    let all = u32::try_from(params.max_connections).unwrap_or(u32::MAX);
    let _ = tokio::time::timeout(Duration::from_secs(10), slots.acquire_many(all)).await;
    Ok(())
}

/// A TCP stream that fails with `TimedOut` once nothing has been read or written for
/// `idle` while hyper waits on it, and that replaces hyper's own bodiless 431 (headers beyond
/// its buffer, before any route sees the request) with a problem+json answer.
struct IdleIo {
    inner: TcpStream,
    idle: Duration,
    timer: Pin<Box<tokio::time::Sleep>>,
    /// The routes' header limit, named in the rewritten 431.
    max_header_bytes: usize,
    /// A rewritten answer being written, and how much of it is out.
    replacing: Option<(Vec<u8>, usize)>,
}

/// hyper's own 431: its status line with an empty body (the routes' 431 has a body).
fn is_bare_431(buf: &[u8]) -> bool {
    if !buf.starts_with(b"HTTP/1.1 431 ") {
        return false;
    }
    let head = String::from_utf8_lossy(&buf[..buf.len().min(1024)]).to_ascii_lowercase();
    head.contains("content-length: 0\r\n") && !head.contains("content-type:")
}

/// The problem+json 431 written instead of hyper's; the connection closes after it, as after
/// hyper's.
fn problem_431(max_header_bytes: usize) -> Vec<u8> {
    let body = serde_json::json!({
        "type": "urn:ashlar:problem:header-fields-too-large",
        "title": "Request header fields too large",
        "status": 431,
        "detail": format!(
            "the request's header fields exceed {HYPER_BUF} bytes or {HYPER_MAX_HEADERS} fields, more than the \
             server reads; it takes at most {max_header_bytes} bytes of headers"
        ),
    })
    .to_string();
    format!(
        "HTTP/1.1 431 Request Header Fields Too Large\r\ncontent-type: application/problem+json\r\n\
         content-length: {}\r\nconnection: close\r\n\r\n{body}",
        body.len()
    )
    .into_bytes()
}

impl IdleIo {
    fn new(inner: TcpStream, idle: Duration, max_header_bytes: usize) -> Self {
        Self {
            inner,
            idle,
            timer: Box::pin(tokio::time::sleep(idle)),
            max_header_bytes,
            replacing: None,
        }
    }
    fn touch(&mut self) {
        let at = tokio::time::Instant::now() + self.idle;
        self.timer.as_mut().reset(at);
    }
    fn expired(&mut self, cx: &mut Context<'_>) -> bool {
        self.timer.as_mut().poll(cx).is_ready()
    }
}

fn idle_error() -> io::Error {
    io::Error::new(io::ErrorKind::TimedOut, "connection idle too long")
}

impl AsyncRead for IdleIo {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        let before = buf.filled().len();
        match Pin::new(&mut this.inner).poll_read(cx, buf) {
            Poll::Ready(r) => {
                if buf.filled().len() > before {
                    this.touch();
                }
                Poll::Ready(r)
            }
            Poll::Pending if this.expired(cx) => Poll::Ready(Err(idle_error())),
            Poll::Pending => Poll::Pending,
        }
    }
}

impl AsyncWrite for IdleIo {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        if this.replacing.is_none() && is_bare_431(buf) {
            this.replacing = Some((problem_431(this.max_header_bytes), 0));
        }
        if let Some((bytes, mut done)) = this.replacing.take() {
            // hyper's bytes count as written once the replacement is out (hyper writes its
            // error answer in one buffer: this stream is not vectored).
            while done < bytes.len() {
                match Pin::new(&mut this.inner).poll_write(cx, &bytes[done..]) {
                    Poll::Ready(Ok(0)) => return Poll::Ready(Ok(0)),
                    Poll::Ready(Ok(n)) => {
                        done += n;
                        this.touch();
                    }
                    Poll::Ready(Err(e)) => return Poll::Ready(Err(e)),
                    Poll::Pending if this.expired(cx) => return Poll::Ready(Err(idle_error())),
                    Poll::Pending => {
                        this.replacing = Some((bytes, done));
                        return Poll::Pending;
                    }
                }
            }
            // Anything hyper writes after its error answer is dropped: the connection closes.
            this.replacing = Some((bytes, done));
            return Poll::Ready(Ok(buf.len()));
        }
        match Pin::new(&mut this.inner).poll_write(cx, buf) {
            Poll::Ready(Ok(n)) => {
                if n > 0 {
                    this.touch();
                }
                Poll::Ready(Ok(n))
            }
            Poll::Ready(Err(e)) => Poll::Ready(Err(e)),
            Poll::Pending if this.expired(cx) => Poll::Ready(Err(idle_error())),
            Poll::Pending => Poll::Pending,
        }
    }
    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_flush(cx)
    }
    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_shutdown(cx)
    }
}
