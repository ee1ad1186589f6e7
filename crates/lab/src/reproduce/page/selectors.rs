//! The interaction model's selectors on the draft's protocol.

use std::fmt::Write as _;

use crate::reproduce::Reproduction;
use crate::spec::Document;
use drive::results::push_task::SelectionCount;

pub(super) fn selectors(results: &Reproduction) -> Result<String, String> {
    let mut out = String::from(
        "| Selector | N_train | selector agreement | actuator key-point | block key-point | block pos | block ori |\n|---|---|---|---|---|---|---|\n",
    );
    for p in &results.produced {
        let Some(kind) = p.entry.name.strip_prefix("selector-") else {
            continue;
        };
        let Document::Push(report) = &p.document else {
            return Err(format!("`{}` is not a push-task document", p.entry.name));
        };
        for e in &report.results {
            let score = |id: u32| {
                e.keypoints.get(&id).map_or_else(
                    || "–".to_owned(),
                    |s| format!("{:.3} / {:.3} / {:.4}", s.final_dif, s.cum_dif, s.mean_dif),
                )
            };
            let agreement = e
                .selection
                .as_ref()
                .and_then(SelectionCount::accuracy)
                .map_or_else(|| "–".to_owned(), |a| format!("{:.1} %", 100.0 * a));
            let _ = writeln!(
                out,
                "| {kind} | {} | {agreement} | {} | {} | {:.4} | {:.4} |",
                e.train_runs,
                score(learner::ACTUATOR_ID),
                score(learner::BLUE_ID),
                e.blue.block_pos_err.mean,
                e.blue.block_ori_err.mean
            );
        }
    }
    Ok(out)
}
