//! The push task's protocol (`docs/spec/experiments.md` §3.1–§3.4): the
//! variants, how the driver's configuration bits change them, and the jobs
//! of one experiment.

use learner::eval::{
    draft_training_starts, test_positions, training_start_in, two_object_test_positions,
    FIXED_TRAINING_STARTS, TRAINING_START_RANGE, WIDE_TRAINING_START_RANGE,
};
use learner::flags;
use learner::{BLUE_ID, RED_ID};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::experiment::seed;
use crate::results::constant_feedback;
use crate::results::push_task::EXPERIMENT;
use crate::scene::{self, Transfer, LOW_RATE_HZ, RATE_HZ};

/// The thesis's learning-curve N_train values (`docs/spec/experiments.md` §3.1).
pub const DEFAULT_TRAIN_RUNS: [usize; 7] = [1, 2, 3, 5, 10, 20, 30];

/// Training starts of the two-object experiment (`docs/spec/experiments.md` §3.3); the
/// first variant uses the first six.
pub const TWO_OBJECT_TRAINING_STARTS: [f64; 7] = [-0.18, 0.18, 0.0, -0.73, -0.47, -0.6, -0.4];

/// The push-task variants of `docs/spec/experiments.md` §3.1–§3.4 (and the
/// draft's protocol), each described in its
/// [`Named`](pushlearn_core::Named) implementation, which `--help` shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Variant {
    Random,
    FixedThree,
    ConstantFeedback,
    TwoObjects,
    Draft,
}

/// Seed of the draft protocol's test starts: the original reseeded its
/// generator with 4321 before every test phase (`docs/spec/experiments.md` §5), which
/// is what the draft's "another seed is set after the training is done, so
/// that all models are tested on the same starting positions" describes.
/// The original's generator cannot be reproduced, so the 20 starts differ
/// from the draft's; they are the same for every model, flag and --seed.
pub const DRAFT_TEST_SEED: u64 = 4321;

/// Number of test runs of the draft protocol (draft §6.1.2: "over 20 test
/// runs").
pub const DRAFT_TEST_RUNS: usize = 20;

/// The draft protocol's test starts: [`DRAFT_TEST_RUNS`] uniform draws in
/// [−0.35, 0.35) from [`DRAFT_TEST_SEED`], in draw order.
#[must_use]
pub fn draft_test_positions() -> Vec<f64> {
    use rand::SeedableRng;
    let mut rng = ChaCha8Rng::seed_from_u64(DRAFT_TEST_SEED);
    (0..DRAFT_TEST_RUNS)
        .map(|_| training_start_in(rng.random::<f64>(), WIDE_TRAINING_START_RANGE))
        .collect()
}

/// How a push-task experiment places its runs and how fast the world
/// publishes: the variant's protocol, changed by the driver's
/// configuration bits (`docs/spec/experiments.md` §1: 2 LOWFREQ, 4 ALLOWMISSPOSITIONS,
/// 8 FIXFIRSTTHREETRAININGRUNS).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Protocol {
    pub variant: Variant,
    /// Training starts that replace the random ones, run by run.
    pub fixed_starts: Vec<f64>,
    /// Width of the random training start range, centred on 0.
    pub start_range: f64,
    pub test_positions: Vec<f64>,
    /// The world's publish rate and the learner's update rate.
    pub rate_hz: u32,
    /// The objects the runs are about, in the `objects` scene; `None`: the
    /// variant's own scene and blocks.
    pub transfer: Option<Transfer>,
}

impl Protocol {
    /// The protocol of `variant` under configuration number `config`.
    #[must_use]
    pub fn new(variant: Variant, config: u32) -> Self {
        let mut fixed_starts = match variant {
            Variant::Draft => draft_training_starts().to_vec(),
            _ => variant.fixed_starts().to_vec(),
        };
        if config & flags::FIXFIRSTTHREETRAININGRUNS != 0 && fixed_starts.is_empty() {
            fixed_starts = FIXED_TRAINING_STARTS.to_vec();
        }
        let wide = variant == Variant::Draft || config & flags::ALLOWMISSPOSITIONS != 0;
        Self {
            variant,
            fixed_starts,
            start_range: if wide {
                WIDE_TRAINING_START_RANGE
            } else {
                TRAINING_START_RANGE
            },
            test_positions: variant.test_positions(),
            rate_hz: if config & flags::LOWFREQ != 0 {
                LOW_RATE_HZ
            } else {
                RATE_HZ
            },
            transfer: None,
        }
    }

    /// The protocol with its runs about the objects of `transfer`.
    #[must_use]
    pub fn with_transfer(mut self, transfer: Option<Transfer>) -> Self {
        self.transfer = transfer;
        self
    }

    /// The scene the world must load.
    #[must_use]
    pub fn scene(&self) -> &'static str {
        if self.transfer.is_some() {
            scene::SCENE
        } else {
            self.variant.scene()
        }
    }
}

impl From<Variant> for Protocol {
    fn from(variant: Variant) -> Self {
        Self::new(variant, 0)
    }
}

