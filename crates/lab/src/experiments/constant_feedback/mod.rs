//! The push task with constant feedback (`docs/spec/experiments.md` §3.4):
//! the error of each chained prediction per run, a table and a figure
//! (qualitative: the thesis shows images, §7).

pub mod figure;
pub mod table;

use std::path::{Path, PathBuf};

use drive::results::run_info::RunInfo;
use drive::results::{FeedbackReport, Setup, UnknownModel};

use super::Experiment;
use crate::report::layout::Printout;
use crate::report::plot::PlotError;

/// The push task with constant feedback.
pub struct ConstantFeedback;

impl Experiment for ConstantFeedback {
    type Report = FeedbackReport;

    fn setup(report: &FeedbackReport) -> &Setup {
        &report.setup
    }

    fn runs(report: &FeedbackReport) -> Vec<&RunInfo> {
        vec![&report.run]
    }

    fn without_timing(mut report: FeedbackReport) -> FeedbackReport {
        report.run = report.run.without_timing();
        report
    }

    fn printout(report: &FeedbackReport) -> Result<Printout, UnknownModel> {
        Ok(table::feedback_printout(
            report,
            report.setup.reference_model()?,
        ))
    }

    fn figures(report: &FeedbackReport, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
        figure::feedback(report, report.setup.reference_model()?, dir)
    }
}
