//! The AIM network: prototypes per (feature, sign), training and the greedy
//! query (docs/spec/inverse-model.md §2, §4).

use serde::{Deserialize, Serialize};

use super::errors::AimError;
use super::hyperparams::AimConfig;
use super::prototype::{Preconditions, Prototype};
use crate::aitm::distance::lr_distance;

/// Direction of a change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Sign {
    /// σ = −1.
    Negative,
    /// σ = +1.
    Positive,
}

/// Key `(i, σ)` of a prototype: feature index and sign of its change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct PrototypeKey {
    /// Feature index i.
    pub feature: usize,
    /// Sign σ.
    pub sign: Sign,
}

impl PrototypeKey {
    /// Shorthand constructor.
    pub fn new(feature: usize, sign: Sign) -> Self {
        Self { feature, sign }
    }

    /// `key_of(j)` of docs/spec/inverse-model.md §4 for a component `D_j = v`: `(j,
    /// sign v)`, but `(0, +)` for a zero of either sign (the original keyed
    /// prototypes by the text of `j · sign(v)`, which is "0" for every zero
    /// component), and `None` for NaN (no prototype can match it).
    fn of_component(j: usize, v: f64) -> Option<Self> {
        if v == 0.0 {
            Some(Self::new(0, Sign::Positive))
        } else if v > 0.0 {
            Some(Self::new(j, Sign::Positive))
        } else if v < 0.0 {
            Some(Self::new(j, Sign::Negative))
        } else {
            None
        }
    }
}

/// Averaging Inverse Model (docs/spec/inverse-model.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "InverseModelState")]
pub struct InverseModel {
    config: AimConfig,
    /// Precondition dimension, fixed by the first training sample.
    precondition_dim: Option<usize>,
    /// In creation order; at most two per feature, so lookups are linear.
    prototypes: Vec<(PrototypeKey, Prototype)>,
    current_key: Option<PrototypeKey>,
    second_key: Option<PrototypeKey>,
}

impl InverseModel {
    /// An untrained model.
    pub fn new(config: AimConfig) -> Self {
        Self {
            config,
            precondition_dim: None,
            prototypes: Vec::new(),
            current_key: None,
            second_key: None,
        }
    }

    /// The validated parameters.
    pub fn config(&self) -> &AimConfig {
        &self.config
    }

    /// The precondition dimension, fixed by the first training sample
    /// (`None` before it).
    pub fn precondition_dim(&self) -> Option<usize> {
        self.precondition_dim
    }

    /// Number of prototypes created so far.
    pub fn prototype_count(&self) -> usize {
        self.prototypes.len()
    }

