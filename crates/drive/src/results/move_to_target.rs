//! What Move to Target (`docs/spec/experiments.md` §4) measured: each test
//! run's outcome and error trace ([`MttRun`]), each job's result, and the
//! §7.6 columns of one target ([`TargetSummary`]).

use std::f64::consts::PI;

use learner::eval::MeanStd;
use learner::{ModelStats, ObjectState};
use serde::{Deserialize, Serialize};

use super::run_info::{Counters, Timing};

/// Name used for seeds and reports.
pub const EXPERIMENT: &str = "move-to-target";

/// The thesis's repetitions per target; the tables compare only runs with
/// as many repetitions with the thesis's values.
pub const REPETITIONS: usize = 5;

/// §4.2: the four targets (global block poses; target 4's θ is π in the
/// original code).
pub const TARGETS: [ObjectState; 4] = [
    ObjectState::new(0.6, 0.7, -2.1),
    ObjectState::new(-0.6, 0.7, 0.75),
    ObjectState::new(-0.6, -0.7, 0.0),
    ObjectState::new(0.6, -0.7, PI),
];

/// Where sampled targets lie (`--sample-targets`, the same region as the
/// Gymnasium environments' `TargetRegion`, `docs/gym.md`): block centres
/// with x in [−0.7, 0.7) m and y in [−0.8, 0.8) m, any yaw in [−π, π); the
/// actuator can reach every side of such a block.
pub const SAMPLED_X: (f64, f64) = (-0.7, 0.7);
/// See [`SAMPLED_X`].
pub const SAMPLED_Y: (f64, f64) = (-0.8, 0.8);
/// A sampled target is at least this far (m) from the block's start, so
/// that no run begins solved.
pub const SAMPLED_MIN_TRAVEL: f64 = 0.3;

/// `n` targets drawn uniformly from the sampled region by rejection, from
/// a generator seeded with `seed` alone, so that every model meets the
/// same targets: x, y and θ in that order per draw.
#[must_use]
pub fn sampled_targets(n: usize, seed: u64, block_start: (f64, f64)) -> Vec<ObjectState> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut targets = Vec::with_capacity(n);
    while targets.len() < n {
        let x = rng.random_range(SAMPLED_X.0..SAMPLED_X.1);
        let y = rng.random_range(SAMPLED_Y.0..SAMPLED_Y.1);
        let theta = rng.random_range(-PI..PI);
        if (x - block_start.0).hypot(y - block_start.1) >= SAMPLED_MIN_TRAVEL {
            targets.push(ObjectState::new(x, y, theta));
        }
    }
    targets
}

/// The outcome of one test run (§4.3, §7.6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MttRun {
    /// The world's block met the goal (`learner::eval::goal_reached`) on
    /// the message that ended the run; never the learner's word.
    pub reached: bool,
    /// `step_counter − 1` on the message that ended the run.
    pub steps: u64,
    /// Final block centre distance to the target.
    pub pos_err: f64,
    /// Final `|wrap(θ − θ_t)|`.
    pub ori_err: f64,
    /// The block's pose in the last message.
    pub final_block: ObjectState,
    /// The block's error to the target during the run, for the figures.
    #[serde(default)]
    pub trace: ErrorTrace,
}

/// Messages between two points of an [`ErrorTrace`].
pub const TRACE_EVERY: u64 = 10;

/// The block's position and orientation error to the target on every
/// [`TRACE_EVERY`]th message of a test run (steps 0, 10, 20, …) and on the
/// one that ended it; rounded to 0.1 mm and 0.1 mrad, which is finer than
/// any figure shows and keeps the JSON small.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorTrace {
    /// Steps (actions sent before the message) of the points.
    pub steps: Vec<u64>,
    pub pos_err: Vec<f64>,
    pub ori_err: Vec<f64>,
}

impl ErrorTrace {
    pub(crate) fn push(&mut self, step: u64, (pos_err, ori_err): (f64, f64)) {
        let round = |v: f64| (v * 1e4).round() / 1e4;
        self.steps.push(step);
        self.pos_err.push(round(pos_err));
        self.ori_err.push(round(ori_err));
    }
}

/// What one finished job contributes to the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MttJobResult {
    pub target_index: usize,
    pub repetition: usize,
    pub run: MttRun,
    pub nodes_after_training: ModelStats,
    pub nodes_after_test: ModelStats,
    pub counters: Counters,
    pub timing: Timing,
}

