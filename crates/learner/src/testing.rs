//! The [`Model`] test double of every crate's tests (the learner's own, the
//! experiment driver's, the learner daemon's): one model whose every call is
//! visible, so that a test can check how a caller drives the trait without a
//! real learner's arithmetic in the way.
//!
//! Behind the `testing` feature (and `cfg(test)`): never part of a shipped
//! build.

use std::collections::BTreeMap;

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::features::{parse_frame, ActuatorYaw, ParseError};
use crate::model::{Model, ModelStats};
use crate::stats::MapName;
use crate::types::{Action, Frame, Poses, Target, TargetError};
use crate::MapStats;

/// Metres the actuator moves per unit of action in a prediction: a visible,
/// exact step (5 mm for the push action), so that prediction chains can be
/// told apart from real states.
pub const PREDICTED_STEP: f64 = 0.01;

/// Predicts "the actuator moves by action · [`PREDICTED_STEP`], blocks stay",
/// logs and counts the calls it gets, and in Move to Target explores along x
/// until its target is reached.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Probe {
    /// `reset y=…` and `update y=… a=…` per call, in order (actuator y to the
    /// millimetre, the action's y).
    pub calls: Vec<String>,
    pub resets: u64,
    pub updates: u64,
    /// Updates made while training was on.
    pub trained_updates: u64,
    pub training_off: bool,
    pub target: Option<Target>,
    /// The world of the last reset or update.
    pub current: Option<Poses>,
    /// `act` reports the target reached after this many calls.
    pub reach_after: Option<u64>,
    pub acts: u64,
}

impl Probe {
    /// The name of the probe's one map.
    pub const MAP: &str = "probe";

    /// The probe's map in statistics it reported.
    #[must_use]
    pub fn map(stats: &ModelStats) -> Option<MapStats> {
        stats.map(&MapName::Other(Self::MAP.to_owned()))
    }
}

impl Model for Probe {
    type World = Poses;

    fn parse(&self, frame: &Frame) -> Result<Poses, ParseError> {
        parse_frame(frame, ActuatorYaw::ForceZero)
    }

    fn poses(world: &Poses) -> Poses {
        world.clone()
    }

    fn reset_objects(&mut self, world: &Poses) {
        self.calls.push(format!("reset y={:.3}", world.actuator.y));
        self.resets += 1;
        self.current = Some(world.clone());
    }

    fn update(&mut self, world: &Poses, action: Action) {
        self.calls
            .push(format!("update y={:.3} a={}", world.actuator.y, action.vy));
        self.updates += 1;
        if !self.training_off {
            self.trained_updates += 1;
        }
        self.current = Some(world.clone());
    }

    fn predict(&self, world: &Poses, action: Action) -> Poses {
        let mut next = world.clone();
        next.actuator.x += action.vx * PREDICTED_STEP;
        next.actuator.y += action.vy * PREDICTED_STEP;
        next
    }

    fn set_training(&mut self, on: bool) {
        self.training_off = !on;
    }

    fn is_training(&self) -> bool {
        !self.training_off
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        if let Some(t) = &target {
            t.check()?;
        }
        self.target = target;
        Ok(())
    }

    fn has_target(&self) -> bool {
        self.target.is_some()
    }

    fn act(&mut self, rng: &mut dyn rand::Rng) -> Action {
        self.acts += 1;
        if self.reach_after.is_some_and(|n| self.acts >= n) {
            self.target = None;
        }
        if self.target.is_none() {
            return Action::ZERO;
        }
        Action::new(rng.random::<f64>() - 0.5, 0.0)
    }

    /// One map, [`Probe::MAP`]: update calls = trained updates, inserts = resets,
    /// nodes = all updates.
    fn stats(&self) -> ModelStats {
        ModelStats::Other(crate::stats::OtherStats {
            maps: BTreeMap::from([(
                Self::MAP.to_owned(),
                MapStats {
                    update_calls: self.trained_updates,
                    inserts: self.resets,
                    nodes: self.updates as usize,
                },
            )]),
            ..crate::stats::OtherStats::default()
        })
    }
}
