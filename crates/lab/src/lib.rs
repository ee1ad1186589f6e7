//! pushlearn's experiments as a library, on the experiment engine
//! (`drive`): what an experiment is as data, what it reports, and the
//! reproduction of the results page. It holds the experiments' arguments
//! and their one lowering onto [`spec::Spec`] ([`args`]), which the
//! application's command line, sweeps and `pushlearn.bench` share; it runs
//! no daemon.
//!
//! * [`args`]: `pushlearn experiment`'s options, parsed and lowered onto a
//!   validated spec and a run's plan;
//! * [`spec`]: an experiment as data, run into its report document;
//! * [`experiments`]: one folder per experiment, each with its tables
//!   beside the thesis's numbers and its figures, behind one
//!   [`Experiment`](experiments::Experiment) trait;
//! * [`report`]: what every experiment's tables and figures are made of
//!   (table layout, the thesis's numbers, the drawing toolkit other tools'
//!   figures share), JSON documents;
//! * [`sweep`]: a grid of push-task configurations as data, planned into
//!   fold jobs with stable ids, their outputs, and the Slurm array script;
//! * [`reproduce`]: every experiment behind `docs/results.md`, and the page
//!   itself, regenerated and checked.
//!
//! Its files are written whole through the engine's
//! [`drive::output`], which the learner daemon shares.

pub mod args;
pub mod experiments;
pub mod report;
pub mod reproduce;
pub mod spec;
pub mod sweep;
