//! `pushlearn experiment`: the thesis's experiments against real worlds.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use learner::ObjectState;
use pushlearn_cli::experiment::move_to_target::{sampled_targets, MAX_STEPS};
use pushlearn_cli::experiment::processes::Processes;
use pushlearn_cli::experiment::push_task::protocol::Variant;
use pushlearn_cli::experiment::run::Plan;
use pushlearn_cli::experiment::run_cache::RunCache;
use pushlearn_cli::experiment::workers::{find_sim_binary, kill_all_worlds, WorldSource, Worlds};
use pushlearn_cli::experiment::{Mode, LATENCY_MAX_STEPS};
use pushlearn_cli::external::LearnerChoice;
use pushlearn_cli::external::{LearnerSpec, Source, DEFAULT_TIMEOUT};
use pushlearn_cli::models::{named, ModelArgs, ModelKind, ModelOptions};
use pushlearn_cli::oracle::OracleLatency;
use pushlearn_cli::results::move_to_target::{REPETITIONS, TARGETS};
use pushlearn_cli::scene::RATE_HZ;
use pushlearn_cli::scene::{Object, Transfer};
use pushlearn_cli::spec::Spec;

use super::parse::parse_pose;

/// Run one of the thesis's experiments and print its table beside the
/// thesis's numbers.
///
/// Each worker has its own world (in the lock-step modes a world inside
/// the worker, by default; with --world spawn or --mode realtime a
/// `pushlearn-sim serve` child on a free port, found as --sim-bin says) and runs independent jobs; results
/// are gathered in job order, so they do not depend on --workers. In the
/// lock-step modes the same --seed gives the same results.
#[derive(Debug, Args)]
pub struct ExperimentArgs {
    #[command(subcommand)]
    command: ExperimentCommand,
}

#[derive(Debug, Subcommand)]
enum ExperimentCommand {
    /// Push Task Simulation: train the forward model on N pushes, then
    /// predict 150 steps of 21 test pushes without feedback (docs/spec/experiments.md §3).
    #[command(after_help = "Thesis tables:\n  \
        pushlearn experiment push-task --model gate                               # §3.4, §4.2\n  \
        pushlearn experiment push-task --model interaction                        # §3.2, §4.1\n  \
        pushlearn experiment push-task --model gate --variant fixed-three         # §5.3\n  \
        pushlearn experiment push-task --model gate --variant two-objects         # §6.1\n  \
        pushlearn experiment push-task --model gate --variant two-objects --train-runs 7   # §6.2\n  \
        pushlearn experiment push-task --model gate --variant constant-feedback   # §7 (qualitative)\n\n\
        New objects (docs/experiments.md):\n  \
        pushlearn experiment push-task --model gate --train-on blue --test-on cylinder --train-runs 10\n  \
        pushlearn experiment push-task --model gate+ --train-on blue,red --test-on cylinder --train-runs 10\n\n\
        Thesis draft (Tables 6.1, 6.2; every row of the draft):\n  \
        pushlearn experiment push-task --report draft\n  \
        pushlearn experiment push-task --model interaction --variant draft --selector tree --train-runs 3,10")]
    PushTask(PushTaskArgs),
    /// Move to Target: train on 8 fixed pushes, then plan pushes until the
    /// block reaches a target pose (docs/spec/experiments.md §4).
    #[command(after_help = "Thesis tables:\n  \
        pushlearn experiment move-to-target --model gate          # §8.2\n  \
        pushlearn experiment move-to-target --model interaction   # §8.1")]
    MoveToTarget(MoveToTargetArgs),
}

/// Where the worlds come from and how they are timed.
#[derive(Debug, Args)]
struct WorldArgs {
    /// World timing: lockstep-jitter (lock-step with seeded command latency of
    /// 0–L_max steps, the thesis's timing noise, reproducible), lockstep (no
    /// latency: folds of fixed-start experiments are identical), or realtime
    /// (the thesis's free-running world; the learner must keep up).
    #[arg(long, value_parser = named::<Mode>(), default_value = "lockstep-jitter")]
    mode: Mode,

