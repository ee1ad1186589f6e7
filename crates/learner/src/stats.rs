//! A model's statistics (`docs/spec/gate-model.md` §7,
//! `docs/spec/interaction-model.md` §6, `docs/spec/experiments.md` §7.5), typed
//! per model.
//!
//! Reports, the daemon's `learn` output and the end-to-end tests read the
//! serialised form `{maps, extra, labels}` with string keys (`"actuator"`,
//! `"predictor/15"`, `"ac/0"`, `"ac_count"`, …), so that form is kept
//! exactly: [`ModelStats`] serialises through the private [`Wire`] struct,
//! and the key names live only in [`MapName`]'s `Display` and in [`Wire`].

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::aitm::MapStats;

/// Value of the stats labels for a hard-coded part of the gate model
/// (`docs/spec/gate-model.md` §5): part of the statistics' serialised form,
/// so it lives here and the model uses it.
pub const HARD_CODED_LABEL: &str = "hard-coded";

/// The gate model's maps (`docs/spec/gate-model.md` §7).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GateStats {
    /// The actuator forward model.
    pub actuator: MapStats,
    /// The gate classifier.
    pub gate: MapStats,
    /// Each block's predictor AITM, by block id.
    pub predictors: BTreeMap<u32, MapStats>,
    /// The actuator model is the hard-coded step, not a learned map.
    pub hard_coded_actuator: bool,
    /// The gate is the hard-coded contact rule, not a learned map.
    pub hard_coded_gate: bool,
}

/// One Abstract Collection (`docs/spec/interaction-model.md` §1).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AcStats {
    /// Its changed-feature set, in the AC's order.
    pub changed: Vec<usize>,
    /// Its forward model.
    pub map: MapStats,
}

/// The interaction model's maps (`docs/spec/interaction-model.md` §6).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct InteractionStats {
    /// The Abstract Collection Selector.
    pub acs: MapStats,
    /// The Abstract Collections, in id order.
    pub collections: Vec<AcStats>,
}

/// The "AC with the most nodes" of `docs/spec/experiments.md` §7.5.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LargestAc {
    /// Its id: the lowest among equally large ACs *(decision)*.
    pub id: usize,
    pub map: MapStats,
}

/// What the original analysis script computed for its AC columns
/// (`docs/spec/experiments.md` §7.5 quirk).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScriptAc {
    /// The maximum update count over all ACs.
    pub update_calls: u64,
    /// A running value over the ACs in id order, set to an AC's *node*
    /// count whenever its *update* count exceeds the value.
    pub nodes: usize,
}

impl InteractionStats {
    /// The AC with the most nodes, `None` without ACs.
    #[must_use]
    pub fn largest(&self) -> Option<LargestAc> {
        // `max_by_key` keeps the last maximum, so scanning in reverse keeps
        // the lowest id.
        self.collections
            .iter()
            .enumerate()
            .rev()
            .max_by_key(|(_, ac)| ac.map.nodes)
            .map(|(id, ac)| LargestAc { id, map: ac.map })
    }

    /// The script's AC columns; zeros without ACs.
    #[must_use]
    pub fn script_quirk(&self) -> ScriptAc {
        let update_calls = self
            .collections
            .iter()
            .map(|ac| ac.map.update_calls)
            .max()
            .unwrap_or(0);
        let mut nodes = 0;
        for ac in &self.collections {
            if ac.map.update_calls > nodes as u64 {
                nodes = ac.map.nodes;
            }
        }
        ScriptAc {
            update_calls,
            nodes,
        }
    }
}

/// Statistics of one model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "Wire", try_from = "Wire")]
pub enum ModelStats {
    Gate(GateStats),
    Interaction(InteractionStats),
    /// A model of neither kind (an external learner, the test double).
    Other(OtherStats),
}

/// The statistics of a model that is neither of the thesis's: whatever
/// maps, numbers and labels it reports, kept and shown as they are. Only
/// the built-in models' map names (`actuator`, `gate`, `predictor/ID`,
/// `acs`, `ac/K`) are reserved: statistics that use one of them are read as
/// that model's, complete and consistent.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OtherStats {
    /// Its memories' counters, by its own names.
    pub maps: BTreeMap<String, MapStats>,
    /// Any further numbers it reports (finite: JSON has no other).
    pub extra: BTreeMap<String, f64>,
    /// Any text it reports.
    pub labels: BTreeMap<String, String>,
}

