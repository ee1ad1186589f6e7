//! `pushlearn experiment`: the thesis's experiments against real worlds.
//! The options and their lowering onto a spec are `lab::args`' (which
//! sweeps and `pushlearn.bench` share); this is the command's run: its
//! worker processes, progress bar and printed tables.

use std::io::{IsTerminal, Write};
use std::sync::{Arc, OnceLock};

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use pushlearn_cli::experiment::processes::Processes;
use pushlearn_cli::experiment::run::Plan;
use pushlearn_cli::experiment::workers::kill_all_worlds;
use pushlearn_cli::external::LearnerChoice;
use pushlearn_cli::scene::RATE_HZ;
use pushlearn_cli::spec::{Spec, Valid};

use lab::args::ArgsError;
pub use lab::args::ExperimentArgs;

/// This program's worker processes for embedded worlds, started when an
/// experiment first needs them (`drive::experiment::processes`); one set for
/// the program's life, so that they keep their worlds and recorded runs
/// from one experiment to the next. `workers` is the most there can be (the
/// first caller's: a program's experiments share one --workers).
///
/// # Errors
/// This program's path is unknown.
pub fn worker_processes(workers: usize) -> Result<Arc<Processes>> {
    static PROCESSES: OnceLock<Arc<Processes>> = OnceLock::new();
    if let Some(processes) = PROCESSES.get() {
        return Ok(Arc::clone(processes));
    }
    let program = std::env::current_exe()
        .context("cannot find this program's path to start worker processes")?;
    Ok(Arc::clone(PROCESSES.get_or_init(|| {
        Arc::new(Processes::new(
            program,
            vec!["experiment-worker".to_owned()],
            workers,
        ))
    })))
}

/// `pushlearn experiment-worker`: a worker process's loop on stdin and stdout.
///
/// # Errors
/// Its pipes broke.
pub fn serve_worker() -> Result<()> {
    let stdout = std::io::stdout();
    pushlearn_cli::experiment::processes::serve(std::io::stdin().lock(), stdout.lock())
        .context("the worker process lost its pipes")
}

/// A progress bar on stderr, hidden when stdout is not a terminal (reports
/// piped into files stay clean, and so do logs).
pub(crate) fn progress(len: usize, what: &str) -> ProgressBar {
    if !std::io::stdout().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "{msg} {wide_bar} {pos}/{len} jobs [{elapsed_precise}, eta {eta_precise}]",
    ) {
        bar.set_style(style);
    }
    bar.set_message(what.to_owned());
    bar
}

/// On Ctrl-C or SIGTERM: kill the world processes, then exit. (An
/// interrupted program does not unwind, so the processes' own clean-up would
/// not run.)
pub(crate) fn end_worlds_on_signal() {
    std::thread::spawn(|| {
        let Ok(runtime) = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
        else {
            return;
        };
        runtime.block_on(async {
            let mut terminate =
                tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()).ok();
            let terminated = async {
                match terminate.as_mut() {
                    Some(signal) => {
                        signal.recv().await;
                    }
                    None => std::future::pending::<()>().await,
                }
            };
            tokio::select! {
                _ = tokio::signal::ctrl_c() => {}
                () = terminated => {}
            }
        });
        kill_all_worlds();
        eprintln!("interrupted; the world processes were stopped");
        std::process::exit(130);
    });
}

/// This program's worker processes, as [`lab::args::WorldArgs::plan`]
/// takes them.
pub(crate) fn start_workers(workers: usize) -> Result<Option<Arc<Processes>>, ArgsError> {
    worker_processes(workers)
        .map(Some)
        .map_err(|err| ArgsError::Refused(format!("{err:#}")))
}

/// Runs `pushlearn experiment`.
pub fn run(args: ExperimentArgs) -> Result<()> {
    end_worlds_on_signal();
    let lab::args::Lowered { spec, world } = args.lower()?;
    world.check_outputs()?;
    let plan = world.plan(spec.scene(), &start_workers)?;
    let bar = progress(spec.jobs(), spec.title());
    let document = spec.run(&plan, |done| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    // The tables first: a file that cannot be written after all (a full
    // disk) must not cost the run's results.
    let printout = document.printout()?;
    {
        let mut out = std::io::stdout().lock();
        printout.write_text(&mut out)?;
        out.flush()?;
    }
    for wrote in world.write_outputs(&document, &printout)? {
        eprintln!("{wrote}");
    }
    Ok(())
}

/// The long option names of `pushlearn experiment push-task` (without
/// `--`): what a sweep file may set (`pushlearn sweep`).
pub(crate) fn push_task_options() -> Vec<String> {
    lab::args::options("push-task")
        .unwrap_or_default()
        .into_iter()
        .map(|option| option.long)
        .collect()
}

/// One sweep configuration, parsed by the same parser as `pushlearn
/// experiment push-task` (so a sweep takes exactly its options).
pub(crate) struct PushTaskLine {
    args: ExperimentArgs,
    pub(crate) spec: Valid,
}

impl PushTaskLine {
    /// Parses `args` (`--model gate --eta 0.1 …`) as the options of
    /// `pushlearn experiment push-task`.
    ///
    /// # Errors
    /// Options the command refuses (clap's first line), or a configuration
    /// that is not a push task with folds.
    pub(crate) fn parse(args: &[String]) -> Result<Self> {
        let args = lab::args::parse("push-task", args)?;
        let spec = args.lower()?.spec;
        if !matches!(*spec, Spec::PushTask { .. }) {
            anyhow::bail!(
                "a sweep job is one fold of a push task; --variant constant-feedback has no folds"
            );
        }
        // The options' fit to the model, checked now rather than in the
        // sweep's first job of this configuration.
        let options = &args.model_options();
        let rate = spec.push_protocol().map_or(RATE_HZ, |p| p.rate_hz);
        match spec.model() {
            Some(LearnerChoice::Builtin(kind)) => kind.check(options, rate)?,
            _ => options.check_external()?,
        }
        Ok(Self { args, spec })
    }

    /// The world plan of the configuration's jobs (starts no world yet).
    ///
    /// # Errors
    /// No world binary, or options that do not fit the mode.
    pub(crate) fn plan(&self) -> Result<Plan> {
        Ok(self.args.world().plan(self.spec.scene(), &start_workers)?)
    }
}
