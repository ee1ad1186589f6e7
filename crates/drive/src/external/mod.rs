//! External learners (`docs/learner-protocol.md`): a learner in another
//! process, in any language, run by the experiment driver exactly as it runs
//! the built-in models.
//!
//! [`ExternalModel`] implements [`learner::Model`] by sending each call of
//! the trait as one request of the learner protocol, so the driver, its tasks
//! and its reports are the built-in models' own. What the trait cannot say —
//! that a call failed — [`Model::failure`] reports: after a failure the model
//! answers neutrally and the driver ends the job with the failure.
//!
//! A fresh learner per fold: every job clones the untrained handle and calls
//! [`Model::start_fold`], which takes an idle connection (or opens one) and
//! sends `NewFold` with the fold's seed. A connection goes back to the idle
//! list when its fold ends, so there are never more learners than workers.

pub mod check;
pub mod server;
pub mod session;
#[cfg(any(test, feature = "testing"))]
pub mod untrusted;

use std::cell::{Cell, RefCell};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use learner::features::{parse_frame, ActuatorYaw, ParseError};
use learner::{Action, Frame, Model, ModelStats, ObjectState, Poses, Target, TargetError};
use pushlearn_core::Named;
use serde::{Deserialize, Serialize};

use learner::registry::ModelKind;
use pushlearn::wire::pb::learner::{self as lp, reply::Answer, request::Call};
use pushlearn::wire::{pb, MAX_POSITION};
use session::Session;
pub use session::Source;

/// How long a learner may take over one answer by default.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(30);

/// An external learner: where it runs and how long it may take.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LearnerSpec {
    pub source: Source,
    /// Per answered message; also for the hello.
    pub timeout: Duration,
}

/// The learner an experiment runs: a built-in model, in-process, or an
/// external one over the learner protocol (this module).
#[derive(Clone, Debug, PartialEq)]
pub enum LearnerChoice {
    Builtin(ModelKind),
    External(LearnerSpec),
    /// The world as a predictor of itself ([`crate::oracle`]): not a
    /// learner, the reference at the other end of the scale from `still`.
    Oracle(crate::oracle::OracleLatency),
    /// A learner object the caller holds and hands to the experiment itself
    /// (`lab::spec::Valid::run_with`): the Python API's `Learner` objects,
    /// called directly in the caller's process.
    InProcess,
}

/// The choice as `pushlearn experiment` flags: `--model gate`,
/// `--learner 'CMD'`, `--learner-connect ADDR` or `--oracle known|unknown`.
impl std::fmt::Display for LearnerChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LearnerChoice::Builtin(kind) => write!(f, "--model {kind}"),
            LearnerChoice::Oracle(latency) => write!(f, "--oracle {}", latency.name()),
            LearnerChoice::InProcess => write!(f, "(a learner object in the calling process)"),
            LearnerChoice::External(spec) => {
                match &spec.source {
                    Source::Command(command) => write!(f, "--learner '{command}'")?,
                    Source::Connect(addr) => write!(f, "--learner-connect {addr}")?,
                }
                if spec.timeout != DEFAULT_TIMEOUT {
                    write!(f, " --learner-timeout {}", spec.timeout.as_secs_f64())?;
                }
                Ok(())
            }
        }
    }
}

impl From<ModelKind> for LearnerChoice {
    fn from(kind: ModelKind) -> Self {
        LearnerChoice::Builtin(kind)
    }
}

