//! One AIM prototype: per sign combination accumulators, merging and
//! preconditions (docs/spec/inverse-model.md §3).

use serde::{Deserialize, Serialize};

use super::hyperparams::AimConfig;

/// Accumulators of one sign combination (docs/spec/inverse-model.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Combination {
    /// The sign combination `c` (−1, 0 or +1 per precondition component).
    pub signs: Vec<i8>,
    /// `W[c]`: sum of the weights `|d_i|`.
    pub w: f64,
    /// `I[c]`: weighted sum of precondition vectors `Σ |d_i| · p`.
    pub i: Vec<f64>,
    /// `N[c]`: number of samples.
    pub n: u64,
}

/// One group of the on-the-fly merge (docs/spec/inverse-model.md §3.2).
#[derive(Debug, Clone, PartialEq)]
pub struct MergedGroup {
    /// Sign combination of `s / w`, recomputed after merging.
    pub key: Vec<i8>,
    /// Summed weights.
    pub w: f64,
    /// Summed weighted preconditions.
    pub s: Vec<f64>,
    /// Summed sample counts.
    pub n: u64,
}

/// Result of [`Prototype::preconditions`]: the best precondition vector and,
/// when a second group contributes more than `ratio` × the best average, an
/// alternative (docs/spec/inverse-model.md §3.3).
#[derive(Debug, Clone, PartialEq)]
pub struct Preconditions {
    /// P1.
    pub primary: Vec<f64>,
    /// P2, if offered.
    pub alternative: Option<Vec<f64>>,
}

/// The prototype of one (feature index, sign) key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Prototype {
    dim: usize,
    /// In first-insertion order (docs/spec/inverse-model.md §6: the original's hash
    /// map order is replaced by this order, a decision of the spec).
    combinations: Vec<Combination>,
}

/// The sign combination of `p` with the zero band `[−eps_node, eps_node]`
/// (a NaN component counts as 0).
pub fn sign_combination(p: &[f64], eps_node: f64) -> Vec<i8> {
    p.iter()
        .map(|&v| {
            if v < -eps_node {
                -1
            } else if v > eps_node {
                1
            } else {
                0
            }
        })
        .collect()
}

/// `equivalent(a, b)` of docs/spec/inverse-model.md §3.2: no opposing signs and at most
/// `max_zero_mismatch` components where exactly one of the two is 0.
fn equivalent(a: &[i8], b: &[i8], max_zero_mismatch: usize) -> bool {
    let mut mismatches = 0;
    for (&x, &y) in a.iter().zip(b) {
        if x * y < 0 {
            return false;
        }
        if (x == 0) != (y == 0) {
            mismatches += 1;
        }
    }
    mismatches <= max_zero_mismatch
}

impl Prototype {
    /// An untrained prototype for `dim`-component preconditions.
    pub fn new(dim: usize) -> Self {
        Self {
            dim,
            combinations: Vec::new(),
        }
    }

    /// Precondition dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The stored combinations in first-insertion order.
    pub fn combinations(&self) -> &[Combination] {
        &self.combinations
    }

    /// `train(p, w)` of docs/spec/inverse-model.md §3.1.
    ///
    /// # Panics
    /// If `p.len() != dim`.
    pub fn train(&mut self, p: &[f64], w: f64, config: &AimConfig) {
        assert_eq!(p.len(), self.dim, "precondition dimension mismatch");
        let signs = sign_combination(p, config.params().eps_node);
        match self.combinations.iter_mut().find(|c| c.signs == signs) {
            Some(c) => {
                c.w += w;
                for (acc, v) in c.i.iter_mut().zip(p) {
                    *acc += w * v;
                }
                c.n += 1;
            }
            None => self.combinations.push(Combination {
                signs,
                w,
                i: p.iter().map(|v| w * v).collect(),
                n: 1,
            }),
        }
    }

