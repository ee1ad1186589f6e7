//! Just enough HTTP/1.1 for one page and one WebSocket endpoint: a web
//! framework would bring a large dependency tree for two routes.

use std::net::IpAddr;
use std::time::Duration;

use tokio::io::{AsyncBufReadExt, AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, BufReader};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::handshake::derive_accept_key;
use tokio_tungstenite::tungstenite::protocol::{Role, WebSocketConfig};
use tokio_tungstenite::WebSocketStream;

use super::PAGE;

/// A page's WebSocket. The buffered reader keeps whatever the browser sent
/// after the request head.
pub type Socket<S = TcpStream> = WebSocketStream<BufReader<S>>;

/// Longest request head read; the page's own requests are under 1 KiB.
const MAX_HEAD: u64 = 16 * 1024;

/// A connection that sends no complete request in this time is dropped.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(10);

/// Largest WebSocket message (and frame) a tab may send. The page sends
/// only controls (`{"type":"control","action":"unpause"}`, under 50 bytes);
/// tungstenite's default of 64 MiB would let one tab make the viewer buffer
/// that much.
pub const MAX_WS_MESSAGE: usize = 4 * 1024;

/// Why a browser connection ended without a WebSocket.
#[derive(Debug, thiserror::Error)]
pub enum HttpError {
    #[error("socket error: {0}")]
    Io(#[from] std::io::Error),
    #[error("no complete request within {0:?}")]
    Timeout(Duration),
    #[error("malformed request: {0}")]
    Malformed(String),
}

/// What became of a connection.
pub enum Accepted<S = TcpStream> {
    /// A response was sent and the connection closed.
    Served,
    /// The page opened its WebSocket (boxed: the stream is large).
    WebSocket(Box<Socket<S>>),
}

/// Reads one request from a browser's connection and answers it: the page,
/// the WebSocket handshake, or an error status.
pub async fn accept<S: AsyncRead + AsyncWrite + Unpin>(
    stream: S,
) -> Result<Accepted<S>, HttpError> {
    let mut stream = BufReader::new(stream);
    let head = tokio::time::timeout(REQUEST_TIMEOUT, read_head(&mut stream))
        .await
        .map_err(|_| HttpError::Timeout(REQUEST_TIMEOUT))??;
    let response = match Request::parse(&head) {
        Ok(request) => route(&request),
        Err(reason) => Route::Refuse {
            status: "400 Bad Request",
            reason,
        },
    };
    match response {
        Route::Page => {
            respond(&mut stream, "200 OK", "text/html; charset=utf-8", PAGE).await?;
            Ok(Accepted::Served)
        }
        Route::WebSocket { accept_key } => {
            let answer = format!(
                "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\n\
                 Connection: Upgrade\r\nSec-WebSocket-Accept: {accept_key}\r\n\r\n"
            );
            stream.write_all(answer.as_bytes()).await?;
            stream.flush().await?;
            let limits = WebSocketConfig::default()
                .max_message_size(Some(MAX_WS_MESSAGE))
                .max_frame_size(Some(MAX_WS_MESSAGE));
            Ok(Accepted::WebSocket(Box::new(
                WebSocketStream::from_raw_socket(stream, Role::Server, Some(limits)).await,
            )))
        }
        Route::Refuse { status, reason } => {
            tracing::debug!(status, %reason, "refused a browser request");
            let body = format!("{reason}\n");
            respond(&mut stream, status, "text/plain; charset=utf-8", &body).await?;
            Ok(Accepted::Served)
        }
    }
}

/// Answers a connection beyond the viewer's limit of `max` with `503
/// Service Unavailable`, after reading its request: closing with the request
/// unread would reset the connection, and the reset may overtake the answer.
pub async fn turn_away(stream: TcpStream, max: usize) -> Result<(), HttpError> {
    let mut stream = BufReader::new(stream);
    tokio::time::timeout(REQUEST_TIMEOUT, read_head(&mut stream))
        .await
        .map_err(|_| HttpError::Timeout(REQUEST_TIMEOUT))??;
    let body = format!("too many connections: the viewer serves at most {max} at once\n");
    respond(
        &mut stream,
        "503 Service Unavailable",
        "text/plain; charset=utf-8",
        &body,
    )
    .await
}

/// The request head, up to and including the empty line.
async fn read_head<S: AsyncRead + Unpin>(stream: &mut BufReader<S>) -> Result<Vec<u8>, HttpError> {
    let mut limited = (&mut *stream).take(MAX_HEAD);
    let mut head = Vec::new();
    loop {
        let read = limited.read_until(b'\n', &mut head).await?;
        if head.ends_with(b"\r\n\r\n") || head.ends_with(b"\n\n") || head == b"\r\n" {
            return Ok(head);
        }
        if read == 0 {
            return Err(HttpError::Malformed(if head.len() as u64 >= MAX_HEAD {
                format!("request head longer than {MAX_HEAD} bytes")
            } else {
                "the connection ended inside the request head".into()
            }));
        }
    }
}

async fn respond<S: AsyncRead + AsyncWrite + Unpin>(
    stream: &mut BufReader<S>,
    status: &str,
    content_type: &str,
    body: &str,
) -> Result<(), HttpError> {
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    );
    stream.write_all(head.as_bytes()).await?;
    stream.write_all(body.as_bytes()).await?;
    stream.shutdown().await?;
    Ok(())
}

