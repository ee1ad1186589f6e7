//! The memory for what the mechanics miss: k nearest neighbours over
//! contact-frame features, inverse-distance weighted (`docs/models.md`
//! "The hybrid model").
//!
//! A memory of residuals rather than of motions: far from everything it
//! has seen, it says nothing and the mechanics stand alone, which is what
//! lets the model carry over to pushes and objects it was not trained on.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

/// Features of one message: the pusher's position and its path over the
/// message, the slider's motion over the previous message, all in the
/// slider's frame (see [`features`]).
pub const FEATURES: usize = 7;

/// What is stored per message: the slider's motion in its own frame
/// (along x, along y, turn) minus the mechanics' prediction.
pub type Residual = [f64; 3];

/// The features of one message, scaled so that a unit in each is a
/// comparable difference in what happens: positions in metres,
/// per-message motions ×10 (a push of 5 mm per message against a
/// position 5 cm off).
#[must_use]
pub fn features(pusher: [f64; 2], path: [f64; 2], motion: [f64; 3]) -> [f64; FEATURES] {
    const MOTION: f64 = 10.0;
    [
        pusher[0],
        pusher[1],
        MOTION * path[0],
        MOTION * path[1],
        MOTION * motion[0],
        MOTION * motion[1],
        // A radian of turn per message is rarer than a metre: one degree
        // per message weighs like 1.7 mm of path.
        MOTION * 0.1 * motion[2],
    ]
}

/// The residual memory: its samples, and an index of them by the cell of
/// [`REACH`] × [`REACH`] their pusher position falls in, so that a query
/// looks at the samples of nine cells instead of all of them. The index
/// is rebuilt from the samples when a memory is read back.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(from = "Samples", into = "Samples")]
pub struct Memory {
    samples: Samples,
    cells: HashMap<(i64, i64), Vec<usize>>,
}

/// A memory's samples, in insertion order.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Samples {
    keys: Vec<[f64; FEATURES]>,
    values: Vec<Residual>,
}

impl From<Samples> for Memory {
    fn from(samples: Samples) -> Self {
        let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (i, k) in samples.keys.iter().enumerate() {
            cells.entry(cell(k)).or_default().push(i);
        }
        Self { samples, cells }
    }
}

impl From<Memory> for Samples {
    fn from(memory: Memory) -> Self {
        memory.samples
    }
}

/// The index cell of a key.
fn cell(key: &[f64; FEATURES]) -> (i64, i64) {
    // Positions are within metres of the block: far inside i64.
    #[allow(clippy::cast_possible_truncation)]
    let at = |x: f64| (x / REACH).floor() as i64;
    (at(key[0]), at(key[1]))
}

/// Neighbours that answer a query.
pub const NEIGHBOURS: usize = 4;

/// A neighbour farther than this (feature units, see [`features`]) says
/// nothing: 1 cm of pusher position, or 1 mm of path per message. Chosen
/// among 2.5 mm, 5 mm, 1 cm and 2 cm on seed 7 (not the test seed), 8
/// folds, by the mean block position and orientation errors over 1, 3,
/// 10 and 30 training runs, each relative to the thesis's 30-run value
/// (`docs/models.md` "The hybrid model").
pub const REACH: f64 = 0.01;

impl Memory {
    pub fn insert(&mut self, key: [f64; FEATURES], value: Residual) {
        self.cells
            .entry(cell(&key))
            .or_default()
            .push(self.samples.keys.len());
        self.samples.keys.push(key);
        self.samples.values.push(value);
    }

    /// The stored residuals, in insertion order, to be recomputed when
    /// the mechanics they are the residual of change.
    pub fn values_mut(&mut self) -> &mut [Residual] {
        &mut self.samples.values
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.samples.keys.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.samples.keys.is_empty()
    }

