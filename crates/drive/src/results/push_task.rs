//! What the push task (`docs/spec/experiments.md` §3) measured: each job's
//! errors and end poses ([`PushJobResult`]), and [`summarise`], which turns
//! them into the learning-curve entries of the §7 tables ([`CurveEntry`]).

use std::collections::BTreeMap;

use learner::eval::{CurveSummary, MeanStd, PositionErrors, RunErrors};
use learner::keypoints::{KeyPointRun, KeyPointScore};
use learner::{ModelStats, Poses, BLUE_ID, RED_ID};
use serde::{Deserialize, Serialize};

use super::nodes::NodeSummary;
use super::run_info::{Counters, Timing};

/// Name used for seeds and reports.
pub const EXPERIMENT: &str = "push-task";

/// Why job results cannot be summarised.
#[derive(Debug, thiserror::Error)]
pub enum SummaryError {
    /// No errors were recorded for a block at some test position.
    #[error("no errors were recorded for block {id} at some test position")]
    MissingBlock { id: u32 },
    /// An N_train value without finished jobs.
    #[error("no finished job for N_train = {n_train}")]
    NoJobs { n_train: usize },
}

/// A test run's end: the real state of the message that ended it and the
/// chained prediction scored against it (`docs/spec/experiments.md` §7.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndPoses {
    /// The run's start x of the actuator.
    pub x0: f64,
    pub actual: Poses,
    pub predicted: Poses,
}

/// How often the model's AC selector chose, for the real state and action
/// of a test message, the AC that the model's own assignment gives to the
/// real transition that followed (models without a selector count nothing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SelectionCount {
    /// Transitions sampled.
    pub samples: u64,
    /// Of those, the selector chose the AC of the transition.
    pub agreed: u64,
    /// Of those, no AC has the transition's changed-feature set, so no
    /// selector could be right.
    pub unknown: u64,
}

impl SelectionCount {
    fn add(&mut self, other: SelectionCount) {
        self.samples += other.samples;
        self.agreed += other.agreed;
        self.unknown += other.unknown;
    }

    /// `agreed / samples`, `None` without samples.
    #[must_use]
    pub fn accuracy(&self) -> Option<f64> {
        (self.samples > 0).then(|| self.agreed as f64 / self.samples as f64)
    }
}

/// What one finished job contributes to the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PushJobResult {
    pub n_train: usize,
    pub fold: usize,
    pub training_starts: Vec<f64>,
    /// Per test position, in order.
    pub errors: Vec<RunErrors>,
    /// Per test position, in order.
    pub end_poses: Vec<EndPoses>,
    pub nodes: ModelStats,
    pub counters: Counters,
    pub timing: Timing,
    /// The draft's key-point scores per test run, in order.
    #[serde(default)]
    pub keypoints: Vec<KeyPointRun>,
    #[serde(default)]
    pub selection: SelectionCount,
}

/// Per-position mean and population std over folds (§7.3) of one block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PositionSummary {
    pub x0: f64,
    pub block_pos_err: MeanStd,
    pub block_ori_err: MeanStd,
    pub actuator_pos_err: MeanStd,
}

/// Learning-curve values of one block for one N_train (§7.4); "std" is the
/// mean of the per-position standard deviations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockCurve {
    pub block_pos_err: MeanStd,
    pub block_ori_err: MeanStd,
    pub actuator_pos_err: MeanStd,
    /// The same over the 15 interacting positions (single-block test
    /// positions only).
    pub interacting: InteractingCurve,
    pub per_position: Vec<PositionSummary>,
}

/// §7.4 over the interacting positions, with the original script's actuator
/// value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InteractingCurve {
    pub block_pos_err: MeanStd,
    pub block_ori_err: MeanStd,
    pub actuator_pos_err: MeanStd,
    /// Mean over the interacting positions of (mean + std) / 2: what the
    /// thesis's figure plotted for the actuator (§7.4 quirk).
    pub actuator_pos_err_script_quirk: f64,
}

