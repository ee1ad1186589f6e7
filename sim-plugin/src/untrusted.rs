//! The daemon's handling of one connection's bytes, without sockets or
//! threads: the same frame decoder, the same gate and the same world
//! commands as a live daemon, applied in the calling thread; and the same
//! messages sent to an [`EmbeddedWorld`] with latency emulation, the entry
//! point of the Python extension's `pushlearn.World`. This is the code
//! under fuzzing (`fuzz/fuzz_targets/daemon_bytes.rs`) and under the property
//! tests that run the fuzzers' inputs in the normal test suite
//! (`docs/reliability.md`).

use std::sync::mpsc::{self, Receiver};

use pushlearn::recording::{self, Direction, RecordingWriter};
use pushlearn::wire::{decode_stream, encode_frame, pb, LENGTH_PREFIX_SIZE};

use crate::replay::{Replay, Served};
use crate::scene::Scene;
use crate::server::gate::{Gate, Op, ToPhysics};
use crate::server::{Config, EmbeddedWorld, Latency, ServerError, Timing};
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

/// A world, its gate and the channel between them; and an embedded world
/// taking the same messages.
pub struct Harness {
    world: World,
    gate: Gate,
    inbox: Receiver<ToPhysics>,
    embedded: EmbeddedWorld,
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
        // With latency emulation, so that delayed Moves and latency seeds
        // are explored too.
        let latency = Latency {
            max_steps: 3,
            seed: 0,
        };
        let embedded = EmbeddedWorld::new(config.scene.clone(), None, Some(latency))?;
        Ok(Harness {
            world,
            gate,
            inbox,
            embedded,
        })
    }

    /// Feeds `bytes` as everything one client sent before closing:
    /// decodes frames as a connection does (a bad frame ends it), passes
    /// each message through the gate, applies what was accepted and steps
    /// the world on each Advance. Each message is also sent to the
    /// embedded world, which answers it as the daemon would.
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
            self.embedded.send(message).map_err(Fault::Step)?;
            while let Some(answer) = self.embedded.next_message() {
                if let Some(pb::server_message::Payload::WorldState(state)) = answer.payload {
                    check_finite_message(&state)?;
                }
            }
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

/// Reads `bytes` as a recording (`pushlearn-sim replay FILE`) and, if it is
/// one, prepares its replay and plays the recorded client back to it.
/// Returns what that served, or `None` for bytes refused as a recording.
///
/// # Errors
/// A recording read in a way that loses or invents something: a cut file
/// whose reported cut is not where the bytes end; a recording that, written
/// out again (`RecordingWriter`) and read back, is not the same (compared as
/// written, so that NaN equals itself); a replay that finds the recorded
/// client's own frames differing from the recording, or serves more states
/// than the recording holds.
pub fn load_untrusted_recording(bytes: &[u8]) -> Result<Option<Served>, Fault> {
    let Ok(recording) = recording::parse(bytes, "fuzz") else {
        return Ok(None);
    };
    if let Some(cut) = recording.truncated {
        if cut.offset + cut.present != bytes.len() {
            return Err(Fault::Recording(format!(
                "cut at {} with {} bytes present, but the input has {}",
                cut.offset,
                cut.present,
                bytes.len()
            )));
        }
    }
    let written = rewrite(&recording)?;
    let reread = recording::parse(&written, "fuzz rewritten")
        .map_err(|err| Fault::Recording(format!("a rewritten recording is refused: {err}")))?;
    if rewrite(&reread)? != written {
        return Err(Fault::Recording(
            "a rewritten recording reads back differently".into(),
        ));
    }
    let replay = Replay::new(recording, "fuzz", true);
    let served = replay.play_back();
    if replay.commands() && served.differing != 0 {
        return Err(Fault::Recording(format!(
            "the recorded client's own frames differ from the recording: {served:?}"
        )));
    }
    if served.states > replay.states() as u64 {
        return Err(Fault::Recording(format!(
            "{} states served from a recording of {}",
            served.states,
            replay.states()
        )));
    }
    Ok(Some(served))
}

/// `recording` as `pushlearn ctl record` would write it.
fn rewrite(recording: &recording::Recording) -> Result<Vec<u8>, Fault> {
    let fail = |err: &dyn std::fmt::Display| Fault::Recording(format!("cannot rewrite: {err}"));
    // The recording holds envelopes without their length prefix.
    let hello = encode_frame(&pb::ServerMessage::from(recording.header.hello.clone()))
        .map_err(|e| fail(&e))?;
    let mut writer = RecordingWriter::new(
        Vec::new(),
        recording.header.commands,
        &hello[LENGTH_PREFIX_SIZE..],
    )
    .map_err(|e| fail(&e))?;
    for record in &recording.records {
        let (direction, frame) = match &record.frame {
            recording::Frame::World(m) => (Direction::FromWorld, encode_frame(m)),
            recording::Frame::Client(m) => (Direction::FromClient, encode_frame(m)),
        };
        let frame = frame.map_err(|e| fail(&e))?;
        writer
            .record(direction, record.at, &frame[LENGTH_PREFIX_SIZE..])
            .map_err(|e| fail(&e))?;
    }
    writer.finish().map_err(|e| fail(&e))
}

