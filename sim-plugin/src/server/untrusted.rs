//! The daemon's handling of one connection's bytes, without sockets or
//! threads: the same frame decoder, the same gate and the same world
//! commands as a live daemon, applied in the calling thread. This is the code
//! under fuzzing (`fuzz/fuzz_targets/daemon_bytes.rs`) and under the property
//! tests that run the fuzzers' inputs in the normal test suite
//! (`docs/reliability.md`).

use std::sync::mpsc::{self, Receiver};

use pushlearn::wire::{decode_stream, pb};

use super::gate::{Gate, Op, ToPhysics};
use super::{Config, ServerError, Timing};
use crate::scene::Scene;
use crate::world::{StepError, World};

/// Steps run per accepted Advance (at most; a live daemon runs to the next
/// publish). Enough to let a command's effect reach the physics.
const STEPS_PER_ADVANCE: usize = 10;

/// What became of one connection's bytes.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Handled {
    /// Frames decoded into envelopes.
    pub messages: usize,
    /// Messages answered with an `Error` (barriers included).
    pub refused: usize,
    /// The bad frame that ended the connection, if any.
    pub frame_error: Option<String>,
    /// Steps after which the world found a non-finite body and reset itself.
    pub diverged: usize,
}

/// A world, its gate and the channel between them.
pub struct Harness {
    world: World,
    gate: Gate,
    inbox: Receiver<ToPhysics>,
}

impl Harness {
    /// A lock-step world of `scene` (every command kind is accepted there
    /// but latency seeds).
    ///
    /// # Errors
    /// The world cannot be built.
    pub fn new(scene: Scene) -> Result<Harness, ServerError> {
        let mut config = Config::new(scene);
        config.timing = Timing::Lockstep { latency: None };
        let (tx, inbox) = mpsc::channel();
        let gate = Gate::new(&config, tx);
        let world = World::new(&config.scene)?;
        Ok(Harness { world, gate, inbox })
    }

    /// Feeds `bytes` as everything one client sent before closing:
    /// decodes frames as a connection does (a bad frame ends it), passes
    /// each message through the gate, applies what was accepted and steps
    /// the world on each Advance.
    ///
    /// # Errors
    /// What a live daemon must never do: a physics failure other than a
    /// blow-up (which resets the world and is counted) would stop the world;
    /// a published non-finite state would reach the learners.
    pub fn handle_untrusted_bytes(&mut self, bytes: &[u8]) -> Result<Handled, Fault> {
        let (messages, error) = decode_stream::<pb::ClientMessage>(bytes);
        let mut handled = Handled {
            messages: messages.len(),
            frame_error: error.map(|err| err.to_string()),
            ..Handled::default()
        };
        for message in &messages {
            if self.gate.admit(1, message).is_err() {
                handled.refused += 1;
            }
            self.apply_accepted(&mut handled)?;
        }
        Ok(handled)
    }

    fn apply_accepted(&mut self, handled: &mut Handled) -> Result<(), Fault> {
        while let Ok(ToPhysics::Command(accepted)) = self.inbox.try_recv() {
            self.gate.taken(1);
            match accepted.op {
                Op::World(commands) => {
                    for command in commands {
                        // The gate ran the same checks; a refusal here is
                        // the bug the daemon logs, not a crash.
                        if self.world.apply(command).is_err() {
                            handled.refused += 1;
                            break;
                        }
                    }
                }
                Op::Advance => {
                    for _ in 0..STEPS_PER_ADVANCE {
                        match self.world.step() {
                            Ok(Some(snapshot)) => check_finite(&snapshot)?,
                            Ok(None) => {}
                            Err(StepError::Diverged { .. }) => handled.diverged += 1,
                            Err(err) => return Err(Fault::Step(err)),
                        }
                    }
                }
                Op::LatencySeed(_) => {}
            }
        }
        Ok(())
    }

    /// The world, to inspect after feeding it.
    pub fn world(&self) -> &World {
        &self.world
    }
}

