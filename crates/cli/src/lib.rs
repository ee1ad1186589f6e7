//! The pushlearn application: everything behind the `pushlearn` command.
//!
//! * [`frame`]: world states as the learner sees them;
//! * [`experiment`]: the thesis's experiments over the sockets;
//! * [`learn`]: the learner daemon;
//! * [`load`]: a load test of a world daemon (`pushlearn ctl load`);
//! * [`soak`]: a long run of a learning daemon beside many subscribers
//!   (`pushlearn ctl soak`);
//! * [`models`]: the learners by name;
//! * [`output`]: output paths checked before the work that fills them, and
//!   files written whole (temporary name, rename);
//! * [`report`]: JSON documents, terminal tables beside the thesis's numbers
//!   and figures;
//! * [`results`]: what the experiments measured, as plain data: filled by
//!   [`experiment`], rendered by [`report`];
//! * [`scene`]: the thesis's set-up the experiments, their documents and
//!   figures and the learner daemon share (rates, start poses, objects);
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

pub mod experiment;
pub mod external;
pub mod frame;
pub mod latency;
pub mod learn;
pub mod load;
pub mod models;
pub mod output;
pub mod process;
pub mod report;
pub mod reproduce;
pub mod results;
pub mod scene;
pub mod soak;
pub mod spec;
pub mod sweep;
pub mod view;
