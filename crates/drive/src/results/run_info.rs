//! How an experiment's run went, beside what it measured: the drivers'
//! message counters, the links' handling times, and their sum over jobs
//! ([`RunInfo`], the `run` of every document).

use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::latency::{budget, Latencies};

/// Counters of one driver, summed over jobs for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters {
    /// Every world state offered to the driver while it was not done.
    pub messages: u64,
    /// Messages dropped after a reset or repositioning (`ignore`).
    pub ignored: u64,
    /// Failed start-position checks, each answered with a SetPose.
    pub reset_errors: u64,
    /// Frames the model could not parse (not a model step).
    pub parse_errors: u64,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, other: Self) {
        self.messages += other.messages;
        self.ignored += other.ignored;
        self.reset_errors += other.reset_errors;
        self.parse_errors += other.parse_errors;
    }
}

/// Handling times of the messages of one or more jobs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// States handled.
    pub messages: u64,
    /// States whose handling (parse, model work, and in realtime sending the
    /// commands; in lock-step they go out with the next Advance) took
    /// longer than 2/f.
    pub too_slow: u64,
    /// Sum of the handling times, seconds.
    pub busy_seconds: f64,
    /// The longest handling time, seconds.
    pub max_seconds: f64,
    /// Wall time embedded worlds spent stepping their physics, seconds
    /// (0 for a world behind a socket, whose cost is not seen here).
    #[serde(default)]
    pub physics_seconds: f64,
    /// The states they published in that time.
    #[serde(default)]
    pub physics_states: u64,
    /// Wall time embedded worlds waited for each other's steps (ODE steps
    /// one world at a time per process), seconds.
    #[serde(default)]
    pub physics_wait_seconds: f64,
    /// All handling times, for percentiles (not serialised).
    #[serde(skip)]
    pub histogram: Latencies,
}

impl Timing {
    pub(crate) fn record(&mut self, took: Duration, budget: Duration) {
        self.messages += 1;
        if took > budget {
            self.too_slow += 1;
        }
        let s = took.as_secs_f64();
        self.busy_seconds += s;
        self.max_seconds = self.max_seconds.max(s);
        self.histogram.record(took);
    }

    /// Fraction of messages that were too slow (0 without messages).
    #[must_use]
    pub fn too_slow_fraction(&self) -> f64 {
        if self.messages == 0 {
            0.0
        } else {
            self.too_slow as f64 / self.messages as f64
        }
    }
}

impl std::ops::AddAssign for Timing {
    fn add_assign(&mut self, other: Self) {
        self.messages += other.messages;
        self.too_slow += other.too_slow;
        self.busy_seconds += other.busy_seconds;
        self.max_seconds = self.max_seconds.max(other.max_seconds);
        self.physics_seconds += other.physics_seconds;
        self.physics_states += other.physics_states;
        self.physics_wait_seconds += other.physics_wait_seconds;
        self.histogram += other.histogram;
    }
}

/// How an experiment's run went: message counts, the timing requirement of
/// `docs/spec/experiments.md` §6, start-position corrections.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    /// World states handled by the drivers.
    pub messages: u64,
    /// 2/f (`docs/spec/experiments.md` §6).
    pub budget_seconds: f64,
    /// Messages dropped after resets and repositionings.
    pub ignored: u64,
    /// Failed start-position checks (each answered by a SetPose).
    pub reset_errors: u64,
    pub parse_errors: u64,
    /// What depends on the machine and its load (and, with reuse, on which
    /// worker got to a run first). Absent from documents that must be
    /// reproducible byte for byte ([`RunInfo::without_timing`]).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<RunTiming>,
}

