//! The thesis's calibration sweep (`docs/spec/world.md` §10): the push action from 21
//! start positions along the start line, one run each.

use serde::{Deserialize, Serialize};

use crate::scene::{Scene, ACTUATOR};
use crate::world::{ActuatorMode, Command, CommandError, Engine, StepError, World, WorldError};

/// The body whose motion the sweep reports (the blue block).
pub const BLUE_BLOCK: &str = pushlearn_core::BLUE_NAME;

/// What to run; [`SweepOptions::default`] is the thesis's Push Task test.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOptions {
    /// Actuator start positions x₀ on the start line y = 0.
    pub starts: Vec<f64>,
    /// Commanded actuator velocity (vx, vy), m/s.
    pub action: [f64; 2],
    /// Messages per run.
    pub messages: u32,
    /// Publish rate, Hz.
    pub rate_hz: u32,
    /// The body pushed: the blue block, or another body that takes the blue
    /// block's start for every run while the blue block takes its place
    /// (the new objects of the `objects` scene).
    pub body: String,
    /// The engine the world runs on.
    pub engine: Engine,
}

impl SweepOptions {
    /// x₀ = −0.35 + 0.035·i, i = 0…20 (`docs/spec/experiments.md`), computed in
    /// millimetres so that every start is the double nearest its decimal.
    pub fn thesis_starts() -> Vec<f64> {
        (0..21).map(|i| f64::from(-350 + 35 * i) / 1000.0).collect()
    }
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            starts: SweepOptions::thesis_starts(),
            action: [0.0, 0.5],
            messages: 150,
            rate_hz: 100,
            body: BLUE_BLOCK.to_owned(),
            engine: Engine::Ode,
        }
    }
}

/// Outcome of one run, for the blue block (metres, radians).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    pub x0: f64,
    /// 1-based number of the first message whose interval (the steps that
    /// produced it) contained a step in which the collider reported the
    /// actuator touching the blue block; `None` if it never did.
    pub first_contact_message: Option<u32>,
    pub block_x: f64,
    pub block_y: f64,
    /// Final yaw in (−π, π].
    pub block_yaw: f64,
    /// Planar distance between the block's start and final centre.
    pub translation: f64,
    /// Final yaw minus start yaw.
    pub rotation: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error(transparent)]
    World(#[from] WorldError),
    #[error("scene `{scene}` has no body named `{body}`")]
    NoBody { scene: String, body: String },
    #[error("sweep command refused: {0}")]
    Command(#[from] CommandError),
    #[error(transparent)]
    Step(#[from] StepError),
}

/// Runs the sweep on a fresh world of `scene` on `options.engine`.
pub fn sweep(scene: &Scene, options: &SweepOptions) -> Result<Vec<SweepRow>, SweepError> {
    let mut world = World::on(scene, options.engine)?;
    sweep_world(&mut world, options)
}

/// Runs the sweep on an existing world (each run starts with a Reset, so
/// the world's history does not matter).
pub fn sweep_world(world: &mut World, options: &SweepOptions) -> Result<Vec<SweepRow>, SweepError> {
    options
        .starts
        .iter()
        .map(|&x0| run(world, options, x0))
        .collect()
}

/// The experiment driver's start of a push run: publish at `rate_hz`,
/// stop, reset, unpause, place the actuator at (`x0`, 0, `z`) and push with
/// `action` (m/s in x and y).
pub fn start_commands(rate_hz: u32, x0: f64, z: f64, action: [f64; 2]) -> [Command; 6] {
    [
        Command::SetPublishRate(rate_hz),
        Command::Actuator {
            mode: ActuatorMode::Move,
            velocity: [0.0; 3],
        },
        Command::Reset,
        Command::Unpause,
        Command::SetPose {
            name: ACTUATOR.into(),
            position: [x0, 0.0, z],
            orientation: [0.0, 0.0, 0.0, 1.0],
        },
        Command::Actuator {
            mode: ActuatorMode::Move,
            velocity: [action[0], action[1], 0.0],
        },
    ]
}

/// One run: the command sequence of the experiment driver (stop, reset,
/// place the actuator, push), then `messages` publish intervals.
pub fn run(world: &mut World, options: &SweepOptions, x0: f64) -> Result<SweepRow, SweepError> {
    let index = |body: &str| {
        world
            .scene()
            .body_index(body)
            .ok_or_else(|| SweepError::NoBody {
                scene: world.scene().name.clone(),
                body: body.to_owned(),
            })
    };
    let blue = index(BLUE_BLOCK)?;
    let pushed = index(&options.body)?;
    let start = world.scene().bodies[blue].start;
    let z = world.scene().drive.z_clamp;
    for cmd in start_commands(options.rate_hz, x0, z, options.action) {
        world.apply(cmd)?;
    }
    if pushed != blue {
        let parked = world.scene().bodies[pushed].start;
        for (name, at) in [(BLUE_BLOCK, parked), (options.body.as_str(), start)] {
            world.apply(Command::SetPose {
                name: pushlearn::wire::BodyName::Body(name.to_owned()),
                position: at.position(),
                orientation: at.orientation(),
            })?;
        }
    }
    let mut message = 0;
    let mut first_contact = None;
    let mut contact_in_interval = false;
    let mut last = world.snapshot();
    while message < options.messages {
        let published = world.step()?;
        contact_in_interval |= world.touched_last_step(ACTUATOR, &options.body);
        if let Some(snapshot) = published {
            message += 1;
            if contact_in_interval && first_contact.is_none() {
                first_contact = Some(message);
            }
            contact_in_interval = false;
            last = snapshot;
        }
    }
    let block = &last.bodies[pushed];
    let yaw = block.yaw();
    Ok(SweepRow {
        x0,
        first_contact_message: first_contact,
        block_x: block.position[0],
        block_y: block.position[1],
        block_yaw: yaw,
        translation: (block.position[0] - start.x).hypot(block.position[1] - start.y),
        rotation: yaw - start.yaw,
    })
}