/// What a daemon must never do, whatever a client sends.
#[derive(Debug, thiserror::Error)]
pub enum Fault {
    #[error("the physics failed: {0}")]
    Step(StepError),
    #[error("a published state has a non-finite value for {0}")]
    NonFinite(String),
    #[error("a recording was misread: {0}")]
    Recording(String),
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

/// [`check_finite`] of a published message.
fn check_finite_message(state: &pb::WorldState) -> Result<(), Fault> {
    let models = state.model_v.as_ref().map_or(&[][..], |v| &v.models[..]);
    for model in models {
        let pose = model.pose.unwrap_or_default();
        let vectors = [pose.position, model.lin_vel, model.ang_vel];
        let q = pose.orientation.unwrap_or_default();
        let finite = vectors
            .iter()
            .flatten()
            .flat_map(|v| [v.x, v.y, v.z])
            .chain([q.x, q.y, q.z, q.w])
            .all(f64::is_finite);
        if !finite {
            return Err(Fault::NonFinite(model.name.clone()));
        }
    }
    Ok(())
}

/// The inputs the fuzzers keep for `target` (the minimised corpus
/// `fuzz/corpus/TARGET`, and every fixed crash in `fuzz/regressions/TARGET`),
/// so that the normal test suites — this crate's and those of the crates
/// other targets test — run them through the target's function without a
/// nightly toolchain.
#[must_use]
pub fn kept_fuzz_inputs(target: &str) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut out = Vec::new();
    for kind in ["corpus", "regressions"] {
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
            let text = include_str!("../scenes/one_block.toml");
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
        assert!(load_untrusted_scene(include_str!("../scenes/one_block.toml")).unwrap());
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

    /// Each target's kept inputs through its function; a target without
    /// any fails, so that an emptied folder does not pass.
    #[test]
    fn the_fuzzers_kept_inputs_never_fault() {
        let kept = |target| {
            let inputs = kept_fuzz_inputs(target);
            assert!(
                inputs.len() >= 5,
                "fuzz/corpus/{target}: {} inputs",
                inputs.len()
            );
            inputs
        };
        for (path, bytes) in kept("daemon_bytes") {
            let handled = harness().handle_untrusted_bytes(&bytes);
            assert!(handled.is_ok(), "{}: {handled:?}", path.display());
        }
        for (path, bytes) in kept("scene") {
            let text = String::from_utf8_lossy(&bytes);
            let loaded = load_untrusted_scene(&text);
            assert!(loaded.is_ok(), "{}: {loaded:?}", path.display());
        }
        let mut replayed = 0;
        for (path, bytes) in kept("recording") {
            let loaded = load_untrusted_recording(&bytes);
            assert!(loaded.is_ok(), "{}: {loaded:?}", path.display());
            replayed += usize::from(loaded.is_ok_and(|l| l.is_some_and(|s| s.states > 0)));
        }
        assert!(replayed > 0, "no kept recording serves a state");
    }

    /// A lock-step recording with the client's frames: two states, a
    /// refused command between them.
    fn recording_bytes() -> Vec<u8> {
        let hello = pb::ServerMessage::from(pb::Hello {
            timing_mode: "lockstep".into(),
            ..Default::default()
        });
        let mut writer = RecordingWriter::new(
            Vec::new(),
            true,
            &encode_frame(&hello).unwrap()[LENGTH_PREFIX_SIZE..],
        )
        .unwrap();
        let state = |step, applied_seq| {
            pb::ServerMessage::from(pb::WorldState {
                step,
                applied_seq,
                ..Default::default()
            })
        };
        let at = std::time::Duration::from_millis(10);
        let client = [
            pb::ClientMessage::advance(101),
            pb::ClientMessage::set_pose(102, "blockC", [0.0; 3], 0.0),
            pb::ClientMessage::advance(103),
        ];
        let world = [
            state(10, 101),
            pb::ServerMessage::error(
                102,
                pb::error::Kind::InvalidCommand,
                "set_pose: unknown body 'blockC'",
            ),
            state(20, 103),
        ];
        for (c, w) in client.iter().zip(&world) {
            let c = encode_frame(c).unwrap();
            let w = encode_frame(w).unwrap();
            writer
                .record(Direction::FromClient, at, &c[LENGTH_PREFIX_SIZE..])
                .unwrap();
            writer
                .record(Direction::FromWorld, at, &w[LENGTH_PREFIX_SIZE..])
                .unwrap();
        }
        writer.finish().unwrap()
    }

    #[test]
    fn a_recording_is_read_rewritten_and_played_back_whole() {
        let bytes = recording_bytes();
        let served = load_untrusted_recording(&bytes).unwrap().unwrap();
        assert_eq!(served.states, 2, "{served:?}");
        assert_eq!(served.differing, 0, "{served:?}");
        // Cut anywhere inside the records: every whole record still served.
        let cut = load_untrusted_recording(&bytes[..bytes.len() - 3])
            .unwrap()
            .unwrap();
        assert_eq!(cut.states, 1, "{cut:?}");
        assert_eq!(load_untrusted_recording(b"PLRECORX").unwrap(), None);
    }
}
