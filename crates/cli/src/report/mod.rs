//! What the experiments report: the JSON documents ([`PushReport`],
//! [`FeedbackReport`], [`MttReport`]) and the terminal tables in the
//! thesis's layout beside the thesis's numbers ([`table`], [`reference`]).
//!
//! Every document separates what the experiment measured (`results`,
//! `runs`, `targets`: identical for identical seeds in lock-step) from how
//! the run went (`run`: wall-clock times, too-slow counts).

pub mod draft;
pub mod plot;
pub mod reference;
pub mod table;

use serde::{Deserialize, Serialize};

use crate::experiment::constant_feedback::FeedbackRun;
use crate::experiment::driver::Counters;
use crate::experiment::link::Timing;
use crate::experiment::move_to_target::{MttRun, TargetSummary};
use crate::experiment::nodes::NodeSummary;
use crate::experiment::push_task::CurveEntry;
use crate::latency::budget;

/// How an experiment's run went: message counts, the timing requirement of
/// `docs/spec/experiments.md` §6, start-position corrections.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    pub workers: usize,
    pub wall_seconds: f64,
    /// World states handled by the drivers.
    pub messages: u64,
    /// Messages whose handling took longer than `budget_seconds`.
    pub too_slow: u64,
    pub too_slow_fraction: f64,
    /// 2/f (`docs/spec/experiments.md` §6).
    pub budget_seconds: f64,
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
    /// Messages dropped after resets and repositionings.
    pub ignored: u64,
    /// Failed start-position checks (each answered by a SetPose).
    pub reset_errors: u64,
    pub parse_errors: u64,
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
        Self {
            workers,
            wall_seconds,
            messages: timing.messages,
            too_slow: timing.too_slow,
            too_slow_fraction: timing.too_slow_fraction(),
            budget_seconds: budget(publish_rate_hz).as_secs_f64(),
            mean_handling_ms: mean * 1e3,
            simulated_states: timing.messages,
            p50_handling_us: timing.histogram.summary().p50_us,
            p99_handling_us: timing.histogram.summary().p99_us,
            max_handling_ms: timing.max_seconds * 1e3,
            ignored: counters.ignored,
            reset_errors: counters.reset_errors,
            parse_errors: counters.parse_errors,
        }
    }
}

/// What identifies an experiment's configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setup {
    pub experiment: String,
    pub model: String,
    pub mode: String,
    pub seed: u64,
}

#[cfg(test)]
impl Setup {
    /// The setup of the tests' reports: `model` in lock-step, seed 1.
    pub(crate) fn for_tests(experiment: &str, model: &str) -> Self {
        Self {
            experiment: experiment.into(),
            model: model.into(),
            mode: "lockstep".into(),
            seed: 1,
        }
    }
}

/// `pushlearn experiment push-task` (all variants but constant feedback).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PushReport {
    #[serde(flatten)]
    pub setup: Setup,
    pub variant: String,
    pub folds: usize,
    pub train_runs: Vec<usize>,
    pub results: Vec<CurveEntry>,
    pub run: RunInfo,
}

/// `pushlearn experiment push-task --variant constant-feedback`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeedbackReport {
    #[serde(flatten)]
    pub setup: Setup,
    pub variant: String,
    pub publish_rate_hz: u32,
    pub runs: Vec<FeedbackRun>,
    pub run: RunInfo,
}

/// One target of `pushlearn experiment move-to-target`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetEntry {
    /// (x, y, θ) of the blue block.
    pub target: [f64; 3],
    pub runs: Vec<MttRun>,
    pub summary: TargetSummary,
    /// Node statistics over repetitions when training ended.
    pub nodes_after_training: NodeSummary,
}

/// `pushlearn experiment move-to-target`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MttReport {
    #[serde(flatten)]
    pub setup: Setup,
    pub repetitions: usize,
    pub max_steps: u64,
    pub targets: Vec<TargetEntry>,
    pub run: RunInfo,
}

/// Any report document, as read back from its JSON.
#[derive(Clone, Debug, PartialEq)]
pub enum AnyReport {
    Push(PushReport),
    Feedback(FeedbackReport),
    MoveToTarget(MttReport),
}

/// Why a saved report cannot be read back.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("not JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("not a pushlearn report: no \"experiment\" key")]
    NoExperiment,
    #[error("unknown experiment {0:?} (expected push-task or move-to-target)")]
    UnknownExperiment(String),
}

impl AnyReport {
    /// Parses a document written by `--json`, telling the kinds apart by
    /// their `experiment` and `variant` keys.
    ///
    /// # Errors
    /// Not JSON, or not one of the report documents.
    pub fn from_json(text: &str) -> Result<Self, ReadError> {
        let value: serde_json::Value = serde_json::from_str(text)?;
        let experiment = value
            .get("experiment")
            .and_then(serde_json::Value::as_str)
            .ok_or(ReadError::NoExperiment)?;
        Ok(match experiment {
            crate::experiment::push_task::EXPERIMENT => {
                if value.get("variant").and_then(serde_json::Value::as_str)
                    == Some(crate::experiment::push_task::Variant::ConstantFeedback.as_str())
                {
                    AnyReport::Feedback(serde_json::from_value(value)?)
                } else {
                    AnyReport::Push(serde_json::from_value(value)?)
                }
            }
            crate::experiment::move_to_target::EXPERIMENT => {
                AnyReport::MoveToTarget(serde_json::from_value(value)?)
            }
            other => return Err(ReadError::UnknownExperiment(other.to_owned())),
        })
    }