    /// With --mode lockstep-jitter: the largest delay of a Move, in physics
    /// steps, each delay uniform over 0…N. The default 2 is derived from the
    /// thesis's timing (docs/spec/world.md §8); 5 is the harsher setting
    /// docs/results.md reports as a robustness row. With --sim, pass the
    /// value the world was started with (it is recorded in the report).
    #[arg(long, value_name = "N", default_value_t = LATENCY_MAX_STEPS)]
    latency_max: u32,

    /// Where the worlds run [default: embedded; spawn with --mode realtime
    /// or --sim-bin].
    #[arg(long, value_parser = named::<Worlds>(), conflicts_with = "sim")]
    world: Option<Worlds>,

    /// Number of worlds running jobs in parallel [default: the number of
    /// CPUs]. With embedded worlds a built-in model's jobs run in as many
    /// worker processes (ODE steps one world at a time per process); an
    /// external learner's worlds share this process.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    workers: Option<u32>,

    /// The world daemon binary to spawn (implies --world spawn) [default:
    /// $PUSHLEARN_SIM_BIN, else `pushlearn-sim` next to this executable, else
    /// on PATH: docs/simulator.md].
    #[arg(long, value_name = "PATH")]
    sim_bin: Option<PathBuf>,

    /// Use the world already running at HOST:PORT instead of starting one
    /// (one worker). Its scene and timing mode must match the experiment.
    #[arg(long, value_name = "HOST:PORT", alias = "connect",
          conflicts_with_all = ["workers", "sim_bin"])]
    sim: Option<String>,

    /// In the lock-step modes, simulate every run afresh instead of reusing
    /// the states of an identical earlier run (same commands since the
    /// world's reset, or with latency since the job's latency seed). Reuse
    /// gives bit-identical results, since a lock-step world is a function of
    /// those commands (docs/performance.md); realtime never reuses.
    #[arg(long)]
    no_reuse: bool,

    /// Seed of every random choice (training starts, exploration, latency).
    #[arg(long, default_value_t = 1)]
    seed: u64,

    /// Also write the results as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,

    /// Also write the figures (PNG and SVG) into DIR, created if needed.
    /// `pushlearn report plot FILE.json` draws them again from saved JSON.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,

    /// Also write every printed table as CSV into DIR (created if needed),
    /// one file per table, named after the experiment and the table.
    #[arg(long, value_name = "DIR")]
    csv: Option<PathBuf>,
}

/// Which learner runs: a built-in model, or an external one over the
/// learner protocol (docs/learner-protocol.md).
#[derive(Debug, Args)]
struct LearnerArgs {
    /// The built-in learner.
    #[arg(long, value_parser = named::<ModelKind>(), default_value_t = ModelKind::Gate)]
    model: ModelKind,

    /// Run an external learner instead: a command (run by `sh -c`, one
    /// process per worker) that speaks the learner protocol on its stdin and
    /// stdout, e.g. "python3 -m pushlearn.serve pushlearn.baselines:KnnLearner".
    /// The report carries the name the learner gives in its hello.
    #[arg(long, value_name = "CMD", conflicts_with = "model")]
    learner: Option<String>,

    /// Run an external learner that serves the learner protocol as a daemon
    /// at HOST:PORT (one connection per worker).
    #[arg(long, value_name = "HOST:PORT", conflicts_with_all = ["model", "learner"])]
    learner_connect: Option<String>,

    /// Run an oracle instead of a learner: a copy of the experiment's world
    /// (its true masses, frictions and shapes) stepped under the same
    /// actions, told when each Move takes effect (known) or predicting the
    /// median outcome over the delays the world may draw (unknown);
    /// docs/models.md "Reference rows". A reference, not a bound. Push
    /// task (new objects included) and constant feedback in lock-step;
    /// refused for Move to Target.
    #[arg(long, value_name = "LATENCY", value_parser = named::<OracleLatency>(), conflicts_with_all = ["model", "learner", "learner_connect"])]
    oracle: Option<OracleLatency>,

