//! pushlearn: the protocol every pushlearn process and client shares.
//!
//! * [`wire`]: the protobuf schema (`proto/pushlearn.proto`), framing,
//!   connections and command validation, used by the world daemon and every
//!   client alike;
//! * [`client`]: an async client for the world daemon;
//! * [`duration`]: the `SECONDS` of every binary's command line;
//! * [`errors`]: how every binary reports a failure and colours its logs;
//! * [`recording`]: the file format of recorded sessions (record, replay).
//!
//! The application (learner daemon, experiments, reports, viewer, `ctl`) is
//! the `pushlearn-cli` crate in `crates/cli`; the world is `sim-plugin`.

pub mod client;
pub mod duration;
pub mod errors;
pub mod recording;
pub mod wire;
