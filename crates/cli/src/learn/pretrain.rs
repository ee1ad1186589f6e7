//! Experience before the daemon pursues its target (`pushlearn learn
//! --pretrain thesis`): an untrained model dithers at the block or pushes it
//! away, while the thesis's Move to Target first trains on eight fixed
//! pushes (`docs/spec/experiments.md` §4.1). These are run here against the
//! connected world by the experiments' own driver, so the daemon starts
//! from exactly the experience a Move to Target test run starts from.

use clap::ValueEnum;
use learner::Model;
use serde::{Deserialize, Serialize};

use crate::experiment::driver::Driver;
use crate::experiment::link::{run_driver, Pacing};
use crate::experiment::move_to_target::{MttTask, TRAINING_RUNS};
use crate::experiment::ExperimentError;
use pushlearn::client::SimClient;
use pushlearn::wire::TimingMode;

/// A training programme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
pub enum Pretrain {
    /// The thesis's eight fixed training pushes of Move to Target (§4.1),
    /// ending with the world reset and the actuator at the test run's start.
    Thesis,
}

impl Pretrain {
    /// Pushes the programme makes.
    #[must_use]
    pub fn pushes(self) -> usize {
        match self {
            Pretrain::Thesis => TRAINING_RUNS.len(),
        }
    }
}

/// What pretraining did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pretrained {
    /// World states handled, dropped ones after resets included.
    pub messages: u64,
    /// Start positions the world had to be corrected to.
    pub corrections: u64,
}

/// Trains `model` with `programme` against the world behind `client`, at
/// the world's own rate and pacing.
///
/// # Errors
/// Socket errors, a command the world refuses, or a world that stopped
/// before the programme ended.
pub async fn pretrain<M: Model>(
    client: &mut SimClient,
    model: M,
    programme: Pretrain,
) -> Result<(M, Pretrained), ExperimentError> {
    let hello = client.hello();
    let pacing = Pacing::of(hello.timing().unwrap_or(TimingMode::Realtime));
    let task = match programme {
        Pretrain::Thesis => MttTask::training_only(),
    };
    let mut driver = Driver::new(model, task, hello.publish_rate);
    run_driver(client, pacing, &mut driver, Vec::new()).await?;
    let (task, model, counters) = driver.into_parts();
    if !task.trained() {
        return Err(ExperimentError::Incomplete(
            "the training pushes did not end".into(),
        ));
    }
    Ok((
        model,
        Pretrained {
            messages: counters.messages,
            corrections: counters.reset_errors,
        },
    ))
}
