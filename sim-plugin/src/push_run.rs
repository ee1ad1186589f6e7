//! Push-task runs as the experiment driver produces them (`docs/spec/experiments.md`
//! §2, §3), in lock-step with the world and without latency: the messages a
//! learner sees in one run, for the trace-driven learner tests and
//! benchmarks.

use crate::calibration::SweepError;
use crate::scene::ACTUATOR;
use crate::world::{ActuatorMode, Command, Snapshot, World};

fn next_message(world: &mut World) -> Result<Snapshot, SweepError> {
    loop {
        if let Some(s) = world.step()? {
            return Ok(s);
        }
    }
}

fn velocity(v: [f64; 2]) -> Command {
    Command::Actuator {
        mode: ActuatorMode::Move,
        velocity: [v[0], v[1], 0.0],
    }
}

/// The first `messages` messages of one push-task run from actuator start
/// `(x0, 0)` with constant `action` (m/s).
///
/// The driver's sequence: stop and reset (`reset_world`; the next message is
/// dropped), place the actuator (`start_run`; the next message is dropped
/// again), then message 1 with everything at rest. The driver sends the
/// action after handling each message, so it is in force from message 2 on.
/// The world's publish rate is left as it is.
pub fn record_push_run(
    world: &mut World,
    x0: f64,
    action: [f64; 2],
    messages: usize,
) -> Result<Vec<Snapshot>, SweepError> {
    world.apply(Command::Unpause)?;
    world.apply(velocity([0.0, 0.0]))?;
    world.apply(Command::Reset)?;
    next_message(world)?;
    let z = world.scene().drive.z_clamp;
    world.apply(Command::SetPose {
        name: ACTUATOR.into(),
        position: [x0, 0.0, z],
        orientation: [0.0, 0.0, 0.0, 1.0],
    })?;
    next_message(world)?;
    let mut out = Vec::with_capacity(messages);
    for _ in 0..messages {
        out.push(next_message(world)?);
        world.apply(velocity(action))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;

    #[test]
    fn the_push_starts_after_the_first_message() {
        let scene = Scene::builtin("one_block").expect("embedded scene parses");
        let mut world = World::new(&scene).expect("world builds");
        world.apply(velocity([0.3, 0.0])).expect("valid");
        let run = record_push_run(&mut world, 0.35, [0.0, 0.5], 3).expect("runs");
        assert_eq!(run.len(), 3);
        let y = |s: &Snapshot| s.body(ACTUATOR).expect("actuator").position[1];
        let x = |s: &Snapshot| s.body(ACTUATOR).expect("actuator").position[0];
        // At rest at the start pose (the earlier command was replaced).
        assert!((x(&run[0]) - 0.35).abs() < 1e-9 && y(&run[0]).abs() < 1e-9);
        // 10 steps of 1 ms at 0.5 m/s per message from message 2 on.
        assert!((y(&run[1]) - 0.005).abs() < 1e-6, "{}", y(&run[1]));
        assert!((y(&run[2]) - 0.010).abs() < 1e-6, "{}", y(&run[2]));
        // Message 1 is the first after the reset and the placement.
        assert_eq!(run[0].step, 30);
    }
}
