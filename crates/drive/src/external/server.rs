//! The learner side of the learner protocol for any [`learner::Model`]:
//! `pushlearn serve-learner` serves the built-in models with it, so that
//! another harness can run them, and so that the protocol path can be
//! checked against the in-process one (the same model must give the same
//! report either way).
//!
//! The world states a request refers to by name (`LAST_OBSERVED`,
//! `LAST_PREDICTION`) are kept as the model's own parsed and predicted
//! worlds, never rebuilt from poses: the gate model's block records depend on
//! the identity of what it parsed (`docs/spec/gate-model.md` §4.1).

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use bytes::BytesMut;
use learner::features::ActuatorYaw;
use learner::{Action, Model, ObjectState, Target};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tokio_util::codec::Decoder;

use pushlearn::wire::pb::learner::{
    self as lp, reply::Answer, request::Call, state_ref::State, Reply, Request,
};
use pushlearn::wire::{
    encode_frame, quoted, FrameDecoder, Shapes, WireError, MAX_ACTION_SPEED, MAX_NAME_BYTES,
    MAX_POSITION,
};

use learner::registry::{ModelKind, ModelOptions, WithModel};

use super::session::steady_timeout;

/// Why serving ended early.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    // The causes are sources, not part of the text: a log line or error
    // report that prints the chain showed each of them twice.
    #[error("reading requests")]
    Read(#[from] WireError),
    #[error("writing replies")]
    Write(#[source] std::io::Error),
    #[error("message {seq}: {why}")]
    Request { seq: u64, why: String },
    #[error("the driver closed the connection before its start")]
    NoStart,
    #[error("no request for {0:?}: closing an idle connection")]
    Idle(Duration),
}

/// The tasks a Start may name (`docs/learner-protocol.md` §5).
pub const TASKS: [&str; 3] = ["push-task", "constant-feedback", "move-to-target"];

/// The Start rules of `docs/learner-protocol.md` §5 that a learner daemon
/// enforces: protocol version 1, a task it knows, and a publish rate a
/// world can have (a divisor of 1000 Hz).
///
/// # Errors
/// The rule broken, worded for the driver.
pub fn check_start(start: &lp::Start) -> Result<(), String> {
    let version = lp::ProtocolVersion::ProtocolVersion as i32;
    if start.protocol_version != version {
        return Err(format!(
            "protocol version {} is not spoken here (this learner speaks version {version})",
            start.protocol_version
        ));
    }
    if !TASKS.contains(&start.task.as_str()) {
        let shown: String = start
            .task
            .chars()
            .take(40)
            .flat_map(char::escape_debug)
            .collect();
        let cut = if start.task.chars().count() > 40 {
            "…"
        } else {
            ""
        };
        return Err(format!(
            "unknown task '{shown}{cut}' (expected one of {})",
            TASKS.join(", ")
        ));
    }
    let hz = start.publish_rate_hz;
    if hz == 0 || 1000 % hz != 0 {
        return Err(format!(
            "publish rate {hz} Hz: a world publishes at a divisor of 1000 Hz (100 or 10 in the \
             experiments)"
        ));
    }
    Ok(())
}

/// What a served model says in its hello (its actuator-yaw rule it says
/// itself, [`Model::actuator_yaw`]).
#[derive(Clone, Debug)]
pub struct Identity {
    pub name: String,
    pub version: String,
}

/// One connection's learner.
struct Served<M: Model> {
    untrained: M,
    model: M,
    rng: ChaCha8Rng,
    observed: Option<M::World>,
    prediction: Option<M::World>,
}

/// Every body of `state` within [`MAX_POSITION`] of the origin, as in any
/// world: the models take finite but absurd positions (1e296 m) and then
/// predict NaN.
fn within_the_world(state: &lp::State) -> Result<(), String> {
    for body in &state.bodies {
        if body.name.len() > MAX_NAME_BYTES {
            return Err(format!(
                "a body name of {} bytes (at most {MAX_NAME_BYTES})",
                body.name.len()
            ));
        }
        let p = body.pose.and_then(|p| p.position).unwrap_or_default();
        for (axis, value) in [("x", p.x), ("y", p.y), ("z", p.z)] {
            if value.abs() > MAX_POSITION {
                return Err(format!(
                    "body {} position.{axis} = {value} is outside any world (at most \
                     {MAX_POSITION} m from the origin)",
                    quoted(&body.name)
                ));
            }
        }
    }
    shapes_of(state).map(drop)
}

/// The shapes `state` sends, each a valid geometry of a body it lists, no
/// body twice: a shape a world cannot have is refused like an absurd
/// position, rather than dropped so that the model falls back on another.
fn shapes_of(state: &lp::State) -> Result<Shapes, String> {
    for (i, shape) in state.shapes.iter().enumerate() {
        let name = quoted(&shape.name);
        if shape.body_shape().is_none() {
            return Err(format!(
                "the shape of body {name} is not one a world can have (a box, a cylinder or a \
                 sphere with finite, positive sizes): {:?}",
                shape.geometry
            ));
        }
        if !state.bodies.iter().any(|b| b.name == shape.name) {
            return Err(format!(
                "a shape for body {name}, which the state does not list"
            ));
        }
        if state.shapes[..i].iter().any(|s| s.name == shape.name) {
            return Err(format!("two shapes for body {name}"));
        }
    }
    Ok(Shapes::from_shapes(&state.shapes))
}

/// The call's action; a non-finite one, or one faster than
/// [`MAX_ACTION_SPEED`], is refused, since a model would learn it (the
/// driver sends only what a world drives, `docs/learner-protocol.md`).
fn action_of(a: Option<lp::Action>) -> Result<Action, String> {
    let a = a.unwrap_or_default();
    let action = Action::new(a.vx(), a.vy());
    if !action.is_finite() {
        return Err(format!(
            "the action ({}, {}) is not finite",
            action.vx, action.vy
        ));
    }
    if action.vx.abs().max(action.vy.abs()) > MAX_ACTION_SPEED {
        return Err(format!(
            "the action ({}, {}) is faster than any world drives (at most {MAX_ACTION_SPEED} \
             m/s a component)",
            action.vx, action.vy
        ));
    }
    Ok(action)
}

impl<M: Model> Served<M> {
    /// The world `state` names: parsed when sent, else the one kept.
    fn resolve(&mut self, state: Option<lp::StateRef>) -> Result<M::World, String> {
        match state.and_then(|s| s.state) {
            Some(State::Observed(observed)) => {
                within_the_world(&observed)?;
                let shapes = shapes_of(&observed)?;
                let world = self
                    .model
                    // The in-process driver's conversion: a body without a pose
                    // is refused, never read as one at the origin; each body
                    // with the shape it was sent with.
                    .parse(&shapes.frame(&observed.bodies))
                    .map_err(|e| format!("the state cannot be parsed: {e}"))?;
                self.observed = Some(world.clone());
                Ok(world)
            }
            Some(State::Recent(r)) if r == lp::Recent::LastObserved as i32 => self
                .observed
                .clone()
                .ok_or_else(|| "LAST_OBSERVED before any state was sent".to_owned()),
            Some(State::Recent(r)) if r == lp::Recent::LastPrediction as i32 => self
                .prediction
                .clone()
                .ok_or_else(|| "LAST_PREDICTION before any prediction".to_owned()),
            _ => Err("a call without a state".to_owned()),
        }
    }

    /// Handles one call; `Some` is the answer to send.
    fn handle(&mut self, call: Call) -> Result<Option<Answer>, String> {
        Ok(match call {
            Call::Start(_) => return Err("a second start".into()),
            Call::NewFold(fold) => {
                self.model = self.untrained.clone();
                self.rng = ChaCha8Rng::seed_from_u64(fold.seed);
                self.observed = None;
                self.prediction = None;
                None
            }
            Call::Reset(reset) => {
                let world = self.resolve(reset.state)?;
                self.model.reset_objects(&world);
                None
            }
            Call::Update(update) => {
                let action = action_of(update.action)?;
                let world = self.resolve(update.state)?;
                self.model.update(&world, action);
                None
            }
            Call::Predict(predict) => {
                let action = action_of(predict.action)?;
                let world = self.resolve(predict.from)?;
                let next = self.model.predict(&world, action);
                let poses = M::poses(&next);
                self.prediction = Some(next);
                let body = |id, s: ObjectState| lp::BodyPose {
                    id,
                    x: Some(s.x),
                    y: Some(s.y),
                    theta: Some(s.theta),
                };
                Some(Answer::Prediction(lp::Prediction {
                    bodies: std::iter::once(body(learner::ACTUATOR_ID, poses.actuator))
                        .chain(poses.blocks.iter().map(|(&id, &s)| body(id, s)))
                        .collect(),
                }))
            }
            Call::SetTraining(training) => {
                self.model.set_training(training.on);
                None
            }
            Call::SetTarget(target) => {
                let wanted = if target.clear {
                    None
                } else {
                    let (Some(x), Some(y), Some(theta)) = (target.x, target.y, target.theta) else {
                        return Err("a target without x, y or theta (or clear)".into());
                    };
                    if [x, y, theta]
                        .iter()
                        .any(|v| !v.is_finite() || v.abs() > MAX_POSITION)
                    {
                        return Err(format!(
                            "the target ({x:?}, {y:?}, {theta:?}) is not a finite pose within \
                             any world (at most {MAX_POSITION} m from the origin)"
                        ));
                    }
                    Some(Target::new(target.id, ObjectState::new(x, y, theta)))
                };
                let reply = match self.model.set_target(wanted) {
                    Ok(()) => lp::TargetReply {
                        accepted: true,
                        refusal: String::new(),
                    },
                    Err(e) => lp::TargetReply {
                        accepted: false,
                        refusal: e.to_string(),
                    },
                };
                Some(Answer::Target(reply))
            }
            Call::Act(_) => {
                let a = self.model.act(&mut self.rng);
                Some(Answer::Action(lp::ActionReply {
                    action: Some(lp::Action {
                        vx: Some(a.vx),
                        vy: Some(a.vy),
                    }),
                    has_target: self.model.has_target(),
                }))
            }
            Call::GetStats(_) => Some(Answer::Stats(stats_message(&self.model.stats())?)),
            Call::Bye(_) => None,
        })
    }
}

/// The reports' serialised statistics as the protocol's message.
fn stats_message(stats: &learner::ModelStats) -> Result<lp::Stats, String> {
    #[derive(serde::Deserialize)]
    struct Wire {
        maps: std::collections::BTreeMap<String, learner::aitm::MapStats>,
        extra: std::collections::BTreeMap<String, f64>,
        labels: std::collections::BTreeMap<String, String>,
    }
    let wire: Wire = serde_json::to_value(stats)
        .and_then(serde_json::from_value)
        .map_err(|e| format!("statistics: {e}"))?;
    Ok(lp::Stats {
        maps: wire
            .maps
            .into_iter()
            .map(|(name, m)| {
                (
                    name,
                    lp::MapStats {
                        update_calls: m.update_calls,
                        inserts: m.inserts,
                        nodes: m.nodes as u64,
                    },
                )
            })
            .collect(),
        extra: wire.extra.into_iter().collect(),
        labels: wire.labels.into_iter().collect(),
    })
}

/// Answers message `seq` with an Error saying `why`, which ends serving:
/// the error to return (the transport's, if the answer cannot be sent).
fn fail(output: &mut impl Write, seq: u64, why: String) -> ServeError {
    let answer = Answer::Error(lp::Error {
        message: why.clone(),
    });
    match send(output, seq, answer) {
        Ok(()) => ServeError::Request { seq, why },
        Err(err) => err,
    }
}

/// The frame of an `Error` reply to message `seq` saying `why`: what a
/// daemon writes to a driver it turns away.
///
/// # Errors
/// The reply is too large for a frame.
pub fn error_frame(seq: u64, why: &str) -> Result<bytes::Bytes, WireError> {
    encode_frame(&Reply {
        seq,
        answer: Some(Answer::Error(lp::Error {
            message: why.to_owned(),
        })),
    })
}

fn send(output: &mut impl Write, seq: u64, answer: Answer) -> Result<(), ServeError> {
    let frame = encode_frame(&Reply {
        seq,
        answer: Some(answer),
    })?;
    output
        .write_all(&frame)
        .and_then(|()| output.flush())
        .map_err(ServeError::Write)
}

/// Standard output as a plain file, for writing frames: `std::io::stdout()`
/// is line-buffered, which splits a frame at every 0x0a byte (a common
/// protobuf tag) into separate writes, each waking the reader. Wrap the file
/// in a `BufWriter`: [`serve`] flushes once per reply.
///
/// # Errors
/// The descriptor cannot be duplicated.
pub fn stdout_file() -> std::io::Result<std::fs::File> {
    use std::os::fd::AsFd;
    Ok(std::fs::File::from(
        std::io::stdout().as_fd().try_clone_to_owned()?,
    ))
}

/// Sets how long the next read of a connection may wait (`None`: forever),
/// as `TcpStream::set_read_timeout` does.
pub type SetReadTimeout = Box<dyn FnMut(Option<Duration>) -> std::io::Result<()> + Send>;

/// The requests of one driver, read frame by frame.
pub struct Requests<R> {
    input: R,
    decoder: FrameDecoder<Request>,
    buffer: BytesMut,
    /// A daemon's idle limit: each request must be complete within this
    /// long of the previous one, however its bytes trickle in.
    idle: Option<(Duration, SetReadTimeout)>,
    /// The read timeout last set through `idle`'s setter.
    timeout_set: Option<Duration>,
}

impl<R: Read> Requests<R> {
    pub fn new(input: R) -> Self {
        Self {
            input,
            decoder: FrameDecoder::new(),
            buffer: BytesMut::with_capacity(4096),
            idle: None,
            timeout_set: None,
        }
    }

    /// Ends reading with [`ServeError::Idle`] when a request is not complete
    /// within `limit` of the previous one (or of the start): a silent or
    /// trickling connection holds a daemon's place, and a stalled frame its
    /// bytes, no longer than that. `set_timeout` bounds each read.
    #[must_use]
    pub fn with_idle_limit(mut self, limit: Duration, set_timeout: SetReadTimeout) -> Self {
        self.idle = Some((limit, set_timeout));
        self
    }

    /// The next request; `None` when the driver closed its end between
    /// requests.
    ///
    /// # Errors
    /// The input is not frames of requests, or ends inside one, or the
    /// idle limit passed.
    pub fn next_request(&mut self) -> Result<Option<Request>, ServeError> {
        let mut chunk = [0_u8; 4096];
        let deadline = self.idle.as_ref().map(|(limit, _)| Instant::now() + *limit);
        loop {
            if let Some(request) = self.decoder.decode(&mut self.buffer)? {
                return Ok(Some(request));
            }
            if let (Some(deadline), Some((limit, set_timeout))) = (deadline, &mut self.idle) {
                let left = deadline.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    return Err(ServeError::Idle(*limit));
                }
                let timeout = steady_timeout(left);
                if self.timeout_set != Some(timeout) {
                    set_timeout(Some(timeout)).map_err(|e| ServeError::Read(WireError::Io(e)))?;
                    self.timeout_set = Some(timeout);
                }
            }
            let n = match self.input.read(&mut chunk) {
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                // A read timeout: the loop finds the deadline passed.
                Err(e)
                    if deadline.is_some()
                        && matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) =>
                {
                    continue
                }
                Err(e) => return Err(ServeError::Read(WireError::Io(e))),
            };
            if n == 0 {
                return if self.buffer.is_empty() {
                    Ok(None)
                } else {
                    Err(WireError::Truncated {
                        buffered: self.buffer.len(),
                    }
                    .into())
                };
            }
            self.buffer.extend_from_slice(&chunk[..n]);
        }
    }

    /// The first request, which must be a Start: its seq and content
    /// (which the model to serve may depend on: the publish rate).
    ///
    /// # Errors
    /// Anything else first, or no request at all.
    pub fn start(&mut self) -> Result<(u64, lp::Start), ServeError> {
        match self.next_request()? {
            Some(Request {
                seq,
                call: Some(Call::Start(start)),
            }) => Ok((seq, start)),
            Some(other) => Err(ServeError::Request {
                seq: other.seq,
                why: "the first request must be a start".into(),
            }),
            None => Err(ServeError::NoStart),
        }
    }
}