/// Everything reported for one N_train.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveEntry {
    pub train_runs: usize,
    /// The blue block's values (flattened: `block_pos_err`, `per_position`, …).
    #[serde(flatten)]
    pub blue: BlockCurve,
    /// The red block's values in the two-object scene.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub red: Option<BlockCurve>,
    pub nodes: NodeSummary,
    pub folds: usize,
    /// The thesis draft's key-point scores (draft §6.1.2) per body id
    /// (actuator 8), each the mean over every test run of every fold.
    #[serde(default)]
    pub keypoints: BTreeMap<u32, KeyPointScore>,
    /// The AC selector's agreement on the test runs' real transitions
    /// (interaction model only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<SelectionCount>,
    /// Per fold (in fold order), the mean actuator error over its test
    /// runs: the actuator prediction of one trained model, whose spread
    /// over folds the learning-curve "std" hides.
    #[serde(default)]
    pub actuator_pos_err_by_fold: Vec<f64>,
    /// Every fold's training starts and test-run errors, in fold order, for
    /// users' own analysis of `--json` (spreads, paired comparisons). Absent
    /// from the reproduction's documents ([`CurveEntry::without_folds`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub by_fold: Vec<FoldDetail>,
    /// The first fold's test-run end configurations, for the snapshot
    /// figures.
    #[serde(default)]
    pub end_poses: Vec<EndPoses>,
}

/// One fold of one N_train: what it trained on and how each test run erred.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FoldDetail {
    pub fold: usize,
    /// The actuator's start x of each training run, in order [m].
    pub training_starts: Vec<f64>,
    /// Means over the fold's test runs: the blue block's position [m] and
    /// orientation [rad] errors and the actuator's position error [m].
    pub block_pos_err: f64,
    pub block_ori_err: f64,
    pub actuator_pos_err: f64,
    /// Per test run, in the order of `per_position`: the actuator's error
    /// and each block's (by id) position and orientation errors.
    pub runs: Vec<RunErrors>,
}

impl FoldDetail {
    fn of(job: &PushJobResult) -> Self {
        let mean = |f: &dyn Fn(&RunErrors) -> Option<f64>| {
            MeanStd::of(&job.errors.iter().filter_map(f).collect::<Vec<_>>()).mean
        };
        Self {
            fold: job.fold,
            training_starts: job.training_starts.clone(),
            block_pos_err: mean(&|e| e.blocks.get(&BLUE_ID).map(|b| b.pos)),
            block_ori_err: mean(&|e| e.blocks.get(&BLUE_ID).map(|b| b.ori)),
            actuator_pos_err: mean(&|e| Some(e.actuator)),
            runs: job.errors.clone(),
        }
    }
}

impl CurveEntry {
    /// The entry without [`CurveEntry::by_fold`]: the reproduction's
    /// documents are the sources of docs/results.md and are checked byte
    /// for byte, so they hold what the page shows; the fold-level data is
    /// for `--json` users (and would make every document several times
    /// larger).
    #[must_use]
    pub fn without_folds(mut self) -> Self {
        self.by_fold = Vec::new();
        self
    }
}

/// Per body, the mean of each key-point score over `runs`.
#[must_use]
pub fn mean_keypoints<'a>(
    runs: impl IntoIterator<Item = &'a KeyPointRun>,
) -> BTreeMap<u32, KeyPointScore> {
    let mut sums: BTreeMap<u32, (KeyPointScore, usize)> = BTreeMap::new();
    for run in runs {
        for (&id, s) in &run.bodies {
            let (sum, n) = sums.entry(id).or_default();
            sum.final_dif += s.final_dif;
            sum.cum_dif += s.cum_dif;
            sum.mean_dif += s.mean_dif;
            sum.predictions += s.predictions;
            *n += 1;
        }
    }
    sums.into_iter()
        .map(|(id, (s, n))| {
            let k = n as f64;
            (
                id,
                KeyPointScore {
                    final_dif: s.final_dif / k,
                    cum_dif: s.cum_dif / k,
                    mean_dif: s.mean_dif / k,
                    predictions: s.predictions / n,
                },
            )
        })
        .collect()
}

