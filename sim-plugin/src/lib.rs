//! The thesis world and the simulator.
//!
//! * [`scene`]: the world as data (TOML scene files, the embedded thesis
//!   scenes);
//! * [`world`]: the faithful thesis world on ODE, or on MuJoCo (feature
//!   `mujoco`, on by default) — bodies, contacts, the per-step actuator
//!   drive, commands, ghosts and publishing;
//! * [`calibration`]: the calibration sweep of `docs/spec/world.md` §10;
//! * [`generate`]: objects drawn from seeded distributions, as scenes;
//! * [`push_run`]: push-task runs as the experiment driver records them.
//! * [`server`]: the `pushlearn-sim` daemon serving the world over TCP
//!   (`docs/protocol.md`);
//! * [`replay`]: a recorded session served as if it were the world;
//! * `untrusted` (feature `testing`): the daemon's, the scene parser's and
//!   the recording loader's handling of untrusted bytes without sockets, for
//!   the fuzzers and the tests that replay their inputs.

pub mod calibration;
pub mod generate;
pub mod lockstep;
pub mod push_run;
pub mod replay;
pub mod scene;
pub mod server;
#[cfg(feature = "testing")]
pub mod untrusted;
pub mod world;

pub use calibration::{sweep, SweepOptions, SweepRow};
pub use scene::Scene;
pub use world::{
    check_command, ActuatorMode, BodyState, Command, CommandError, Engine, Snapshot, StepError,
    World, WorldError,
};

/// The top-level collision space kinds (for the hash-space regression test).
pub use ode::SpaceKind;