impl pushlearn_core::Named for Variant {
    const ALL: &'static [Self] = &[
        Variant::Random,
        Variant::FixedThree,
        Variant::ConstantFeedback,
        Variant::TwoObjects,
        Variant::Draft,
    ];

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            Variant::Random => {
                "§3.1: every training start uniform in [−0.25, 0.25) (configuration 0)"
            }
            Variant::FixedThree => "§3.2: configuration 8, training starts −0.18, 0.18, 0.0",
            Variant::ConstantFeedback => {
                "§3.4: no training, feedback from real states, 10 Hz (qualitative)"
            }
            Variant::TwoObjects => {
                "§3.3: both blocks; six (or, with `--train-runs 7`, seven) fixed starts"
            }
            Variant::Draft => {
                "The thesis draft's protocol (draft §6.1.1): training starts at the block's \
                 left end, right end and centre, then uniform in [−0.35, 0.35); 20 test starts \
                 drawn once from a fixed seed in the same range"
            }
        }
    }
}

impl Variant {
    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Variant::Random => "random",
            Variant::FixedThree => "fixed-three",
            Variant::ConstantFeedback => constant_feedback::VARIANT,
            Variant::TwoObjects => "two-objects",
            Variant::Draft => "draft",
        }
    }

    /// The scene the world must load.
    #[must_use]
    pub fn scene(self) -> &'static str {
        match self {
            Variant::TwoObjects => "two_blocks",
            _ => "one_block",
        }
    }

    /// Fixed training starts that replace the random ones, run by run.
    #[must_use]
    pub fn fixed_starts(self) -> &'static [f64] {
        match self {
            Variant::Random | Variant::ConstantFeedback | Variant::Draft => &[],
            Variant::FixedThree => &FIXED_TRAINING_STARTS,
            Variant::TwoObjects => &TWO_OBJECT_TRAINING_STARTS,
        }
    }

    /// The N_train values the thesis used for this variant.
    #[must_use]
    pub fn default_train_runs(self) -> Vec<usize> {
        match self {
            Variant::Random => DEFAULT_TRAIN_RUNS.to_vec(),
            Variant::FixedThree => vec![3],
            Variant::TwoObjects => vec![6],
            Variant::ConstantFeedback => Vec::new(),
            // The draft's tables: 3 and 10 training runs.
            Variant::Draft => vec![3, 10],
        }
    }

    /// The test starts.
    #[must_use]
    pub fn test_positions(self) -> Vec<f64> {
        match self {
            Variant::TwoObjects => two_object_test_positions().to_vec(),
            // §3.4: the left corner, then the right one.
            Variant::ConstantFeedback => vec![-0.25, 0.25],
            Variant::Random | Variant::FixedThree => test_positions().to_vec(),
            Variant::Draft => draft_test_positions(),
        }
    }

    /// Blocks whose errors are reported: the blue one, and in the two-object
    /// scene the red one too.
    #[must_use]
    pub fn blocks(self) -> &'static [u32] {
        match self {
            Variant::TwoObjects => &[BLUE_ID, RED_ID],
            _ => &[BLUE_ID],
        }
    }
}

/// One (N_train, fold) of a push-task experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PushJob {
    pub n_train: usize,
    pub fold: usize,
    pub protocol: Protocol,
    /// Seed of the job's generator (training starts).
    pub seed: u64,
    /// Seed for the world's latency emulation.
    pub latency_seed: u64,
}

impl PushJob {
    /// The job in messages, e.g. `N_train 10 fold 3`.
    #[must_use]
    pub fn name(&self) -> String {
        format!("N_train {} fold {}", self.n_train, self.fold)
    }

    /// The jobs of one experiment in report order: for each N_train, for each
    /// fold (`docs/spec/experiments.md` §3, outer loops).
    #[must_use]
    pub fn all(
        protocol: impl Into<Protocol>,
        train_runs: &[usize],
        folds: usize,
        seed: u64,
    ) -> Vec<PushJob> {
        let protocol = protocol.into();
        let mut jobs = Vec::with_capacity(train_runs.len() * folds);
        for &n_train in train_runs {
            for fold in 0..folds {
                let coords = [n_train as u64, fold as u64];
                jobs.push(PushJob {
                    n_train,
                    fold,
                    protocol: protocol.clone(),
                    seed: seed::derive(seed, EXPERIMENT, &coords, seed::Stream::Driver),
                    latency_seed: seed::derive(seed, EXPERIMENT, &coords, seed::Stream::Latency),
                });
            }
        }
        jobs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_draft_protocol_starts_at_the_blocks_ends_and_tests_on_a_fixed_seed() {
        let p = Protocol::from(Variant::Draft);
        assert_eq!(p.fixed_starts, [-0.25, 0.25, 0.0]);
        assert_eq!(p.start_range, 0.7);
        assert_eq!(p.rate_hz, 100);
        assert_eq!(p.test_positions.len(), DRAFT_TEST_RUNS);
        assert!(p.test_positions.iter().all(|x| (-0.35..0.35).contains(x)));
        // The same 20 starts whatever the seed, N_train or fold.
        let jobs = PushJob::all(Variant::Draft, &[3, 10], 2, 99);
        assert!(jobs
            .iter()
            .all(|j| j.protocol.test_positions == p.test_positions));
        assert_eq!(Variant::Draft.default_train_runs(), [3, 10]);
    }

    #[test]
    fn jobs_are_ordered_by_n_train_then_fold_with_distinct_seeds() {
        let jobs = PushJob::all(Variant::Random, &[1, 3], 2, 5);
        let coords: Vec<(usize, usize)> = jobs.iter().map(|j| (j.n_train, j.fold)).collect();
        assert_eq!(coords, [(1, 0), (1, 1), (3, 0), (3, 1)]);
        let mut seeds: Vec<u64> = jobs.iter().flat_map(|j| [j.seed, j.latency_seed]).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), 8);
    }
}
