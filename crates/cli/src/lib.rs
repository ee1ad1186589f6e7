//! The pushlearn application: everything behind the `pushlearn` command,
//! on the experiment engine (`drive`, whose modules [`experiment`],
//! [`external`], [`results`], [`scene`], [`frame`], [`latency`] and
//! [`process`] are re-exported here under the paths they always had) and
//! the experiments (`lab`, whose [`spec`], [`report`], [`sweep`],
//! [`reproduce`] and [`output`] are re-exported likewise).
//!
//! * [`learn`]: the learner daemon;
//! * [`load`]: a load test of a world daemon (`pushlearn ctl load`);
//! * [`soak`]: a long run of a learning daemon beside many subscribers
//!   (`pushlearn ctl soak`);
//! * [`models`]: the built-in models on the command line (clap's side of
//!   the model registry);
//! * [`view`]: the browser viewer (`pushlearn view`).
//!
//! The wire types and the world client come from the root protocol crate,
//! `pushlearn`.

pub mod learn;
pub mod load;
pub mod models;
pub mod soak;
pub mod view;

// The experiment engine, a crate of its own (`crates/drive`), under the
// paths the application has always used.
pub use drive::{experiment, external, frame, latency, process, results, scene};

// The experiments, a crate of their own (`crates/lab`), likewise.
pub use lab::{output, report, reproduce, spec, sweep};