/// The parts of a request the viewer looks at.
#[derive(Debug)]
struct Request {
    method: String,
    path: String,
    headers: Vec<(String, String)>,
}

impl Request {
    fn parse(head: &[u8]) -> Result<Self, String> {
        let mut headers = [httparse::EMPTY_HEADER; 64];
        let mut request = httparse::Request::new(&mut headers);
        match request.parse(head) {
            Ok(httparse::Status::Complete(_)) => {}
            Ok(httparse::Status::Partial) => return Err("incomplete request head".into()),
            Err(err) => return Err(err.to_string()),
        }
        Ok(Self {
            method: request.method.unwrap_or_default().to_owned(),
            path: request.path.unwrap_or_default().to_owned(),
            headers: request
                .headers
                .iter()
                .map(|h| {
                    (
                        h.name.to_ascii_lowercase(),
                        String::from_utf8_lossy(h.value).trim().to_owned(),
                    )
                })
                .collect(),
        })
    }

    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// Whether a comma-separated header lists `token` (case-insensitive).
    fn lists(&self, name: &str, token: &str) -> bool {
        self.header(name).is_some_and(|value| {
            value
                .split(',')
                .any(|item| item.trim().eq_ignore_ascii_case(token))
        })
    }
}

/// The answer to a request.
#[derive(Debug, PartialEq)]
enum Route {
    Page,
    WebSocket {
        accept_key: String,
    },
    Refuse {
        status: &'static str,
        reason: String,
    },
}

fn refuse(status: &'static str, reason: impl Into<String>) -> Route {
    Route::Refuse {
        status,
        reason: reason.into(),
    }
}

