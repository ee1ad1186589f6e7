//! A browser connection's bytes as the viewer reads them, without a socket:
//! the request head ([`super::http::accept`]: its limits, parsing and
//! routing), and after a WebSocket handshake the frames a tab sends, each
//! message decided on as a live tab's is ([`super::from_tab`]). The code
//! under fuzzing (`fuzz/fuzz_targets/viewer.rs`) and under the test that
//! replays the fuzzer's corpus (`docs/reliability.md`).

use futures::StreamExt;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

use super::http::{self, Accepted, MAX_WS_MESSAGE};
use super::{from_tab, FromTab};

/// What became of one connection's bytes.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Browser {
    /// The status line answered, if one was (`HTTP/1.1 200 OK`).
    pub status: Option<String>,
    /// Controls a tab sent that would be forwarded to the world.
    pub controls: usize,
    /// Messages answered with an error.
    pub answered: usize,
    /// Whether the viewer closed the WebSocket for a message too large.
    pub closed_for_size: bool,
}

/// The statuses the viewer answers with.
const STATUSES: [&str; 7] = [
    "101 Switching Protocols",
    "200 OK",
    "400 Bad Request",
    "403 Forbidden",
    "404 Not Found",
    "405 Method Not Allowed",
    "426 Upgrade Required",
];

/// Feeds `bytes` as everything a browser sent before closing its side, and
/// checks what the viewer answered: nothing (a head too long or cut off),
/// or one response with a status the viewer uses and, for any but the
/// WebSocket's, exactly `Content-Length` bytes of body; a WebSocket delivers
/// no message above [`MAX_WS_MESSAGE`].
///
/// # Errors
/// The property that was broken (a panic is the fuzzer's to catch).
pub fn serve_untrusted_bytes(bytes: &[u8]) -> Result<Browser, String> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .build()
        .map_err(|err| format!("no runtime: {err}"))?;
    runtime.block_on(async {
        let (mut browser, viewer) = tokio::io::duplex(64 * 1024);
        let browser_side = async {
            // The viewer may answer before it has read everything (a
            // refusal): the rest then cannot be written, as on a socket.
            let _ = browser.write_all(bytes).await;
            let _ = browser.shutdown().await;
            let mut answer = Vec::new();
            let _ = browser.read_to_end(&mut answer).await;
            answer
        };
        let viewer_side = async {
            let mut seen = Browser::default();
            let Ok(Accepted::WebSocket(mut socket)) = http::accept(viewer).await else {
                return Ok(seen);
            };
            loop {
                let incoming = socket.next().await;
                if let Some(Ok(message)) = &incoming {
                    if message.len() > MAX_WS_MESSAGE {
                        return Err(format!(
                            "a message of {} bytes (above {MAX_WS_MESSAGE}) reached the tab's handling",
                            message.len()
                        ));
                    }
                }
                match from_tab(incoming) {
                    FromTab::Control(_) => seen.controls += 1,
                    FromTab::Answer(_) => seen.answered += 1,
                    FromTab::Close(_) => {
                        seen.closed_for_size = true;
                        return Ok(seen);
                    }
                    FromTab::Gone => return Ok(seen),
                    FromTab::Nothing => {}
                }
            }
        };
        let (answer, seen) = tokio::join!(browser_side, viewer_side);
        let mut seen = seen?;
        seen.status = check_answer(&answer)?;
        Ok(seen)
    })
}