impl Default for ModelStats {
    fn default() -> Self {
        Self::Other(OtherStats::default())
    }
}

/// Names a map of [`ModelStats`]; its `Display` is the map's key in the
/// serialised form and in `NodeSummary`.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum MapName {
    Actuator,
    Gate,
    Predictor(u32),
    Acs,
    Ac(usize),
    Other(String),
}

const ACTUATOR: &str = "actuator";
const GATE: &str = "gate";
const PREDICTOR_PREFIX: &str = "predictor/";
const ACS: &str = "acs";
const AC_PREFIX: &str = "ac/";
const AC_COUNT: &str = "ac_count";
const AC_LARGEST_ID: &str = "ac_largest_id";
const AC_LARGEST_UPDATES: &str = "ac_largest_updates";
const AC_LARGEST_NODES: &str = "ac_largest_nodes";
const AC_SCRIPT_UPDATES: &str = "ac_script_updates";
const AC_SCRIPT_NODES: &str = "ac_script_nodes";

impl fmt::Display for MapName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Actuator => f.write_str(ACTUATOR),
            Self::Gate => f.write_str(GATE),
            Self::Predictor(id) => write!(f, "{PREDICTOR_PREFIX}{id}"),
            Self::Acs => f.write_str(ACS),
            Self::Ac(k) => write!(f, "{AC_PREFIX}{k}"),
            Self::Other(name) => f.write_str(name),
        }
    }
}

impl ModelStats {
    /// Every map with its name: the gate model's actuator, gate and
    /// predictors in id order; the interaction model's ACS and ACs in id
    /// order.
    #[must_use]
    pub fn maps(&self) -> Vec<(MapName, MapStats)> {
        match self {
            Self::Gate(g) => [(MapName::Actuator, g.actuator), (MapName::Gate, g.gate)]
                .into_iter()
                .chain(
                    g.predictors
                        .iter()
                        .map(|(&id, &m)| (MapName::Predictor(id), m)),
                )
                .collect(),
            Self::Interaction(i) => std::iter::once((MapName::Acs, i.acs))
                .chain(
                    i.collections
                        .iter()
                        .enumerate()
                        .map(|(k, ac)| (MapName::Ac(k), ac.map)),
                )
                .collect(),
            Self::Other(other) => other
                .maps
                .iter()
                .map(|(name, &m)| (MapName::Other(name.clone()), m))
                .collect(),
        }
    }

    /// One map by name, if this model has it.
    #[must_use]
    pub fn map(&self, name: &MapName) -> Option<MapStats> {
        self.maps()
            .into_iter()
            .find_map(|(n, m)| (n == *name).then_some(m))
    }

    #[must_use]
    pub fn as_gate(&self) -> Option<&GateStats> {
        match self {
            Self::Gate(g) => Some(g),
            _ => None,
        }
    }

    #[must_use]
    pub fn as_interaction(&self) -> Option<&InteractionStats> {
        match self {
            Self::Interaction(i) => Some(i),
            _ => None,
        }
    }

    #[must_use]
    pub fn as_other(&self) -> Option<&OtherStats> {
        match self {
            Self::Other(o) => Some(o),
            _ => None,
        }
    }
}

/// Why a serialised `{maps, extra, labels}` is not a model's statistics.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StatsError {
    #[error("map {0:?} does not belong with the others ({RESERVED})")]
    UnexpectedMap(String),
    #[error("map {0:?} is missing ({RESERVED})")]
    MissingMap(String),
    #[error("label {key:?} = {value:?} is not valid here ({RESERVED})")]
    BadLabel { key: String, value: String },
    #[error("extra value {0:?} is missing, unknown or does not match the maps ({RESERVED})")]
    BadExtra(String),
}

/// What a [`StatsError`] is about: only statistics that use a built-in
/// model's map names are held to a shape.
const RESERVED: &str = "the map names actuator, gate, predictor/ID, acs and ac/K are reserved for \
                        the built-in models' statistics, which must then be complete";

/// The serialised form: the shape `ModelStats` had when it was string-keyed.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Wire {
    maps: BTreeMap<String, MapStats>,
    extra: BTreeMap<String, f64>,
    labels: BTreeMap<String, String>,
}

