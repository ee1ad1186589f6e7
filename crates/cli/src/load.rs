//! A load test of a running world daemon (`pushlearn ctl load`): many
//! subscribers at once plus one controlling client that sends a Move for
//! every state, as a learner does. Reports what each saw — missed states
//! (gaps in `publish_seq`), intervals between states against the real-time
//! budget — and the daemon's resident memory over time
//! (`docs/reliability.md`, "Load").

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

/// The outcome.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoadReport {
    pub clients: usize,
    pub seconds: f64,
    /// The controlling client (a Move per state).
    pub controller: ClientCounts,
    /// Intervals between the controller's states, against the 2/f budget.
    pub intervals: WorkSummary,
    /// Publishes per wall-clock second.
    pub publish_rate_wall: f64,
    /// Over all other clients.
    pub subscribers: ClientCounts,
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

fn count(counts: &mut ClientCounts, last: &mut Option<u64>, publish_seq: u64) {
    counts.states += 1;
    if let Some(prev) = *last {
        counts.missed += publish_seq.saturating_sub(prev + 1);
    }
    *last = Some(publish_seq);
}

async fn connect(addr: &str) -> Result<SimClient, ClientError> {
    let options = ClientOptions {
        first_seq: seq_base_from_clock(),
        ..ClientOptions::default()
    };
    SimClient::connect_with(addr, options).await
}

/// A subscriber: reads states until `until`.
async fn subscribe(mut client: SimClient, until: Instant) -> (ClientCounts, bool) {
    let mut counts = ClientCounts::default();
    let mut last = None;
    loop {
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return (counts, true);
        }
        client.set_timeout(Some(left));
        match client.next_state().await {
            Ok(state) => count(&mut counts, &mut last, state.publish_seq),
            Err(ClientError::Timeout { .. }) => return (counts, true),
            Err(_) => return (counts, false),
        }
    }
}

/// Connects `options.clients` clients to the realtime world at `addr`; the
/// first sends a Move for every state it receives (alternating directions
/// every second so that the actuator stays in its bounds).
///
/// # Errors
/// Connecting fails, or the controlling client's connection does.
pub async fn run_load(addr: &str, options: &LoadOptions) -> Result<LoadReport, ClientError> {
    let mut controller = connect(addr).await?;
    let rate = controller.hello().publish_rate;
    let mut subscribers = Vec::new();
    for _ in 1..options.clients {
        subscribers.push(connect(addr).await?);
    }
    let start = Instant::now();
    let until = start + options.duration;
    let tasks: Vec<_> = subscribers
        .into_iter()
        .map(|client| tokio::spawn(subscribe(client, until)))
        .collect();
    let pid = options.pid;
    let sample_every = options.sample_every;
    let sampler = tokio::spawn(async move {
        let mut samples = Vec::new();
        let mut tick = tokio::time::interval(sample_every);
        while Instant::now() < until {
            tick.tick().await;
            if let Some(kib) = rss_kib(pid) {
                samples.push((start.elapsed().as_secs_f64(), kib));
            }
        }
        samples
    });

    let mut counts = ClientCounts::default();
    let mut last = None;
    let mut intervals = WorkTimes::default();
    let limit = budget(rate);
    let mut previous: Option<Instant> = None;
    let mut first_last_seq = (None, 0);
    let per_second = u64::from(rate.max(1));
    loop {
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        controller.set_timeout(Some(left));
        let state = match controller.next_state().await {
            Ok(state) => state,
            Err(ClientError::Timeout { .. }) => break,
            Err(err) => return Err(err),
        };
        let now = Instant::now();
        if let Some(previous) = previous {
            intervals.record(now - previous, limit);
        }
        previous = Some(now);
        count(&mut counts, &mut last, state.publish_seq);
        first_last_seq.0.get_or_insert(state.publish_seq);
        first_last_seq.1 = state.publish_seq;
        let direction = if (counts.states / per_second) % 2 == 0 {
            0.1
        } else {
            -0.1
        };
        controller.send(Payload::move_(0.0, direction)).await?;
    }
    let seconds = start.elapsed().as_secs_f64();
    controller.set_timeout(Some(Duration::from_secs(10)));
    controller.send(Payload::move_(0.0, 0.0)).await?;
    controller.sync().await?;

    let mut report = LoadReport {
        clients: options.clients,
        seconds,
        controller: counts,
        intervals: intervals.summary(),
        publish_rate_wall: first_last_seq
            .0
            .map_or(0.0, |first| (first_last_seq.1 - first) as f64 / seconds),
        subscribers: ClientCounts::default(),
        subscriber_min_states: u64::MAX,
        subscribers_lost: 0,
        rss_kib: sampler.await.unwrap_or_default(),
    };
    for task in tasks {
        let (c, finished) = task.await.unwrap_or_default();
        report.subscribers.states += c.states;
        report.subscribers.missed += c.missed;
        report.subscriber_min_states = report.subscriber_min_states.min(c.states);
        report.subscribers_lost += usize::from(!finished);
    }
    if options.clients <= 1 {
        report.subscriber_min_states = 0;
    }
    Ok(report)
}

impl std::fmt::Display for LoadReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} clients for {:.1} s; the world published {:.1} states per second",
            self.clients, self.seconds, self.publish_rate_wall
        )?;
        writeln!(
            f,
            "controlling client: {} states, {} missed; intervals: p50 {:.3} ms, p99 {:.3} ms, \
             max {:.3} ms, {} ({:.4} %) over the 2/f budget",
            self.controller.states,
            self.controller.missed,
            self.intervals.p50_ms,
            self.intervals.p99_ms,
            self.intervals.max_ms,
            self.intervals.too_slow,
            100.0 * self.intervals.too_slow_fraction
        )?;
        writeln!(
            f,
            "{} subscribers: {} states, {} missed, at least {} each, {} disconnected early",
            self.clients.saturating_sub(1),
            self.subscribers.states,
            self.subscribers.missed,
            self.subscriber_min_states,
            self.subscribers_lost
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
