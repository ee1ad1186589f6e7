//! The push task (`docs/spec/experiments.md` §3.1–§3.3): its tables beside
//! the thesis's (curves §3.2, §3.4; nodes §4; positions §5; two objects
//! §6), its figures, and the new-object experiments, which are push tasks on
//! other objects (`Transfer`) shown without the thesis's numbers.

pub mod figures;
pub mod table;

use std::path::{Path, PathBuf};

use drive::results::run_info::RunInfo;
use drive::results::{PushReport, Setup, UnknownModel};

use super::{draft, Experiment};
use crate::report::layout::Printout;
use crate::report::plot::PlotError;

/// The push-task experiment (`Spec::PushTask`, `pushlearn experiment
/// push-task`), the one thing the name `PushTask` means; the engine's
/// handler of one of its jobs is `drive`'s `PushJobTask`.
pub struct PushTask;

impl Experiment for PushTask {
    type Report = PushReport;

    fn setup(report: &PushReport) -> &Setup {
        &report.setup
    }

    fn runs(report: &PushReport) -> Vec<&RunInfo> {
        vec![&report.run]
    }

    fn without_timing(mut report: PushReport) -> PushReport {
        report.run = report.run.without_timing();
        report
    }

    /// Without the per-fold detail of each curve entry
    /// ([`CurveEntry::without_folds`](drive::results::push_task::CurveEntry::without_folds)).
    fn without_folds(mut report: PushReport) -> PushReport {
        report.results = std::mem::take(&mut report.results)
            .into_iter()
            .map(|e| e.without_folds())
            .collect();
        report
    }

    /// The push task's tables, then the key-point section.
    fn printout(report: &PushReport) -> Result<Printout, UnknownModel> {
        let mut printout = table::push_printout(report, report.setup.reference_model()?);
        printout.tables.push(draft::keypoint_table(report));
        Ok(printout)
    }

    fn figures(report: &PushReport, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
        figures::push(report, report.setup.reference_model()?, dir)
    }
}