/// The machine-dependent part of a [`RunInfo`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunTiming {
    pub workers: usize,
    pub wall_seconds: f64,
    /// Messages whose handling took longer than `budget_seconds`.
    pub too_slow: u64,
    pub too_slow_fraction: f64,
    pub mean_handling_ms: f64,
    /// Median and 99th percentile of the handling times (within 1/16).
    #[serde(default)]
    pub p50_handling_us: f64,
    #[serde(default)]
    pub p99_handling_us: f64,
    pub max_handling_ms: f64,
    /// World states the worlds simulated: `messages` without reuse, fewer
    /// when lockstep runs were replayed (docs/performance.md).
    #[serde(default)]
    pub simulated_states: u64,
    /// What one state's physics cost, measured in this run's embedded
    /// worlds (absent for worlds behind a socket), µs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics_us_per_state: Option<f64>,
    /// How long the embedded worlds waited for each other's physics, summed
    /// over the workers, seconds (absent for worlds behind sockets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics_wait_seconds: Option<f64>,
}

impl RunInfo {
    /// Sums the jobs' counters and timings.
    #[must_use]
    pub fn of(
        jobs: impl IntoIterator<Item = (Counters, Timing)>,
        publish_rate_hz: u32,
        workers: usize,
        wall_seconds: f64,
    ) -> Self {
        let mut counters = Counters::default();
        let mut timing = Timing::default();
        for (c, t) in jobs {
            counters += c;
            timing += t;
        }
        let mean = if timing.messages == 0 {
            0.0
        } else {
            timing.busy_seconds / timing.messages as f64
        };
        let summary = timing.histogram.summary();
        Self {
            messages: timing.messages,
            budget_seconds: budget(publish_rate_hz).as_secs_f64(),
            ignored: counters.ignored,
            reset_errors: counters.reset_errors,
            parse_errors: counters.parse_errors,
            timing: Some(RunTiming {
                workers,
                wall_seconds,
                too_slow: timing.too_slow,
                too_slow_fraction: timing.too_slow_fraction(),
                mean_handling_ms: mean * 1e3,
                p50_handling_us: summary.p50_us,
                p99_handling_us: summary.p99_us,
                max_handling_ms: timing.max_seconds * 1e3,
                simulated_states: timing.messages,
                physics_us_per_state: (timing.physics_states > 0)
                    .then(|| timing.physics_seconds / timing.physics_states as f64 * 1e6),
                physics_wait_seconds: (timing.physics_states > 0)
                    .then_some(timing.physics_wait_seconds),
            }),
        }
    }

    /// This run without its machine-dependent part.
    #[must_use]
    pub fn without_timing(self) -> Self {
        Self {
            timing: None,
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timing_counts_only_messages_over_budget() {
        let mut t = Timing::default();
        let b = budget(100);
        t.record(Duration::from_millis(5), b);
        t.record(Duration::from_millis(25), b);
        t.record(Duration::from_millis(20), b);
        assert_eq!((t.messages, t.too_slow), (3, 1));
        assert!((t.too_slow_fraction() - 1.0 / 3.0).abs() < 1e-12);
        assert!((t.max_seconds - 0.025).abs() < 1e-12);
        let mut sum = Timing::default();
        sum += t;
        sum += t;
        assert_eq!((sum.messages, sum.too_slow), (6, 2));
        assert_eq!(Timing::default().too_slow_fraction(), 0.0);
    }

    #[test]
    fn timing_is_optional_in_documents_and_flat_when_present() {
        let run = RunInfo::of([(Counters::default(), Timing::default())], 100, 2, 1.5);
        let with = serde_json::to_value(&run).unwrap();
        assert_eq!(with["wall_seconds"], 1.5);
        assert_eq!(with["workers"], 2);
        let back: RunInfo = serde_json::from_value(with).unwrap();
        assert_eq!(back, run);
        let without = serde_json::to_value(run.clone().without_timing()).unwrap();
        assert!(without.get("wall_seconds").is_none() && without.get("workers").is_none());
        let back: RunInfo = serde_json::from_value(without).unwrap();
        assert_eq!(back, run.without_timing());
    }
}