    /// How long an external learner may take over one answer (its hello
    /// included) before the job fails, in seconds.
    #[arg(long, value_name = "SECS", default_value_t = DEFAULT_TIMEOUT.as_secs_f64(), value_parser = parse_timeout)]
    learner_timeout: f64,
}

impl LearnerArgs {
    fn choice(&self) -> LearnerChoice {
        let timeout = Duration::from_secs_f64(self.learner_timeout);
        let external = |source| LearnerChoice::External(LearnerSpec { source, timeout });
        match (&self.learner, &self.learner_connect) {
            (Some(command), _) => external(Source::Command(command.clone())),
            (None, Some(addr)) => external(Source::Connect(addr.clone())),
            (None, None) => match self.oracle {
                Some(latency) => LearnerChoice::Oracle(latency),
                None => LearnerChoice::Builtin(self.model),
            },
        }
    }
}

fn parse_timeout(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0 && *v <= 86_400.0)
        .ok_or_else(|| format!("'{text}' is not a number of seconds in (0, 86400]"))
}

#[derive(Debug, Args)]
struct PushTaskArgs {
    #[command(flatten)]
    learner: LearnerArgs,

    /// Which experiment of the thesis: random training starts (§3.1),
    /// the three selected starts (§3.2), two blocks (§3.3), constant
    /// feedback at 10 Hz (§3.4), or the thesis draft's protocol (starts at
    /// the block's ends and centre, then random in [−0.35, 0.35); 20 test
    /// runs from one fixed seed).
    #[arg(long, value_parser = named::<Variant>(), default_value = "random")]
    variant: Variant,

    /// Which tables to print: the final thesis's (for --variant), or the
    /// thesis draft's Tables 6.1 and 6.2, which runs every row of the draft
    /// (its own models, flags and protocol) and ignores --model.
    #[arg(long, value_enum, default_value_t = ReportKind::Thesis)]
    report: ReportKind,

    /// Numbers of training runs, comma-separated [default: 1,2,3,5,10,20,30
    /// for random, 3 for fixed-three, 6 for two-objects (7 for the thesis's
    /// second variant)].
    #[arg(long, value_name = "N,…", value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..))]
    train_runs: Option<Vec<u32>>,

    /// Repetitions (folds) per number of training runs, each with a fresh
    /// model [default: 20; 1 for the draft's protocol, which trained one
    /// model per row].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    folds: Option<u32>,

    /// New objects (the `objects` scene, docs/experiments.md): the objects
    /// the training runs are about, taken in turn (blue, red, cylinder;
    /// e.g. blue,red) [default with --test-on: blue]. The learner sees only
    /// the run's object, as the blue block.
    #[arg(long, value_name = "OBJECT,…", value_parser = named::<Object>(), value_delimiter = ',')]
    train_on: Option<Vec<Object>>,

    /// New objects: the object every test run is about [default with
    /// --train-on: blue].
    #[arg(long, value_name = "OBJECT", value_parser = named::<Object>())]
    test_on: Option<Object>,

    #[command(flatten)]
    options: ModelArgs,

    #[command(flatten)]
    world: WorldArgs,
}

/// The table layouts of `push-task`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum ReportKind {
    /// The final thesis's tables for the chosen variant.
    Thesis,
    /// The thesis draft's Tables 6.1 and 6.2.
    Draft,
}

#[derive(Debug, Args)]
struct MoveToTargetArgs {
    #[command(flatten)]
    learner: LearnerArgs,

    /// A target pose X,Y,ORI of the blue block (metres, radians); repeat for
    /// more [default: the thesis's four targets].
    #[arg(long, value_name = "X,Y,ORI", allow_hyphen_values = true, value_parser = parse_pose)]
    target: Vec<ObjectState>,

