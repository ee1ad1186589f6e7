//! A load test of a running world daemon (`pushlearn ctl load`): many
//! subscribers at once plus, optionally, one controlling client that sends a
//! Move for every state, as a learner does. Reports what each saw — missed
//! states (gaps in `publish_seq`), intervals between states against the
//! real-time budget — and the daemon's resident memory over time
//! (`docs/reliability.md`, "Load"). `pushlearn ctl soak` runs it beside a
//! real learner.

use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::latency::budget;
use crate::learn::{WorkSummary, WorkTimes};
use pushlearn::client::{seq_base_from_clock, ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb::client_message::Payload;

/// What to run.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Connections in all, the controlling one included.
    pub clients: usize,
    pub duration: Duration,
    /// The first connection sends a Move for every state it receives, as a
    /// learner does. Without, every connection only reads: something else
    /// controls the world (`pushlearn ctl soak` runs a real learner).
    pub control: bool,
    /// The daemon's process id, whose RSS is sampled (`None`: this
    /// process's, for a daemon served in-process).
    pub pid: Option<u32>,
    /// How often to sample the RSS.
    pub sample_every: Duration,
}

/// What one client saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ClientCounts {
    pub states: u64,
    /// States the daemon published but this client never received.
    pub missed: u64,
}

/// The controlling client's view.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Controller {
    pub counts: ClientCounts,
    /// Intervals between its states, against the 2/f budget.
    pub intervals: WorkSummary,
}

/// The outcome.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoadReport {
    pub clients: usize,
    pub seconds: f64,
    /// The controlling client (a Move per state), if there was one.
    pub controller: Option<Controller>,
    /// Publishes per wall-clock second.
    pub publish_rate_wall: f64,
    /// Over all other clients.
    pub subscribers: ClientCounts,
    /// Intervals between consecutive states at every subscriber, all in one
    /// distribution, against the 2/f budget: how evenly the world's states
    /// reached its readers.
    pub subscriber_intervals: WorkSummary,
    /// The fewest states any subscriber received.
    pub subscriber_min_states: u64,
    /// Subscribers whose connection ended early.
    pub subscribers_lost: usize,
    /// (seconds since start, resident set in KiB).
    pub rss_kib: Vec<(f64, u64)>,
}

/// The resident set size of `pid` (or this process) in KiB, from
/// `/proc/PID/status` (Linux).
#[must_use]
pub fn rss_kib(pid: Option<u32>) -> Option<u64> {
    let path = match pid {
        Some(pid) => format!("/proc/{pid}/status"),
        None => "/proc/self/status".to_owned(),
    };
    let status = std::fs::read_to_string(path).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

async fn connect(addr: &str) -> Result<SimClient, ClientError> {
    let options = ClientOptions {
        first_seq: seq_base_from_clock(),
        ..ClientOptions::default()
    };
    SimClient::connect_with(addr, options).await
}

/// What one client received.
#[derive(Default)]
struct Received {
    states: u64,
    /// The first and the latest `publish_seq`.
    seqs: Option<(u64, u64)>,
    intervals: WorkTimes,
    previous: Option<Instant>,
    /// Read off the client when it is done ([`SimClient::missed_states`]).
    missed: u64,
}

impl Received {
    fn record(&mut self, publish_seq: u64, budget: Duration) {
        let now = Instant::now();
        if let Some(previous) = self.previous {
            self.intervals.record(now - previous, budget);
        }
        self.previous = Some(now);
        self.states += 1;
        let first = self.seqs.map_or(publish_seq, |(first, _)| first);
        self.seqs = Some((first, publish_seq));
    }

    /// Done: what `client` missed is read off it.
    fn done(mut self, client: &SimClient) -> Self {
        self.missed = client.missed_states();
        self
    }

    fn counts(&self) -> ClientCounts {
        ClientCounts {
            states: self.states,
            missed: self.missed,
        }
    }
}

/// A subscriber: reads states until `until`. Returns what it received and
/// whether it lasted.
async fn subscribe(mut client: SimClient, until: Instant, budget: Duration) -> (Received, bool) {
    let mut received = Received::default();
    let lasted = loop {
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break true;
        }
        client.set_timeout(Some(left));
        match client.next_state().await {
            Ok(state) => received.record(state.publish_seq, budget),
            Err(ClientError::Timeout { .. }) => break true,
            Err(_) => break false,
        }
    };
    (received.done(&client), lasted)
}

/// Samples `probe` every `every` until `until`; each sample is tagged with
/// the seconds since `start`.
pub async fn sample_until<T>(
    start: Instant,
    until: Instant,
    every: Duration,
    mut probe: impl FnMut() -> Option<T>,
) -> Vec<(f64, T)> {
    let mut samples = Vec::new();
    let mut tick = tokio::time::interval(every);
    while Instant::now() < until {
        tick.tick().await;
        if let Some(sample) = probe() {
            samples.push((start.elapsed().as_secs_f64(), sample));
        }
    }
    samples
}