/// The interaction model's scalar statistics, derived from its maps.
fn interaction_extra(i: &InteractionStats) -> BTreeMap<String, f64> {
    let mut extra = BTreeMap::from([(AC_COUNT.to_owned(), i.collections.len() as f64)]);
    if let Some(largest) = i.largest() {
        let quirk = i.script_quirk();
        extra.extend([
            (AC_LARGEST_ID.to_owned(), largest.id as f64),
            (
                AC_LARGEST_UPDATES.to_owned(),
                largest.map.update_calls as f64,
            ),
            (AC_LARGEST_NODES.to_owned(), largest.map.nodes as f64),
            (AC_SCRIPT_UPDATES.to_owned(), quirk.update_calls as f64),
            (AC_SCRIPT_NODES.to_owned(), quirk.nodes as f64),
        ]);
    }
    extra
}

/// A changed-feature set as the AC index key, e.g. "2,3,5" ("" for the
/// empty set).
pub(crate) fn changed_label(changed: &[usize]) -> String {
    let parts: Vec<String> = changed.iter().map(ToString::to_string).collect();
    parts.join(",")
}

fn parse_changed(label: &str) -> Option<Vec<usize>> {
    if label.is_empty() {
        return Some(Vec::new());
    }
    label.split(',').map(|p| p.parse().ok()).collect()
}

impl From<ModelStats> for Wire {
    fn from(stats: ModelStats) -> Self {
        let maps = stats
            .maps()
            .into_iter()
            .map(|(name, m)| (name.to_string(), m))
            .collect();
        let mut wire = Self {
            maps,
            ..Self::default()
        };
        match &stats {
            ModelStats::Gate(g) => {
                for (hard, name) in [
                    (g.hard_coded_actuator, MapName::Actuator),
                    (g.hard_coded_gate, MapName::Gate),
                ] {
                    if hard {
                        wire.labels
                            .insert(name.to_string(), HARD_CODED_LABEL.to_owned());
                    }
                }
            }
            ModelStats::Interaction(i) => {
                for (k, ac) in i.collections.iter().enumerate() {
                    wire.labels
                        .insert(MapName::Ac(k).to_string(), changed_label(&ac.changed));
                }
                wire.extra = interaction_extra(i);
            }
            ModelStats::Other(other) => {
                wire.extra.clone_from(&other.extra);
                wire.labels.clone_from(&other.labels);
            }
        }
        wire
    }
}

impl TryFrom<Wire> for ModelStats {
    type Error = StatsError;

