//! Push-task runs of the in-process world as a learner sees them. One file,
//! included with `#[path]` by the trace-driven learner tests and by the model
//! benchmarks, so that what is tested is what is timed.

use learner::eval::{MESSAGES_PER_RUN, PUSH_ACTION};
use learner::Frame;
use sim_plugin::push_run::record_push_run;
use sim_plugin::{Snapshot, World};

/// The learner's view of a published snapshot: what the daemon's
/// `WorldState` carries, ghosts included (the learner skips `*Shadow`).
pub fn frame(s: &Snapshot) -> Frame {
    Frame {
        objects: s
            .bodies
            .iter()
            .chain(&s.ghosts)
            .map(sim_plugin::BodyState::observation)
            .collect(),
    }
}

/// The 151 messages of one push-task run from `x0` as the driver meets them:
/// 150 processed and the one that ends the run (`docs/spec/experiments.md` §2).
pub fn record_run(world: &mut World, x0: f64) -> Vec<Frame> {
    let action = [PUSH_ACTION.vx, PUSH_ACTION.vy];
    record_push_run(world, x0, action, MESSAGES_PER_RUN + 1)
        .expect("the thesis world runs the push task")
        .iter()
        .map(frame)
        .collect()
}