/// Connects `options.clients` clients to the realtime world at `addr`; with
/// `options.control` the first sends a Move for every state it receives
/// (alternating directions every second so that the actuator stays in its
/// bounds), the others only read.
///
/// # Errors
/// Connecting fails, or the controlling client's connection does.
pub async fn run_load(addr: &str, options: &LoadOptions) -> Result<LoadReport, ClientError> {
    let mut clients = Vec::with_capacity(options.clients);
    for _ in 0..options.clients {
        clients.push(connect(addr).await?);
    }
    let Some(rate) = clients.first().map(|c| c.hello().publish_rate) else {
        return Err(ClientError::Protocol("a load run needs a client".into()));
    };
    let limit = budget(rate);
    let controller = if options.control {
        Some(clients.remove(0))
    } else {
        None
    };
    let start = Instant::now();
    let until = start + options.duration;
    let tasks: Vec<_> = clients
        .into_iter()
        .map(|client| tokio::spawn(subscribe(client, until, limit)))
        .collect();
    let pid = options.pid;
    let sampler = tokio::spawn(sample_until(
        start,
        until,
        options.sample_every,
        move || rss_kib(pid),
    ));
    let controller = match controller {
        Some(client) => Some(control(client, until, limit, rate).await?),
        None => None,
    };

    let mut seqs = controller.as_ref().and_then(|received| received.seqs);
    let mut report = LoadReport {
        clients: options.clients,
        seconds: 0.0,
        controller: controller.map(|received| Controller {
            counts: received.counts(),
            intervals: received.intervals.summary(),
        }),
        publish_rate_wall: 0.0,
        subscribers: ClientCounts::default(),
        subscriber_intervals: WorkSummary::default(),
        subscriber_min_states: u64::MAX,
        subscribers_lost: 0,
        rss_kib: sampler.await.unwrap_or_default(),
    };
    let mut intervals = WorkTimes::default();
    let mut subscribers = 0;
    for task in tasks {
        let Ok((received, lasted)) = task.await else {
            report.subscribers_lost += 1;
            continue;
        };
        subscribers += 1;
        let counts = received.counts();
        report.subscribers.states += counts.states;
        report.subscribers.missed += counts.missed;
        report.subscriber_min_states = report.subscriber_min_states.min(counts.states);
        report.subscribers_lost += usize::from(!lasted);
        intervals += received.intervals;
        if let Some((first, last)) = received.seqs {
            seqs = Some(seqs.map_or((first, last), |(f, l)| (f.min(first), l.max(last))));
        }
    }
    if subscribers == 0 {
        report.subscriber_min_states = 0;
    }
    // Every client has read until the end.
    report.seconds = start.elapsed().as_secs_f64();
    report.subscriber_intervals = intervals.summary();
    report.publish_rate_wall =
        seqs.map_or(0.0, |(first, last)| (last - first) as f64 / report.seconds);
    Ok(report)
}

/// The controlling client: a Move for every state until `until`, then the
/// actuator stopped.
async fn control(
    mut client: SimClient,
    until: Instant,
    limit: Duration,
    rate: u32,
) -> Result<Received, ClientError> {
    let mut received = Received::default();
    let per_second = u64::from(rate.max(1));
    loop {
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        client.set_timeout(Some(left));
        let state = match client.next_state().await {
            Ok(state) => state,
            Err(ClientError::Timeout { .. }) => break,
            Err(err) => return Err(err),
        };
        received.record(state.publish_seq, limit);
        let direction = if (received.states / per_second) % 2 == 0 {
            0.1
        } else {
            -0.1
        };
        client.send(Payload::move_(0.0, direction)).await?;
    }
    client.set_timeout(Some(Duration::from_secs(10)));
    client.send(Payload::move_(0.0, 0.0)).await?;
    client.sync().await?;
    Ok(received.done(&client))
}

/// `p50 …, p99 …, max … ms, N (x %) over the 2/f budget`.
fn describe_intervals(intervals: &WorkSummary) -> String {
    format!(
        "p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms, {} ({:.4} %) over the 2/f budget",
        intervals.p50_ms,
        intervals.p99_ms,
        intervals.max_ms,
        intervals.too_slow,
        100.0 * intervals.too_slow_fraction
    )
}

impl std::fmt::Display for LoadReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} clients for {:.1} s; the world published {:.1} states per second",
            self.clients, self.seconds, self.publish_rate_wall
        )?;
        if let Some(controller) = &self.controller {
            writeln!(
                f,
                "controlling client: {} states, {} missed; intervals: {}",
                controller.counts.states,
                controller.counts.missed,
                describe_intervals(&controller.intervals)
            )?;
        }
        writeln!(
            f,
            "{} subscribers: {} states, {} missed, at least {} each, {} disconnected early; \
             intervals: {}",
            self.clients - usize::from(self.controller.is_some()),
            self.subscribers.states,
            self.subscribers.missed,
            self.subscriber_min_states,
            self.subscribers_lost,
            describe_intervals(&self.subscriber_intervals)
        )?;
        match (self.rss_kib.first(), self.rss_kib.iter().map(|s| s.1).max()) {
            (Some(first), Some(max)) => write!(
                f,
                "daemon RSS: {} KiB at the start, {} KiB at most, {} KiB at the end ({} samples)",
                first.1,
                max,
                self.rss_kib.last().map_or(0, |s| s.1),
                self.rss_kib.len()
            ),
            _ => write!(f, "daemon RSS: not sampled (give --pid)"),
        }
    }
}
