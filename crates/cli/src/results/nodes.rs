//! Node statistics over folds (`docs/spec/experiments.md` §7.5): mean and population
//! standard deviation of every map's counters, and for the interaction
//! model the Abstract Collections, by the thesis's stated definition and by
//! what its analysis script actually computed.

use std::collections::BTreeMap;

use learner::eval::MeanStd;
use learner::{stat_keys, MapStats, ModelStats};
use serde::{Deserialize, Serialize};

/// One map's counters over folds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapSummary {
    pub update_calls: MeanStd,
    pub inserts: MeanStd,
    pub nodes: MeanStd,
}

impl MapSummary {
    fn of(maps: &[MapStats]) -> Self {
        let field = |f: fn(&MapStats) -> f64| MeanStd::of(&maps.iter().map(f).collect::<Vec<_>>());
        Self {
            update_calls: field(|m| m.update_calls as f64),
            inserts: field(|m| m.inserts as f64),
            nodes: field(|m| m.nodes as f64),
        }
    }
}

/// The interaction model's Abstract Collections over folds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AcSummary {
    /// # ACs.
    pub count: MeanStd,
    /// The AC with the most nodes (ties: the lowest id): its update calls…
    pub largest_update_calls: MeanStd,
    /// … and node count — the thesis's stated definition.
    pub largest_nodes: MeanStd,
    /// What the original script computed, for comparison with its table.
    pub script_quirk: AcQuirk,
}

/// §7.5 quirk: the maximum update count over all ACs, a node count from a
/// scan that compares update counts with node counts, and both (with # ACs)
/// over all folds but the last.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AcQuirk {
    pub count: MeanStd,
    pub update_calls: MeanStd,
    pub nodes: MeanStd,
    pub folds: usize,
}

/// Node statistics of one N_train (or one Move-to-Target target).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NodeSummary {
    /// Every map but the ACs (`actuator`, `gate`, `predictor/15`, `acs`, …);
    /// a map a fold does not have counts as zero there.
    pub maps: BTreeMap<String, MapSummary>,
    /// Present for models with ACs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub acs: Option<AcSummary>,
}

fn ac_count(stats: &ModelStats) -> f64 {
    stats
        .extra
        .get(stat_keys::AC_COUNT)
        .copied()
        .unwrap_or_else(|| stats.indexed(stat_keys::AC_PREFIX).len() as f64)
}

/// (update calls, nodes) of the AC with the most nodes; zeros without ACs.
fn largest_ac(stats: &ModelStats) -> (f64, f64) {
    let mut best: Option<&MapStats> = None;
    for (_, ac) in stats.indexed(stat_keys::AC_PREFIX) {
        if best.is_none_or(|b| ac.nodes > b.nodes) {
            best = Some(ac);
        }
    }
    best.map_or((0.0, 0.0), |b| (b.update_calls as f64, b.nodes as f64))
}

/// The original script's (max update calls, scanned node value).
fn quirky_ac(stats: &ModelStats) -> (f64, f64) {
    let acs = stats.indexed(stat_keys::AC_PREFIX);
    let max_updates = acs.iter().map(|(_, a)| a.update_calls).max().unwrap_or(0);
    let mut m: u64 = 0;
    for (_, ac) in &acs {
        if ac.update_calls > m {
            m = ac.nodes as u64;
        }
    }
    (max_updates as f64, m as f64)
}

impl NodeSummary {
    /// Summarises one statistics record per fold, in fold order.
    #[must_use]
    pub fn of(folds: &[&ModelStats]) -> Self {
        let keys: std::collections::BTreeSet<&String> = folds
            .iter()
            .flat_map(|s| s.maps.keys())
            .filter(|k| !k.starts_with(stat_keys::AC_PREFIX))
            .collect();
        let maps = keys
            .into_iter()
            .map(|k| {
                let per_fold: Vec<MapStats> = folds
                    .iter()
                    .map(|s| s.maps.get(k).copied().unwrap_or_default())
                    .collect();
                (k.clone(), MapSummary::of(&per_fold))
            })
            .collect();
        let has_acs = folds.iter().any(|s| {
            s.extra.contains_key(stat_keys::AC_COUNT) || !s.indexed(stat_keys::AC_PREFIX).is_empty()
        });
        let acs = has_acs.then(|| {
            let over = |f: &dyn Fn(&ModelStats) -> f64, folds: &[&ModelStats]| {
                MeanStd::of(&folds.iter().map(|s| f(s)).collect::<Vec<_>>())
            };
            let quirk_folds = if folds.len() > 1 {
                &folds[..folds.len() - 1]
            } else {
                folds
            };
            AcSummary {
                count: over(&ac_count, folds),
                largest_update_calls: over(&|s| largest_ac(s).0, folds),
                largest_nodes: over(&|s| largest_ac(s).1, folds),
                script_quirk: AcQuirk {
                    count: over(&ac_count, quirk_folds),
                    update_calls: over(&|s| quirky_ac(s).0, quirk_folds),
                    nodes: over(&|s| quirky_ac(s).1, quirk_folds),
                    folds: quirk_folds.len(),
                },
            }
        });
        Self { maps, acs }
    }

