//! The pushlearn application: everything behind the `pushlearn` command,
//! on the experiment engine (`drive`, whose modules [`experiment`],
//! [`external`], [`results`], [`scene`], [`frame`], [`latency`] and
//! [`process`] are re-exported here under the paths they always had).
//!
//! * [`learn`]: the learner daemon;
//! * [`load`]: a load test of a world daemon (`pushlearn ctl load`);
//! * [`soak`]: a long run of a learning daemon beside many subscribers
//!   (`pushlearn ctl soak`);
//! * [`models`]: the built-in models on the command line (clap's side of
//!   the model registry);
//! * [`output`]: output paths checked before the work that fills them, and
//!   files written whole (temporary name, rename);
//! * [`report`]: JSON documents, terminal tables beside the thesis's numbers
//!   and figures;
//! * [`spec`]: an experiment as data, run into its report document;
//! * [`sweep`]: a grid of push-task configurations as data, planned into
//!   fold jobs with stable ids, their outputs, and the Slurm array script
//!   (`pushlearn sweep`);
//! * [`reproduce`]: every experiment behind `docs/results.md`, and the page
//!   itself, regenerated and checked (`pushlearn reproduce`);
//! * [`view`]: the browser viewer (`pushlearn view`).
//!
//! The wire types and the world client come from the root protocol crate,
//! `pushlearn`.

pub mod learn;
pub mod load;
pub mod models;
pub mod output;
pub mod report;
pub mod reproduce;
pub mod soak;
pub mod spec;
pub mod sweep;
pub mod view;

// The experiment engine, a crate of its own (`crates/drive`), under the
// paths the application has always used.
pub use drive::{experiment, external, frame, latency, process, results, scene};