    /// The report's setup (experiment, model, mode, seed).
    #[must_use]
    pub fn setup(&self) -> &Setup {
        match self {
            AnyReport::Push(r) => &r.setup,
            AnyReport::Feedback(r) => &r.setup,
            AnyReport::MoveToTarget(r) => &r.setup,
        }
    }
}

/// Writes `report` as pretty JSON to `path`.
///
/// # Errors
/// The file cannot be written.
pub fn write_json<T: Serialize>(path: &std::path::Path, report: &T) -> std::io::Result<()> {
    let mut text = serde_json::to_string_pretty(report).map_err(std::io::Error::other)?;
    text.push('\n');
    std::fs::write(path, text)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use learner::eval::{BlockError, RunErrors};
    use learner::{MapStats, ModelStats, ObjectState, BLUE_ID, RED_ID};
    use serde_json::Value;

    use super::*;
    use crate::experiment::move_to_target::MttRun;
    use crate::experiment::push_task::{summarise, PushJobResult, Variant};
    use crate::models::ModelKind;

    fn job(n_train: usize, fold: usize, two_blocks: bool) -> PushJobResult {
        let e = |x: f64| BlockError {
            pos: x,
            ori: 2.0 * x,
        };
        let errors = (0..21)
            .map(|i| {
                let mut blocks = BTreeMap::from([(BLUE_ID, e(0.01 * (i + fold) as f64))]);
                if two_blocks {
                    blocks.insert(RED_ID, e(0.02));
                }
                RunErrors {
                    actuator: 0.002,
                    blocks,
                }
            })
            .collect();
        let mut nodes = ModelStats::default();
        nodes.maps.insert(
            "gate".into(),
            MapStats {
                update_calls: 149 * n_train as u64,
                inserts: 4,
                nodes: 4,
            },
        );
        PushJobResult {
            n_train,
            fold,
            training_starts: vec![0.0; n_train],
            errors,
            end_poses: Vec::new(),
            nodes,
            counters: Counters {
                messages: 100,
                ignored: 3,
                reset_errors: 1,
                parse_errors: 0,
            },
            timing: Timing {
                messages: 100,
                too_slow: 1,
                busy_seconds: 0.1,
                max_seconds: 0.03,
                ..Timing::default()
            },
            keypoints: Vec::new(),
            selection: Default::default(),
        }
    }

    fn push_report(variant: Variant, train_runs: &[usize]) -> PushReport {
        let jobs: Vec<PushJobResult> = train_runs
            .iter()
            .flat_map(|&n| (0..2).map(move |f| job(n, f, variant == Variant::TwoObjects)))
            .collect();
        PushReport {
            setup: Setup::for_tests("push-task", "gate"),
            variant: variant.as_str().into(),
            folds: 2,
            train_runs: train_runs.to_vec(),
            results: summarise(&variant.into(), train_runs, &jobs).unwrap(),
            run: RunInfo::of(jobs.iter().map(|j| (j.counters, j.timing)), 100, 2, 1.5),
        }
    }

    fn keys(v: &Value) -> Vec<&str> {
        v.as_object()
            .map(|o| o.keys().map(String::as_str).collect())
            .unwrap_or_default()
    }

    #[test]
    fn push_task_json_has_the_documented_shape() {
        let report = push_report(Variant::Random, &[1, 3]);
        let v: Value = serde_json::to_value(&report).unwrap();
        for k in [
            "experiment",
            "model",
            "variant",
            "mode",
            "folds",
            "seed",
            "results",
            "run",
        ] {
            assert!(v.get(k).is_some(), "missing {k}: {:?}", keys(&v));
        }
        assert_eq!(v["experiment"], "push-task");
        assert_eq!(v["variant"], "random");
        let r = &v["results"][1];
        assert_eq!(r["train_runs"], 3);
        for k in ["block_pos_err", "block_ori_err", "actuator_pos_err"] {
            assert!(r[k]["mean"].is_f64() && r[k]["std"].is_f64(), "{k}: {r}");
            assert!(r["interacting"][k]["mean"].is_f64(), "{k}");
        }
        assert!(r["interacting"]["actuator_pos_err_script_quirk"].is_f64());
        assert!(r.get("red").is_none());
        let p = &r["per_position"][20];
        assert_eq!(p["x0"].as_f64().map(|x| (x * 1000.0).round()), Some(350.0));
        assert!(p["block_pos_err"]["std"].is_f64() && p["block_ori_err"]["mean"].is_f64());
        assert_eq!(r["per_position"].as_array().map(Vec::len), Some(21));
        let gate = &r["nodes"]["maps"]["gate"];
        assert_eq!(gate["update_calls"]["mean"], 447.0);
        assert!(gate["nodes"]["std"].is_f64());
        // Position i of fold f errs by 0.01 (i + f): the per-position std
        // over the two folds is 0.005 everywhere.
        assert!((r["block_pos_err"]["std"].as_f64().unwrap() - 0.005).abs() < 1e-12);
        assert_eq!(v["run"]["messages"], 400);
        assert_eq!(v["run"]["too_slow"], 4);
        assert_eq!(v["run"]["reset_errors"], 4);
        assert!((v["run"]["budget_seconds"].as_f64().unwrap() - 0.02).abs() < 1e-12);
        // And back.
        let back: PushReport = serde_json::from_value(v).unwrap();
        assert_eq!(back, report);
    }

    #[test]
    fn saved_reports_are_read_back_by_kind() {
        let report = push_report(Variant::Random, &[1, 3]);
        let text = serde_json::to_string(&report).unwrap();
        assert_eq!(
            AnyReport::from_json(&text).unwrap(),
            AnyReport::Push(report)
        );
        assert!(matches!(
            AnyReport::from_json(r#"{"experiment": "juggling"}"#),
            Err(ReadError::UnknownExperiment(e)) if e == "juggling"
        ));
        assert!(matches!(
            AnyReport::from_json("{}"),
            Err(ReadError::NoExperiment)
        ));
        assert!(matches!(
            AnyReport::from_json(r#"{"experiment": "move-to-target"}"#),
            Err(ReadError::Json(_))
        ));
    }

    #[test]
    fn two_object_json_adds_the_red_block() {
        let v = serde_json::to_value(push_report(Variant::TwoObjects, &[6])).unwrap();
        let r = &v["results"][0];
        assert!((r["red"]["block_ori_err"]["mean"].as_f64().unwrap() - 0.04).abs() < 1e-12);
        assert_eq!(r["red"]["per_position"].as_array().map(Vec::len), Some(21));
    }

    #[test]
    fn move_to_target_json_has_the_documented_shape() {
        let run = MttRun {
            reached: false,
            steps: 3000,
            pos_err: 0.5,
            ori_err: 0.1,
            final_block: ObjectState::new(0.1, 0.2, 0.3),
            trace: Default::default(),
        };
        let report = MttReport {
            setup: Setup {
                experiment: "move-to-target".into(),
                model: "interaction".into(),
                mode: "lockstep-jitter".into(),
                seed: 1,
            },
            repetitions: 1,
            max_steps: 3000,
            targets: vec![TargetEntry {
                target: [0.6, 0.7, -2.1],
                runs: vec![run.clone()],
                summary: crate::experiment::move_to_target::TargetSummary::of(&[run]),
                nodes_after_training: Default::default(),
            }],
            run: RunInfo::default(),
        };
        let v = serde_json::to_value(&report).unwrap();
        assert_eq!(v["experiment"], "move-to-target");
        assert_eq!(v["model"], "interaction");
        let t = &v["targets"][0];
        assert_eq!(t["target"], serde_json::json!([0.6, 0.7, -2.1]));
        let r = &t["runs"][0];
        assert_eq!(r["reached"], false);
        assert_eq!(r["steps"], 3000);
        assert_eq!(r["pos_err"], 0.5);
        assert_eq!(r["ori_err"], 0.1);
        assert_eq!(t["summary"]["reached"], 0);

        let mut text = Vec::new();
        table::move_to_target(&mut text, &report, ModelKind::Interaction).unwrap();
        let text = String::from_utf8(text).unwrap();
        assert!(text.contains("0/1"), "{text}");
        assert!(text.contains("3000.0 (–)"), "{text}");
        // One repetition is not the thesis's protocol: no reference shown.
        assert!(!text.contains("2689.2"), "{text}");
    }

    #[test]
    fn learning_curve_table_shows_the_thesis_beside_ours() {
        let report = push_report(Variant::Random, &[1, 3]);
        let mut text = Vec::new();
        table::push(&mut text, &report, ModelKind::Gate).unwrap();
        let text = String::from_utf8(text).unwrap();
        // §3.4 row N_train = 3, all positions and interacting.
        assert!(text.contains("[0.1405 ± 0.1292]"), "{text}");
        assert!(text.contains("[0.1557 ± 0.1154]"), "{text}");
        // §4.2 node counts, N_train = 1.
        assert!(text.contains("[3.7 (0.46)]"), "{text}");
        assert!(text.contains("400 messages"), "{text}");
        let mut fixed = Vec::new();
        let report = push_report(Variant::FixedThree, &[3]);
        table::push(&mut fixed, &report, ModelKind::Interaction).unwrap();
        let fixed = String::from_utf8(fixed).unwrap();
        // §5.2 position 9 (x0 = −0.07).
        assert!(fixed.contains("[0.0536 ± 0.0205]"), "{fixed}");
        assert!(fixed.contains("-0.070"), "{fixed}");
    }
}
