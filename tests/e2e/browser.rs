//! Headless Chromium driven over the Chrome DevTools Protocol: one
//! WebSocket to the browser, no WebDriver in between.
//!
//! The browser is Debian's `chromium` (`scripts/ensure-deps.sh --test`
//! installs it), or the program named by `PUSHLEARN_CHROMIUM`. A missing
//! browser fails the test: the test command installs it.

use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use futures::{SinkExt, StreamExt};
use pushlearn_cli::process::kill_group;
use serde_json::{json, Value};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

use crate::experiment::TempDir;

/// Limit for the browser to start and for each DevTools command.
const LIMIT: Duration = Duration::from_secs(30);

/// How often a condition is re-checked in [`Page::wait_for`].
const POLL: Duration = Duration::from_millis(50);

/// A headless Chromium with one page; the browser (its whole process group)
/// is killed when dropped, also when a test fails.
pub struct Browser {
    child: Child,
    socket: WebSocketStream<MaybeTlsStream<TcpStream>>,
    session: String,
    next_id: u64,
    _profile: TempDir,
}

fn program() -> String {
    std::env::var("PUSHLEARN_CHROMIUM").unwrap_or_else(|_| "chromium".into())
}

impl Browser {
    /// Starts the browser with a `width` × `height` window and opens a blank page.
    pub async fn start(width: u32, height: u32) -> Browser {
        // One profile per browser: Chromium locks its profile directory, and
        // tests in this process may run browsers side by side.
        static STARTED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = STARTED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let profile = TempDir::new(&format!("chromium-profile-{n}"));
        let program = program();
        let mut command = Command::new(&program);
        command
            .args([
                "--headless=new",
                // Containers run tests as root, where Chromium's sandbox cannot start.
                "--no-sandbox",
                "--disable-gpu",
                "--disable-dev-shm-usage",
                "--no-first-run",
                "--hide-scrollbars",
                "--remote-debugging-port=0",
                &format!("--window-size={width},{height}"),
                &format!("--user-data-dir={}", profile.0.display()),
                "about:blank",
            ])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            // Its own process group, so that drop ends the renderers too.
            .process_group(0);
        let mut child = command.spawn().unwrap_or_else(|err| {
            panic!(
                "cannot start the browser '{program}': {err}. Install Debian's chromium with \
                 `scripts/ensure-deps.sh --test` (or set PUSHLEARN_CHROMIUM to a Chromium or Chrome)"
            )
        });
        let url = match devtools_url(&mut child) {
            Ok(url) => url,
            Err(message) => {
                kill_group(&mut child);
                panic!("{program} did not start: {message}");
            }
        };
        let socket = match tokio::time::timeout(LIMIT, tokio_tungstenite::connect_async(&url)).await
        {
            Ok(Ok((socket, _))) => socket,
            Ok(Err(err)) => {
                kill_group(&mut child);
                panic!("cannot open the DevTools socket {url}: {err}");
            }
            Err(_) => {
                kill_group(&mut child);
                panic!("the DevTools socket {url} did not open within {LIMIT:?}");
            }
        };
        let mut browser = Browser {
            child,
            socket,
            session: String::new(),
            next_id: 0,
            _profile: profile,
        };
        let target = browser
            .call("Target.createTarget", json!({"url": "about:blank"}))
            .await;
        let target_id = target["targetId"].as_str().unwrap_or_default().to_owned();
        let attached = browser
            .call(
                "Target.attachToTarget",
                json!({"targetId": target_id, "flatten": true}),
            )
            .await;
        browser.session = attached["sessionId"]
            .as_str()
            .unwrap_or_else(|| panic!("no session from Target.attachToTarget: {attached}"))
            .to_owned();
        browser
    }

