//! Generalisation with constant feedback (`docs/spec/experiments.md` §3.4), a
//! qualitative experiment: no training phase; in each test run the model
//! keeps learning from the real states while its predictions are chained
//! without correction. The thesis showed images only; we report, per run,
//! the error of every chained prediction against the state it predicted.

use learner::eval::{RunErrors, PUSH_ACTION};
use learner::{Action, Model, Poses};

use super::driver::{Core, Task};
use crate::results::constant_feedback::FeedbackRun;
use crate::scene::push_task_blocks;

/// Name used for seeds and reports.
pub const EXPERIMENT: &str = "push-task/constant-feedback";

/// The §3.4 handler. Note the spec's quirk, kept here: the step counter is
/// never incremented, so only the actuator's 1 m distance ends a run.
#[derive(Debug)]
pub struct FeedbackTask {
    test_positions: Vec<f64>,
    test_run: usize,
    /// The finished and current runs.
    pub runs: Vec<FeedbackRun>,
}

impl FeedbackTask {
    /// Runs from each of `test_positions` in turn.
    #[must_use]
    pub fn new(test_positions: Vec<f64>) -> Self {
        Self {
            test_positions,
            test_run: 0,
            runs: Vec::new(),
        }
    }
}

impl<M: Model> Task<M> for FeedbackTask {
    fn run_name(&self) -> String {
        let n_test = self.test_positions.len();
        format!("test run {} of {n_test}", (self.test_run + 1).min(n_test))
    }

    fn handle(&mut self, core: &mut Core<M>, model: &mut M, world: &M::World, poses: &Poses) {
        let n_test = self.test_positions.len();
        if core.run_started {
            if let (Some(p), Some(run)) = (&core.last_prediction, self.runs.last_mut()) {
                run.errors.push(RunErrors::score(poses, &M::poses(p)));
            }
            if core.run_ended(poses) {
                core.reset_world();
                core.run_started = false;
            }
        } else {
            if let Some(&x0) = self.test_positions.get(self.test_run) {
                self.runs.push(FeedbackRun {
                    x0,
                    errors: Vec::new(),
                });
                core.start_run((x0, 0.0), &push_task_blocks(), true);
            }
            return;
        }
        if self.test_run < n_test {
            if core.run_started {
                let direction = PUSH_ACTION;
                let next = match core.last_prediction.take() {
                    None => {
                        // Predicted before the model registers the world, as
                        // in the original (`docs/spec/experiments.md` §3.4).
                        let first = model.predict(world, direction);
                        model.reset_objects(world);
                        core.last_action = Some(Action::ZERO);
                        first
                    }
                    Some(previous) => model.predict(&previous, direction),
                };
                core.last_prediction = Some(next);
                model.update(world, core.last_action.unwrap_or(Action::ZERO));
                core.last_action = Some(direction);
                core.send_move(direction);
            } else {
                self.test_run += 1;
                if self.test_run == n_test {
                    core.finish();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use learner::BLUE_ID;

    use super::super::driver::test_support::{blue_home, describe, frame};
    use super::super::driver::Driver;
    use super::*;
    use learner::testing::Probe;

    #[test]
    fn runs_end_only_beyond_one_metre_and_training_stays_on() {
        let mut d = Driver::new(Probe::default(), FeedbackTask::new(vec![-0.25, 0.25]), 10);
        let mut y = 0.0;
        let mut x = 0.0;
        let mut velocity = 0.0;
        let mut sent = Vec::new();
        for _ in 0..200 {
            if d.is_done() {
                break;
            }
            y += velocity * 0.1;
            let c = describe(&d.on_state(&frame((x, y), &blue_home())));
            for c in &c {
                match c.as_str() {
                    "move(0,0.5)" => velocity = 0.5,
                    "move(0,0)" => velocity = 0.0,
                    "reset" => (x, y) = (0.0, 0.0),
                    "pose(actuator,-0.25,0)" => x = -0.25,
                    "pose(actuator,0.25,0)" => x = 0.25,
                    _ => {}
                }
            }
            sent.extend(c);
        }
        assert!(d.is_done());
        assert_eq!(sent[0], "rate(10)");
        let (task, model, _) = d.into_parts();
        assert_eq!(task.runs.len(), 2);
        // |(0.25, y)| > 1 first at y = 1.0 (about 20 messages at 10 Hz);
        // far beyond the push task's 150-message limit it would not be.
        for run in &task.runs {
            assert_eq!(run.errors.len(), 20, "{run:?}");
            // The world moves 5 cm per message, the probe predicts 5 mm: a
            // chain that is never corrected by the real states drifts by
            // 4.5 cm more with every message.
            for (k, e) in run.errors.iter().enumerate() {
                assert!(
                    (e.actuator - 0.045 * (k + 1) as f64).abs() < 1e-9,
                    "{k}: {e:?}"
                );
                assert_eq!(e.blocks[&BLUE_ID].pos, 0.0);
            }
        }
        assert!(model.is_training());
        assert_eq!(model.trained_updates, 2 * 20);
        assert_eq!(model.resets, 2);
    }
}