/// Steps a world built from an untrusted scene runs in [`load_untrusted_scene`].
const SCENE_STEPS: usize = 20;

/// Parses `text` as a scene file (`pushlearn-sim serve --scene FILE`) and, if
/// it is accepted, builds its world and steps it: an invalid scene must be
/// refused with an error, a valid one must simulate. Returns whether the
/// scene was accepted.
///
/// # Errors
/// See [`Harness::handle_untrusted_bytes`].
pub fn load_untrusted_scene(text: &str) -> Result<bool, Fault> {
    let Ok(scene) = Scene::from_toml_str(text) else {
        return Ok(false);
    };
    let Ok(mut world) = World::new(&scene) else {
        return Ok(false);
    };
    for _ in 0..SCENE_STEPS {
        match world.step() {
            Ok(Some(snapshot)) => check_finite(&snapshot)?,
            Ok(None) | Err(StepError::Diverged { .. }) => {}
            Err(err) => return Err(Fault::Step(err)),
        }
    }
    Ok(true)
}

/// What a daemon must never do, whatever a client sends.
#[derive(Debug, thiserror::Error)]
pub enum Fault {
    #[error("the physics failed: {0}")]
    Step(StepError),
    #[error("a published state has a non-finite value for {0}")]
    NonFinite(String),
}

/// The daemon never publishes a non-finite state: the world resets before.
fn check_finite(snapshot: &crate::world::Snapshot) -> Result<(), Fault> {
    for body in &snapshot.bodies {
        let mut values = body
            .position
            .iter()
            .chain(&body.orientation)
            .chain(&body.lin_vel)
            .chain(&body.ang_vel);
        if !values.all(|v| v.is_finite()) {
            return Err(Fault::NonFinite(body.name.clone()));
        }
    }
    Ok(())
}

