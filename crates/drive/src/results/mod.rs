//! What the experiments measured, as plain data: each job's results, their
//! summaries in the thesis's terms, and the documents that hold them
//! ([`PushReport`], [`FeedbackReport`], [`MttReport`]). The experiments
//! (`crate::experiment`) fill them; the reports (`crate::report`) render
//! them as JSON, tables and figures, and read them back.
//!
//! * [`push_task`], [`constant_feedback`], [`move_to_target`]: the
//!   experiments' results and summaries (`docs/spec/experiments.md` §7);
//! * [`nodes`]: node statistics over folds (§7.5);
//! * [`run_info`]: how a run went (message counts, handling times).
//!
//! Every document separates what the experiment measured (`results`,
//! `runs`, `targets`: identical for identical seeds in lock-step) from how
//! the run went (`run`: wall-clock times, too-slow counts).

pub mod constant_feedback;
pub mod move_to_target;
pub mod nodes;
pub mod push_task;
pub mod run_info;
#[cfg(any(test, feature = "testing"))]
pub mod test_support;

use serde::{Deserialize, Serialize};

use constant_feedback::FeedbackRun;
use move_to_target::{MttRun, TargetSummary};
use nodes::NodeSummary;
use push_task::CurveEntry;
use run_info::RunInfo;

use learner::registry::ModelKind;

/// What identifies an experiment's configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setup {
    pub experiment: String,
    pub model: String,
    pub mode: String,
    /// With latency emulation, the largest delay of a Move in physics steps
    /// (absent without; documents written before it was recorded used 5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latency_max_steps: Option<u32>,
    pub seed: u64,
    /// An external learner's version and where it ran (`--learner`);
    /// absent for the built-in models. `model` is the name it gave.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learner: Option<LearnerRecord>,
}

/// A document's model that is neither a name the built-in models are
/// reported under nor an external learner's (`Setup::learner` absent).
#[derive(Debug, thiserror::Error)]
#[error("unknown model {0:?}")]
pub struct UnknownModel(pub String);

impl Setup {
    /// The built-in model the document is shown against (its tables,
    /// figures and the thesis's reference numbers): the one `model` names
    /// ([`ModelKind::of_report_name`]), or for an external learner of
    /// another name (`knn`) and the oracles the gate model, whose thesis
    /// numbers every learner is compared with.
    ///
    /// # Errors
    /// Any other name: a document we did not write, or a hand-edited one.
    pub fn reference_model(&self) -> Result<ModelKind, UnknownModel> {
        match ModelKind::of_report_name(&self.model) {
            Some(kind) => Ok(kind),
            None if self.learner.is_some()
                || crate::oracle::OracleLatency::of_report_name(&self.model).is_some() =>
            {
                Ok(ModelKind::Gate)
            }
            None => Err(UnknownModel(self.model.clone())),
        }
    }
}

/// An external learner, as its reports record it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LearnerRecord {
    /// The version its hello gave.
    pub version: String,
    /// The command or the daemon's address.
    pub source: String,
}

#[cfg(any(test, feature = "testing"))]
impl Setup {
    /// The setup of the tests' reports: `model` in lock-step, seed 1.
    pub fn for_tests(experiment: &str, model: &str) -> Self {
        Self {
            experiment: experiment.into(),
            model: model.into(),
            mode: "lockstep".into(),
            latency_max_steps: None,
            seed: 1,
            learner: None,
        }
    }
}

use crate::scene::Transfer;

/// `pushlearn experiment push-task` (all variants but constant feedback).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PushReport {
    #[serde(flatten)]
    pub setup: Setup,
    pub variant: String,
    /// The objects the runs were about (the new-object experiments); absent
    /// for the thesis's blocks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transfer: Option<Transfer>,
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
    /// The actuator's start (x, y) of each training run [m], the same for
    /// every repetition (each repetition's test run is in `targets[].runs`);
    /// for users' own analysis of `--json`, absent from the reproduction's
    /// documents (as [`push_task::CurveEntry::by_fold`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub training_starts: Vec<[f64; 2]>,
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
    /// JSON of a known experiment that does not fit its document.
    #[error("not a {experiment} document as this version writes it: {source}")]
    Shape {
        experiment: String,
        source: serde_json::Error,
    },
    #[error("not a pushlearn report: no \"experiment\" key")]
    NoExperiment,
    #[error("unknown experiment {0:?} (expected push-task or move-to-target)")]
    UnknownExperiment(String),
    #[error(transparent)]
    UnknownModel(#[from] UnknownModel),
}