    /// Which model wrote the statistics is told by its maps: the gate
    /// model always has `actuator` and `gate`, the interaction model always
    /// has `acs`; anything else must not use their names.
    fn try_from(mut wire: Wire) -> Result<Self, StatsError> {
        let take = |maps: &mut BTreeMap<String, MapStats>, key: &str| {
            maps.remove(key)
                .ok_or_else(|| StatsError::MissingMap(key.to_owned()))
        };
        let is_gate = |k: &str| k == ACTUATOR || k == GATE || k.starts_with(PREDICTOR_PREFIX);
        let is_interaction = |k: &str| k == ACS || k.starts_with(AC_PREFIX);
        if wire.maps.keys().any(|k| is_gate(k)) {
            let actuator = take(&mut wire.maps, ACTUATOR)?;
            let gate = take(&mut wire.maps, GATE)?;
            let predictors = wire
                .maps
                .into_iter()
                .map(
                    |(k, m)| match k.strip_prefix(PREDICTOR_PREFIX).map(str::parse) {
                        Some(Ok(id)) => Ok((id, m)),
                        _ => Err(StatsError::UnexpectedMap(k)),
                    },
                )
                .collect::<Result<_, _>>()?;
            if let Some(k) = wire.extra.keys().next() {
                return Err(StatsError::BadExtra(k.clone()));
            }
            let mut hard = [false; 2];
            for (key, value) in wire.labels {
                let slot = match key.as_str() {
                    ACTUATOR => 0,
                    GATE => 1,
                    _ => return Err(StatsError::BadLabel { key, value }),
                };
                if value != HARD_CODED_LABEL {
                    return Err(StatsError::BadLabel { key, value });
                }
                hard[slot] = true;
            }
            return Ok(Self::Gate(GateStats {
                actuator,
                gate,
                predictors,
                hard_coded_actuator: hard[0],
                hard_coded_gate: hard[1],
            }));
        }
        if wire.maps.keys().any(|k| is_interaction(k)) {
            let acs = take(&mut wire.maps, ACS)?;
            let mut collections = Vec::with_capacity(wire.maps.len());
            // ACs are numbered 0, 1, …: ask for each id in turn, so that a
            // gap or a stray name is left over below.
            while let Some(map) = wire
                .maps
                .remove(&MapName::Ac(collections.len()).to_string())
            {
                let key = MapName::Ac(collections.len()).to_string();
                let value = wire
                    .labels
                    .remove(&key)
                    .ok_or_else(|| StatsError::BadLabel {
                        key: key.clone(),
                        value: String::new(),
                    })?;
                let changed = parse_changed(&value).ok_or(StatsError::BadLabel { key, value })?;
                collections.push(AcStats { changed, map });
            }
            if let Some(k) = wire.maps.into_keys().next() {
                return Err(StatsError::UnexpectedMap(k));
            }
            if let Some((key, value)) = wire.labels.into_iter().next() {
                return Err(StatsError::BadLabel { key, value });
            }
            let stats = InteractionStats { acs, collections };
            let derived = interaction_extra(&stats);
            if let Some(k) = derived
                .keys()
                .chain(wire.extra.keys())
                .find(|k| derived.get(*k) != wire.extra.get(*k))
            {
                return Err(StatsError::BadExtra(k.clone()));
            }
            return Ok(Self::Interaction(stats));
        }
        Ok(Self::Other(OtherStats {
            maps: wire.maps,
            extra: wire.extra,
            labels: wire.labels,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(update_calls: u64, inserts: u64, nodes: usize) -> MapStats {
        MapStats {
            update_calls,
            inserts,
            nodes,
        }
    }

    fn interaction() -> ModelStats {
        ModelStats::Interaction(InteractionStats {
            acs: ms(7, 4, 4),
            collections: vec![
                AcStats {
                    changed: vec![2, 3, 5],
                    map: ms(3, 3, 3),
                },
                AcStats {
                    changed: vec![],
                    map: ms(4, 2, 2),
                },
            ],
        })
    }

    fn gate() -> ModelStats {
        ModelStats::Gate(GateStats {
            actuator: ms(298, 2, 2),
            gate: ms(298, 5, 5),
            predictors: BTreeMap::from([(15, ms(90, 20, 19)), (7, ms(0, 0, 0))]),
            hard_coded_actuator: false,
            hard_coded_gate: true,
        })
    }

    const INTERACTION_JSON: &str = concat!(
        r#"{"maps":{"ac/0":{"update_calls":3,"inserts":3,"nodes":3},"#,
        r#""ac/1":{"update_calls":4,"inserts":2,"nodes":2},"#,
        r#""acs":{"update_calls":7,"inserts":4,"nodes":4}},"#,
        r#""extra":{"ac_count":2.0,"ac_largest_id":0.0,"ac_largest_nodes":3.0,"#,
        r#""ac_largest_updates":3.0,"ac_script_nodes":2.0,"ac_script_updates":4.0},"#,
        r#""labels":{"ac/0":"2,3,5","ac/1":""}}"#
    );

    const GATE_JSON: &str = concat!(
        r#"{"maps":{"actuator":{"update_calls":298,"inserts":2,"nodes":2},"#,
        r#""gate":{"update_calls":298,"inserts":5,"nodes":5},"#,
        r#""predictor/15":{"update_calls":90,"inserts":20,"nodes":19},"#,
        r#""predictor/7":{"update_calls":0,"inserts":0,"nodes":0}},"#,
        r#""extra":{},"labels":{"gate":"hard-coded"}}"#
    );

    #[test]
    fn serialises_to_the_string_keyed_shape_exactly() {
        assert_eq!(
            serde_json::to_string(&interaction()).unwrap(),
            INTERACTION_JSON
        );
        assert_eq!(serde_json::to_string(&gate()).unwrap(), GATE_JSON);
        let probe = ModelStats::Other(OtherStats {
            maps: BTreeMap::from([("probe".to_owned(), ms(3, 1, 4))]),
            ..OtherStats::default()
        });
        assert_eq!(
            serde_json::to_string(&probe).unwrap(),
            r#"{"maps":{"probe":{"update_calls":3,"inserts":1,"nodes":4}},"extra":{},"labels":{}}"#
        );
        let empty = ModelStats::Interaction(InteractionStats::default());
        assert_eq!(
            serde_json::to_string(&empty).unwrap(),
            r#"{"maps":{"acs":{"update_calls":0,"inserts":0,"nodes":0}},"extra":{"ac_count":0.0},"labels":{}}"#
        );
    }

    #[test]
    fn reads_the_string_keyed_shape_back() {
        let back: ModelStats = serde_json::from_str(INTERACTION_JSON).unwrap();
        assert_eq!(back, interaction());
        let back: ModelStats = serde_json::from_str(GATE_JSON).unwrap();
        assert_eq!(back, gate());
        let back: ModelStats = serde_json::from_str(
            r#"{"maps":{"probe":{"update_calls":3,"inserts":1,"nodes":4}},"extra":{},"labels":{}}"#,
        )
        .unwrap();
        assert_eq!(back.map(&MapName::Other("probe".into())), Some(ms(3, 1, 4)));
        for s in [interaction(), gate(), ModelStats::default()] {
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(serde_json::from_str::<ModelStats>(&json).unwrap(), s);
        }
    }

    #[test]
    fn inconsistent_shapes_are_refused() {
        let bad = [
            // A gate model without its actuator.
            GATE_JSON.replace("\"actuator\"", "\"other\""),
            // A gap in the AC ids.
            INTERACTION_JSON.replace("\"ac/1\"", "\"ac/2\""),
            // A derived value that does not match the maps.
            INTERACTION_JSON.replace("\"ac_count\":2.0", "\"ac_count\":3.0"),
            // A changed-feature list that is not one.
            INTERACTION_JSON.replace("\"2,3,5\"", "\"2,x\""),
            // A predictor that is not a block id.
            GATE_JSON.replace("predictor/7", "predictor/seven"),
        ];
        for json in bad {
            assert!(serde_json::from_str::<ModelStats>(&json).is_err(), "{json}");
        }
    }

    #[test]
    fn a_learner_of_its_own_keeps_its_maps_numbers_and_labels() {
        let json = concat!(
            r#"{"maps":{"memory":{"update_calls":9,"inserts":4,"nodes":4}},"#,
            r#""extra":{"k":4.0,"contact_distance":0.071},"labels":{"kind":"knn"}}"#
        );
        let back: ModelStats = serde_json::from_str(json).unwrap();
        let ModelStats::Other(other) = &back else {
            panic!("read as a built-in model's: {back:?}");
        };
        assert_eq!(other.maps["memory"], ms(9, 4, 4));
        assert_eq!(other.extra["contact_distance"], 0.071);
        assert_eq!(other.labels["kind"], "knn");
        let again: ModelStats =
            serde_json::from_str(&serde_json::to_string(&back).unwrap()).unwrap();
        assert_eq!(again, back);
        // A reserved name makes the statistics a built-in model's, held to
        // its shape: a lone `gate` map is an incomplete gate model.
        let borrowed =
            r#"{"maps":{"gate":{"update_calls":1,"inserts":1,"nodes":1}},"extra":{},"labels":{}}"#;
        let err = serde_json::from_str::<ModelStats>(borrowed)
            .unwrap_err()
            .to_string();
        assert!(err.contains("map \"actuator\" is missing"), "{err}");
        assert!(err.contains("reserved"), "{err}");
    }

    #[test]
    fn the_largest_ac_and_the_scripts_columns() {
        let of = |maps: &[MapStats]| InteractionStats {
            acs: MapStats::default(),
            collections: maps
                .iter()
                .map(|&map| AcStats {
                    changed: vec![],
                    map,
                })
                .collect(),
        };
        let s = of(&[ms(10, 3, 3), ms(5, 8, 8), ms(20, 2, 2)]);
        assert_eq!(
            s.largest(),
            Some(LargestAc {
                id: 1,
                map: ms(5, 8, 8)
            })
        );
        // m: 10 > 0 → 3; 5 > 3 → 8; 20 > 8 → 2.
        assert_eq!(
            s.script_quirk(),
            ScriptAc {
                update_calls: 20,
                nodes: 2
            }
        );
        assert_eq!(of(&[ms(1, 4, 4), ms(9, 4, 4)]).largest().unwrap().id, 0);
        assert_eq!(of(&[]).largest(), None);
        assert_eq!(of(&[]).script_quirk(), ScriptAc::default());
    }
}
