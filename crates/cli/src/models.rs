//! The built-in models on the command line: the model registry
//! (`learner::registry`), which holds the models, their options and their
//! checks, and clap's side of it (`drive::cli_args`, which the
//! experiments' arguments in `lab::args` share).

pub use drive::cli_args::{named, ModelArgs};
pub use learner::registry::{
    ConfigFlag, Improvement, ModelKind, ModelOptions, ModelOptionsError, Named, Parts, WithModel,
};