fn route(request: &Request) -> Route {
    // The WebSocket can pause and reset the world, so only pages the viewer
    // served may open it: a page from another site gets a different Origin,
    // and one that reaches us through a rebound DNS name (DNS rebinding)
    // gets a Host that is not an address.
    let Some(host) = request.header("host") else {
        return refuse("400 Bad Request", "no Host header");
    };
    if !is_address(host) {
        return refuse(
            "403 Forbidden",
            format!("Host '{host}' is not an IP address or localhost: open the address the viewer printed"),
        );
    }
    if request.method != "GET" {
        return refuse("405 Method Not Allowed", "only GET is served");
    }
    let path = request.path.split('?').next().unwrap_or_default();
    match path {
        "/" | "/index.html" => Route::Page,
        "/ws" => {
            if let Some(origin) = request.header("origin") {
                if origin != format!("http://{host}") {
                    return refuse(
                        "403 Forbidden",
                        format!("WebSocket from origin '{origin}' refused: only the viewer's own page may connect"),
                    );
                }
            }
            let upgrade =
                request.lists("upgrade", "websocket") && request.lists("connection", "upgrade");
            match (upgrade, request.header("sec-websocket-key")) {
                (true, Some(key)) if request.header("sec-websocket-version") == Some("13") => {
                    Route::WebSocket {
                        accept_key: derive_accept_key(key.as_bytes()),
                    }
                }
                _ => refuse(
                    "426 Upgrade Required",
                    "/ws is a WebSocket (version 13) endpoint",
                ),
            }
        }
        _ => refuse(
            "404 Not Found",
            format!("nothing at {path}; the viewer is at /"),
        ),
    }
}

/// `HOST[:PORT]` where HOST is an IP address (IPv6 in brackets) or localhost.
fn is_address(host: &str) -> bool {
    let name = match host.strip_prefix('[') {
        Some(rest) => rest.split(']').next().unwrap_or_default(),
        None => host.rsplit_once(':').map_or(host, |(name, _)| name),
    };
    name.parse::<IpAddr>().is_ok() || name.eq_ignore_ascii_case("localhost")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(text: &str) -> Request {
        Request::parse(text.replace('\n', "\r\n").as_bytes()).unwrap()
    }

    const UPGRADE: &str = "GET /ws HTTP/1.1\nHost: 127.0.0.1:8000\nUpgrade: websocket\n\
         Connection: keep-alive, Upgrade\nSec-WebSocket-Version: 13\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\n";

    #[test]
    fn the_page_is_served_at_the_root() {
        let r = request("GET /?x=1 HTTP/1.1\nHost: localhost:8000\n\n");
        assert_eq!(route(&r), Route::Page);
        assert!(
            PAGE.contains("<canvas"),
            "the embedded page draws on a canvas"
        );
    }

    #[test]
    fn the_websocket_handshake_answers_with_the_rfc_key() {
        let r = request(&format!("{UPGRADE}Origin: http://127.0.0.1:8000\n\n"));
        // RFC 6455 §1.3's example.
        assert_eq!(
            route(&r),
            Route::WebSocket {
                accept_key: "s3pPLMBiTxaQ9kYGzzhZRbK+xOo=".into()
            }
        );
        // Non-browser clients send no Origin.
        assert!(matches!(
            route(&request(&format!("{UPGRADE}\n"))),
            Route::WebSocket { .. }
        ));
    }

    #[test]
    fn other_sites_and_rebound_names_are_refused() {
        let status = |text: &str| match route(&request(text)) {
            Route::Refuse { status, .. } => status,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            status(&format!("{UPGRADE}Origin: http://evil.example\n\n")),
            "403 Forbidden"
        );
        assert_eq!(
            status("GET / HTTP/1.1\nHost: evil.example:8000\n\n"),
            "403 Forbidden"
        );
        assert_eq!(status("GET / HTTP/1.1\n\n"), "400 Bad Request");
        assert_eq!(
            status("POST / HTTP/1.1\nHost: [::1]:8000\n\n"),
            "405 Method Not Allowed"
        );
        assert_eq!(
            status("GET /x HTTP/1.1\nHost: 127.0.0.1\n\n"),
            "404 Not Found"
        );
        assert_eq!(
            status("GET /ws HTTP/1.1\nHost: 127.0.0.1\n\n"),
            "426 Upgrade Required"
        );
    }

    #[test]
    fn hosts_are_addresses_or_localhost() {
        assert!(is_address("127.0.0.1:11346"));
        assert!(is_address("[::1]:11346"));
        assert!(is_address("LOCALHOST"));
        assert!(is_address("192.168.1.5"));
        assert!(!is_address("example.com:11346"));
        assert!(!is_address("127.0.0.1.nip.io"));
    }
}
