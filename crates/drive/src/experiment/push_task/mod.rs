//! Push Task Simulation (`docs/spec/experiments.md` §3): the forward-model test.
//!
//! One job is one (N_train, fold): a fresh model, N_train training runs
//! pushing straight ahead from the job's training starts, then one chained
//! test run per test position.
//!
//! * [`protocol`]: the variants, the driver's configuration bits and the
//!   jobs ([`protocol::PushJob`]);
//! * [`task`]: [`task::PushJobTask`], the §3 handler for one job;
//! * [`objects`]: the new-object experiments' objects and what the learner
//!   is shown of them.
//!
//! What the jobs measured, and its §7 summary, are
//! [`crate::results::push_task`].

pub mod objects;
pub mod protocol;
pub mod task;
