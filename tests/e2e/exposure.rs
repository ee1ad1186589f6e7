//! Every listening socket's limits over real sockets (`docs/reliability.md`
//! §5): where it binds by default, how many connections it serves, the
//! largest frame it reads, and what it does with a browser's request.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::Command;
use std::time::Duration;

use futures::{SinkExt, StreamExt};
use prost::Message as _;
use pushlearn::client::{ClientError, SimClient};
use pushlearn::recording::RecordingWriter;
use pushlearn::wire::pb::learner::{reply::Answer, request::Call, Reply, Request, Start};
use pushlearn::wire::pb::{self, server_message};
use pushlearn::wire::{decode_stream, encode_frame, MAX_FRAME_SIZE};
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::Message;

use crate::daemon::{binary, Daemon};
use crate::experiment::TempDir;
use crate::process::{Background, CHILD_LIMIT};

/// What a browser sends first when a page fetches an address: the request
/// line and headers. To a length-prefixed protocol its first four bytes,
/// `GET `, are a length of 1 195 725 856 bytes.
const BROWSER_REQUEST: &[u8] =
    b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nOrigin: http://evil.example\r\n\r\n";

fn address_of(line: &str, prefix: &str) -> SocketAddr {
    line.trim_end()
        .strip_prefix(prefix)
        .and_then(|a| {
            a.trim_start_matches("http://")
                .trim_end_matches('/')
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no address in {line:?}"))
}

fn connect(addr: SocketAddr) -> TcpStream {
    let stream = TcpStream::connect(addr).expect("connects");
    stream.set_read_timeout(Some(CHILD_LIMIT)).expect("timeout");
    stream
}

/// Everything the peer sends until it closes.
fn read_to_close(stream: &mut TcpStream) -> Vec<u8> {
    let mut bytes = Vec::new();
    match stream.read_to_end(&mut bytes) {
        Ok(_) => bytes,
        // Closed with our bytes unread: a reset after what it sent.
        Err(err) if err.kind() == std::io::ErrorKind::ConnectionReset => bytes,
        Err(err) => panic!("reading until the close: {err}"),
    }
}

// ---------------------------------------------------------------- the viewer

struct Viewer {
    addr: SocketAddr,
    _process: Background,
}

fn viewer(world: SocketAddr, extra: &[&str]) -> Viewer {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .args(["view", "--port", "0", "--sim"])
        .arg(world.to_string())
        .args(extra);
    let (process, line) = Background::start(command, "pushlearn view");
    Viewer {
        addr: address_of(&line, "viewer on "),
        _process: process,
    }
}

fn http_get(addr: SocketAddr, path: &str, headers: &str) -> String {
    let mut stream = connect(addr);
    let request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\n{headers}\r\n");
    stream.write_all(request.as_bytes()).expect("request");
    String::from_utf8_lossy(&read_to_close(&mut stream)).into_owned()
}

const UPGRADE: &str = "Upgrade: websocket\r\nConnection: Upgrade\r\n\
    Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n";

#[test]
fn the_viewer_binds_loopback_and_refuses_other_origins_with_403() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let viewer = viewer(world.addr, &[]);
    assert!(viewer.addr.ip().is_loopback(), "{}", viewer.addr);
    let other = http_get(
        viewer.addr,
        "/ws",
        &format!("{UPGRADE}Origin: http://evil.example\r\n"),
    );
    assert!(other.starts_with("HTTP/1.1 403 Forbidden"), "{other}");
    assert!(
        other.contains("origin 'http://evil.example' refused"),
        "{other}"
    );
    // The same port under another name (DNS rebinding) is refused too.
    let mut stream = connect(viewer.addr);
    stream
        .write_all(b"GET / HTTP/1.1\r\nHost: rebound.example\r\n\r\n")
        .expect("request");
    let rebound = String::from_utf8_lossy(&read_to_close(&mut stream)).into_owned();
    assert!(rebound.starts_with("HTTP/1.1 403 Forbidden"), "{rebound}");
    // The page's own origin is let in (and the WebSocket stays open: only
    // the response's head is read).
    let mut own = connect(viewer.addr);
    let request = format!(
        "GET /ws HTTP/1.1\r\nHost: {0}\r\n{UPGRADE}Origin: http://{0}\r\n\r\n",
        viewer.addr
    );
    own.write_all(request.as_bytes()).expect("request");
    let mut head = Vec::new();
    let mut byte = [0_u8; 1];
    while !head.ends_with(b"\r\n\r\n") {
        own.read_exact(&mut byte).expect("the response's head");
        head.push(byte[0]);
    }
    let head = String::from_utf8_lossy(&head);
    assert!(
        head.starts_with("HTTP/1.1 101 Switching Protocols"),
        "{head}"
    );
}

#[test]
fn the_viewer_drops_a_request_head_above_16_kib() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let viewer = viewer(world.addr, &[]);
    let mut stream = connect(viewer.addr);
    let head = format!(
        "GET / HTTP/1.1\r\nHost: {}\r\nX-Filler: {}\r\n\r\n",
        viewer.addr,
        "x".repeat(16 * 1024)
    );
    // The viewer may close before it has taken all of it.
    let _ = stream.write_all(head.as_bytes());
    assert!(
        read_to_close(&mut stream).is_empty(),
        "answered an oversized head"
    );
    // At the limit's other side a request is answered.
    let page = http_get(
        viewer.addr,
        "/",
        &format!("X-Filler: {}\r\n", "x".repeat(1024)),
    );
    assert!(page.starts_with("HTTP/1.1 200 OK"), "{page}");
}