/// Why an external learner could not be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LearnerError {
    /// It could not be started or reached.
    #[error("{0}")]
    Start(String),
    /// It said hello in a way the driver cannot work with.
    #[error("{0}")]
    Hello(String),
    /// It cannot do what the experiment needs.
    #[error("learner '{name}' cannot run {task}: it announces {has}, {task} needs {needs}")]
    Incapable {
        name: String,
        task: String,
        has: String,
        needs: &'static str,
    },
    /// No answer in time.
    #[error("no answer to message {seq} ({call}) within {after:?}; a learner may take longer with --learner-timeout SECS")]
    Timeout {
        seq: u64,
        call: &'static str,
        after: Duration,
    },
    /// It went away.
    #[error("the learner went away while the driver waited for the answer to message {seq} ({call}): {status}")]
    Exited {
        seq: u64,
        call: &'static str,
        status: String,
    },
    /// Its output is not the protocol's framing.
    #[error("at message {seq} ({call}) the learner {what}")]
    Garbage {
        seq: u64,
        call: &'static str,
        what: String,
    },
    /// It broke a rule of the protocol.
    #[error("at message {seq} ({call}) the learner {what}")]
    Protocol {
        seq: u64,
        call: &'static str,
        what: String,
    },
    /// It reported an error itself.
    #[error("the learner failed on message {seq} ({call}): {message}")]
    Reported {
        seq: u64,
        call: &'static str,
        message: String,
    },
}

/// What the learner said in its hello.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LearnerInfo {
    pub name: String,
    pub version: String,
    pub inverse: bool,
    /// The driver reads the actuator's yaw as 0 (`Hello.ignores_actuator_yaw`).
    pub ignores_actuator_yaw: bool,
}

/// State shared by every handle of one external learner.
struct Shared {
    spec: LearnerSpec,
    start: lp::Start,
    info: LearnerInfo,
    idle: Mutex<Vec<Session>>,
}

impl std::fmt::Debug for Shared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shared")
            .field("source", &self.spec.source)
            .field("info", &self.info)
            .finish_non_exhaustive()
    }
}

impl Shared {
    /// A new connection, greeted and checked.
    fn open(spec: &LearnerSpec, start: &lp::Start) -> Result<(Session, LearnerInfo), LearnerError> {
        let mut session = Session::open(&spec.source, spec.timeout)?;
        let answer = session
            .call(Call::Start(start.clone()))
            .map_err(|e| LearnerError::Hello(format!("{} did not say hello: {e}", spec.source)))?;
        let Some(Answer::Hello(hello)) = answer else {
            return Err(LearnerError::Hello(format!(
                "{} answered the start with something else than a hello",
                spec.source
            )));
        };
        Ok((session, greeting(hello, &spec.source)?))
    }
}

/// What a learner's Hello says, checked: the protocol version, a name, and
/// the FORWARD capability every experiment needs.
fn greeting(hello: lp::Hello, source: &Source) -> Result<LearnerInfo, LearnerError> {
    if hello.protocol_version != lp::ProtocolVersion::ProtocolVersion as i32 {
        return Err(LearnerError::Hello(format!(
            "{} speaks learner protocol version {}, the driver version {}",
            source,
            hello.protocol_version,
            lp::ProtocolVersion::ProtocolVersion as i32
        )));
    }
    if hello.name.trim().is_empty() {
        return Err(LearnerError::Hello(format!(
            "{} said hello without a name",
            source
        )));
    }
    let has = |c: lp::Capability| hello.capabilities.contains(&(c as i32));
    if !has(lp::Capability::Forward) {
        return Err(LearnerError::Hello(format!(
                "learner '{}' ({}) does not announce the FORWARD capability, which every experiment needs",
                hello.name, source
            )));
    }
    let info = LearnerInfo {
        name: hello.name,
        version: hello.version,
        inverse: has(lp::Capability::Inverse),
        ignores_actuator_yaw: hello.ignores_actuator_yaw,
    };
    Ok(info)
}

/// A handle on an external learner; see the module documentation.
pub struct ExternalModel {
    shared: Arc<Shared>,
    session: RefCell<Option<Session>>,
    failure: RefCell<Option<LearnerError>>,
    /// Numbers the worlds this handle parsed or predicted.
    serial: Cell<u64>,
    /// The observed world the learner holds as `LAST_OBSERVED`.
    sent_observed: Cell<Option<u64>>,
    /// The learner's latest prediction, as `LAST_PREDICTION`.
    last_prediction: Cell<Option<u64>>,
    training: bool,
    has_target: bool,
}

impl std::fmt::Debug for ExternalModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExternalModel")
            .field("learner", &self.shared.info.name)
            .field("training", &self.training)
            .finish_non_exhaustive()
    }
}

