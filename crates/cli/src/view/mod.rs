//! `pushlearn view`: a live top-down view of a running world in the browser.
//!
//! The viewer is an ordinary client of the world daemon: it subscribes to the
//! world-state stream like the learner does, and serves one embedded HTML
//! page plus a WebSocket (`/ws`) on which every browser tab gets the scene
//! (bodies and their sizes, from `Hello.shapes`), then the latest world state
//! as JSON, and may send pause, unpause and reset, which the viewer forwards
//! as `SimControl`. The message format is documented in docs/viewer.md.
//!
//! The world itself stays free of HTTP: the daemon keeps its one protocol and
//! the viewer can run anywhere a client can.

mod http;
mod json;
#[cfg(any(test, feature = "testing"))]
pub mod untrusted;

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use futures::{SinkExt, StreamExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{broadcast, mpsc, watch, Semaphore};
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::protocol::CloseFrame;
use tokio_tungstenite::tungstenite::{Message, Utf8Bytes};

use pushlearn::client::{ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb::{client_message::Payload, server_message};

pub use json::{Control, Outgoing};

/// The page, shipped inside the binary: no build step, no files to install.
pub const PAGE: &str = include_str!("page.html");

/// The viewer's default port (the world's is 11345).
pub const DEFAULT_PORT: u16 = 11346;

/// How long the viewer waits before trying to reach a lost world again.
const RECONNECT_EVERY: Duration = Duration::from_secs(1);

/// Control results and world errors kept for tabs that read slowly; a tab
/// that falls further behind skips the oldest (states are never queued: a tab
/// always gets the newest one).
const EVENT_BACKLOG: usize = 64;

/// Pause after a failed accept(), so that a persistent failure (no file
/// descriptors left) does not spin.
const ACCEPT_BACKOFF: Duration = Duration::from_millis(100);

/// Controls waiting to be forwarded to the world.
const CONTROL_BACKLOG: usize = 16;

/// Browser connections served at once by default (page loads and open tabs
/// together); one more is answered `503 Service Unavailable`. As many as the
/// world daemon's clients: a tab costs a task and a socket, nothing more.
pub const DEFAULT_MAX_CONNECTIONS: usize = 64;

/// Why the viewer cannot start.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The listening socket could not be opened.
    #[error("cannot listen on {addr}: {reason}")]
    Bind {
        /// The address asked for.
        addr: SocketAddr,
        /// Why.
        reason: std::io::Error,
    },
}

/// What the world task shares with the browser tabs.
#[derive(Debug)]
struct Hub {
    /// The scene as JSON (`Outgoing::Hello`), replaced on every (re)connection.
    hello: watch::Sender<Utf8Bytes>,
    /// The newest world state as JSON (`Outgoing::State`), or nothing yet.
    state: watch::Sender<Option<Utf8Bytes>>,
    /// The connection to the world (`Outgoing::Status`), for tabs opened
    /// later too.
    status: watch::Sender<Utf8Bytes>,
    /// Control results and world errors.
    events: broadcast::Sender<Utf8Bytes>,
    /// Browser → world.
    controls: mpsc::Sender<Control>,
}

impl Hub {
    fn event(&self, message: &Outgoing) {
        // No receiver (no tab open) is not an error: the news is for tabs.
        let _ = self.events.send(message.to_json());
    }
}

/// A viewer listening for browsers; [`Viewer::run`] serves them.
#[derive(Debug)]
pub struct Viewer {
    listener: TcpListener,
    addr: SocketAddr,
    max_connections: usize,
}

impl Viewer {
    /// Opens the listening socket (port 0 picks a free one).
    ///
    /// # Errors
    /// The address is taken or cannot be bound.
    pub async fn bind(addr: SocketAddr) -> Result<Self, ViewError> {
        let listener = TcpListener::bind(addr)
            .await
            .map_err(|reason| ViewError::Bind { addr, reason })?;
        let addr = listener
            .local_addr()
            .map_err(|reason| ViewError::Bind { addr, reason })?;
        Ok(Self {
            listener,
            addr,
            max_connections: DEFAULT_MAX_CONNECTIONS,
        })
    }

    /// Serves at most `max` browser connections at once (at least one).
    #[must_use]
    pub fn with_max_connections(mut self, max: usize) -> Self {
        self.max_connections = max.clamp(1, Semaphore::MAX_PERMITS);
        self
    }

    /// Where browsers find the page.
    #[must_use]
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's address to print for people.
    #[must_use]
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Serves browsers until `shutdown` completes. `world` is the connected
    /// world, `world_addr` where to reach it again if the connection is lost.
    pub async fn run(
        self,
        world: SimClient,
        world_addr: String,
        shutdown: impl Future<Output = ()>,
    ) {
        let (controls, control_rx) = mpsc::channel(CONTROL_BACKLOG);
        let hub = Arc::new(Hub {
            hello: watch::Sender::new(Outgoing::hello(&world_addr, world.hello()).to_json()),
            state: watch::Sender::new(None),
            status: watch::Sender::new(connected(&world_addr)),
            events: broadcast::Sender::new(EVENT_BACKLOG),
            controls,
        });
        let world_task = tokio::spawn(follow_world(
            world,
            world_addr,
            Arc::clone(&hub),
            control_rx,
        ));
        tokio::pin!(shutdown);
        let places = Arc::new(Semaphore::new(self.max_connections));
        loop {
            tokio::select! {
                accepted = self.listener.accept() => match accepted {
                    Ok((stream, peer)) => {
                        let Ok(place) = Arc::clone(&places).try_acquire_owned() else {
                            let max = self.max_connections;
                            tracing::warn!(%peer, "turning a browser away: {max} connections are open");
                            tokio::spawn(async move {
                                if let Err(err) = http::turn_away(stream, max).await {
                                    tracing::debug!(%peer, %err, "turning a browser away");
                                }
                            });
                            continue;
                        };
                        let hub = Arc::clone(&hub);
                        tokio::spawn(async move {
                            let _place = place;
                            if let Err(err) = serve_browser(stream, &hub).await {
                                tracing::debug!(%peer, %err, "browser connection ended");
                            }
                        });
                    }
                    // Failures of accept() concern one connection or are
                    // transient (out of descriptors): the page stays up.
                    Err(err) => {
                        tracing::warn!(%err, "accepting a browser connection failed");
                        tokio::time::sleep(ACCEPT_BACKOFF).await;
                    }
                },
                () = &mut shutdown => break,
            }
        }
        world_task.abort();
    }
}

fn connected(addr: &str) -> Utf8Bytes {
    Outgoing::Status {
        connected: true,
        message: format!("connected to the world at {addr}"),
    }
    .to_json()
}

/// Follows the world for the viewer's whole life: publishes every state,
/// forwards controls, and reconnects when the world goes away (a restarted
/// `pushlearn-sim` is picked up without reloading the page).
async fn follow_world(
    mut client: SimClient,
    addr: String,
    hub: Arc<Hub>,
    mut controls: mpsc::Receiver<Control>,
) {
    loop {
        hub.hello
            .send_replace(Outgoing::hello(&addr, client.hello()).to_json());
        hub.state.send_replace(None);
        hub.status.send_replace(connected(&addr));
        let lost = pump(&mut client, &hub, &mut controls).await;
        tracing::warn!(%addr, %lost, "lost the world; reconnecting");
        hub.status.send_replace(
            Outgoing::Status {
                connected: false,
                message: format!("lost the world at {addr}: {lost}; reconnecting"),
            }
            .to_json(),
        );
        client = reconnect(&addr, &hub, &mut controls).await;
    }
}

async fn reconnect(addr: &str, hub: &Hub, controls: &mut mpsc::Receiver<Control>) -> SimClient {
    loop {
        let sleep = tokio::time::sleep(RECONNECT_EVERY);
        tokio::pin!(sleep);
        // Controls clicked meanwhile are answered, not silently kept for a
        // world that may come back in another state.
        loop {
            tokio::select! {
                () = &mut sleep => break,
                Some(control) = controls.recv() => hub.event(&Outgoing::refused(
                    control,
                    "the viewer is not connected to the world".into(),
                )),
            }
        }
        match SimClient::connect_with(addr, ClientOptions::clock_seqs()).await {
            Ok(client) => return client,
            Err(err) => tracing::debug!(%addr, %err, "world still unreachable"),
        }
    }
}

/// Publishes states and forwards controls until the connection fails.
async fn pump(
    client: &mut SimClient,
    hub: &Hub,
    controls: &mut mpsc::Receiver<Control>,
) -> ClientError {
    loop {
        tokio::select! {
            message = client.next_message() => match message {
                Ok(server_message::Payload::WorldState(state)) => {
                    hub.state.send_replace(Some(Outgoing::state(&state).to_json()));
                }
                Ok(server_message::Payload::Error(error)) => hub.event(&Outgoing::Error {
                    message: error.message,
                }),
                Ok(server_message::Payload::Hello(_)) => {
                    return ClientError::Protocol("a second Hello on the same connection".into())
                }
                // A paused or lock-step world may be quiet for long; the page
                // shows how old its newest state is.
                Err(ClientError::Timeout { .. }) => {}
                Err(err) => return err,
            },
            Some(control) = controls.recv() => {
                // `command` waits for the world's acceptance (a barrier), so
                // the page learns whether the world took it.
                match client.command(control.payload()).await {
                    Ok(_) => hub.event(&Outgoing::accepted(control)),
                    Err(ClientError::Refused { message, .. }) => {
                        hub.event(&Outgoing::refused(control, message));
                    }
                    // An error not about this command (the physics blew up)
                    // arrived first: the connection is fine, the command's
                    // fate unknown; the barrier's late answer is skipped.
                    Err(ClientError::World { message, .. }) => {
                        hub.event(&Outgoing::refused(
                            control,
                            "not confirmed: the world reported an error first".into(),
                        ));
                        hub.event(&Outgoing::Error { message });
                    }
                    Err(err) => {
                        hub.event(&Outgoing::refused(control, err.to_string()));
                        return err;
                    }
                }
            }
        }
    }
}

/// What a tab sent, and what the viewer does about it.
#[derive(Debug, PartialEq)]
enum FromTab {
    /// A control to forward to the world.
    Control(Control),
    /// A message that is not a control: this error goes back to the tab.
    Answer(Utf8Bytes),
    /// The tab broke a limit (a message above [`http::MAX_WS_MESSAGE`]):
    /// the viewer closes with this frame, so that the tab learns why.
    Close(CloseFrame),
    /// The tab closed, or its connection broke.
    Gone,
    /// Pings (answered by the library), pongs and binary messages.
    Nothing,
}

fn from_tab(incoming: Option<Result<Message, tokio_tungstenite::tungstenite::Error>>) -> FromTab {
    match incoming {
        Some(Ok(Message::Text(text))) => match Control::parse(&text) {
            Ok(control) => FromTab::Control(control),
            Err(message) => FromTab::Answer(Outgoing::Error { message }.to_json()),
        },
        Some(Err(tokio_tungstenite::tungstenite::Error::Capacity(err))) => {
            FromTab::Close(CloseFrame {
                code: CloseCode::Size,
                reason: format!("{err}").into(),
            })
        }
        Some(Ok(Message::Close(_)) | Err(_)) | None => FromTab::Gone,
        Some(Ok(_)) => FromTab::Nothing,
    }
}

impl Control {
    fn payload(self) -> Payload {
        match self {
            Control::Pause => Payload::pause(),
            Control::Unpause => Payload::unpause(),
            Control::Reset => Payload::reset(),
        }
    }
}

/// One browser connection: the page, a WebSocket, or an error response.
async fn serve_browser(stream: TcpStream, hub: &Hub) -> Result<(), http::HttpError> {
    if let Err(err) = stream.set_nodelay(true) {
        tracing::debug!("cannot set TCP_NODELAY: {err}");
    }
    match http::accept(stream).await? {
        http::Accepted::Served => Ok(()),
        http::Accepted::WebSocket(socket) => {
            follow_tab(*socket, hub).await;
            Ok(())
        }
    }
}

/// Feeds one tab: the scene, then the newest state whenever there is a new
/// one, and every event; reads its controls.
async fn follow_tab(mut socket: http::Socket, hub: &Hub) {
    let mut hello = hub.hello.subscribe();
    let mut state = hub.state.subscribe();
    let mut status = hub.status.subscribe();
    let mut events = hub.events.subscribe();
    // The scene first, then the connection, then the newest state if any.
    let first = [
        hello.borrow_and_update().clone(),
        status.borrow_and_update().clone(),
    ];
    let newest = state.borrow_and_update().clone();
    for json in first.into_iter().chain(newest) {
        if socket.send(Message::Text(json)).await.is_err() {
            return;
        }
    }
    loop {
        let outgoing = tokio::select! {
            // A new scene (after a reconnection) goes out before the states
            // that belong to it.
            biased;
            changed = hello.changed() => match changed {
                Ok(()) => hello.borrow_and_update().clone(),
                Err(_) => return,
            },
            changed = status.changed() => match changed {
                Ok(()) => status.borrow_and_update().clone(),
                Err(_) => return,
            },
            changed = state.changed() => match changed {
                Ok(()) => match state.borrow_and_update().clone() {
                    Some(json) => json,
                    None => continue,
                },
                Err(_) => return,
            },
            event = events.recv() => match event {
                Ok(json) => json,
                Err(broadcast::error::RecvError::Lagged(_)) => continue,
                Err(broadcast::error::RecvError::Closed) => return,
            },
            incoming = socket.next() => match from_tab(incoming) {
                FromTab::Control(control) => {
                    if hub.controls.try_send(control).is_err() {
                        hub.event(&Outgoing::refused(control, "too many controls waiting; try again".into()));
                    }
                    continue;
                }
                FromTab::Answer(reply) => reply,
                FromTab::Close(frame) => {
                    let _ = socket.close(Some(frame)).await;
                    return;
                }
                FromTab::Gone => return,
                FromTab::Nothing => continue,
            },
        };
        if socket.send(Message::Text(outgoing)).await.is_err() {
            return;
        }
    }
}