    /// N targets drawn from the reachable region instead (block centres
    /// with x in [−0.7, 0.7) m, y in [−0.8, 0.8) m, any yaw, at least 0.3 m
    /// from the block's start; the Gymnasium environments' region,
    /// docs/gym.md), seeded by --seed.
    #[arg(long, value_name = "N", conflicts_with = "target", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    sample_targets: Option<u32>,

    /// Test runs per target, each with a freshly trained model.
    #[arg(long, default_value_t = REPETITIONS as u32, value_parser = clap::value_parser!(u32).range(1..))]
    repetitions: u32,

    /// Longest test run, in messages.
    #[arg(long, default_value_t = MAX_STEPS, value_parser = clap::value_parser!(u64).range(1..))]
    max_steps: u64,

    #[command(flatten)]
    options: ModelArgs,

    #[command(flatten)]
    world: WorldArgs,
}

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

impl WorldArgs {
    fn plan(&self, scene: &str) -> Result<Plan> {
        if self.mode != Mode::LockstepJitter && self.latency_max != LATENCY_MAX_STEPS {
            bail!("--latency-max sets the latency emulation of --mode lockstep-jitter; drop it or add --mode lockstep-jitter");
        }
        let worlds = choose_worlds(
            self.world,
            self.sim_bin.is_some(),
            Worlds::default_for(self.mode),
        )?;
        let source = match &self.sim {
            Some(addr) => WorldSource::Connect(addr.clone()),
            None => worlds.source(self.mode, scene, self.latency_max, || {
                find_sim_binary(self.sim_bin.as_deref())
            })?,
        };
        let cpus = std::thread::available_parallelism().map_or(1, usize::from);
        let workers = self.workers.map_or(cpus, |n| n as usize);
        let processes = match source {
            WorldSource::Embedded { .. } => Some(worker_processes(workers)?),
            _ => None,
        };
        Ok(Plan {
            mode: self.mode,
            latency_max: self.latency_max,
            workers,
            source,
            seed: self.seed,
            model: String::new(),
            learner: None,
            runs: (self.mode.reuses_runs() && !self.no_reuse)
                .then(|| std::sync::Arc::new(RunCache::new())),
            processes,
            recipe: None,
        })
    }

    /// Checks before the experiment runs that its outputs can be written —
    /// the figure directory created, the CSV directory created and
    /// writable, the JSON file's directory present — so
    /// that a typo does not cost a whole run.
    fn check_outputs(&self) -> Result<()> {
        if let Some(dir) = &self.plots {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create the figure directory {}", dir.display()))?;
        }
        if let Some(dir) = &self.csv {
            pushlearn_cli::output::check_writable_dir(dir)
                .with_context(|| format!("cannot write CSV files into {}", dir.display()))?;
        }
        if let Some(path) = &self.json {
            pushlearn_cli::output::check_file(path, "--json")?;
        }
        Ok(())
    }
}