/// A clone is an untrained handle on the same learner: the trait's clones
/// are how a fold gets a fresh model, and a learner's memory lives in its
/// own process.
impl Clone for ExternalModel {
    fn clone(&self) -> Self {
        Self::handle(Arc::clone(&self.shared))
    }
}

/// The learner's memory is in its own process, so there is nothing to save;
/// saving is refused rather than writing a memory that cannot be restored.
impl Serialize for ExternalModel {
    fn serialize<S: serde::Serializer>(&self, _: S) -> Result<S::Ok, S::Error> {
        Err(serde::ser::Error::custom(format!(
            "learner '{}' keeps its memory in its own process; it cannot be saved",
            self.shared.info.name
        )))
    }
}

impl<'de> Deserialize<'de> for ExternalModel {
    fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom(
            "an external learner's memory cannot be restored",
        ))
    }
}

impl Drop for ExternalModel {
    fn drop(&mut self) {
        let Some(session) = self.session.get_mut().take() else {
            return;
        };
        if self.failure.get_mut().is_none() && !session.has_failed() {
            self.shared
                .idle
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push(session);
        }
    }
}

/// A world as the external learner's handle sees it: its poses (for the
/// driver's checks and metrics) and where it came from.
#[derive(Clone, Debug)]
pub struct ExternalWorld {
    poses: Poses,
    serial: u64,
    origin: Origin,
}

#[derive(Clone, Debug)]
enum Origin {
    /// Parsed from a world message.
    Observed(Arc<Frame>),
    /// Returned by the learner.
    Predicted,
}

impl ExternalModel {
    /// Starts the learner once, reads its hello and checks that it can run
    /// `task` (`"move-to-target"` needs the INVERSE capability). The
    /// connection is kept for the first fold.
    ///
    /// # Errors
    /// The learner cannot be started, does not greet properly or cannot do
    /// the task.
    pub fn connect(
        spec: &LearnerSpec,
        task: &str,
        publish_rate_hz: u32,
    ) -> Result<Self, LearnerError> {
        let start = lp::Start {
            protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
            task: task.to_owned(),
            publish_rate_hz,
        };
        let (session, info) = Shared::open(spec, &start)?;
        if task == "move-to-target" && !info.inverse {
            return Err(LearnerError::Incapable {
                name: info.name,
                task: task.to_owned(),
                has: "FORWARD only".to_owned(),
                needs: "INVERSE (actions towards a target)",
            });
        }
        let shared = Arc::new(Shared {
            spec: spec.clone(),
            start,
            info,
            idle: Mutex::new(vec![session]),
        });
        Ok(Self::handle(shared))
    }

    fn handle(shared: Arc<Shared>) -> Self {
        Self {
            shared,
            session: RefCell::new(None),
            failure: RefCell::new(None),
            serial: Cell::new(0),
            sent_observed: Cell::new(None),
            last_prediction: Cell::new(None),
            training: true,
            has_target: false,
        }
    }

    /// What the learner said in its hello.
    #[must_use]
    pub fn info(&self) -> &LearnerInfo {
        &self.shared.info
    }

    /// The learner's actuator-yaw rule, as its hello announced it.
    fn actuator_yaw_rule(&self) -> ActuatorYaw {
        if self.shared.info.ignores_actuator_yaw {
            ActuatorYaw::ForceZero
        } else {
            ActuatorYaw::Keep
        }
    }

    fn next_serial(&self) -> u64 {
        let serial = self.serial.get() + 1;
        self.serial.set(serial);
        serial
    }

    fn fail(&self, error: LearnerError) {
        let mut failure = self.failure.borrow_mut();
        if failure.is_none() {
            *failure = Some(error);
        }
    }

    fn failed(&self) -> bool {
        self.failure.borrow().is_some()
    }