/// Serves `untrained` (a fresh clone per fold) to one driver whose Start
/// (`start_seq`) was read already, until it says bye or closes its end. A
/// request the model cannot handle is answered with an Error reply and ends
/// serving.
///
/// # Errors
/// The transport failed, or a request could not be handled (after the Error
/// reply was sent).
pub fn serve<M: Model>(
    untrained: M,
    identity: &Identity,
    start_seq: u64,
    mut requests: Requests<impl Read>,
    mut output: impl Write,
) -> Result<(), ServeError> {
    let mut served = Served {
        model: untrained.clone(),
        untrained,
        rng: ChaCha8Rng::seed_from_u64(0),
        observed: None,
        prediction: None,
    };
    send(
        &mut output,
        start_seq,
        Answer::Hello(lp::Hello {
            protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
            name: identity.name.clone(),
            version: identity.version.clone(),
            capabilities: vec![
                lp::Capability::Forward as i32,
                lp::Capability::Inverse as i32,
            ],
            // The driver reads states as the model would have it read them
            // in process.
            ignores_actuator_yaw: served.untrained.actuator_yaw() == ActuatorYaw::ForceZero,
        }),
    )?;
    let mut last = start_seq;
    while let Some(request) = requests.next_request()? {
        let seq = request.seq;
        let result = match request.call {
            _ if seq <= last => Err(format!(
                "seq {seq} after seq {last}: a driver numbers its requests 1, 2, 3, …"
            )),
            Some(Call::Bye(_)) => return Ok(()),
            Some(call) => served.handle(call),
            None => Err("a request without a call".to_owned()),
        };
        last = seq;
        match result {
            Ok(Some(answer)) => send(&mut output, seq, answer)?,
            Ok(None) => {}
            Err(why) => return Err(fail(&mut output, seq, why)),
        }
    }
    Ok(())
}

