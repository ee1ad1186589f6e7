//! Move to Target (`docs/spec/experiments.md` §4): the table in the layout
//! of the thesis's §8 beside its numbers, and the figures of the errors over
//! steps with the final block poses. Success is judged from the world
//! (`drive::experiment::move_to_target`).

pub mod figures;
pub mod table;

use std::path::{Path, PathBuf};

use drive::results::run_info::RunInfo;
use drive::results::{MttReport, Setup, UnknownModel};

use super::Experiment;
use crate::report::layout::Printout;
use crate::report::plot::PlotError;

/// Move to Target.
pub struct MoveToTarget;

impl Experiment for MoveToTarget {
    type Report = MttReport;

    fn setup(report: &MttReport) -> &Setup {
        &report.setup
    }

    fn runs(report: &MttReport) -> Vec<&RunInfo> {
        vec![&report.run]
    }

    fn without_timing(mut report: MttReport) -> MttReport {
        report.run = report.run.without_timing();
        report
    }

    /// Without the training runs' start poses.
    fn without_folds(mut report: MttReport) -> MttReport {
        report.training_starts = Vec::new();
        report
    }

    fn printout(report: &MttReport) -> Result<Printout, UnknownModel> {
        Ok(table::move_to_target_printout(
            report,
            report.setup.reference_model()?,
        ))
    }

    fn figures(report: &MttReport, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
        figures::move_to_target(report, report.setup.reference_model()?, dir)
    }
}
