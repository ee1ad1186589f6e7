//! What the constant-feedback experiment (`docs/spec/experiments.md` §3.4)
//! measured: per test run, the error of every chained prediction.

use learner::eval::RunErrors;
use serde::{Deserialize, Serialize};

/// The `variant` of constant-feedback documents, which tells them apart
/// from the other push-task documents (same `experiment`, other shape).
pub const VARIANT: &str = "constant-feedback";

/// One test run: its start and the error of each message's prediction.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FeedbackRun {
    pub x0: f64,
    /// Errors of the prediction made on message k against message k + 1,
    /// for every message of the run that had a prediction, the last one
    /// (which ended the run) included.
    pub errors: Vec<RunErrors>,
}
