//! A tiny stand-in for `pushlearn-sim`, speaking the real protocol over a real
//! socket bound to 127.0.0.1:0, with kinematics instead of physics: the
//! actuator moves at its commanded velocity, blocks stay where they are put.
//!
//! It is built the way the daemon is meant to be: one task per connection that
//! validates every frame on arrival (with `pushlearn::wire::validate` plus the
//! world-dependent checks) and applies valid commands in arrival order, and a
//! broadcast of every published state to every connection.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use pushlearn::wire::pb::{self, client_message::Payload, sim_control::Action};
use pushlearn::wire::{validate, InvalidCommand, ServerConnection, TimingMode};
use tokio::net::TcpListener;
use tokio::sync::broadcast;

const STEP_SIZE: f64 = 0.001;
const ACTUATOR_START: [f64; 3] = [0.0, 0.0, 0.03];
const BLOCK_A_START: [f64; 3] = [0.0, 0.25, 0.05];
/// Wall-clock time between publishes in realtime mode (fast, to keep tests short).
const REALTIME_TICK: Duration = Duration::from_millis(2);

#[derive(Debug)]
struct Body {
    name: &'static str,
    id: u32,
    start: [f64; 3],
    position: [f64; 3],
    yaw: f64,
}

impl Body {
    fn new(name: &'static str, id: u32, start: [f64; 3]) -> Self {
        Self {
            name,
            id,
            start,
            position: start,
            yaw: 0.0,
        }
    }

    fn model(&self, position: [f64; 3], yaw: f64) -> pb::ModelState {
        pb::ModelState {
            name: self.name.to_owned(),
            id: self.id,
            pose: Some(pb::Pose::from_position_yaw(position, yaw)),
            ..Default::default()
        }
    }
}

#[derive(Debug)]
struct Model {
    timing: TimingMode,
    bodies: Vec<Body>,
    velocity: [f64; 2],
    paused: bool,
    rate_hz: u32,
    step: u64,
    publish_seq: u64,
    applied_seq: u64,
    /// Every decoded frame, valid or not, in arrival order.
    frames: Vec<pb::ClientMessage>,
    /// The commands that were applied, in order.
    applied: Vec<pb::ClientMessage>,
}

impl Model {
    fn hello(&self) -> pb::Hello {
        pb::Hello {
            scene: "one_block".into(),
            step_size: STEP_SIZE,
            publish_rate: self.rate_hz,
            timing_mode: self.timing.as_str().into(),
            bodies: self.bodies.iter().map(|b| b.model(b.start, 0.0)).collect(),
        }
    }

    /// The checks that need the world, after the wire's own.
    fn check(&self, message: &pb::ClientMessage) -> Result<(), InvalidCommand> {
        validate(message)?;
        match &message.payload {
            Some(Payload::SetPose(poses)) => {
                for model in &poses.models {
                    let known = self.bodies.iter().any(|b| b.name == model.name);
                    if !known && !model.name.contains("Shadow") {
                        return Err(InvalidCommand::UnknownBody {
                            name: model.name.clone(),
                            known: self.bodies.iter().map(|b| b.name.to_owned()).collect(),
                        });
                    }
                }
                Ok(())
            }
            Some(Payload::Control(pb::SimControl {
                action: Some(Action::Advance(_)),
            })) => match (self.timing, self.paused) {
                (TimingMode::Realtime, _) => Err(InvalidCommand::AdvanceInRealtime),
                (TimingMode::Lockstep, true) => Err(InvalidCommand::AdvanceWhilePaused),
                (TimingMode::Lockstep, false) => Ok(()),
            },
            _ => Ok(()),
        }
    }

    /// Applies a checked command; returns a state if it made the world publish.
    fn apply(&mut self, message: pb::ClientMessage) -> Option<pb::WorldState> {
        self.applied_seq = message.seq;
        let mut publish = None;
        match &message.payload {
            Some(Payload::Actuator(command)) => {
                let d = command.direction.unwrap_or_default();
                self.velocity = [d.x, d.y];
            }
            Some(Payload::Control(control)) => match control.action {
                Some(Action::Pause(paused)) => self.paused = paused,
                Some(Action::Reset(_)) => {
                    self.step = 0;
                    for body in &mut self.bodies {
                        body.position = body.start;
                        body.yaw = 0.0;
                    }
                }
                Some(Action::PublishRateHz(hz)) => self.rate_hz = hz,
                Some(Action::Advance(_)) => publish = Some(self.run_interval()),
                None => {}
            },
            Some(Payload::SetPose(poses)) => {
                for model in &poses.models {
                    let Some(body) = self.bodies.iter_mut().find(|b| b.name == model.name) else {
                        continue;
                    };
                    let pose = model.pose.unwrap_or_default();
                    let p = pose.position.unwrap_or_default();
                    body.position = [p.x, p.y, p.z];
                    body.yaw = pose.orientation.unwrap_or_default().yaw();
                }
            }
            None => {}
        }
        self.applied.push(message);
        publish
    }

