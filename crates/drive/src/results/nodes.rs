//! Node statistics over folds (`docs/spec/experiments.md` §7.5): mean and population
//! standard deviation of every map's counters, and for the interaction
//! model the Abstract Collections, by the thesis's stated definition and by
//! what its analysis script actually computed.

use std::collections::BTreeMap;

use learner::eval::MeanStd;
use learner::{InteractionStats, MapName, MapStats, ModelStats};
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
    /// The further numbers a learner of its own reports (an external
    /// learner's `Stats.extra`), over the folds that report each.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub extra: BTreeMap<String, MeanStd>,
    /// Its labels: every value a fold gave, in order, without repeats.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub labels: BTreeMap<String, Vec<String>>,
}

/// # ACs of one fold; 0 for a fold of another model, as for the columns
/// below.
fn ac_count(stats: &ModelStats) -> f64 {
    stats
        .as_interaction()
        .map_or(0.0, |i| i.collections.len() as f64)
}

/// (update calls, nodes) of the AC with the most nodes; zeros without ACs.
fn largest_ac(stats: &ModelStats) -> (f64, f64) {
    stats
        .as_interaction()
        .and_then(InteractionStats::largest)
        .map_or((0.0, 0.0), |b| {
            (b.map.update_calls as f64, b.map.nodes as f64)
        })
}

/// The original script's (max update calls, scanned node value).
fn quirky_ac(stats: &ModelStats) -> (f64, f64) {
    let q = stats
        .as_interaction()
        .map(InteractionStats::script_quirk)
        .unwrap_or_default();
    (q.update_calls as f64, q.nodes as f64)
}

impl NodeSummary {
    /// Summarises one statistics record per fold, in fold order.
    #[must_use]
    pub fn of(folds: &[&ModelStats]) -> Self {
        let per_fold: Vec<BTreeMap<String, MapStats>> = folds
            .iter()
            .map(|s| {
                s.maps()
                    .into_iter()
                    .filter(|(name, _)| !matches!(name, MapName::Ac(_)))
                    .map(|(name, m)| (name.to_string(), m))
                    .collect()
            })
            .collect();
        let keys: std::collections::BTreeSet<&String> =
            per_fold.iter().flat_map(BTreeMap::keys).collect();
        let maps = keys
            .into_iter()
            .map(|k| {
                let counts: Vec<MapStats> = per_fold
                    .iter()
                    .map(|maps| maps.get(k).copied().unwrap_or_default())
                    .collect();
                (k.clone(), MapSummary::of(&counts))
            })
            .collect();
        let has_acs = folds.iter().any(|s| s.as_interaction().is_some());
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
        let mut extra: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut labels: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for other in folds.iter().filter_map(|s| s.as_other()) {
            for (key, &value) in &other.extra {
                extra.entry(key.clone()).or_default().push(value);
            }
            for (key, value) in &other.labels {
                let seen = labels.entry(key.clone()).or_default();
                if !seen.contains(value) {
                    seen.push(value.clone());
                }
            }
        }
        Self {
            maps,
            acs,
            extra: extra
                .into_iter()
                .map(|(key, values)| (key, MeanStd::of(&values)))
                .collect(),
            labels,
        }
    }

    /// Mean ± std of one map's counters, if the map exists.
    #[must_use]
    pub fn map(&self, name: &MapName) -> Option<&MapSummary> {
        self.maps.get(&name.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use learner::{AcStats, GateStats};

    fn map(update_calls: u64, nodes: usize) -> MapStats {
        MapStats {
            update_calls,
            inserts: nodes as u64,
            nodes,
        }
    }

    fn gate(gate: MapStats, predictors: &[(u32, MapStats)]) -> ModelStats {
        ModelStats::Gate(GateStats {
            gate,
            predictors: predictors.iter().copied().collect(),
            ..GateStats::default()
        })
    }

    fn interaction(acs: MapStats, collections: &[MapStats]) -> ModelStats {
        ModelStats::Interaction(InteractionStats {
            acs,
            collections: collections
                .iter()
                .map(|&map| AcStats {
                    changed: Vec::new(),
                    map,
                })
                .collect(),
        })
    }

    #[test]
    fn maps_are_averaged_with_population_std_and_missing_maps_count_zero() {
        let a = gate(map(149, 3), &[(15, map(90, 20))]);
        let b = gate(map(149, 5), &[]);
        let s = NodeSummary::of(&[&a, &b]);
        let gate = s.map(&MapName::Gate).unwrap();
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
        assert_eq!(s.map(&MapName::Predictor(15)).unwrap().nodes.mean, 10.0);
        assert!(s.acs.is_none());
    }

    #[test]
    fn acs_by_definition_and_by_the_scripts_scan() {
        // AC 0: many updates, few nodes; AC 1: the most nodes; AC 2: more
        // updates than AC 1 has nodes... the scan's comparison of update
        // counts with node counts picks AC 2's nodes.
        let fold =
            |bump: usize| interaction(map(149, 40), &[map(60, 5 + bump), map(30, 18), map(10, 2)]);
        let (a, b, c) = (fold(0), fold(2), fold(100));
        let s = NodeSummary::of(&[&a, &b, &c]);
        assert!(!s.maps.keys().any(|k| k.starts_with("ac/")));
        assert_eq!(s.map(&MapName::Acs).unwrap().nodes.mean, 40.0);
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
        let a = interaction(MapStats::default(), &[map(12, 4)]);
        let acs = NodeSummary::of(&[&a]).acs.unwrap();
        assert_eq!(acs.count.mean, 1.0);
        assert_eq!(acs.script_quirk.folds, 1);
        assert_eq!(acs.script_quirk.nodes.mean, 4.0);
    }
}