impl AnyReport {
    /// Parses a document written by `--json`, telling the kinds apart by
    /// their `experiment` and `variant` keys.
    ///
    /// # Errors
    /// Not JSON, not one of the report documents, or a model that is
    /// neither built in nor an external learner
    /// ([`Setup::reference_model`]).
    pub fn from_json(text: &str) -> Result<Self, ReadError> {
        let report = Self::parse(text)?;
        report.setup().reference_model()?;
        Ok(report)
    }

    fn parse(text: &str) -> Result<Self, ReadError> {
        let value: serde_json::Value = serde_json::from_str(text)?;
        let experiment = value
            .get("experiment")
            .and_then(serde_json::Value::as_str)
            .ok_or(ReadError::NoExperiment)?;
        let experiment = experiment.to_owned();
        let shape = |source| ReadError::Shape {
            experiment: experiment.clone(),
            source,
        };
        Ok(match experiment.as_str() {
            push_task::EXPERIMENT => {
                if value.get("variant").and_then(serde_json::Value::as_str)
                    == Some(constant_feedback::VARIANT)
                {
                    AnyReport::Feedback(serde_json::from_value(value).map_err(shape)?)
                } else {
                    AnyReport::Push(serde_json::from_value(value).map_err(shape)?)
                }
            }
            move_to_target::EXPERIMENT => {
                AnyReport::MoveToTarget(serde_json::from_value(value).map_err(shape)?)
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

#[cfg(test)]
mod tests {
    use serde_json::Value;

    use super::test_support::{mtt_report, push_report};
    use super::*;

    fn keys(v: &Value) -> Vec<&str> {
        v.as_object()
            .map(|o| o.keys().map(String::as_str).collect())
            .unwrap_or_default()
    }

    #[test]
    fn push_task_json_has_the_documented_shape() {
        let report = push_report("random", &[1, 3]);
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
        let report = push_report("random", &[1, 3]);
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
            Err(ReadError::Shape { experiment, .. }) if experiment == "move-to-target"
        ));
        assert!(matches!(
            AnyReport::from_json("{\"experiment\""),
            Err(ReadError::Json(_))
        ));
    }

    #[test]
    fn a_documents_model_is_built_in_or_an_external_learner() {
        let named = |model: &str, external: bool| {
            let mut report = push_report("random", &[1]);
            report.setup.model = model.to_owned();
            report.setup.learner = external.then(|| LearnerRecord {
                version: "1".into(),
                source: "`python3 -m pushlearn.baselines knn`".into(),
            });
            AnyReport::from_json(&serde_json::to_string(&report).unwrap())
        };
        let model = |model: &str, external: bool| {
            named(model, external).map(|r| r.setup().reference_model().unwrap())
        };
        assert_eq!(model("interaction", false).unwrap(), ModelKind::Interaction);
        assert_eq!(model("gate+unrounded", false).unwrap(), ModelKind::GatePlus);
        // An external learner's own name: compared with the gate model, as
        // the built-in learners are; a built-in name keeps its model.
        assert_eq!(model("knn", true).unwrap(), ModelKind::Gate);
        assert_eq!(model("interaction", true).unwrap(), ModelKind::Interaction);
        for unknown in ["knn", "gate+turbo", "Gate"] {
            let err = named(unknown, false).unwrap_err();
            assert!(matches!(&err, ReadError::UnknownModel(UnknownModel(m)) if m == unknown));
            assert_eq!(err.to_string(), format!("unknown model {unknown:?}"));
        }
    }

    #[test]
    fn two_object_json_adds_the_red_block() {
        let v = serde_json::to_value(push_report("two-objects", &[6])).unwrap();
        let r = &v["results"][0];
        assert!((r["red"]["block_ori_err"]["mean"].as_f64().unwrap() - 0.04).abs() < 1e-12);
        assert_eq!(r["red"]["per_position"].as_array().map(Vec::len), Some(21));
    }

    #[test]
    fn move_to_target_json_has_the_documented_shape() {
        let report = mtt_report();
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
    }
}