    /// Mean ± std of one counter of one map, if the map exists.
    #[must_use]
    pub fn map(&self, key: &str) -> Option<&MapSummary> {
        self.maps.get(key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(update_calls: u64, nodes: usize) -> MapStats {
        MapStats {
            update_calls,
            inserts: nodes as u64,
            nodes,
        }
    }

    fn stats(maps: &[(&str, MapStats)], ac_count: Option<f64>) -> ModelStats {
        let mut s = ModelStats::default();
        for (k, m) in maps {
            s.maps.insert((*k).into(), *m);
        }
        if let Some(n) = ac_count {
            s.extra.insert(stat_keys::AC_COUNT.into(), n);
        }
        s
    }

    #[test]
    fn maps_are_averaged_with_population_std_and_missing_maps_count_zero() {
        let a = stats(
            &[("gate", map(149, 3)), ("predictor/15", map(90, 20))],
            None,
        );
        let b = stats(&[("gate", map(149, 5))], None);
        let s = NodeSummary::of(&[&a, &b]);
        let gate = s.map("gate").unwrap();
        assert_eq!(
            gate.update_calls,
            MeanStd {
                mean: 149.0,
                std: 0.0
            }
        );
        assert_eq!(
            gate.nodes,
            MeanStd {
                mean: 4.0,
                std: 1.0
            }
        );
        assert_eq!(s.map("predictor/15").unwrap().nodes.mean, 10.0);
        assert!(s.acs.is_none());
    }

    #[test]
    fn acs_by_definition_and_by_the_scripts_scan() {
        // AC 0: many updates, few nodes; AC 1: the most nodes; AC 2: more
        // updates than AC 1 has nodes... the scan's comparison of update
        // counts with node counts picks AC 2's nodes.
        let fold = |bump: usize| {
            stats(
                &[
                    ("acs", map(149, 40)),
                    ("ac/0", map(60, 5 + bump)),
                    ("ac/1", map(30, 18)),
                    ("ac/2", map(10, 2)),
                ],
                Some(3.0),
            )
        };
        let (a, b, c) = (fold(0), fold(2), fold(100));
        let s = NodeSummary::of(&[&a, &b, &c]);
        assert!(!s.maps.keys().any(|k| k.starts_with("ac/")));
        assert_eq!(s.map("acs").unwrap().nodes.mean, 40.0);
        let acs = s.acs.unwrap();
        assert_eq!(acs.count.mean, 3.0);
        // Largest AC: AC 1 (18 nodes) in folds a and b, AC 0 (105) in c.
        assert_eq!(acs.largest_nodes.mean, (18.0 + 18.0 + 105.0) / 3.0);
        assert_eq!(acs.largest_update_calls.mean, (30.0 + 30.0 + 60.0) / 3.0);
        // Scan: m = 0 → AC 0 (60 > 0) m = 5 → AC 1 (30 > 5) m = 18 → AC 2
        // (10 > 18? no): 18; fold b the same; the last fold is dropped.
        assert_eq!(acs.script_quirk.folds, 2);
        assert_eq!(acs.script_quirk.nodes.mean, 18.0);
        assert_eq!(acs.script_quirk.update_calls.mean, 60.0);
    }

    #[test]
    fn one_fold_keeps_its_quirk_values() {
        let a = stats(&[("ac/0", map(12, 4))], None);
        let acs = NodeSummary::of(&[&a]).acs.unwrap();
        assert_eq!(acs.count.mean, 1.0);
        assert_eq!(acs.script_quirk.folds, 1);
        assert_eq!(acs.script_quirk.nodes.mean, 4.0);
    }
}