/// The inputs the fuzzers keep for `target` (`fuzz/seeds/TARGET`, and every
/// fixed crash in `fuzz/regressions/TARGET`), so that the normal test
/// suites — this crate's and those of the crates other targets test — run
/// them through the target's function without a nightly toolchain.
#[must_use]
pub fn kept_fuzz_inputs(target: &str) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut out = Vec::new();
    for kind in ["seeds", "regressions"] {
        let Ok(entries) = std::fs::read_dir(root.join(kind).join(target)) else {
            continue;
        };
        for entry in entries.flatten() {
            if let Ok(bytes) = std::fs::read(entry.path()) {
                out.push((entry.path(), bytes));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use pushlearn::wire::encode_frame;

    use super::*;

    fn harness() -> Harness {
        Harness::new(Scene::builtin("one_block").unwrap()).unwrap()
    }

    fn float() -> impl Strategy<Value = f64> {
        prop_oneof![
            -1.0..1.0f64,
            any::<f64>(),
            Just(1e300),
            Just(-f64::MAX),
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(999.0),
        ]
    }

    fn name() -> impl Strategy<Value = String> {
        prop_oneof![
            Just("actuator".to_owned()),
            Just("blockA".to_owned()),
            Just("blockAShadow".to_owned()),
            "[a-zA-Z]{0,10}",
        ]
    }

    /// Every kind of command with hostile values.
    fn message() -> impl Strategy<Value = pb::ClientMessage> {
        (
            0u8..8,
            any::<u64>(),
            name(),
            [float(), float(), float(), float()],
            any::<u32>(),
        )
            .prop_map(|(kind, seq, name, v, n)| match kind {
                0 => pb::ClientMessage::move_(seq, v[0], v[1]),
                1 => pb::ClientMessage::set_pose(seq, name, [v[0], v[1], v[2]], v[3]),
                2 => pb::ClientMessage::reset(seq),
                3 => pb::ClientMessage::pause(seq),
                4 => pb::ClientMessage::unpause(seq),
                5 => pb::ClientMessage::publish_rate(seq, n % 1200),
                6 => pb::ClientMessage::latency_seed(seq, u64::from(n)),
                _ => pb::ClientMessage::advance(seq),
            })
    }

    fn stream(messages: &[pb::ClientMessage]) -> Vec<u8> {
        messages
            .iter()
            .flat_map(|m| encode_frame(m).unwrap().to_vec())
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The `daemon_bytes` fuzz target's property: any bytes at all.
        #[test]
        fn any_bytes_are_answered_without_a_fault(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            let handled = harness().handle_untrusted_bytes(&bytes);
            prop_assert!(handled.is_ok(), "{handled:?}");
        }

        /// Well-framed commands with hostile values, then garbage.
        #[test]
        fn hostile_commands_never_fault(
            messages in proptest::collection::vec(message(), 0..24),
            tail in proptest::collection::vec(any::<u8>(), 0..8),
        ) {
            let mut bytes = stream(&messages);
            bytes.extend(tail);
            let handled = harness().handle_untrusted_bytes(&bytes).unwrap();
            prop_assert!(handled.messages >= messages.len());
        }

        /// The `scene` fuzz target's property: a scene file with one value
        /// replaced by anything is refused or simulates.
        #[test]
        fn edited_scene_files_are_refused_or_simulate(
            which in any::<prop::sample::Index>(),
            value in prop_oneof![any::<f64>().prop_map(|v| format!("{v:?}")), "[-0-9.e+]{1,8}", Just("nan".to_owned()), Just("1e308".to_owned())],
        ) {
            let text = include_str!("../../scenes/one_block.toml");
            let numbers: Vec<(usize, usize)> = number_spans(text);
            let (start, end) = numbers[which.index(numbers.len())];
            let edited = format!("{}{}{}", &text[..start], value, &text[end..]);
            prop_assert!(load_untrusted_scene(&edited).is_ok());
        }
    }

    /// Byte ranges of the numbers in `text`.
    fn number_spans(text: &str) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut start = None;
        for (i, c) in text.char_indices() {
            let numeric = c.is_ascii_digit() || (start.is_some() && matches!(c, '.' | 'e' | '-'));
            match (numeric, start) {
                (true, None) => start = Some(i),
                (false, Some(s)) => {
                    out.push((s, i));
                    start = None;
                }
                _ => {}
            }
        }
        out
    }

    #[test]
    fn the_unedited_scene_simulates() {
        assert!(load_untrusted_scene(include_str!("../../scenes/one_block.toml")).unwrap());
        assert!(!load_untrusted_scene("name = 3").unwrap());
    }

    #[test]
    fn a_hostile_stream_is_refused_where_the_daemon_refuses_it() {
        let mut h = harness();
        let messages = [
            pb::ClientMessage::move_(1, 0.0, 0.5),
            pb::ClientMessage::set_pose(2, "blockA", [f64::NAN, 0.0, 0.0], 0.0),
            pb::ClientMessage::advance(3),
        ];
        let mut bytes = stream(&messages);
        bytes.extend([0, 0, 0, 5, 0xff]);
        let handled = h.handle_untrusted_bytes(&bytes).unwrap();
        assert_eq!(handled.messages, 3);
        assert_eq!(handled.refused, 1);
        assert!(
            handled
                .frame_error
                .as_ref()
                .is_some_and(|e| e.contains("closed in the middle of a frame")),
            "{handled:?}"
        );
        assert!(h.world().step_count() > 0);
    }

    #[test]
    fn the_fuzzers_kept_inputs_never_fault() {
        for (path, bytes) in kept_fuzz_inputs("daemon_bytes") {
            let handled = harness().handle_untrusted_bytes(&bytes);
            assert!(handled.is_ok(), "{}: {handled:?}", path.display());
        }
        for (path, bytes) in kept_fuzz_inputs("scene") {
            let text = String::from_utf8_lossy(&bytes);
            let loaded = load_untrusted_scene(&text);
            assert!(loaded.is_ok(), "{}: {loaded:?}", path.display());
        }
    }
}
