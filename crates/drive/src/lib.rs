//! The experiment engine: what runs a learner against worlds, and what it
//! measures.
//!
//! * [`experiment`]: the thesis's experiments over the sockets — the §2
//!   driver, the tasks, links paced in lock-step or realtime, workers, seeds,
//!   the run cache, whole experiments into their documents;
//! * [`external`]: a learner in another process over the learner protocol,
//!   the server side for any model, and which learner an experiment runs;
//! * [`results`]: what the experiments measured, as plain data;
//! * [`scene`]: the thesis's set-up the experiments, their documents and
//!   figures and the learner daemon share (rates, start poses, objects);
//! * [`frame`]: world states as the learner sees them;
//! * [`latency`]: per-message work times in bounded memory and the budget
//!   they are held to;
//! * [`process`]: child processes and their groups;
//! * [`cli_args`]: argument values several command lines take (the
//!   built-in models' options, clap's side of the model registry; names,
//!   poses, actions);
//! * [`output`]: output paths checked before the work that fills them, and
//!   files written whole (temporary name, rename), for the experiments'
//!   documents and figures and the learner daemon's files alike.
//!
//! No figures, no sockets of its own beyond the worlds' and the learners',
//! and of clap only the shared argument values ([`cli_args`], which the
//! application's learner daemon and the experiments' arguments in `lab`
//! share): the experiments' arguments are lowered onto what this crate runs
//! by `lab::args`, and the application renders what it returns.

pub mod cli_args;
pub mod experiment;
pub mod external;
pub mod frame;
pub mod latency;
pub mod oracle;
pub mod output;
pub mod process;
pub mod results;
pub mod scene;
