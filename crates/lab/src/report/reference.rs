//! The thesis's numbers, as data: `crates/lab/data/reference.toml`, each
//! table with its source in `docs/spec/reference-results.md` ([text]: printed
//! in the thesis; [figure]: read out of its vector figures to about
//! ±0.0005). The file is embedded at build time and parsed at first use. The
//! report prints them beside ours; nothing else uses them.

use std::sync::LazyLock;

use learner::registry::{ModelKind, ThesisModel};
use serde::Deserialize;

/// The data file, in the binary: a report never depends on where it runs.
const SOURCE: &str = include_str!("../../data/reference.toml");

/// Mean ± standard deviation as the thesis reports it (`[mean, std]` in the
/// data file).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct Ms(pub f64, pub f64);

/// One N_train of a learning curve (§3.2, §3.4): all 21 positions and the
/// 15 interacting ones; the actuator over the interacting positions is the
/// original script's (mean + std) / 2 value (`docs/spec/experiments.md` §7.4).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveRef {
    pub train_runs: usize,
    pub pos: Ms,
    pub pos_interacting: Ms,
    pub ori: Ms,
    pub ori_interacting: Ms,
    pub actuator: Ms,
    pub actuator_interacting_quirk: Ms,
}

/// Interaction model node counts of one N_train (§4.1).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InteractionNodesRef {
    pub train_runs: usize,
    pub ac_updates: Ms,
    pub ac_nodes: Ms,
    pub ac_count: Ms,
    pub acs_updates: f64,
    pub acs_nodes: Ms,
}

/// Gate model node counts of one N_train (§4.2); the actuator model always
/// has 2 nodes.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GateNodesRef {
    pub train_runs: usize,
    pub object_updates: Ms,
    pub object_nodes: Ms,
    pub gate_updates: f64,
    pub gate_nodes: Ms,
}

/// One test position of a per-position table (§5.2, §5.3).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PositionRef {
    pub x0: f64,
    pub pos: Ms,
    pub ori: Ms,
}

/// One test position of the two-object tables (§6.1, §6.2).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TwoObjectRef {
    pub x0: f64,
    pub red_pos: Ms,
    pub red_ori: Ms,
    pub blue_pos: Ms,
    pub blue_ori: Ms,
}

/// One target of a Move-to-Target table (§8): reached count of 5, mean
/// remaining errors of the failed runs, mean steps (bracket: successful runs
/// only, shown when some failed).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MttRef {
    pub reached: usize,
    pub pos: Option<f64>,
    pub ori: Option<f64>,
    pub steps: f64,
    pub steps_reached: Option<f64>,
}

/// Every table of the data file, by its key there. The lengths are the
/// thesis's (7 N_train, 21 test positions, 4 targets): a row too many or too
/// few is a parse error, not a table that silently lacks a value.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Thesis {
    interaction_curve: [CurveRef; 7],
    gate_curve: [CurveRef; 7],
    interaction_nodes: [InteractionNodesRef; 7],
    gate_nodes: [GateNodesRef; 7],
    interaction_fixed_three: [PositionRef; 21],
    gate_fixed_three: [PositionRef; 21],
    two_objects_six: [TwoObjectRef; 21],
    two_objects_seven: [TwoObjectRef; 21],
    interaction_mtt: [MttRef; 4],
    gate_mtt: [MttRef; 4],
}

/// The data file does not parse: a broken build, never a user's input.
#[derive(Debug, thiserror::Error)]
#[error("the thesis's reference numbers (crates/lab/data/reference.toml) do not parse: {0}")]
struct ReferenceError(#[from] toml::de::Error);

fn parse(text: &str) -> Result<Thesis, ReferenceError> {
    Ok(toml::from_str(text)?)
}

/// The parsed tables. The file is compiled in and `tests::the_data_file_has_every_table`
/// parses it, so a build that passed its tests cannot fail here; should an
/// untested edit break it, every report stops at once naming the file and
/// the line, rather than printing tables without the thesis's column.
fn thesis() -> &'static Thesis {
    static THESIS: LazyLock<Thesis> =
        LazyLock::new(|| parse(SOURCE).unwrap_or_else(|e| panic!("{e}")));
    &THESIS
}

/// The learning curve of `model` for `train_runs`, if the thesis has it.
#[must_use]
pub fn curve(model: ModelKind, train_runs: usize) -> Option<&'static CurveRef> {
    let t = thesis();
    let table = match model.family() {
        ThesisModel::Gate => &t.gate_curve,
        ThesisModel::Interaction => &t.interaction_curve,
    };
    table.iter().find(|r| r.train_runs == train_runs)
}