#[tokio::test]
async fn the_viewer_serves_at_most_max_connections_and_answers_503_beyond() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let viewer = viewer(world.addr, &["--max-connections", "2"]);
    let url = format!("ws://{}/ws", viewer.addr);
    let (mut first, _) = tokio_tungstenite::connect_async(&url)
        .await
        .expect("first tab");
    let (_second, _) = tokio_tungstenite::connect_async(&url)
        .await
        .expect("second tab");
    // Both tabs have their scene: both places are taken.
    for tab in [&mut first] {
        let hello = tab.next().await.expect("a message").expect("readable");
        assert!(hello
            .to_text()
            .expect("text")
            .contains("\"type\":\"hello\""));
    }
    let addr = viewer.addr;
    let busy = tokio::task::spawn_blocking(move || http_get(addr, "/", ""))
        .await
        .expect("joins");
    assert!(
        busy.starts_with("HTTP/1.1 503 Service Unavailable"),
        "{busy}"
    );
    assert!(
        busy.contains("too many connections: the viewer serves at most 2 at once"),
        "{busy}"
    );
    // A tab that leaves gives its place back (once the viewer has seen it go).
    first.close(None).await.expect("closes");
    while first.next().await.is_some() {}
    let page = tokio::task::spawn_blocking(move || loop {
        let answer = http_get(addr, "/", "");
        if !answer.starts_with("HTTP/1.1 503") {
            return answer;
        }
        std::thread::sleep(Duration::from_millis(10));
    })
    .await
    .expect("joins");
    assert!(page.starts_with("HTTP/1.1 200 OK"), "{page}");
}

#[tokio::test]
async fn the_viewer_closes_a_websocket_that_sends_more_than_4_kib() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let viewer = viewer(world.addr, &[]);
    let url = format!("ws://{}/ws", viewer.addr);
    let (mut tab, _) = tokio_tungstenite::connect_async(&url).await.expect("a tab");
    // A control at the limit is read (and refused as no control).
    let fits = format!("{{\"type\":\"{}\"}}", "x".repeat(4096 - 11));
    assert_eq!(fits.len(), 4096);
    tab.send(Message::Text(fits.into())).await.expect("sent");
    let huge = "x".repeat(4097);
    tab.send(Message::Text(huge.into())).await.expect("sent");
    let mut errors = 0;
    let close = loop {
        match tab.next().await {
            Some(Ok(Message::Close(frame))) => break frame,
            Some(Ok(Message::Text(text))) => {
                errors += usize::from(text.contains("\"type\":\"error\""));
            }
            Some(Ok(_)) => {}
            other => panic!("expected a close frame, got {other:?}"),
        }
    };
    assert_eq!(errors, 1, "the message at the limit was read and answered");
    let close = close.expect("a close frame with a code");
    assert_eq!(close.code, CloseCode::Size, "{close:?}");
}

