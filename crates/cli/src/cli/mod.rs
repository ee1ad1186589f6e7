//! Subcommands of the `pushlearn` binary.

pub mod ctl;
#[cfg(feature = "lab")]
pub mod experiment;
pub mod learn;
pub mod learner_check;
#[cfg(feature = "lab")]
pub mod report;
#[cfg(feature = "lab")]
pub mod reproduce;
pub mod serve_learner;
#[cfg(feature = "lab")]
pub mod sweep;
#[cfg(feature = "viewer")]
pub mod view;

/// Whether `err` comes from writing to a closed stdout pipe.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain()
        .filter_map(|cause| cause.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}