fn mean_std(p: learner::eval::CurvePoint) -> MeanStd {
    MeanStd {
        mean: p.mean,
        std: p.error_bar,
    }
}

fn block_curve(
    positions: &[PositionErrors],
    x0: &[f64],
    id: u32,
) -> Result<BlockCurve, SummaryError> {
    let summary = CurveSummary::of(positions, id).ok_or(SummaryError::MissingBlock { id })?;
    let per_position = positions
        .iter()
        .zip(x0)
        .map(|(p, &x0)| {
            let get = |m: &BTreeMap<u32, Vec<f64>>| MeanStd::of(m.get(&id).map_or(&[][..], |v| v));
            PositionSummary {
                x0,
                block_pos_err: get(&p.block_pos),
                block_ori_err: get(&p.block_ori),
                actuator_pos_err: MeanStd::of(&p.actuator),
            }
        })
        .collect();
    Ok(BlockCurve {
        block_pos_err: mean_std(summary.block_pos),
        block_ori_err: mean_std(summary.block_ori),
        actuator_pos_err: mean_std(summary.actuator),
        interacting: InteractingCurve {
            block_pos_err: mean_std(summary.block_pos_interacting),
            block_ori_err: mean_std(summary.block_ori_interacting),
            actuator_pos_err: mean_std(summary.actuator_interacting),
            actuator_pos_err_script_quirk: summary.actuator_interacting_quirk,
        },
        per_position,
    })
}