/// §7.6 columns of one target, and the final error of all its runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetSummary {
    /// Runs that reached the target, as the world judged them.
    pub reached: usize,
    pub runs: usize,
    /// Mean final position error of the runs that failed (`None` if all reached).
    pub pos_err_failed: Option<f64>,
    /// Mean final orientation error of the runs that failed.
    pub ori_err_failed: Option<f64>,
    /// Mean steps over all runs (failures count the limit).
    pub steps: f64,
    /// Mean steps over the runs that reached the target (`None` if none did).
    pub steps_reached: Option<f64>,
    /// Mean final position error of every run, reached or not (`None` in
    /// documents written before it was kept).
    #[serde(default)]
    pub pos_err_all: Option<f64>,
    /// Mean final orientation error of every run, reached or not.
    #[serde(default)]
    pub ori_err_all: Option<f64>,
}

impl TargetSummary {
    /// Summarises one target's runs.
    #[must_use]
    pub fn of(runs: &[MttRun]) -> Self {
        let mean = |v: &[f64]| (!v.is_empty()).then(|| MeanStd::of(v).mean);
        let failed: Vec<&MttRun> = runs.iter().filter(|r| !r.reached).collect();
        let reached: Vec<f64> = runs
            .iter()
            .filter(|r| r.reached)
            .map(|r| r.steps as f64)
            .collect();
        let all: Vec<f64> = runs.iter().map(|r| r.steps as f64).collect();
        Self {
            reached: reached.len(),
            runs: runs.len(),
            pos_err_failed: mean(&failed.iter().map(|r| r.pos_err).collect::<Vec<_>>()),
            ori_err_failed: mean(&failed.iter().map(|r| r.ori_err).collect::<Vec<_>>()),
            steps: mean(&all).unwrap_or(f64::NAN),
            steps_reached: mean(&reached),
            pos_err_all: mean(&runs.iter().map(|r| r.pos_err).collect::<Vec<_>>()),
            ori_err_all: mean(&runs.iter().map(|r| r.ori_err).collect::<Vec<_>>()),
        }
    }
}

#[cfg(test)]
mod tests {

    #[test]
    fn sampled_targets_are_seeded_reachable_and_away_from_the_start() {
        let targets = super::sampled_targets(200, 1, (0.0, 0.25));
        assert_eq!(targets, super::sampled_targets(200, 1, (0.0, 0.25)));
        assert_ne!(targets, super::sampled_targets(200, 2, (0.0, 0.25)));
        for t in &targets {
            assert!(
                (-0.7..0.7).contains(&t.x) && (-0.8..0.8).contains(&t.y),
                "{t:?}"
            );
            assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(&t.theta));
            assert!(t.x.hypot(t.y - 0.25) >= super::SAMPLED_MIN_TRAVEL, "{t:?}");
        }
        // Uniform, not clustered: every quadrant of the region gets some.
        for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            let n = targets
                .iter()
                .filter(|t| t.x * sx > 0.0 && t.y * sy > 0.0)
                .count();
            assert!(n > 20, "{n} in quadrant ({sx}, {sy})");
        }
    }
    use super::*;

    #[test]
    fn target_summary_follows_the_thesis_columns() {
        let run = |reached, steps, pos_err| MttRun {
            reached,
            steps,
            pos_err,
            ori_err: pos_err / 10.0,
            final_block: ObjectState::default(),
            trace: ErrorTrace::default(),
        };
        let s = TargetSummary::of(&[
            run(true, 1000, 0.0),
            run(false, 3000, 0.5),
            run(true, 2000, 0.0),
            run(false, 3000, 0.7),
        ]);
        assert_eq!((s.reached, s.runs), (2, 4));
        assert!((s.pos_err_failed.unwrap() - 0.6).abs() < 1e-12);
        assert!((s.ori_err_failed.unwrap() - 0.06).abs() < 1e-12);
        assert_eq!(s.steps, 2250.0);
        assert_eq!(s.steps_reached, Some(1500.0));
        assert!((s.pos_err_all.unwrap() - 0.3).abs() < 1e-12);
        assert!((s.ori_err_all.unwrap() - 0.03).abs() < 1e-12);
        let all = TargetSummary::of(&[run(true, 10, 0.0)]);
        assert_eq!(all.pos_err_failed, None);
        assert_eq!(all.steps_reached, Some(10.0));
    }
}