/// The status of `answer` (`None` for no answer), if it is a response the
/// viewer may give.
fn check_answer(answer: &[u8]) -> Result<Option<String>, String> {
    if answer.is_empty() {
        return Ok(None);
    }
    let mut headers = [httparse::EMPTY_HEADER; 16];
    let mut response = httparse::Response::new(&mut headers);
    let head = match response.parse(answer) {
        Ok(httparse::Status::Complete(head)) => head,
        other => return Err(format!("not a whole response ({other:?}): {answer:?}")),
    };
    let status = format!(
        "{} {}",
        response.code.unwrap_or_default(),
        response.reason.unwrap_or_default()
    );
    if !STATUSES.contains(&status.as_str()) {
        return Err(format!("an unexpected status {status}"));
    }
    if response.code == Some(101) {
        return Ok(Some(status));
    }
    let length = response
        .headers
        .iter()
        .find(|h| h.name.eq_ignore_ascii_case("content-length"))
        .and_then(|h| std::str::from_utf8(h.value).ok()?.parse::<usize>().ok());
    if length != Some(answer.len() - head) {
        return Err(format!(
            "{status}: Content-Length {length:?}, but {} bytes of body",
            answer.len() - head
        ));
    }
    Ok(Some(status))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    const UPGRADE: &str = "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:11346\r\n\
        Upgrade: websocket\r\nConnection: Upgrade\r\n\
        Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";

    /// A masked text frame, as a browser sends it.
    fn text_frame(text: &str) -> Vec<u8> {
        let mask = [1_u8, 2, 3, 4];
        let mut frame = vec![0x81];
        match text.len() {
            n if n < 126 => frame.push(0x80 | n as u8),
            n => {
                frame.push(0x80 | 126);
                frame.extend(u16::try_from(n).unwrap().to_be_bytes());
            }
        }
        frame.extend(mask);
        frame.extend(
            text.bytes()
                .enumerate()
                .map(|(i, b)| b ^ mask[i % mask.len()]),
        );
        frame
    }

    #[test]
    fn the_page_and_refusals_are_whole_responses() {
        let page = serve_untrusted_bytes(b"GET / HTTP/1.1\r\nHost: localhost\r\n\r\n").unwrap();
        assert_eq!(page.status.as_deref(), Some("200 OK"));
        let other = serve_untrusted_bytes(b"GET / HTTP/1.1\r\nHost: evil.example\r\n\r\n").unwrap();
        assert_eq!(other.status.as_deref(), Some("403 Forbidden"));
        let junk = serve_untrusted_bytes(b"\x00\x01junk\r\n\r\n").unwrap();
        assert_eq!(junk.status.as_deref(), Some("400 Bad Request"));
        let cut = serve_untrusted_bytes(b"GET / HTTP/1.1\r\nHost: loc").unwrap();
        assert_eq!(cut, Browser::default());
    }

    #[test]
    fn a_tab_s_controls_are_read_and_a_message_above_the_cap_closes_it() {
        let mut bytes = UPGRADE.as_bytes().to_vec();
        bytes.extend(text_frame(r#"{"control":"pause"}"#));
        bytes.extend(text_frame("not json"));
        bytes.extend(text_frame(&"x".repeat(MAX_WS_MESSAGE + 1)));
        bytes.extend(text_frame(r#"{"control":"reset"}"#));
        let seen = serve_untrusted_bytes(&bytes).unwrap();
        assert_eq!(
            seen,
            Browser {
                status: Some("101 Switching Protocols".into()),
                controls: 1,
                answered: 1,
                closed_for_size: true,
            }
        );
    }

    /// The fuzz target's kept inputs, through its property; the folder
    /// must not be empty.
    #[test]
    fn the_fuzzers_kept_browser_inputs_keep_their_property() {
        let kept = sim_plugin::untrusted::kept_fuzz_inputs("viewer");
        assert!(kept.len() >= 5, "{} kept inputs", kept.len());
        for (path, bytes) in kept {
            let seen = serve_untrusted_bytes(&bytes);
            assert!(seen.is_ok(), "{}: {seen:?}", path.display());
        }
    }

    proptest! {
        #[test]
        fn any_bytes_from_a_browser_get_a_whole_answer_or_none(
            bytes in proptest::collection::vec(any::<u8>(), 0..512),
        ) {
            let seen = serve_untrusted_bytes(&bytes);
            prop_assert!(seen.is_ok(), "{seen:?}");
        }

        #[test]
        fn any_frames_after_a_handshake_are_read_safely(
            tail in proptest::collection::vec(any::<u8>(), 0..512),
        ) {
            let mut bytes = UPGRADE.as_bytes().to_vec();
            bytes.extend(tail);
            let seen = serve_untrusted_bytes(&bytes);
            prop_assert!(seen.is_ok(), "{seen:?}");
            let status = seen.ok().and_then(|s| s.status);
            prop_assert_eq!(status.as_deref(), Some("101 Switching Protocols"));
        }
    }
}