/// The report entries, one per N_train in the order of `train_runs`, from
/// job results in any order: errors at `test_positions` (the jobs' test
/// starts, in order) of the blue block, and of the red one if `blocks` (the
/// blocks whose errors are reported) has it.
///
/// # Errors
/// A block without errors at some position (e.g. the red block asked for in
/// a one-block scene), or an N_train without jobs.
pub fn summarise(
    test_positions: &[f64],
    blocks: &[u32],
    train_runs: &[usize],
    results: &[PushJobResult],
) -> Result<Vec<CurveEntry>, SummaryError> {
    let x0 = test_positions;
    train_runs
        .iter()
        .map(|&n| {
            let mut jobs: Vec<&PushJobResult> = results.iter().filter(|r| r.n_train == n).collect();
            jobs.sort_by_key(|r| r.fold);
            if jobs.is_empty() {
                return Err(SummaryError::NoJobs { n_train: n });
            }
            let mut positions = vec![PositionErrors::default(); x0.len()];
            for job in &jobs {
                for (p, e) in positions.iter_mut().zip(&job.errors) {
                    p.push(e);
                }
            }
            let blue = block_curve(&positions, x0, BLUE_ID)?;
            let red = blocks
                .contains(&RED_ID)
                .then(|| block_curve(&positions, x0, RED_ID))
                .transpose()?;
            let stats: Vec<&ModelStats> = jobs.iter().map(|j| &j.nodes).collect();
            let by_fold: Vec<FoldDetail> = jobs.iter().map(|j| FoldDetail::of(j)).collect();
            let actuator_pos_err_by_fold = by_fold.iter().map(|f| f.actuator_pos_err).collect();
            Ok(CurveEntry {
                train_runs: n,
                blue,
                red,
                nodes: NodeSummary::of(&stats),
                folds: jobs.len(),
                keypoints: mean_keypoints(jobs.iter().flat_map(|j| &j.keypoints)),
                selection: jobs
                    .iter()
                    .map(|j| j.selection)
                    .reduce(|mut a, b| {
                        a.add(b);
                        a
                    })
                    .filter(|c| c.samples > 0),
                actuator_pos_err_by_fold,
                by_fold,
                end_poses: jobs[0].end_poses.clone(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use learner::eval::{test_positions, two_object_test_positions, BlockError};

    use super::*;

    fn result(n_train: usize, fold: usize, pos: impl Fn(usize) -> f64) -> PushJobResult {
        let errors = (0..21)
            .map(|i| RunErrors {
                actuator: 0.001,
                blocks: BTreeMap::from([(
                    BLUE_ID,
                    BlockError {
                        pos: pos(i),
                        ori: 0.0,
                    },
                )]),
            })
            .collect();
        PushJobResult {
            n_train,
            fold,
            training_starts: vec![0.0; n_train],
            errors,
            end_poses: Vec::new(),
            nodes: ModelStats::default(),
            counters: Counters::default(),
            timing: Default::default(),
            keypoints: Vec::new(),
            selection: SelectionCount::default(),
        }
    }

    #[test]
    fn summaries_use_per_position_population_stds_in_the_given_order() {
        // Fold 0 errs by 0.1 everywhere, fold 1 by 0.3: per-position mean
        // 0.2, population std 0.1 (not the sample std 0.141).
        let results = vec![
            result(3, 1, |_| 0.3),
            result(1, 0, |_| 0.0),
            result(3, 0, |_| 0.1),
        ];
        let curve = summarise(&test_positions(), &[BLUE_ID], &[3, 1], &results).unwrap();
        assert_eq!(curve[0].train_runs, 3);
        assert_eq!(curve[0].folds, 2);
        let pos = curve[0].blue.block_pos_err;
        assert!((pos.mean - 0.2).abs() < 1e-12 && (pos.std - 0.1).abs() < 1e-12);
        assert_eq!(curve[0].blue.per_position.len(), 21);
        assert_eq!(curve[0].blue.per_position[0].x0, -0.35);
        assert_eq!(curve[1].blue.block_pos_err.mean, 0.0);
        assert!(curve[0].red.is_none());
        // The red block cannot be summarised without its errors.
        assert!(matches!(
            summarise(
                &two_object_test_positions(),
                &[BLUE_ID, RED_ID],
                &[1],
                &results
            ),
            Err(SummaryError::MissingBlock { id: RED_ID })
        ));
        assert!(matches!(
            summarise(&test_positions(), &[BLUE_ID], &[5], &results),
            Err(SummaryError::NoJobs { n_train: 5 })
        ));
    }

    #[test]
    fn fold_detail_has_every_run_of_every_fold_and_the_curve_mean() {
        let results: Vec<PushJobResult> = (0..3)
            .map(|f| {
                let mut r = result(2, f, move |i| 0.01 * (i + 7 * f) as f64);
                r.training_starts = vec![0.1 * f as f64, -0.2];
                r
            })
            .collect();
        let curve = summarise(&test_positions(), &[BLUE_ID], &[2], &results).unwrap();
        let e = &curve[0];
        assert_eq!(e.by_fold.len(), 3);
        assert!(e.by_fold.iter().all(|f| f.runs.len() == 21));
        assert_eq!(e.by_fold[1].fold, 1);
        assert_eq!(e.by_fold[2].training_starts, vec![0.2, -0.2]);
        let mean = e.by_fold.iter().map(|f| f.block_pos_err).sum::<f64>() / 3.0;
        assert!((mean - e.blue.block_pos_err.mean).abs() < 1e-12);
        assert_eq!(
            e.actuator_pos_err_by_fold,
            e.by_fold
                .iter()
                .map(|f| f.actuator_pos_err)
                .collect::<Vec<_>>()
        );
        // Kept out of the reproduction's documents, and then not written.
        let stripped = e.clone().without_folds();
        assert!(stripped.by_fold.is_empty());
        let json = serde_json::to_value(&stripped).unwrap();
        assert!(json.get("by_fold").is_none());
        assert!(serde_json::to_value(e).unwrap()["by_fold"][2]["runs"][20].is_object());
    }

    #[test]
    fn interacting_values_leave_out_the_misses() {
        let results = vec![result(
            1,
            0,
            |i| if (3..=17).contains(&i) { 0.0 } else { 1.0 },
        )];
        let curve = summarise(&test_positions(), &[BLUE_ID], &[1], &results).unwrap();
        assert_eq!(curve[0].blue.interacting.block_pos_err.mean, 0.0);
        assert!((curve[0].blue.block_pos_err.mean - 6.0 / 21.0).abs() < 1e-12);
        assert!((curve[0].blue.interacting.actuator_pos_err_script_quirk - 0.0005).abs() < 1e-12);
    }
}
