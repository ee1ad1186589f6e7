//! The experiments of `docs/spec/experiments.md`, one folder each: what an
//! experiment's document looks like to a reader (its tables beside the
//! thesis's numbers, its figures) lives with it, behind [`Experiment`].
//! What runs it (its task, the driver) and what it measures (its report
//! type) are the engine's (`drive::experiment`, `drive::results`), because
//! the learner daemon runs Move to Target's task too.
//!
//! * [`push_task`]: the push task (§3.1–§3.3), the thesis's variants and
//!   the new-object experiments (a push task on other objects);
//! * [`constant_feedback`]: the push task with feedback at every message
//!   (§3.4);
//! * [`move_to_target`]: Move to Target (§4);
//! * [`draft`]: the thesis draft's tables (its own protocol and rows), and
//!   the key-point section every push-task table ends with.

pub mod constant_feedback;
pub mod draft;
pub mod move_to_target;
pub mod push_task;

use std::path::{Path, PathBuf};

use drive::results::run_info::RunInfo;
use drive::results::{Setup, UnknownModel};

use crate::report::layout::Printout;
use crate::report::plot::PlotError;

/// One experiment's document and how it is shown.
pub trait Experiment {
    /// The document it writes.
    type Report;

    /// The document's setup (its experiment, model, mode and seed).
    fn setup(report: &Self::Report) -> &Setup;

    /// How its runs went: one, or one per row of the draft's tables.
    fn runs(report: &Self::Report) -> Vec<&RunInfo>;

    /// The document without its machine-dependent parts (wall and handling
    /// times), so that two runs of the same spec give the same bytes.
    fn without_timing(report: Self::Report) -> Self::Report;

    /// The document without the detail the reproduction does not keep.
    fn without_folds(report: Self::Report) -> Self::Report {
        report
    }

    /// The terminal tables beside the thesis's numbers, as `pushlearn
    /// experiment` prints them, each also as CSV.
    ///
    /// # Errors
    /// A model the thesis's numbers cannot be chosen for
    /// ([`Setup::reference_model`]).
    fn printout(report: &Self::Report) -> Result<Printout, UnknownModel>;

    /// Draws its figures into `dir`, returning the files written.
    ///
    /// # Errors
    /// A figure cannot be drawn or written, or an unknown model.
    fn figures(_report: &Self::Report, _dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
        Ok(Vec::new())
    }
}