    /// The merge of docs/spec/inverse-model.md §3.2, computed afresh (the stored
    /// accumulators are not modified).
    pub fn merge(&self, config: &AimConfig) -> Vec<MergedGroup> {
        let params = config.params();
        let combos = &self.combinations;
        if combos.is_empty() {
            return Vec::new();
        }
        let total: u64 = combos.iter().map(|c| c.n).sum();
        // Arithmetic mean as a double, as the original's array library did.
        let mean = total as f64 / combos.len() as f64;
        let mut pending: Vec<usize> = (0..combos.len())
            .filter(|&c| combos[c].n as f64 >= mean)
            .collect();
        let zeros = |c: usize| combos[c].signs.iter().filter(|&&s| s == 0).count();
        // Stable: equal zero counts keep first-insertion order.
        pending.sort_by_key(|&c| std::cmp::Reverse(zeros(c)));

        let mut result: Vec<MergedGroup> = Vec::new();
        while let Some((&c0, rest)) = pending.split_first() {
            let first = &combos[c0];
            let (mut w, mut s, mut n) = (first.w, first.i.clone(), first.n);
            let mut remaining = Vec::with_capacity(rest.len());
            for &c in rest {
                // Against the group's first member, not the growing group.
                if equivalent(&first.signs, &combos[c].signs, params.max_zero_mismatch) {
                    w += combos[c].w;
                    for (acc, v) in s.iter_mut().zip(&combos[c].i) {
                        *acc += v;
                    }
                    n += combos[c].n;
                } else {
                    remaining.push(c);
                }
            }
            pending = remaining;
            let mean_p: Vec<f64> = s.iter().map(|v| v / w).collect();
            let key = sign_combination(&mean_p, params.eps_node);
            let group = MergedGroup { key, w, s, n };
            // A recomputed key equal to an earlier group's replaces that
            // group in its original position (original behaviour, §6).
            match result.iter_mut().find(|g| g.key == group.key) {
                Some(slot) => *slot = group,
                None => result.push(group),
            }
        }
        result
    }

    /// `preconditions()` of docs/spec/inverse-model.md §3.3; `None` if never trained.
    pub fn preconditions(&self, config: &AimConfig) -> Option<Preconditions> {
        let merged = self.merge(config);
        let avg = |g: &MergedGroup| g.w / g.n as f64;
        let mut order: Vec<usize> = (0..merged.len()).collect();
        // Descending by average contribution, stable for ties.
        order.sort_by(|&a, &b| avg(&merged[b]).total_cmp(&avg(&merged[a])));
        let g1 = &merged[*order.first()?];
        if let Some(&second) = order.get(1) {
            let g2 = &merged[second];
            if avg(g2) / avg(g1) > config.params().ratio {
                let mut p1 = Vec::with_capacity(self.dim);
                let mut p2 = Vec::with_capacity(self.dim);
                for j in 0..self.dim {
                    if g1.key[j] == g2.key[j] {
                        // Agreeing signs are pooled.
                        let v = (g1.s[j] + g2.s[j]) / (g1.w + g2.w);
                        p1.push(v);
                        p2.push(v);
                    } else {
                        p1.push(g1.s[j] / g1.w);
                        p2.push(g2.s[j] / g2.w);
                    }
                }
                return Some(Preconditions {
                    primary: p1,
                    alternative: Some(p2),
                });
            }
        }
        Some(Preconditions {
            primary: g1.s.iter().map(|v| v / g1.w).collect(),
            alternative: None,
        })
    }

    /// Structural check used when deserialising.
    pub(crate) fn is_consistent(&self) -> bool {
        !self.combinations.is_empty()
            && self.combinations.iter().enumerate().all(|(k, c)| {
                c.signs.len() == self.dim
                    && c.i.len() == self.dim
                    && c.n >= 1
                    && c.signs.iter().all(|s| (-1..=1).contains(s))
                    && self.combinations[..k].iter().all(|o| o.signs != c.signs)
            })
    }
}