    /// The inverse-distance-weighted mean residual of the nearest
    /// neighbours within [`REACH`]; zero when there are none. Ties in
    /// distance go to the earlier sample, so the answer does not depend on
    /// anything but the order of insertion.
    #[must_use]
    pub fn query(&self, key: &[f64; FEATURES]) -> Residual {
        let reach2 = REACH * REACH;
        let mut best: [(f64, usize); NEIGHBOURS] = [(f64::INFINITY, usize::MAX); NEIGHBOURS];
        // Within REACH in all features is within REACH in the pusher's
        // position: the neighbouring cells hold every candidate.
        let (cx, cy) = cell(key);
        for dx in -1..=1 {
            for dy in -1..=1 {
                let Some(indices) = self.cells.get(&(cx + dx, cy + dy)) else {
                    continue;
                };
                for &i in indices {
                    let k = &self.samples.keys[i];
                    let mut d2 = 0.0;
                    for f in 0..FEATURES {
                        let d = k[f] - key[f];
                        d2 += d * d;
                    }
                    // Ordered by distance, then by insertion: the cells'
                    // order does not matter.
                    if d2 >= reach2 || (d2, i) >= best[NEIGHBOURS - 1] {
                        continue;
                    }
                    let mut at = NEIGHBOURS - 1;
                    while at > 0 && best[at - 1] > (d2, i) {
                        best[at] = best[at - 1];
                        at -= 1;
                    }
                    best[at] = (d2, i);
                }
            }
        }
        let mut sum = [0.0; 3];
        let mut weights = 0.0;
        for &(d2, i) in best.iter().filter(|(_, i)| *i != usize::MAX) {
            // Exact repeats would divide by zero: a floor of 0.1 mm.
            let w = 1.0 / d2.sqrt().max(1e-4);
            for (s, v) in sum.iter_mut().zip(self.samples.values[i]) {
                *s += w * v;
            }
            weights += w;
        }
        if weights == 0.0 {
            return [0.0; 3];
        }
        sum.map(|s| s / weights)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(x: f64) -> [f64; FEATURES] {
        [x, 0.0, 0.0, 0.05, 0.0, 0.0, 0.0]
    }

    #[test]
    fn an_empty_or_distant_memory_answers_zero() {
        let mut m = Memory::default();
        assert_eq!(m.query(&key(0.0)), [0.0; 3]);
        m.insert(key(0.0), [1.0, 2.0, 3.0]);
        assert_eq!(m.query(&key(REACH * 1.01)), [0.0; 3]);
        assert_eq!(m.query(&key(0.0)), [1.0, 2.0, 3.0]);
    }

    #[test]
    fn a_memory_read_back_answers_as_the_original() {
        let mut m = Memory::default();
        for i in 0..50 {
            let x = f64::from(i) * 0.003 - 0.07;
            m.insert(key(x), [x, 1.0, 0.0]);
        }
        let back: Memory = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        for q in [-0.07, -0.0101, 0.0, 0.033, 0.079, 0.2] {
            assert_eq!(m.query(&key(q)), back.query(&key(q)), "{q}");
        }
        // Across a cell's edge: neighbours on both sides count.
        let edge = m.query(&key(REACH * 2.0));
        assert!(
            edge[0] > REACH * 2.0 - 0.003 && edge[0] < REACH * 2.0 + 0.003,
            "{edge:?}"
        );
    }

    #[test]
    fn nearer_neighbours_weigh_more_and_only_four_count() {
        let mut m = Memory::default();
        m.insert(key(0.001), [1.0, 0.0, 0.0]);
        m.insert(key(0.003), [0.0, 0.0, 0.0]);
        for _ in 0..3 {
            m.insert(key(0.002), [0.5, 0.0, 0.0]);
        }
        m.insert(key(-0.0011), [9.0, 0.0, 0.0]);
        // Four nearest of 0.0: 0.001 (w 1000), −0.0011 (w ≈ 909), and two
        // of the three at 0.002 (w 500 each); 0.003 is fifth.
        let r = m.query(&key(0.0));
        let want = (1000.0 * 1.0 + 1000.0 / 1.1 * 9.0 + 500.0 * 0.5 * 2.0)
            / (1000.0 + 1000.0 / 1.1 + 1000.0);
        assert!((r[0] - want).abs() < 1e-9, "{} vs {want}", r[0]);
    }
}
