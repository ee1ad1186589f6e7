//! Attempts at a target (`pushlearn learn --target … --episodes N`): the
//! lifelong setting the thesis motivates. An episode is one attempt from
//! the scene's start, judged as a Move to Target test run is: it ends when
//! the world's block meets the goal ([`learner::eval::goal_reached`]), when
//! the model clears its target, or after the step limit, and counts as
//! reached only if the world's block met the goal; then the world is reset
//! and the next attempt starts with everything learned so far.

use learner::eval::goal_reached;
use learner::ObjectState;
use serde::{Deserialize, Serialize};

use crate::experiment::move_to_target::{target_errors, MAX_STEPS};

/// How one attempt ended.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpisodeResult {
    /// Whether the world's block met the goal when the attempt ended.
    pub reached: bool,
    /// Actions sent before the state that ended the attempt.
    pub steps: u64,
    /// The blue block's distance to the target then, in metres.
    pub pos_err: f64,
    /// `|wrap(θ − θ_target)|` then, in radians.
    pub ori_err: f64,
}

/// The daemon's attempts at its target. Part of the learner's persistent
/// memory: a daemon resumed from `--state` goes on with the attempt it was in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Episodes {
    /// Attempts to make.
    pub total: u32,
    /// Step limit of one attempt.
    pub max_steps: u64,
    /// States handled in the current attempt.
    pub handled: u64,
    /// The block's distance and angle to the target in the last state.
    pub errors: Option<(f64, f64)>,
    /// The attempts that have ended, in order.
    pub ended: Vec<EpisodeResult>,
}

impl Default for Episodes {
    fn default() -> Self {
        Episodes::new(1, MAX_STEPS)
    }
}

/// What one state meant for the current attempt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step {
    /// The attempt goes on.
    Running,
    /// It ended; more attempts follow.
    Ended,
    /// It ended, and it was the last one.
    Finished,
}

impl Episodes {
    /// `total` attempts of at most `max_steps` steps each.
    #[must_use]
    pub fn new(total: u32, max_steps: u64) -> Self {
        Episodes {
            total: total.max(1),
            max_steps,
            handled: 0,
            errors: None,
            ended: Vec::new(),
        }
    }

    /// Counts one handled state with the world's block at `block`;
    /// `has_target` is the model's word after acting on it (false: it
    /// believes it arrived, or gave up).
    pub fn step(
        &mut self,
        block: Option<ObjectState>,
        target: ObjectState,
        has_target: bool,
    ) -> Step {
        self.handled += 1;
        let errors = target_errors(block, target);
        self.errors = Some(errors);
        let reached = block.is_some_and(|b| goal_reached(&b, &target));
        // As a Move to Target test run: the step counter includes this
        // state, the steps taken do not.
        if !reached && has_target && self.handled <= self.max_steps {
            return Step::Running;
        }
        let steps = self.handled - 1;
        self.ended.push(EpisodeResult {
            reached,
            steps,
            pos_err: errors.0,
            ori_err: errors.1,
        });
        self.handled = 0;
        if self.finished() {
            Step::Finished
        } else {
            Step::Ended
        }
    }

    /// Whether every attempt has ended.
    #[must_use]
    pub fn finished(&self) -> bool {
        self.ended.len() >= self.total as usize
    }

    /// The current attempt's number, from 1 (the last one once finished).
    #[must_use]
    pub fn current(&self) -> usize {
        (self.ended.len() + 1).min(self.total as usize)
    }

    /// Attempts that reached the target.
    #[must_use]
    pub fn reached(&self) -> usize {
        self.ended.iter().filter(|e| e.reached).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TARGET: ObjectState = ObjectState::new(0.0, 0.0, 0.0);

    #[test]
    fn an_attempt_ends_when_the_model_stops_when_the_world_is_there_or_at_the_limit() {
        let mut e = Episodes::new(3, 3);
        let away = Some(ObjectState::new(0.3, 0.4, 0.5));
        assert_eq!(e.step(away, TARGET, true), Step::Running);
        // The model stops, claiming the target; the world disagrees.
        assert_eq!(e.step(away, TARGET, false), Step::Ended);
        assert_eq!(
            e.ended[0],
            EpisodeResult {
                reached: false,
                steps: 1,
                pos_err: 0.5,
                ori_err: 0.5
            }
        );
        assert_eq!(e.current(), 2);
        // The block arrives (within 1 cm and 1 mrad, across the angle's
        // seam not at all): the world ends the attempt, the model still going.
        let there = Some(ObjectState::new(0.005, -0.004, 0.001));
        assert_eq!(e.step(away, TARGET, true), Step::Running);
        assert_eq!(e.step(there, TARGET, true), Step::Ended);
        assert!(e.ended[1].reached);
        assert_eq!(e.ended[1].steps, 1);
        for _ in 0..3 {
            assert_eq!(e.step(away, TARGET, true), Step::Running);
        }
        // The fourth state of a 3-step attempt ends it, unreached.
        assert_eq!(e.step(away, TARGET, true), Step::Finished);
        assert_eq!(e.ended[2].steps, 3);
        assert!(!e.ended[2].reached);
        assert!(e.finished());
        assert_eq!(e.reached(), 1);
    }

    #[test]
    fn without_a_block_the_errors_are_not_numbers() {
        let mut e = Episodes::new(1, 10);
        e.step(None, TARGET, true);
        let (pos, ori) = e.errors.unwrap();
        assert!(pos.is_nan() && ori.is_nan());
    }
}