    /// Sends `call`; `None` once failed (or for a one-way call).
    fn call(&self, call: Call) -> Option<Answer> {
        if self.failed() {
            return None;
        }
        let mut slot = self.session.borrow_mut();
        let Some(session) = slot.as_mut() else {
            drop(slot);
            self.fail(LearnerError::Start(
                "the driver called the learner outside a fold (no start_fold)".into(),
            ));
            return None;
        };
        match session.call(call) {
            Ok(answer) => answer,
            Err(err) => {
                drop(slot);
                self.fail(err);
                None
            }
        }
    }

    /// A protocol violation in an answer's content.
    fn reject(&self, call: &'static str, what: String) {
        let seq = self.session.borrow().as_ref().map_or(0, Session::last_seq);
        self.fail(LearnerError::Protocol { seq, call, what });
    }

    /// The reference the learner resolves to `world`: a world it already
    /// holds by name, else the observed state in full.
    fn state_ref(&self, world: &ExternalWorld) -> lp::StateRef {
        use lp::state_ref::State;
        let state = match &world.origin {
            Origin::Observed(_) if self.sent_observed.get() == Some(world.serial) => {
                State::Recent(lp::Recent::LastObserved as i32)
            }
            Origin::Observed(frame) => {
                self.sent_observed.set(Some(world.serial));
                State::Observed(state_of(frame))
            }
            Origin::Predicted => {
                if self.last_prediction.get() != Some(world.serial) {
                    // The driver only ever continues from the latest
                    // prediction (`docs/learner-protocol.md` §3).
                    self.reject(
                        "update",
                        "was asked about a prediction older than its latest (a driver bug)".into(),
                    );
                }
                State::Recent(lp::Recent::LastPrediction as i32)
            }
        };
        lp::StateRef { state: Some(state) }
    }
}

/// The world message's bodies as the protocol sends them, with the shape
/// each was observed with.
fn state_of(frame: &Frame) -> lp::State {
    lp::State {
        shapes: frame
            .objects
            .iter()
            .filter_map(|o| Some(pb::Shape::of_body(&o.name, o.shape?)))
            .collect(),
        bodies: frame
            .objects
            .iter()
            .map(|o| pb::ModelState {
                name: o.name.clone(),
                id: o.id,
                pose: Some(pb::Pose {
                    position: Some(pb::Vector3d::new(
                        o.position[0],
                        o.position[1],
                        o.position[2],
                    )),
                    orientation: Some(pb::Quaternion {
                        x: o.orientation[0],
                        y: o.orientation[1],
                        z: o.orientation[2],
                        w: o.orientation[3],
                    }),
                }),
                ..pb::ModelState::default()
            })
            .collect(),
    }
}

fn action(a: Action) -> lp::Action {
    lp::Action {
        vx: Some(a.vx),
        vy: Some(a.vy),
    }
}

/// A prediction's poses, checked: the actuator and exactly the blocks of
/// the world it was made from, every number finite. `bodies` are
/// `(id, x, y, theta)`, as a learner's reply lists them.
///
/// # Errors
/// What is wrong with the prediction, for people.
pub fn predicted_poses(
    bodies: impl IntoIterator<Item = (u32, f64, f64, f64)>,
    from: &Poses,
) -> Result<Poses, String> {
    let mut actuator = None;
    let mut blocks = std::collections::BTreeMap::new();
    for (id, x, y, theta) in bodies {
        if ![x, y, theta].iter().all(|v| v.is_finite()) {
            return Err(format!(
                "predicted a non-finite pose for body {id}: ({x}, {y}, {theta})"
            ));
        }
        // Finite but absurd (1.7e308) is refused too: its error squared is
        // infinite, and the report printed `inf ± NaN` and wrote nulls.
        if [x, y, theta].iter().any(|v| v.abs() > MAX_POSITION) {
            return Err(format!(
                "predicted a pose outside any world for body {id}: ({x}, {y}, {theta}) (at \
                 most {MAX_POSITION} m from the origin on each axis, and {MAX_POSITION} rad)"
            ));
        }
        let state = ObjectState::new(x, y, theta);
        let duplicate = if id == learner::ACTUATOR_ID {
            actuator.replace(state).is_some()
        } else if from.blocks.contains_key(&id) {
            blocks.insert(id, state).is_some()
        } else {
            return Err(format!(
                "predicted body {id}, which the state it predicted from does not have"
            ));
        };
        if duplicate {
            return Err(format!("predicted body {id} twice"));
        }
    }
    let actuator = actuator.ok_or("predicted no actuator (id 8)")?;
    if let Some(missing) = from.blocks.keys().find(|id| !blocks.contains_key(id)) {
        return Err(format!("predicted no pose for block {missing}"));
    }
    Ok(Poses { actuator, blocks })
}