/// Serves one driver with a built-in model, as `pushlearn serve-learner`
/// does on each connection: reads its Start, builds `kind` with `options`
/// for the publish rate the Start names and [`serve`]s it. A model that
/// cannot be built (options it does not take) is refused with an Error reply
/// to the Start naming why, so that the driver can say it.
///
/// # Errors
/// As [`serve`]; and the Start's refusal.
pub fn serve_driver(
    kind: ModelKind,
    options: &ModelOptions,
    mut requests: Requests<impl Read>,
    mut output: impl Write,
) -> Result<(), ServeError> {
    // Every broken Start rule is answered with an Error naming it
    // (`docs/learner-protocol.md` §8), not just a closed connection.
    let (seq, start) = match requests.start() {
        Ok(started) => started,
        Err(ServeError::Request { seq, why }) => return Err(fail(&mut output, seq, why)),
        Err(err) => return Err(err),
    };
    if let Err(why) = check_start(&start) {
        return Err(fail(&mut output, seq, why));
    }
    let job = Driver {
        identity: Identity {
            name: options.report_name(kind),
            version: env!("CARGO_PKG_VERSION").to_owned(),
        },
        seq,
        requests,
        output: &mut output,
    };
    match kind.dispatch(options, start.publish_rate_hz, job) {
        Ok(served) => served,
        Err(err) => {
            let why = format!(
                "cannot serve the {kind} model at {} Hz: {err}",
                start.publish_rate_hz
            );
            Err(fail(&mut output, seq, why))
        }
    }
}

/// One driver's model, built by [`ModelKind::dispatch`].
struct Driver<'o, R, W> {
    identity: Identity,
    seq: u64,
    requests: Requests<R>,
    output: &'o mut W,
}

impl<R: Read, W: Write> WithModel for Driver<'_, R, W> {
    type Output = Result<(), ServeError>;

    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        serve(
            untrained,
            &self.identity,
            self.seq,
            self.requests,
            self.output,
        )
    }
}