    /// Sends one DevTools command (to the page once attached) and returns
    /// its result; an error answer or no answer within [`LIMIT`] fails.
    pub async fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut command = json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            command["sessionId"] = json!(self.session);
        }
        let deadline = tokio::time::Instant::now() + LIMIT;
        let send = self.socket.send(Message::text(command.to_string()));
        match tokio::time::timeout_at(deadline, send).await {
            Ok(Ok(())) => {}
            Ok(Err(err)) => panic!("DevTools {method}: cannot send: {err}"),
            Err(_) => panic!("DevTools {method}: not sent within {LIMIT:?}"),
        }
        loop {
            let message = match tokio::time::timeout_at(deadline, self.socket.next()).await {
                Ok(Some(Ok(message))) => message,
                Ok(Some(Err(err))) => panic!("DevTools {method}: socket error: {err}"),
                Ok(None) => panic!("DevTools {method}: the browser closed the socket"),
                Err(_) => panic!("DevTools {method}: no answer within {LIMIT:?}"),
            };
            let Message::Text(text) = message else {
                continue;
            };
            let answer: Value = serde_json::from_str(&text)
                .unwrap_or_else(|err| panic!("DevTools sent no JSON ({err}): {text}"));
            // Events (no id) and answers to other commands are not ours.
            if answer["id"] != json!(id) {
                continue;
            }
            if let Some(error) = answer.get("error") {
                panic!("DevTools {method} failed: {error}");
            }
            return answer["result"].clone();
        }
    }

    /// Loads `url` in the page.
    pub async fn navigate(&mut self, url: &str) {
        let result = self.call("Page.navigate", json!({"url": url})).await;
        if let Some(error) = result.get("errorText") {
            panic!("cannot load {url}: {error}");
        }
    }

    /// The value of a JavaScript expression in the page (promises awaited);
    /// a thrown exception fails the test.
    pub async fn eval(&mut self, expression: &str) -> Value {
        let result = self
            .call(
                "Runtime.evaluate",
                json!({"expression": expression, "returnByValue": true, "awaitPromise": true}),
            )
            .await;
        if let Some(exception) = result.get("exceptionDetails") {
            panic!("{expression} threw: {exception}");
        }
        result["result"]["value"].clone()
    }

    /// Re-evaluates `expression` until it is `true`; fails after `limit`
    /// with `what` and the last value of `report` (a JavaScript expression
    /// that shows the page's state).
    pub async fn wait_for(&mut self, expression: &str, what: &str, report: &str, limit: Duration) {
        let deadline = Instant::now() + limit;
        loop {
            if self.eval(&format!("Boolean({expression})")).await == json!(true) {
                return;
            }
            if Instant::now() >= deadline {
                let state = self.eval(report).await;
                panic!("the page did not show {what} within {limit:?}; the page has: {state}");
            }
            tokio::time::sleep(POLL).await;
        }
    }

    /// A PNG of the page as it is shown.
    pub async fn screenshot(&mut self) -> Vec<u8> {
        let shot = self
            .call("Page.captureScreenshot", json!({"format": "png"}))
            .await;
        let data = shot["data"].as_str().unwrap_or_default();
        data_encoding::BASE64
            .decode(data.as_bytes())
            .unwrap_or_else(|err| panic!("the screenshot is not base64: {err}"))
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        kill_group(&mut self.child);
    }
}

/// Reads the browser's stderr until it says where DevTools listen; keeps
/// draining it afterwards so that the browser never blocks on it.
fn devtools_url(child: &mut Child) -> Result<String, String> {
    let stderr = child.stderr.take().ok_or("no stderr")?;
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        let mut seen = Vec::new();
        let mut sent = false;
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if !sent {
                if let Some(url) = line.split_once("DevTools listening on ").map(|(_, u)| u) {
                    let _ = tx.send(Ok(url.trim().to_owned()));
                    sent = true;
                } else {
                    seen.push(line);
                }
            }
        }
        if !sent {
            let _ = tx.send(Err(format!(
                "it exited without a DevTools address; it said:\n{}",
                seen.join("\n")
            )));
        }
    });
    rx.recv_timeout(LIMIT)
        .map_err(|_| format!("no DevTools address within {LIMIT:?}"))?
}
