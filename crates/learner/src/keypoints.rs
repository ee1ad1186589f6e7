//! The thesis draft's key-point score (draft §6.1.2): for each body its
//! centre and two key points on the block's edges, the corners
//! `R(θ)·(w, h) + p` and `R(θ)·(−w, −h) + p` that the original's recorder
//! also wrote (`docs/spec/experiments.md` §7.1). One number measures position and
//! orientation together:
//!
//! `s = (1/3) Σᵢ |pᵢ(predicted) − pᵢ(actual)|`
//!
//! per message with a prediction; a run reports the final `s`, the
//! accumulated `s` and their mean (accumulated / number of predictions).
//! The actuator is a sphere: its half extents are 0, so its three points
//! coincide and its score is the centre distance.

use std::collections::BTreeMap;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::features::{global_point, Shape};
use crate::types::{ObjectState, Poses, ACTUATOR_ID};

/// Half extents `(w, h)` of a body from the shape table (`docs/spec/features.md` §4):
/// the largest corner coordinates; (0, 0) for round or unknown bodies.
#[must_use]
pub fn half_extents(id: u32) -> (f64, f64) {
    Shape::of_or_point(id)
        .corners
        .iter()
        .fold((0.0, 0.0), |(w, h), c| {
            (c[0].abs().max(w), c[1].abs().max(h))
        })
}

/// The centre and the two key points of a body of half extents `(w, h)` in
/// state `s`.
#[must_use]
pub fn key_points(s: &ObjectState, (w, h): (f64, f64)) -> [Vector2<f64>; 3] {
    let p = s.position();
    [
        p,
        global_point(s.theta, p, Vector2::new(w, h)),
        global_point(s.theta, p, Vector2::new(-w, -h)),
    ]
}

/// `s` for one body: the mean distance of its three points.
#[must_use]
pub fn body_score(actual: &ObjectState, predicted: &ObjectState, extents: (f64, f64)) -> f64 {
    let a = key_points(actual, extents);
    let p = key_points(predicted, extents);
    a.iter().zip(&p).map(|(a, p)| (a - p).norm()).sum::<f64>() / 3.0
}

/// Final, accumulated and mean score of one body over one run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyPointScore {
    /// `s` of the last message of the run.
    pub final_dif: f64,
    /// Σ `s` over the messages with a prediction.
    pub cum_dif: f64,
    /// `cum_dif` / `predictions`.
    pub mean_dif: f64,
    /// Number of predictions compared.
    pub predictions: usize,
}

impl KeyPointScore {
    fn add(&mut self, s: f64) {
        self.final_dif = s;
        self.cum_dif += s;
        self.predictions += 1;
        self.mean_dif = self.cum_dif / self.predictions as f64;
    }
}

/// The key-point scores of one run, per body (the actuator under its id 8).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyPointRun {
    pub bodies: BTreeMap<u32, KeyPointScore>,
}

impl KeyPointRun {
    /// Scores one message: `actual` against the prediction made for it.
    /// Blocks present on one side only are skipped (as in
    /// [`crate::eval::RunErrors::score`]).
    pub fn add(&mut self, actual: &Poses, predicted: &Poses) {
        for (id, a) in actual.objects() {
            let Some(p) = predicted.get(id) else { continue };
            self.bodies
                .entry(id)
                .or_default()
                .add(body_score(&a, &p, half_extents(id)));
        }
    }

    /// The actuator's scores.
    #[must_use]
    pub fn actuator(&self) -> Option<&KeyPointScore> {
        self.bodies.get(&ACTUATOR_ID)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::BLUE_ID;

    #[test]
    fn extents_come_from_the_shape_table() {
        assert_eq!(half_extents(BLUE_ID), (0.25, 0.05));
        assert_eq!(half_extents(27), (0.15, 0.15));
        assert_eq!(half_extents(ACTUATOR_ID), (0.0, 0.0));
    }

    #[test]
    fn a_rotation_in_place_is_seen_through_the_corners() {
        let a = ObjectState::new(0.0, 0.25, 0.0);
        let p = ObjectState::new(0.0, 0.25, std::f64::consts::FRAC_PI_2);
        // Centre distance 0; each corner moves along a chord of a circle of
        // radius |(0.25, 0.05)| through 90°: √2 · r.
        let r = 0.25_f64.hypot(0.05);
        let s = body_score(&a, &p, half_extents(BLUE_ID));
        assert!(
            (s - 2.0 * std::f64::consts::SQRT_2 * r / 3.0).abs() < 1e-12,
            "{s}"
        );
        // A translation moves all three points equally.
        let t = ObjectState::new(0.03, 0.29, 0.0);
        assert!((body_score(&a, &t, half_extents(BLUE_ID)) - 0.05).abs() < 1e-12);
    }

    #[test]
    fn a_run_accumulates_final_total_and_mean() {
        let mut actual = Poses::default();
        actual
            .blocks
            .insert(BLUE_ID, ObjectState::new(0.0, 0.25, 0.0));
        let mut run = KeyPointRun::default();
        for k in 1..=4 {
            let mut predicted = actual.clone();
            predicted.actuator.y += 0.01 * f64::from(k);
            run.add(&actual, &predicted);
        }
        let act = run.actuator().copied().expect("actuator scored");
        assert_eq!(act.predictions, 4);
        assert!((act.final_dif - 0.04).abs() < 1e-12);
        assert!((act.cum_dif - 0.1).abs() < 1e-12);
        assert!((act.mean_dif - 0.025).abs() < 1e-12);
        assert_eq!(run.bodies[&BLUE_ID].cum_dif, 0.0);
    }
}
