//! The `pushlearn` command line. Subcommands live in `cli/`; this file only
//! parses arguments, sets up logging and turns errors into an exit status.
//! Built without default features it is the learner daemon and the world
//! tools alone: no experiments or figures (feature `lab`), no viewer
//! (feature `viewer`).

mod cli;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tracing_subscriber::EnvFilter;

/// Memory-based online learning of object manipulation: tools around the
/// pushlearn world daemon (`pushlearn-sim`).
///
/// Logging goes to stderr and is controlled by RUST_LOG (e.g. RUST_LOG=debug);
/// it is coloured only on a terminal and never with NO_COLOR set. A failure
/// prints `error: …` (with a `caused by:` line per further cause) and exits
/// with status 1; a command line clap cannot parse exits with status 2.
#[derive(Debug, Parser)]
#[command(name = "pushlearn", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per process, so the size of the largest variant (the
// learner daemon's, once the experiments are left out) costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
enum Command {
    Ctl(cli::ctl::CtlArgs),
    #[cfg(feature = "lab")]
    Experiment(cli::experiment::ExperimentArgs),
    Learn(cli::learn::LearnArgs),
    LearnerCheck(cli::learner_check::LearnerCheckArgs),
    #[cfg(feature = "viewer")]
    View(cli::view::ViewArgs),
    #[cfg(feature = "lab")]
    Report(cli::report::ReportArgs),
    #[cfg(feature = "lab")]
    Reproduce(cli::reproduce::ReproduceArgs),
    ServeLearner(cli::serve_learner::ServeLearnerArgs),
    #[cfg(feature = "lab")]
    Sweep(cli::sweep::SweepArgs),
    /// Runs experiment jobs for the experiment that started it (JSON lines
    /// on stdin and stdout); not for people.
    #[cfg(feature = "lab")]
    #[command(hide = true)]
    ExperimentWorker,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .with_ansi(pushlearn::errors::colours())
        .init();
    let result = match cli.command {
        Command::Ctl(args) => cli::ctl::run(args),
        #[cfg(feature = "lab")]
        Command::Experiment(args) => cli::experiment::run(args),
        Command::Learn(args) => cli::learn::run(args),
        Command::LearnerCheck(args) => cli::learner_check::run(args),
        #[cfg(feature = "viewer")]
        Command::View(args) => cli::view::run(args),
        #[cfg(feature = "lab")]
        Command::Report(args) => cli::report::run(args),
        #[cfg(feature = "lab")]
        Command::Reproduce(args) => cli::reproduce::run(args),
        Command::ServeLearner(args) => cli::serve_learner::run(args),
        #[cfg(feature = "lab")]
        Command::Sweep(args) => cli::sweep::run(args),
        #[cfg(feature = "lab")]
        Command::ExperimentWorker => cli::experiment::serve_worker(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // `pushlearn ctl watch | head` closing the pipe is a normal way to stop.
        Err(err) if cli::is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("{}", pushlearn::errors::describe(err.as_ref()));
            ExitCode::FAILURE
        }
    }
}
