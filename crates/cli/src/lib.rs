//! The pushlearn application: everything behind the `pushlearn` command,
//! on the experiment engine (`drive`, whose modules [`experiment`],
//! [`external`], [`results`], [`scene`], [`frame`], [`latency`] and
//! [`process`] and [`output`] are re-exported here under the paths they
//! always had) and the experiments (`lab`, whose [`spec`], [`report`],
//! [`sweep`] and [`reproduce`] are re-exported likewise).
//!
//! Features: `lab` (the experiments, their reports and figures, and the
//! soak, which draws one) and `viewer` (the browser viewer's WebSocket
//! stack), both default. Without them the crate is the learner daemon,
//! the learner-protocol tools and `pushlearn ctl`.
//!
//! * [`learn`]: the learner daemon;
//! * [`load`]: a load test of a world daemon (`pushlearn ctl load`);
//! * [`soak`]: a long run of a learning daemon beside many subscribers
//!   (`pushlearn ctl soak`; feature `lab`);
//! * [`models`]: the built-in models on the command line (clap's side of
//!   the model registry);
//! * [`view`]: the browser viewer (`pushlearn view`; feature `viewer`).
//!
//! The wire types and the world client come from the root protocol crate,
//! `pushlearn`.

pub mod learn;
pub mod load;
pub mod models;
#[cfg(feature = "lab")]
pub mod soak;
#[cfg(feature = "viewer")]
pub mod view;

// The experiment engine, a crate of its own (`crates/drive`), under the
// paths the application has always used.
pub use drive::{experiment, external, frame, latency, oracle, output, process, results, scene};

// The experiments, a crate of their own (`crates/lab`), likewise.
#[cfg(feature = "lab")]
pub use lab::{experiments, report, reproduce, spec, sweep};