// ------------------------------------------------ the learner protocol daemon

fn learner_daemon(extra: &[&str]) -> (Background, SocketAddr) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .args(["serve-learner", "--model", "gate"])
        .args(extra);
    let (process, line) = Background::start(command, "pushlearn serve-learner");
    let addr = address_of(&line, "listening on ");
    (process, addr)
}

fn start_frame() -> Vec<u8> {
    let start = Request {
        seq: 1,
        call: Some(Call::Start(Start {
            protocol_version: 1,
            task: "push-task".into(),
            publish_rate_hz: 100,
        })),
    };
    encode_frame(&start).expect("encodes").to_vec()
}

/// Sends Start on `stream` and reads the one reply.
fn say_start(stream: &mut TcpStream) -> Reply {
    stream.write_all(&start_frame()).expect("start");
    let mut prefix = [0_u8; 4];
    stream.read_exact(&mut prefix).expect("a reply");
    let mut body = vec![0_u8; u32::from_be_bytes(prefix) as usize];
    stream.read_exact(&mut body).expect("the reply's body");
    Reply::decode(body.as_slice()).expect("a Reply")
}

#[test]
fn the_learner_daemon_binds_loopback_for_a_bare_port_and_caps_connections() {
    let (_daemon, addr) = learner_daemon(&["--listen", "0", "--max-connections", "1"]);
    assert!(addr.ip().is_loopback(), "{addr}");
    let mut first = connect(addr);
    assert!(matches!(
        say_start(&mut first).answer,
        Some(Answer::Hello(_))
    ));
    let mut second = connect(addr);
    match say_start(&mut second).answer {
        Some(Answer::Error(error)) => assert_eq!(
            error.message,
            "too many connections: this learner daemon serves at most 1 at once"
        ),
        other => panic!("expected an Error, got {other:?}"),
    }
    assert!(read_to_close(&mut second).is_empty());
    // The first driver leaves; its place is free once the daemon saw it go.
    drop(first);
    loop {
        let mut again = connect(addr);
        if let Some(Answer::Hello(_)) = say_start(&mut again).answer {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn the_learner_daemon_closes_a_connection_announcing_a_frame_above_16_mib() {
    let (_daemon, addr) = learner_daemon(&["--listen", "127.0.0.1:0"]);
    let mut hostile = connect(addr);
    let too_long = u32::try_from(MAX_FRAME_SIZE + 1).expect("fits");
    hostile.write_all(&too_long.to_be_bytes()).expect("prefix");
    assert!(read_to_close(&mut hostile).is_empty());
    // A browser's request is such a prefix.
    let mut browser = connect(addr);
    browser.write_all(BROWSER_REQUEST).expect("request");
    assert!(read_to_close(&mut browser).is_empty());
    // Everyone else is served.
    let mut driver = connect(addr);
    assert!(matches!(
        say_start(&mut driver).answer,
        Some(Answer::Hello(_))
    ));
}

/// Sends `requests` and reads the replies until the daemon closes (it
/// answers a broken rule with an Error and closes): the last one.
fn reply_to(addr: SocketAddr, requests: &[Request]) -> Reply {
    let mut stream = connect(addr);
    for request in requests {
        stream
            .write_all(&encode_frame(request).expect("encodes"))
            .expect("request");
    }
    let bytes = read_to_close(&mut stream);
    let (mut replies, error) = decode_stream::<Reply>(&bytes);
    assert!(error.is_none(), "{error:?}");
    replies.pop().expect("at least one reply")
}

fn error_text(reply: Reply) -> String {
    match reply.answer {
        Some(Answer::Error(error)) => error.message,
        other => panic!("expected an Error, got {other:?}"),
    }
}

fn request(seq: u64, call: Call) -> Request {
    Request {
        seq,
        call: Some(call),
    }
}

fn start(protocol_version: i32, task: &str, publish_rate_hz: u32) -> Call {
    Call::Start(Start {
        protocol_version,
        task: task.into(),
        publish_rate_hz,
    })
}

/// Issue 49, item 11: a first request that is not a Start was closed without
/// the promised Error; Start with protocol version 99, a publish rate of 0, 7
/// or 2^32 - 1, or a 1000-character task was answered with Hello; a
/// decreasing seq and a SetTarget without x were accepted.
#[test]
fn the_learner_daemon_answers_every_broken_start_rule_with_an_error() {
    use pushlearn::wire::pb::learner::{Bye, SetTarget};
    let (_daemon, addr) = learner_daemon(&["--listen", "0"]);
    let first = error_text(reply_to(addr, &[request(1, Call::Bye(Bye {}))]));
    assert!(
        first.contains("the first request must be a start"),
        "{first}"
    );
    let cases: [(Call, &str); 6] = [
        (start(99, "push-task", 100), "protocol version 99"),
        (start(1, "push-task", 0), "publish rate 0 Hz"),
        (start(1, "push-task", 7), "publish rate 7 Hz"),
        (
            start(1, "push-task", u32::MAX),
            "publish rate 4294967295 Hz",
        ),
        (start(1, &"x".repeat(1000), 100), "unknown task"),
        (start(1, "push-tusk", 100), "unknown task 'push-tusk'"),
    ];
    for (call, expected) in cases {
        let text = error_text(reply_to(addr, &[request(1, call)]));
        assert!(text.contains(expected), "{text}");
        assert!(text.len() < 300, "the task is not echoed whole: {text}");
    }
    let good = || request(1, start(1, "push-task", 100));
    let target = |x: Option<f64>| {
        Call::SetTarget(SetTarget {
            clear: false,
            id: 15,
            x,
            y: Some(0.5),
            theta: Some(0.0),
        })
    };
    let text = error_text(reply_to(addr, &[good(), request(2, target(None))]));
    assert!(text.contains("a target without x"), "{text}");
    let text = error_text(reply_to(addr, &[good(), request(2, target(Some(1e300)))]));
    assert!(
        text.contains("not a finite pose within any world"),
        "{text}"
    );
    let text = error_text(reply_to(
        addr,
        &[
            good(),
            request(3, target(Some(0.5))),
            request(2, target(Some(0.5))),
        ],
    ));
    assert!(text.contains("seq 2 after seq 3"), "{text}");
}

/// The daemon's threads, from /proc.
fn threads(pid: u32) -> usize {
    std::fs::read_dir(format!("/proc/{pid}/task"))
        .expect("the daemon's /proc")
        .count()
}

/// Issue 49, items 2 and 3: 64 silent connections locked every other
/// driver out of `serve-learner` (no idle timeout), and every connection
/// beyond the cap got an OS thread of its own (800 connections: 801
/// threads). Now a silent connection is closed after --idle-timeout, and
/// the refused ones cost no thread.
#[test]
fn silent_drivers_are_closed_after_the_idle_timeout_and_refusals_cost_no_thread() {
    let (daemon, addr) = learner_daemon(&[
        "--listen",
        "0",
        "--max-connections",
        "2",
        "--idle-timeout",
        "1",
    ]);
    let base = threads(daemon.pid());
    let mut silent: Vec<TcpStream> = (0..2).map(|_| connect(addr)).collect();
    // Beyond the cap, silent too: each waits for its Start in a task.
    let refused: Vec<TcpStream> = (0..100).map(|_| connect(addr)).collect();
    std::thread::sleep(Duration::from_millis(300));
    let during = threads(daemon.pid());
    assert!(
        during <= base + 2 + 2,
        "{during} threads with 2 served and 100 refused connections (from {base})"
    );
    drop(refused);
    // The silent ones are closed once idle (bounded wait: CHILD_LIMIT)…
    for stream in &mut silent {
        assert!(read_to_close(stream).is_empty());
    }
    // …and a driver is served again.
    let mut driver = connect(addr);
    assert!(matches!(
        say_start(&mut driver).answer,
        Some(Answer::Hello(_))
    ));
    // A driver trickling a frame a byte at a time is idle too: the limit is
    // on whole requests.
    let mut trickle = connect(addr);
    let frame = start_frame();
    let mut closed = false;
    // 100 ms a byte: a whole request would take 2.2 s, over the 1 s limit.
    for byte in &frame[..frame.len() - 1] {
        if trickle.write_all(&[*byte]).is_err() {
            closed = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(closed || read_to_close(&mut trickle).is_empty());
}

// ----------------------------------------- the world daemon and its replay

/// The world's answer to a browser's request: an Error about the frame's
/// length, then the close. (The daemon's other limits have their tests in
/// `sim-plugin/tests/sim/daemon/`.)
#[test]
fn the_world_refuses_a_browser_request_as_an_oversized_frame() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    assert!(world.addr.ip().is_loopback(), "{}", world.addr);
    let mut browser = connect(world.addr);
    browser.write_all(BROWSER_REQUEST).expect("request");
    let (messages, _) = decode_stream::<pb::ServerMessage>(&read_to_close(&mut browser));
    let last = messages.last().and_then(|m| m.payload.clone());
    match last {
        Some(server_message::Payload::Error(error)) => {
            assert!(error.message.contains("1195725856"), "{}", error.message);
        }
        other => panic!("expected an Error last, got {other:?}"),
    }
}

#[tokio::test]
async fn a_replay_serves_at_most_max_clients() {
    let dir = TempDir::new("replay-cap");
    let world = Daemon::start(&["--mode", "lockstep"]);
    let hello = SimClient::connect(world.addr)
        .await
        .expect("the world")
        .hello()
        .clone();
    let file = dir.file("empty.plrec");
    let frame = pb::ServerMessage::from(hello).encode_to_vec();
    let out = std::fs::File::create(&file).expect("file");
    RecordingWriter::new(out, false, &frame)
        .and_then(RecordingWriter::finish)
        .expect("a recording with its Hello only");
    let mut command = Command::new(binary());
    command.args([
        "replay",
        &file,
        "--listen",
        "127.0.0.1:0",
        "--max-clients",
        "1",
    ]);
    let (_replay, line) = Background::start(command, "pushlearn-sim replay");
    let addr = address_of(&line, "listening on ");
    let first = SimClient::connect(addr).await.expect("the first client");
    match SimClient::connect(addr).await {
        Err(ClientError::World { kind, message }) => {
            assert_eq!(kind, pb::error::Kind::TooManyClients, "{message}");
            assert!(message.contains("serves at most 1 at once"), "{message}");
        }
        other => panic!("expected to be turned away, got {other:?}"),
    }
    // Its place free again, a browser's request (an oversized frame) gets
    // the Hello and the close, nothing else.
    first.close().await.expect("closes");
    let bytes = tokio::task::spawn_blocking(move || loop {
        let mut browser = connect(addr);
        let _ = browser.write_all(BROWSER_REQUEST);
        let bytes = read_to_close(&mut browser);
        let (messages, _) = decode_stream::<pb::ServerMessage>(&bytes);
        if !matches!(
            messages.first().and_then(|m| m.payload.clone()),
            Some(server_message::Payload::Error(_))
        ) {
            return messages;
        }
        std::thread::sleep(Duration::from_millis(10));
    })
    .await
    .expect("joins");
    assert_eq!(bytes.len(), 1, "{bytes:?}");
    assert!(matches!(
        bytes[0].payload,
        Some(server_message::Payload::Hello(_))
    ));
}

/// `ctl record --listen PORT`: on the loopback address, for one client;
/// the next is refused by the kernel (the proxy listens no more).
#[test]
fn the_recording_proxy_binds_loopback_for_a_bare_port_and_serves_one_client() {
    let dir = TempDir::new("record-cap");
    let world = Daemon::start(&["--mode", "lockstep"]);
    let file = dir.file("one.plrec");
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args([
        "ctl",
        "--sim",
        &world.addr.to_string(),
        "record",
        &file,
        "--listen",
        "0",
    ]);
    let (_proxy, line) = Background::start(command, "ctl record");
    let addr = address_of(&line, "listening on ");
    assert!(addr.ip().is_loopback(), "{addr}");
    let mut first = connect(addr);
    let mut prefix = [0_u8; 4];
    first
        .read_exact(&mut prefix)
        .expect("the world's Hello through the proxy");
    let refused = TcpStream::connect(addr).map(|_| ()).unwrap_err();
    assert_eq!(
        refused.kind(),
        std::io::ErrorKind::ConnectionRefused,
        "{refused}"
    );
}