/// `--world` and `--sim-bin` together: a daemon binary named means
/// spawned worlds, and `default` otherwise.
///
/// # Errors
/// `--sim-bin` with `--world embedded`.
pub(crate) fn choose_worlds(
    world: Option<Worlds>,
    sim_bin: bool,
    default: Worlds,
) -> Result<Worlds> {
    Ok(match (world, sim_bin) {
        (Some(Worlds::Embedded), true) => {
            bail!("--sim-bin names the daemon to spawn; it has no use with --world embedded")
        }
        (Some(worlds), _) => worlds,
        (None, true) => Worlds::Spawn,
        (None, false) => default,
    })
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

impl ExperimentArgs {
    /// The experiment the command line asks for, and where its worlds come
    /// from: the inverse of `lab::reproduce::manifest::Entry::command`.
    fn spec(&self) -> Result<(Spec, &WorldArgs)> {
        Ok(match &self.command {
            ExperimentCommand::PushTask(args) => (push_task_spec(args)?, &args.world),
            ExperimentCommand::MoveToTarget(args) => (move_to_target_spec(args), &args.world),
        })
    }
}

/// Runs `pushlearn experiment`.
pub fn run(args: ExperimentArgs) -> Result<()> {
    end_worlds_on_signal();
    let (spec, world) = args.spec()?;
    spec.validate()?;
    world.check_outputs()?;
    let plan = world.plan(spec.scene())?;
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
    if let Some(path) = &world.json {
        pushlearn_cli::output::write_atomically(path, document.to_json()?.as_bytes())
            .with_context(|| format!("cannot write --json {}", path.display()))?;
    }
    if let Some(dir) = &world.plots {
        let written = document.plot(dir)?;
        eprintln!("wrote {} figures to {}", written.len(), dir.display());
    }
    if let Some(dir) = &world.csv {
        let written = printout
            .write_csv(dir)
            .with_context(|| format!("writing CSV files into {}", dir.display()))?;
        eprintln!("wrote {} CSV files to {}", written.len(), dir.display());
    }
    Ok(())
}

/// The long option names of `pushlearn experiment push-task` (without
/// `--`): what a sweep file may set (`pushlearn sweep`).
pub(crate) fn push_task_options() -> Vec<String> {
    use clap::Args as _;
    PushTaskArgs::augment_args(clap::Command::new("push-task"))
        .get_arguments()
        .filter_map(|arg| arg.get_long().map(str::to_owned))
        .collect()
}

/// One sweep configuration, parsed by the same parser as `pushlearn
/// experiment push-task` (so a sweep takes exactly its options).
pub(crate) struct PushTaskLine {
    args: PushTaskArgs,
    pub(crate) spec: Spec,
}

impl PushTaskLine {
    /// Parses `args` (`--model gate --eta 0.1 …`) as the options of
    /// `pushlearn experiment push-task`.
    ///
    /// # Errors
    /// Options the command refuses (clap's first line), or a configuration
    /// that is not a push task with folds.
    pub(crate) fn parse(args: &[String]) -> Result<Self> {
        #[derive(clap::Parser)]
        #[command(name = "push-task", no_binary_name = true)]
        struct Line {
            #[command(flatten)]
            args: PushTaskArgs,
        }
        let line = <Line as clap::Parser>::try_parse_from(args).map_err(|err| {
            let text = err.render().to_string();
            let first = text.lines().next().unwrap_or_default();
            anyhow::anyhow!("{}", first.strip_prefix("error: ").unwrap_or(first))
        })?;
        let spec = push_task_spec(&line.args)?;
        if !matches!(spec, Spec::PushTask { .. }) {
            bail!(
                "a sweep job is one fold of a push task; --variant constant-feedback has no folds"
            );
        }
        spec.validate()?;
        // The options' fit to the model, checked now rather than in the
        // sweep's first job of this configuration.
        let options = &line.args.options.options();
        let rate = spec.push_protocol().map_or(RATE_HZ, |p| p.rate_hz);
        match line.args.learner.choice() {
            LearnerChoice::Builtin(kind) => kind.check(options, rate)?,
            LearnerChoice::External(_) | LearnerChoice::Oracle(_) | LearnerChoice::InProcess => {
                options.check_external()?;
            }
        }
        Ok(Self {
            args: line.args,
            spec,
        })
    }

    /// The world plan of the configuration's jobs (starts no world yet).
    ///
    /// # Errors
    /// No world binary, or options that do not fit the mode.
    pub(crate) fn plan(&self) -> Result<Plan> {
        self.args.world.plan(self.spec.scene())
    }
}

fn push_task_spec(args: &PushTaskArgs) -> Result<Spec> {
    let variant = args.variant;
    if args.report == ReportKind::Draft {
        if args.learner.learner.is_some() || args.learner.learner_connect.is_some() {
            bail!("--report draft runs the draft's own built-in models; drop --learner/--learner-connect");
        }
        if variant != Variant::Random
            || args.train_runs.is_some()
            || args.train_on.is_some()
            || args.test_on.is_some()
            || args.options.options() != ModelOptions::default()
        {
            bail!("--report draft runs the draft's own rows (models, flags, training runs, protocol); drop --variant, --train-runs, --train-on, --test-on and the model options");
        }
        let folds = args
            .folds
            .map_or(variant_folds(Variant::Draft), |n| n as usize);
        return Ok(Spec::DraftTables { folds });
    }
    let transfer = match (&args.train_on, args.test_on) {
        (None, None) => None,
        (train, test) => Some(Transfer::new(
            train.clone().unwrap_or_else(|| vec![Object::Blue]),
            test.unwrap_or(Object::Blue),
        )?),
    };
    if variant == Variant::ConstantFeedback {
        if transfer.is_some() {
            bail!("--train-on and --test-on are push tasks with training; drop them with --variant constant-feedback");
        }
        if args.train_runs.is_some() {
            bail!("--variant constant-feedback has no training phase; drop --train-runs");
        }
        return Ok(Spec::ConstantFeedback {
            model: args.learner.choice(),
            options: args.options.options(),
        });
    }
    Ok(Spec::PushTask {
        model: args.learner.choice(),
        options: args.options.options(),
        variant,
        transfer,
        train_runs: match &args.train_runs {
            Some(list) => list.iter().map(|&n| n as usize).collect(),
            None => variant.default_train_runs(),
        },
        folds: args.folds.map_or(variant_folds(variant), |n| n as usize),
    })
}

/// Folds when --folds is not given: the thesis's 20, and one model per row
/// for the draft, which reports 20 test runs of one training sequence.
fn variant_folds(variant: Variant) -> usize {
    if variant == Variant::Draft {
        1
    } else {
        20
    }
}

fn move_to_target_spec(args: &MoveToTargetArgs) -> Spec {
    Spec::MoveToTarget {
        model: args.learner.choice(),
        options: args.options.options(),
        targets: match args.sample_targets {
            Some(n) => sampled_targets(n as usize, args.world.seed),
            None if args.target.is_empty() => TARGETS.to_vec(),
            None => args.target.clone(),
        },
        repetitions: args.repetitions as usize,
        max_steps: args.max_steps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The command the reproduction prints beside each of its documents
    /// (`Entry::command`, on the page and in `docs/results/timing.md`),
    /// parsed by this command's own parser, is the experiment it was
    /// printed for: the manifest's specs and the command line cannot drift
    /// apart.
    #[test]
    fn the_reproductions_commands_parse_back_into_their_experiments() {
        use clap::Parser as _;
        use pushlearn_cli::reproduce::manifest;

        #[derive(clap::Parser)]
        #[command(name = "pushlearn")]
        struct Line {
            #[command(subcommand)]
            command: Top,
        }
        #[derive(clap::Subcommand)]
        enum Top {
            Experiment(ExperimentArgs),
        }

        let entries: Vec<_> = manifest::full()
            .into_iter()
            .chain(manifest::quick())
            .collect();
        assert!(entries.len() > 60, "the full set and the quick one");
        for entry in entries {
            let command = entry.command("docs/results");
            let words = shlex::split(&command).expect("the command is valid shell words");
            let line = Line::try_parse_from(&words)
                .unwrap_or_else(|err| panic!("`{command}` does not parse: {err}"));
            let Top::Experiment(args) = line.command;
            let (spec, world) = args
                .spec()
                .unwrap_or_else(|err| panic!("`{command}` is refused: {err}"));
            assert_eq!(spec, entry.spec, "`{command}`");
            assert_eq!(
                (world.mode, world.latency_max, world.seed),
                (entry.mode, entry.latency_max, entry.seed),
                "`{command}`"
            );
            assert_eq!(
                world.json,
                Some(PathBuf::from(format!("docs/results/{}.json", entry.name))),
                "`{command}`"
            );
        }
    }
}
