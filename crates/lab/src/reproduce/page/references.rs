//! The reference rows every table of learners carries (`docs/models.md`,
//! "Reference rows"), and the normalised score they define:
//! `(E_still − E) / (E_still − E_oracle)`, 0 for predicting that nothing
//! moves and 1 for the oracle that does not know the latency, so that
//! learners compare across tasks whose scales differ.

use drive::oracle::OracleLatency;
use drive::results::push_task::CurveEntry;
use drive::results::PushReport;
use drive::scene::Transfer;

use super::{entry_at, push_doc};
use crate::reproduce::manifest::{
    cross_entry_name, object_entry_name, reference_entry_name, references, STILL,
};
use crate::reproduce::Reproduction;

/// The reference rows of one task, in the manifest's order: `still`, the
/// oracle that knows the latency, the one that does not.
pub(super) struct References<'r> {
    reports: Vec<&'r PushReport>,
}

impl<'r> References<'r> {
    /// The references of the learning curves at one timing (`suffix`: "",
    /// "-lockstep", "-latency5").
    pub(super) fn of_timing(results: &'r Reproduction, suffix: &str) -> Result<Self, String> {
        Self::named(results, |name| reference_entry_name(name, suffix))
    }

    /// The references of one new-object condition.
    pub(super) fn of_objects(
        results: &'r Reproduction,
        transfer: &Transfer,
    ) -> Result<Self, String> {
        Self::named(results, |name| object_entry_name(name, transfer))
    }

    /// The references of one cross-object condition.
    pub(super) fn of_cross(results: &'r Reproduction, transfer: &Transfer) -> Result<Self, String> {
        Self::named(results, |name| cross_entry_name(name, transfer))
    }

    fn named(results: &'r Reproduction, name: impl Fn(&str) -> String) -> Result<Self, String> {
        let reports = references()
            .into_iter()
            .map(|(reference, _)| push_doc(results, &name(reference)))
            .collect::<Result<_, _>>()?;
        Ok(Self { reports })
    }

    /// Their reports, in the manifest's order.
    pub(super) fn reports(&self) -> &[&'r PushReport] {
        &self.reports
    }

    fn entry(&self, reference: &str, n: usize) -> Result<&'r CurveEntry, String> {
        let report = self
            .reports
            .iter()
            .find(|r| r.setup.model == reference)
            .ok_or_else(|| format!("no reference `{reference}`"))?;
        entry_at(report, &report.setup.model, n)
    }

    /// The normalised block position and orientation scores of `e` after
    /// `n` training runs, as a cell: `0.93 / 0.88`; `–` where the
    /// references do not differ.
    pub(super) fn normalised(&self, e: &CurveEntry, n: usize) -> Result<String, String> {
        let still = self.entry(STILL, n)?;
        let oracle = self.entry(OracleLatency::Unknown.report_name(), n)?;
        let score = |get: fn(&CurveEntry) -> f64| {
            normalised(get(e), get(still), get(oracle))
                .map_or_else(|| "–".to_owned(), |v| format!("{v:.2}"))
        };
        Ok(format!(
            "{} / {}",
            score(|e| e.blue.block_pos_err.mean),
            score(|e| e.blue.block_ori_err.mean)
        ))
    }
}

/// `(still − error) / (still − oracle)`; `None` when the references are
/// too close to tell anything apart.
pub(super) fn normalised(error: f64, still: f64, oracle: f64) -> Option<f64> {
    let scale = still - oracle;
    (scale.abs() > 1e-9).then(|| (still - error) / scale)
}

/// How tables and figures name a reference row, if `model` is one.
pub(super) fn reference_label(model: &str) -> Option<&'static str> {
    if model == STILL {
        return Some("still: nothing moves");
    }
    OracleLatency::of_report_name(model).map(OracleLatency::label)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_score_is_zero_for_still_one_for_the_oracle_and_none_without_a_scale() {
        assert_eq!(normalised(0.2, 0.2, 0.01), Some(0.0));
        assert_eq!(normalised(0.01, 0.2, 0.01), Some(1.0));
        let half = normalised(0.105, 0.2, 0.01).unwrap();
        assert!((half - 0.5).abs() < 1e-12);
        assert!(
            normalised(0.3, 0.2, 0.01).unwrap() < 0.0,
            "worse than still"
        );
        assert_eq!(normalised(0.1, 0.01, 0.01), None);
        assert_eq!(reference_label("still"), Some("still: nothing moves"));
        assert_eq!(
            reference_label("oracle-known"),
            Some("oracle: true parameters, latency known")
        );
        assert_eq!(reference_label("gate"), None);
    }
}