    /// Steps to the next publish and returns the state published there.
    fn run_interval(&mut self) -> pb::WorldState {
        let steps = u64::from(1000 / self.rate_hz.max(1));
        let dt = steps as f64 * STEP_SIZE;
        self.step += steps;
        self.publish_seq += 1;
        let velocity = self.velocity;
        if let Some(actuator) = self.bodies.iter_mut().find(|b| b.name == "actuator") {
            actuator.position[0] += velocity[0] * dt;
            actuator.position[1] += velocity[1] * dt;
        }
        pb::WorldState {
            model_v: Some(pb::ModelStateV {
                models: self
                    .bodies
                    .iter()
                    .map(|b| b.model(b.position, b.yaw))
                    .collect(),
            }),
            step: self.step,
            sim_time: self.step as f64 * STEP_SIZE,
            publish_seq: self.publish_seq,
            applied_seq: self.applied_seq,
        }
    }
}

/// A running fake world.
pub struct FakeWorld {
    pub addr: SocketAddr,
    model: Arc<Mutex<Model>>,
}

impl FakeWorld {
    /// Starts a world on the current tokio runtime.
    pub async fn start(timing: TimingMode) -> FakeWorld {
        let listener = TcpListener::bind("127.0.0.1:0")
            .await
            .expect("bind 127.0.0.1:0");
        let addr = listener.local_addr().expect("local address");
        let model = Arc::new(Mutex::new(Model {
            timing,
            bodies: vec![
                Body::new("actuator", 8, ACTUATOR_START),
                Body::new("blockA", 15, BLOCK_A_START),
            ],
            velocity: [0.0, 0.0],
            paused: false,
            rate_hz: 100,
            step: 0,
            publish_seq: 0,
            applied_seq: 0,
            frames: Vec::new(),
            applied: Vec::new(),
        }));
        let (states, _) = broadcast::channel(4096);
        if timing == TimingMode::Realtime {
            tokio::spawn(publish_in_realtime(model.clone(), states.clone()));
        }
        tokio::spawn(accept(listener, model.clone(), states));
        FakeWorld { addr, model }
    }

    fn lock(&self) -> MutexGuard<'_, Model> {
        self.model
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Every decoded frame so far, barriers and refused commands included.
    pub fn frames(&self) -> Vec<pb::ClientMessage> {
        self.lock().frames.clone()
    }

    /// The commands applied so far, in order.
    pub fn applied(&self) -> Vec<pb::ClientMessage> {
        self.lock().applied.clone()
    }

    /// `Payload::kind` of every applied command.
    pub fn applied_kinds(&self) -> Vec<&'static str> {
        self.applied()
            .iter()
            .filter_map(|m| m.payload.as_ref().map(Payload::kind))
            .collect()
    }
}

fn lock(model: &Mutex<Model>) -> MutexGuard<'_, Model> {
    model
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

async fn publish_in_realtime(
    model: Arc<Mutex<Model>>,
    states: broadcast::Sender<pb::ServerMessage>,
) {
    let mut tick = tokio::time::interval(REALTIME_TICK);
    loop {
        tick.tick().await;
        let state = {
            let mut model = lock(&model);
            (!model.paused).then(|| model.run_interval())
        };
        if let Some(state) = state {
            // No receivers is fine: nobody is connected.
            let _ = states.send(state.into());
        }
    }
}

async fn accept(
    listener: TcpListener,
    model: Arc<Mutex<Model>>,
    states: broadcast::Sender<pb::ServerMessage>,
) {
    while let Ok((stream, _)) = listener.accept().await {
        tokio::spawn(serve(
            ServerConnection::new(stream),
            model.clone(),
            states.clone(),
        ));
    }
}

async fn serve(
    connection: ServerConnection,
    model: Arc<Mutex<Model>>,
    states: broadcast::Sender<pb::ServerMessage>,
) {
    let mut published = states.subscribe();
    let hello = lock(&model).hello();
    let (mut reader, mut writer) = connection.split();
    if writer.write(&hello.into()).await.is_err() {
        return;
    }
    loop {
        tokio::select! {
            frame = reader.read() => match frame {
                Ok(Some(message)) => {
                    let (reply, state) = {
                        let mut model = lock(&model);
                        model.frames.push(message.clone());
                        match model.check(&message) {
                            Err(invalid) => (Some(invalid.reply(message.seq)), None),
                            Ok(()) => (None, model.apply(message)),
                        }
                    };
                    if let Some(state) = state {
                        let _ = states.send(state.into());
                    }
                    if let Some(reply) = reply {
                        if writer.write(&reply).await.is_err() {
                            return;
                        }
                    }
                }
                Ok(None) => return,
                Err(err) => {
                    if let Some(reply) = err.error_reply() {
                        let _ = writer.write(&reply).await;
                    }
                    let _ = writer.close().await;
                    return;
                }
            },
            state = published.recv() => match state {
                Ok(state) => {
                    if writer.write(&state).await.is_err() {
                        return;
                    }
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => return,
            },
        }
    }
}

/// A fake world with its own runtime, for tests that block on a child process.
pub struct BackgroundWorld {
    pub world: FakeWorld,
    // Keeps the world's tasks running; dropped with the test.
    _runtime: tokio::runtime::Runtime,
}

impl BackgroundWorld {
    pub fn start(timing: TimingMode) -> Self {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .expect("tokio runtime");
        let world = runtime.block_on(FakeWorld::start(timing));
        Self {
            world,
            _runtime: runtime,
        }
    }
}

impl std::ops::Deref for BackgroundWorld {
    type Target = FakeWorld;

    fn deref(&self) -> &FakeWorld {
        &self.world
    }
}