    /// The prototypes in creation order.
    pub fn prototypes(&self) -> impl ExactSizeIterator<Item = (PrototypeKey, &Prototype)> + '_ {
        self.prototypes.iter().map(|(k, p)| (*k, p))
    }

    /// The prototype of `key`, if it exists.
    pub fn prototype(&self, key: PrototypeKey) -> Option<&Prototype> {
        self.prototypes
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, p)| p)
    }

    /// The feature currently being reduced.
    pub fn current_key(&self) -> Option<PrototypeKey> {
        self.current_key
    }

    /// The feature expected to be reduced next (persists between queries).
    pub fn second_key(&self) -> Option<PrototypeKey> {
        self.second_key
    }

    /// Forgets the feature currently being reduced (the next query selects
    /// one afresh); `second_key` is left as it is.
    pub fn clear_current(&mut self) {
        self.current_key = None;
    }

    /// `train(p, d)` of docs/spec/inverse-model.md §2.1: every change component with
    /// `|d_i| > eps_dif` trains prototype `(i, sign d_i)` with weight `|d_i|`.
    ///
    /// # Panics
    /// If `p` has a different length than the preconditions of earlier
    /// calls (a programming error).
    pub fn train(&mut self, p: &[f64], d: &[f64]) {
        let dim = *self.precondition_dim.get_or_insert(p.len());
        assert_eq!(p.len(), dim, "precondition dimension mismatch");
        let eps_dif = self.config.params().eps_dif;
        for (i, &di) in d.iter().enumerate() {
            if di.abs() > eps_dif {
                let sign = if di > 0.0 {
                    Sign::Positive
                } else {
                    Sign::Negative
                };
                let key = PrototypeKey::new(i, sign);
                let slot = match self.prototypes.iter().position(|(k, _)| *k == key) {
                    Some(slot) => slot,
                    None => {
                        self.prototypes.push((key, Prototype::new(dim)));
                        self.prototypes.len() - 1
                    }
                };
                self.prototypes[slot].1.train(p, di.abs(), &self.config);
            }
        }
    }

    /// `preconditions_for(D)` of docs/spec/inverse-model.md §4: the precondition
    /// vector to reach next for the target difference `D`, or `None` if no
    /// component of `D` has a prototype.
    pub fn preconditions_for(&mut self, d: &[f64]) -> Option<Vec<f64>> {
        let mut found: Option<Preconditions> = None;
        if let Some(key) = self.current_key {
            let sign_matches = d.get(key.feature).is_some_and(|&v| match key.sign {
                Sign::Positive => v > 0.0,
                Sign::Negative => v < 0.0,
            });
            let large = d
                .get(key.feature)
                .is_some_and(|v| v.abs() > self.config.params().eps_keep);
            if sign_matches && large {
                found = self.preconditions_of(key);
            }
            if found.is_none() {
                self.current_key = None;
            }
        }

        if self.current_key.is_none() {
            // Indices by |D_i| descending, ties to the higher index: an
            // ascending stable sort read from the end (§4).
            let mut order: Vec<usize> = (0..d.len()).collect();
            order.sort_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()));
            order.reverse();
            for (r, &i) in order.iter().enumerate() {
                if let Some(&next) = order.get(r + 1) {
                    self.second_key = PrototypeKey::of_component(next, d[next]);
                }
                let Some(key) = PrototypeKey::of_component(i, d[i]) else {
                    continue;
                };
                if let Some(pre) = self.preconditions_of(key) {
                    self.current_key = Some(key);
                    found = Some(pre);
                    break;
                }
            }
        }

        let Preconditions {
            primary: p1,
            alternative,
        } = found?;
        let Some(p2) = alternative else {
            return Some(p1);
        };
        let Some(second) = self.second_key.and_then(|k| self.preconditions_of(k)) else {
            return Some(p1);
        };
        // Choose the alternative nearer to how the next feature would be
        // reduced (distances over all components, left-to-right norms).
        let o1 = lr_distance(&second.primary, &p1);
        let o2 = lr_distance(&second.primary, &p2);
        let choose_p1 = match &second.alternative {
            None => o1 <= o2,
            Some(s2) => {
                let o3 = lr_distance(s2, &p1);
                let o4 = lr_distance(s2, &p2);
                o1.min(o3) <= o2.min(o4)
            }
        };
        Some(if choose_p1 { p1 } else { p2 })
    }

    fn preconditions_of(&self, key: PrototypeKey) -> Option<Preconditions> {
        self.prototype(key)?.preconditions(&self.config)
    }
}

/// The serialised form, validated before it becomes an [`InverseModel`].
#[derive(Deserialize)]
struct InverseModelState {
    config: AimConfig,
    precondition_dim: Option<usize>,
    prototypes: Vec<(PrototypeKey, Prototype)>,
    current_key: Option<PrototypeKey>,
    second_key: Option<PrototypeKey>,
}

impl TryFrom<InverseModelState> for InverseModel {
    type Error = AimError;

    fn try_from(s: InverseModelState) -> Result<Self, Self::Error> {
        use AimError::InconsistentState as Bad;
        for (k, (key, proto)) in s.prototypes.iter().enumerate() {
            if Some(proto.dim()) != s.precondition_dim {
                return Err(Bad("prototype dimension"));
            }
            if !proto.is_consistent() {
                return Err(Bad("prototype accumulators"));
            }
            if s.prototypes[..k].iter().any(|(other, _)| other == key) {
                return Err(Bad("duplicate prototype key"));
            }
        }
        if let Some(current) = s.current_key {
            if !s.prototypes.iter().any(|(k, _)| *k == current) {
                return Err(Bad("current key names no prototype"));
            }
        }
        Ok(Self {
            config: s.config,
            precondition_dim: s.precondition_dim,
            prototypes: s.prototypes,
            current_key: s.current_key,
            second_key: s.second_key,
        })
    }
}
