//! Per-message work times in bounded memory: a log-linear histogram (16
//! buckets per power of two, so a reported percentile is at most 1/16 above
//! the true value), mergeable across jobs, with the exact maximum; and the
//! budget those times are held to.

use std::time::Duration;

use serde::{Deserialize, Serialize};

/// The original's per-message budget: 2/f seconds (0.02 s at 100 Hz)
/// (`docs/spec/experiments.md` §6).
#[must_use]
pub fn budget(publish_rate_hz: u32) -> Duration {
    Duration::from_secs_f64(2.0 / f64::from(publish_rate_hz.max(1)))
}

/// Sub-buckets per power of two.
const SUB: u64 = 16;
/// Exact buckets for 0‥15 ns, then 16 per octave up to 2⁴¹ ns (≈ 37 min).
const BUCKETS: usize = 16 + 37 * 16;

/// A histogram of durations.
///
/// Serialised sparsely (the non-empty buckets) so that a worker process can
/// send a job's histogram back with its result ([`crate::experiment::processes`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "SparseLatencies", try_from = "SparseLatencies")]
pub struct Latencies {
    counts: [u32; BUCKETS],
    count: u64,
    max_ns: u64,
}

impl Default for Latencies {
    fn default() -> Self {
        Self {
            counts: [0; BUCKETS],
            count: 0,
            max_ns: 0,
        }
    }
}

fn bucket(ns: u64) -> usize {
    let ns = ns.min((1 << 41) - 1);
    if ns < SUB {
        return ns as usize;
    }
    let e = 63 - u64::from(ns.leading_zeros());
    let sub = (ns >> (e - 4)) & (SUB - 1);
    (SUB + (e - 4) * SUB + sub) as usize
}

/// The largest value of bucket `i`.
fn upper(i: usize) -> u64 {
    let i = i as u64;
    if i < SUB {
        return i;
    }
    let e = (i - SUB) / SUB + 4;
    let sub = (i - SUB) % SUB;
    ((SUB + sub) << (e - 4)) + (1 << (e - 4)) - 1
}

impl Latencies {
    /// Records one duration.
    pub fn record(&mut self, took: Duration) {
        let ns = u64::try_from(took.as_nanos()).unwrap_or(u64::MAX);
        let b = &mut self.counts[bucket(ns)];
        *b = b.saturating_add(1);
        self.count += 1;
        self.max_ns = self.max_ns.max(ns);
    }

    /// Number of recorded durations.
    #[must_use]
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Nearest-rank percentile `p` in [0, 1]: the upper end of the bucket
    /// holding it, never above the maximum; zero without data.
    #[must_use]
    pub fn quantile(&self, p: f64) -> Duration {
        if self.count == 0 {
            return Duration::ZERO;
        }
        let rank = ((p * self.count as f64).ceil() as u64).clamp(1, self.count);
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += u64::from(c);
            if seen >= rank {
                return Duration::from_nanos(upper(i).min(self.max_ns));
            }
        }
        Duration::from_nanos(self.max_ns)
    }

    /// The longest duration.
    #[must_use]
    pub fn max(&self) -> Duration {
        Duration::from_nanos(self.max_ns)
    }

    /// p50, p99 and max in microseconds.
    #[must_use]
    pub fn summary(&self) -> LatencySummary {
        let us = |d: Duration| d.as_secs_f64() * 1e6;
        LatencySummary {
            count: self.count,
            p50_us: us(self.quantile(0.5)),
            p99_us: us(self.quantile(0.99)),
            max_us: us(self.max()),
        }
    }
}

impl std::ops::AddAssign for Latencies {
    fn add_assign(&mut self, other: Self) {
        for (a, b) in self.counts.iter_mut().zip(other.counts) {
            *a = a.saturating_add(b);
        }
        self.count += other.count;
        self.max_ns = self.max_ns.max(other.max_ns);
    }
}

/// [`Latencies`] as sent: `(bucket, count)` for the non-empty buckets.
#[derive(Serialize, Deserialize)]
struct SparseLatencies {
    count: u64,
    max_ns: u64,
    buckets: Vec<(usize, u32)>,
}

impl From<Latencies> for SparseLatencies {
    fn from(l: Latencies) -> Self {
        Self {
            count: l.count,
            max_ns: l.max_ns,
            buckets: l
                .counts
                .iter()
                .enumerate()
                .filter(|(_, &c)| c > 0)
                .map(|(i, &c)| (i, c))
                .collect(),
        }
    }
}

impl TryFrom<SparseLatencies> for Latencies {
    type Error = String;
    fn try_from(sparse: SparseLatencies) -> Result<Self, String> {
        let mut l = Latencies {
            count: sparse.count,
            max_ns: sparse.max_ns,
            ..Latencies::default()
        };
        for (i, c) in sparse.buckets {
            *l.counts
                .get_mut(i)
                .ok_or_else(|| format!("latency bucket {i} is out of range (0..{BUCKETS})"))? = c;
        }
        Ok(l)
    }
}

/// What reports show of a [`Latencies`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LatencySummary {
    pub count: u64,
    pub p50_us: f64,
    pub p99_us: f64,
    pub max_us: f64,
}

impl std::fmt::Display for LatencySummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs",
            self.p50_us, self.p99_us, self.max_us
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_histogram_survives_its_journey_to_another_process() {
        let mut l = Latencies::default();
        for us in [3, 3, 40, 900, 25_000] {
            l.record(Duration::from_micros(us));
        }
        let text = serde_json::to_string(&l).expect("serialise");
        let back: Latencies = serde_json::from_str(&text).expect("parse");
        assert_eq!(back, l);
        assert_eq!(back.summary(), l.summary());
        let bad = r#"{"count":1,"max_ns":5,"buckets":[[100000,1]]}"#;
        let err = serde_json::from_str::<Latencies>(bad).expect_err("out of range");
        assert!(err.to_string().contains("bucket 100000"), "{err}");
    }

    #[test]
    fn the_budget_is_two_intervals() {
        assert_eq!(budget(100), Duration::from_millis(20));
        assert_eq!(budget(10), Duration::from_millis(200));
    }

    #[test]
    fn buckets_cover_their_values_within_a_sixteenth() {
        for ns in (0..5000).chain([65_535, 1 << 20, 123_456_789, (1 << 41) - 1]) {
            let b = bucket(ns);
            assert!(upper(b) >= ns, "{ns}");
            assert!(b == 0 || upper(b - 1) < ns, "{ns}");
            assert!(upper(b) - ns <= ns / 16, "{ns}: {}", upper(b));
        }
        assert_eq!(bucket(u64::MAX), BUCKETS - 1);
    }

    #[test]
    fn percentiles_are_nearest_rank_and_merge() {
        let mut a = Latencies::default();
        for us in 1..=100 {
            a.record(Duration::from_micros(us));
        }
        let s = a.summary();
        assert_eq!(s.count, 100);
        // 50 µs and 99 µs, each reported at most 1/16 above.
        assert!((50.0..=50.0 * 17.0 / 16.0).contains(&s.p50_us), "{s:?}");
        assert!((99.0..=99.0 * 17.0 / 16.0).contains(&s.p99_us), "{s:?}");
        assert_eq!(s.max_us, 100.0);
        let mut b = Latencies::default();
        b.record(Duration::from_millis(5));
        a += b;
        assert_eq!(a.count(), 101);
        assert_eq!(a.max(), Duration::from_millis(5));
        assert_eq!(Latencies::default().summary(), LatencySummary::default());
    }
}