/// The gate model's node counts for `train_runs`, if the thesis has them.
#[must_use]
pub fn gate_nodes(train_runs: usize) -> Option<&'static GateNodesRef> {
    thesis()
        .gate_nodes
        .iter()
        .find(|r| r.train_runs == train_runs)
}

/// The interaction model's node counts for `train_runs`, if the thesis has
/// them.
#[must_use]
pub fn interaction_nodes(train_runs: usize) -> Option<&'static InteractionNodesRef> {
    thesis()
        .interaction_nodes
        .iter()
        .find(|r| r.train_runs == train_runs)
}

/// The per-position table of the three selected training runs for `model`.
#[must_use]
pub fn fixed_three(model: ModelKind) -> &'static [PositionRef; 21] {
    let t = thesis();
    match model.family() {
        ThesisModel::Gate => &t.gate_fixed_three,
        ThesisModel::Interaction => &t.interaction_fixed_three,
    }
}

/// The two-object table for `train_runs` (6 or 7).
#[must_use]
pub fn two_objects(train_runs: usize) -> Option<&'static [TwoObjectRef; 21]> {
    let t = thesis();
    match train_runs {
        6 => Some(&t.two_objects_six),
        7 => Some(&t.two_objects_seven),
        _ => None,
    }
}

/// The Move-to-Target table of `model`, targets 1–4 in order.
#[must_use]
pub fn move_to_target(model: ModelKind) -> &'static [MttRef; 4] {
    let t = thesis();
    match model.family() {
        ThesisModel::Gate => &t.gate_mtt,
        ThesisModel::Interaction => &t.interaction_mtt,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_data_file_has_every_table() {
        // Every table the functions above read is a field of `Thesis`, with
        // its length: parsing is the check.
        if let Err(e) = parse(SOURCE) {
            panic!("{e}");
        }
    }

    #[test]
    fn a_broken_data_file_is_refused_naming_the_file() {
        let short = SOURCE.replacen("{ reached = 5, steps = 1597.4 },", "", 1);
        let e = parse(&short).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("crates/lab/data/reference.toml"), "{e}");
        assert!(e.contains("gate_mtt"), "{e}");
        let unknown = SOURCE.replacen("gate_mtt = [", "gate_mtt_typo = [", 1);
        assert!(parse(&unknown).is_err());
    }

    #[test]
    fn tables_are_complete_and_ordered() {
        let t = thesis();
        let runs: Vec<usize> = t.gate_curve.iter().map(|r| r.train_runs).collect();
        assert_eq!(runs, [1, 2, 3, 5, 10, 20, 30]);
        assert_eq!(
            t.interaction_curve.map(|r| r.train_runs),
            t.gate_curve.map(|r| r.train_runs)
        );
        assert_eq!(
            t.gate_nodes.map(|r| r.train_runs),
            t.gate_curve.map(|r| r.train_runs)
        );
        assert_eq!(
            t.interaction_nodes.map(|r| r.train_runs),
            t.gate_curve.map(|r| r.train_runs)
        );
        // 149 updates per training run (`docs/spec/experiments.md` §8).
        for r in t.gate_nodes {
            assert_eq!(r.gate_updates, 149.0 * r.train_runs as f64);
        }
        for r in t.interaction_nodes {
            assert_eq!(r.acs_updates, 149.0 * r.train_runs as f64);
        }
        // Test positions −0.35 + 0.035 i and −0.8 + 0.06 i.
        for (i, r) in t.gate_fixed_three.iter().enumerate() {
            assert!((r.x0 - (-0.35 + 0.035 * i as f64)).abs() < 1e-9);
            assert_eq!(r.x0, t.interaction_fixed_three[i].x0);
        }
        for (i, r) in t.two_objects_six.iter().enumerate() {
            assert!((r.x0 - (-0.8 + 0.06 * i as f64)).abs() < 1e-9);
            assert_eq!(r.x0, t.two_objects_seven[i].x0);
        }
    }

    #[test]
    fn spot_checks_against_the_source() {
        let t = thesis();
        assert_eq!(t.gate_curve[4].pos, Ms(0.0487, 0.0432));
        assert_eq!(t.interaction_curve[6].ori, Ms(0.2502, 0.0875));
        assert_eq!(t.gate_nodes[6].object_nodes, Ms(603.05, 36.16));
        assert_eq!(t.interaction_fixed_three[8].ori, Ms(0.4484, 0.0068));
        assert_eq!(t.gate_fixed_three[3].pos, Ms(0.14, 0.0));
        assert_eq!(t.two_objects_seven[12].blue_ori, Ms(1.0479, 0.0918));
        assert_eq!(t.interaction_mtt[3].steps_reached, Some(1730.5));
        assert_eq!(t.gate_mtt[1].pos, None);
    }
}