/// A Prediction reply's bodies as [`predicted_poses`] takes them.
pub(crate) fn bodies_of(
    prediction: &lp::Prediction,
) -> impl Iterator<Item = (u32, f64, f64, f64)> + '_ {
    prediction
        .bodies
        .iter()
        .map(|b| (b.id, b.x(), b.y(), b.theta()))
}

/// The action an Act reply chose, checked: finite.
fn chosen_action(reply: &lp::ActionReply) -> Result<Action, String> {
    let a = reply.action.unwrap_or_default();
    let action = Action::new(a.vx(), a.vy());
    if action.is_finite() {
        Ok(action)
    } else {
        Err(format!(
            "chose a non-finite action ({}, {})",
            action.vx, action.vy
        ))
    }
}

/// Statistics from the protocol's form, read as the reports' serialised form.
///
/// # Errors
/// A non-finite number, or maps under a built-in model's names that are not
/// that model's complete statistics.
pub fn stats_of(stats: lp::Stats) -> Result<ModelStats, String> {
    let maps: std::collections::BTreeMap<String, serde_json::Value> = stats
        .maps
        .into_iter()
        .map(|(name, m)| {
            (
                name,
                serde_json::json!({
                    "update_calls": m.update_calls,
                    "inserts": m.inserts,
                    "nodes": m.nodes,
                }),
            )
        })
        .collect();
    if let Some((key, value)) = stats.extra.iter().find(|(_, v)| !v.is_finite()) {
        return Err(format!("sent a non-finite statistic {key} = {value}"));
    }
    let extra: std::collections::BTreeMap<_, _> = stats.extra.into_iter().collect();
    let labels: std::collections::BTreeMap<_, _> = stats.labels.into_iter().collect();
    serde_json::from_value(serde_json::json!({ "maps": maps, "extra": extra, "labels": labels }))
        .map_err(|e| format!("sent statistics that are not a model's: {e}"))
}

impl Model for ExternalModel {
    type World = ExternalWorld;

    fn parse(&self, frame: &Frame) -> Result<ExternalWorld, ParseError> {
        Ok(ExternalWorld {
            poses: parse_frame(frame, self.actuator_yaw_rule())?,
            serial: self.next_serial(),
            origin: Origin::Observed(Arc::new(frame.clone())),
        })
    }

    fn poses(world: &ExternalWorld) -> Poses {
        world.poses.clone()
    }

    fn reset_objects(&mut self, world: &ExternalWorld) {
        let state = self.state_ref(world);
        self.call(Call::Reset(lp::Reset { state: Some(state) }));
    }

    fn update(&mut self, world: &ExternalWorld, a: Action) {
        let state = self.state_ref(world);
        self.call(Call::Update(lp::Update {
            state: Some(state),
            action: Some(action(a)),
        }));
    }

    fn predict(&self, world: &ExternalWorld, a: Action) -> ExternalWorld {
        let from = self.state_ref(world);
        let serial = self.next_serial();
        let neutral = || ExternalWorld {
            poses: world.poses.clone(),
            serial,
            origin: Origin::Predicted,
        };
        let Some(answer) = self.call(Call::Predict(lp::Predict {
            from: Some(from),
            action: Some(action(a)),
        })) else {
            return neutral();
        };
        let Answer::Prediction(prediction) = answer else {
            return neutral();
        };
        match predicted_poses(bodies_of(&prediction), &world.poses) {
            Ok(poses) => {
                self.last_prediction.set(Some(serial));
                ExternalWorld {
                    poses,
                    serial,
                    origin: Origin::Predicted,
                }
            }
            Err(what) => {
                self.reject("predict", what);
                neutral()
            }
        }
    }

    fn set_training(&mut self, on: bool) {
        self.training = on;
        self.call(Call::SetTraining(lp::SetTraining { on }));
    }

    fn is_training(&self) -> bool {
        self.training
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        let request = match target {
            Some(t) => {
                t.check()?;
                lp::SetTarget {
                    clear: false,
                    id: t.id,
                    x: Some(t.pose.x),
                    y: Some(t.pose.y),
                    theta: Some(t.pose.theta),
                }
            }
            None => lp::SetTarget {
                clear: true,
                ..lp::SetTarget::default()
            },
        };
        match self.call(Call::SetTarget(request)) {
            Some(Answer::Target(reply)) if reply.accepted => {
                self.has_target = target.is_some();
                Ok(())
            }
            Some(Answer::Target(reply)) => {
                self.reject(
                    "set_target",
                    format!("refused the target: {}", reply.refusal),
                );
                Err(TargetError::UnknownObject {
                    id: target.map_or(0, |t| t.id),
                })
            }
            // Failed: the driver stops at the end of this message.
            _ => Ok(()),
        }
    }

    fn has_target(&self) -> bool {
        self.has_target
    }

    /// The learner explores with its own generator (seeded by `NewFold`), so
    /// `rng` is not drawn from.
    fn act(&mut self, _rng: &mut dyn rand::Rng) -> Action {
        match self.call(Call::Act(lp::Act {})) {
            Some(Answer::Action(reply)) => match chosen_action(&reply) {
                Ok(action) => {
                    self.has_target = reply.has_target;
                    action
                }
                Err(what) => {
                    self.reject("act", what);
                    Action::ZERO
                }
            },
            _ => Action::ZERO,
        }
    }

    fn stats(&self) -> ModelStats {
        match self.call(Call::GetStats(lp::GetStats {})) {
            Some(Answer::Stats(stats)) => stats_of(stats).unwrap_or_else(|what| {
                self.reject("get_stats", what);
                ModelStats::default()
            }),
            _ => ModelStats::default(),
        }
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        self.actuator_yaw_rule()
    }

    fn start_fold(&mut self, seed: u64) {
        let idle = self
            .shared
            .idle
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .pop();
        let session = match idle {
            Some(session) => session,
            None => match Shared::open(&self.shared.spec, &self.shared.start) {
                Ok((session, _)) => session,
                Err(err) => {
                    self.fail(err);
                    return;
                }
            },
        };
        *self.session.get_mut() = Some(session);
        self.training = true;
        self.has_target = false;
        self.sent_observed.set(None);
        self.last_prediction.set(None);
        self.call(Call::NewFold(lp::NewFold { seed }));
    }

    fn failure(&self) -> Option<String> {
        self.failure.borrow().as_ref().map(|e| {
            format!(
                "learner '{}' ({}): {e}",
                self.shared.info.name, self.shared.spec.source
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 49, item 9: a prediction of 1.7e308 m was scored, printed as
    /// `inf ± NaN` and written as nulls into the report.
    #[test]
    fn a_prediction_outside_any_world_is_refused_like_a_non_finite_one() {
        let from = Poses {
            actuator: ObjectState::new(0.0, 0.0, 0.0),
            blocks: [(15, ObjectState::new(0.0, 0.25, 0.0))].into(),
        };
        let fine = [(8, 0.0, 0.01, 0.0), (15, 0.0, 0.25, 0.1)];
        assert!(predicted_poses(fine, &from).is_ok());
        for absurd in [1.7e308, -1001.0] {
            let err = predicted_poses([(8, 0.0, 0.0, 0.0), (15, absurd, 0.25, 0.0)], &from)
                .expect_err("refused");
            assert!(err.contains("outside any world for body 15"), "{err}");
        }
        let err = predicted_poses([(8, 0.0, 0.0, 0.0), (15, 0.0, 0.25, 1e300)], &from)
            .expect_err("refused");
        assert!(err.contains("outside any world"), "{err}");
    }
}
