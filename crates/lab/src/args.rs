//! `pushlearn experiment`'s arguments and their one lowering onto a
//! [`Spec`] (ripgrep's low-level arguments into high-level ones): the
//! command line, a sweep's configurations (`pushlearn sweep`) and
//! `pushlearn.bench`'s keyword arguments (which the Python side spells as
//! these options, `train_runs=[1, 3]` as `--train-runs=1 --train-runs=3`)
//! go through [`parse`] and [`ExperimentArgs::lower`], so that they accept
//! the same options, refuse the same combinations with the same messages,
//! and give the same spec. The spec is validated here, once: what runs it
//! takes it as given.
//!
//! [`WorldArgs::plan`] is where a run's [`Plan`] comes from, for the command
//! line, sweeps and the bench alike; only the worker processes differ (the
//! application's own executable, or none in a Python interpreter).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use clap::{Args, Subcommand};
use drive::cli_args::{named, parse_pose, ModelArgs};
use drive::experiment::move_to_target::{sampled_targets, MAX_STEPS};
use drive::experiment::processes::Processes;
use drive::experiment::push_task::protocol::Variant;
use drive::experiment::run::Plan;
use drive::experiment::run_cache::RunCache;
use drive::experiment::workers::{find_sim_binary, WorldSource, Worlds};
use drive::experiment::{ExperimentError, Mode, LATENCY_MAX_STEPS};
use drive::external::{LearnerChoice, LearnerSpec, Source, DEFAULT_TIMEOUT};
use drive::oracle::OracleLatency;
use drive::results::move_to_target::{REPETITIONS, TARGETS};
use drive::scene::{Object, Transfer};
use learner::registry::{ModelKind, ModelOptions};
use learner::ObjectState;

use crate::report::layout::Printout;
use crate::spec::{Document, Spec, SpecError, Valid};

/// Why arguments do not make a run.
#[derive(Debug, thiserror::Error)]
pub enum ArgsError {
    /// The parser refused them: its message, naming the option.
    #[error("{0}")]
    Parse(String),
    /// Options that do not go together.
    #[error("{0}")]
    Refused(String),
    /// A spec the experiment cannot run.
    #[error(transparent)]
    Spec(#[from] SpecError),
    /// No world to run on (no daemon binary, embedded worlds in realtime).
    #[error(transparent)]
    Worlds(#[from] ExperimentError),
    /// An output (`--json`, `--plots`, `--csv`) that cannot be written.
    #[error("{0}")]
    Output(String),
}

fn refuse<T>(why: &str) -> Result<T, ArgsError> {
    Err(ArgsError::Refused(why.to_owned()))
}

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
    pub command: ExperimentCommand,
}

#[derive(Debug, Subcommand)]
pub enum ExperimentCommand {
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
pub struct WorldArgs {
    /// World timing: lockstep-jitter (lock-step with seeded command latency of
    /// 0–L_max steps, the thesis's timing noise, reproducible), lockstep (no
    /// latency: folds of fixed-start experiments are identical), or realtime
    /// (the thesis's free-running world; the learner must keep up).
    #[arg(long, value_parser = named::<Mode>(), default_value = "lockstep-jitter")]
    pub mode: Mode,

    /// With --mode lockstep-jitter: the largest delay of a Move, in physics
    /// steps, each delay uniform over 0…N. The default 2 is derived from the
    /// thesis's timing (docs/spec/world.md §8); 5 is the harsher setting
    /// docs/results.md reports as a robustness row. With --sim, pass the
    /// value the world was started with (it is recorded in the report).
    #[arg(long, value_name = "N", default_value_t = LATENCY_MAX_STEPS)]
    pub latency_max: u32,

    /// Where the worlds run [default: embedded; spawn with --mode realtime
    /// or --sim-bin].
    #[arg(long, value_parser = named::<Worlds>(), conflicts_with = "sim")]
    pub world: Option<Worlds>,

    /// Number of worlds running jobs in parallel [default: the number of
    /// CPUs]. With embedded worlds a built-in model's jobs run in as many
    /// worker processes (ODE steps one world at a time per process); an
    /// external learner's worlds share this process.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub workers: Option<u32>,

    /// The world daemon binary to spawn (implies --world spawn) [default:
    /// $PUSHLEARN_SIM_BIN, else `pushlearn-sim` next to this executable, else
    /// on PATH: docs/simulator.md].
    #[arg(long, value_name = "PATH")]
    pub sim_bin: Option<PathBuf>,

    /// Use the world already running at HOST:PORT instead of starting one
    /// (one worker). Its scene and timing mode must match the experiment.
    #[arg(long, value_name = "HOST:PORT", alias = "connect",
          conflicts_with_all = ["workers", "sim_bin"])]
    pub sim: Option<String>,

    /// In the lock-step modes, simulate every run afresh instead of reusing
    /// the states of an identical earlier run (same commands since the
    /// world's reset, or with latency since the job's latency seed). Reuse
    /// gives bit-identical results, since a lock-step world is a function of
    /// those commands (docs/performance.md); realtime never reuses.
    #[arg(long)]
    pub no_reuse: bool,

    /// Seed of every random choice (training starts, exploration, latency).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,

    /// Also write the results as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,

    /// Also write the figures (PNG and SVG) into DIR, created if needed.
    /// `pushlearn report plot FILE.json` draws them again from saved JSON.
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,

    /// Also write every printed table as CSV into DIR (created if needed),
    /// one file per table, named after the experiment and the table.
    #[arg(long, value_name = "DIR")]
    pub csv: Option<PathBuf>,
}

/// Which learner runs: a built-in model, or an external one over the
/// learner protocol (docs/learner-protocol.md).
#[derive(Debug, Args)]
pub struct LearnerArgs {
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
    /// The learner these options choose.
    #[must_use]
    pub fn choice(&self) -> LearnerChoice {
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
pub struct PushTaskArgs {
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
pub enum ReportKind {
    /// The final thesis's tables for the chosen variant.
    Thesis,
    /// The thesis draft's Tables 6.1 and 6.2.
    Draft,
}

#[derive(Debug, Args)]
pub struct MoveToTargetArgs {
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

/// `--world` and `--sim-bin` together: a daemon binary named means
/// spawned worlds, and `default` otherwise.
///
/// # Errors
/// `--sim-bin` with `--world embedded`.
pub fn choose_worlds(
    world: Option<Worlds>,
    sim_bin: bool,
    default: Worlds,
) -> Result<Worlds, ArgsError> {
    Ok(match (world, sim_bin) {
        (Some(Worlds::Embedded), true) => {
            return refuse(
                "--sim-bin names the daemon to spawn; it has no use with --world embedded",
            )
        }
        (Some(worlds), _) => worlds,
        (None, true) => Worlds::Spawn,
        (None, false) => default,
    })
}

fn push_task_spec(args: &PushTaskArgs, given: Option<&LearnerChoice>) -> Result<Spec, ArgsError> {
    let variant = args.variant;
    if args.report == ReportKind::Draft {
        if args.learner.learner.is_some()
            || args.learner.learner_connect.is_some()
            || given.is_some()
        {
            return refuse("--report draft runs the draft's own built-in models; drop --learner/--learner-connect (or the learner object)");
        }
        if variant != Variant::Random
            || args.train_runs.is_some()
            || args.train_on.is_some()
            || args.test_on.is_some()
            || args.options.options() != ModelOptions::default()
        {
            return refuse("--report draft runs the draft's own rows (models, flags, training runs, protocol); drop --variant, --train-runs, --train-on, --test-on and the model options");
        }
        let folds = args
            .folds
            .map_or(variant_folds(Variant::Draft), |n| n as usize);
        return Ok(Spec::DraftTables { folds });
    }
    let transfer = match (&args.train_on, args.test_on) {
        (None, None) => None,
        (train, test) => Some(
            Transfer::new(
                train.clone().unwrap_or_else(|| vec![Object::Blue]),
                test.unwrap_or(Object::Blue),
            )
            .map_err(|err| ArgsError::Refused(err.to_string()))?,
        ),
    };
    if variant == Variant::ConstantFeedback {
        if transfer.is_some() {
            return refuse("--train-on and --test-on are push tasks with training; drop them with --variant constant-feedback");
        }
        if args.train_runs.is_some() {
            return refuse("--variant constant-feedback has no training phase; drop --train-runs");
        }
        return Ok(Spec::ConstantFeedback {
            model: given.cloned().unwrap_or_else(|| args.learner.choice()),
            options: args.options.options(),
        });
    }
    Ok(Spec::PushTask {
        model: given.cloned().unwrap_or_else(|| args.learner.choice()),
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

fn move_to_target_spec(args: &MoveToTargetArgs, given: Option<&LearnerChoice>) -> Spec {
    Spec::MoveToTarget {
        model: given.cloned().unwrap_or_else(|| args.learner.choice()),
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

/// An experiment the arguments ask for, validated, and where its worlds
/// come from.
#[derive(Debug)]
pub struct Lowered<'a> {
    pub spec: Valid,
    pub world: &'a WorldArgs,
}

impl ExperimentArgs {
    /// The experiment the arguments ask for, validated, and where its worlds
    /// come from: the inverse of `reproduce::manifest::Entry::command`.
    ///
    /// # Errors
    /// Options that do not go together, or a spec that cannot run.
    pub fn lower(&self) -> Result<Lowered<'_>, ArgsError> {
        self.lower_with(None)
    }

    /// As [`lower`](Self::lower), with `given` as the learner instead of the
    /// one the options choose (`pushlearn.bench`'s learner objects,
    /// [`LearnerChoice::InProcess`]).
    ///
    /// # Errors
    /// As [`lower`](Self::lower).
    pub fn lower_with(&self, given: Option<&LearnerChoice>) -> Result<Lowered<'_>, ArgsError> {
        let spec = match &self.command {
            ExperimentCommand::PushTask(args) => push_task_spec(args, given)?,
            ExperimentCommand::MoveToTarget(args) => move_to_target_spec(args, given),
        };
        let world = self.world();
        let spec = spec.validated()?;
        if world.mode != Mode::LockstepJitter && world.latency_max != LATENCY_MAX_STEPS {
            return refuse("--latency-max sets the latency emulation of --mode lockstep-jitter; drop it or add --mode lockstep-jitter");
        }
        Ok(Lowered { spec, world })
    }

    /// Where the worlds come from and how they are timed.
    #[must_use]
    pub fn world(&self) -> &WorldArgs {
        match &self.command {
            ExperimentCommand::PushTask(args) => &args.world,
            ExperimentCommand::MoveToTarget(args) => &args.world,
        }
    }

    /// The model options given (the registry's defaults for the draft's
    /// tables, which refuse any other).
    #[must_use]
    pub fn model_options(&self) -> ModelOptions {
        match &self.command {
            ExperimentCommand::PushTask(args) => args.options.options(),
            ExperimentCommand::MoveToTarget(args) => args.options.options(),
        }
    }
}

/// Parses `words` as the options of `pushlearn experiment COMMAND`
/// (`push-task` or `move-to-target`), with the command's own parser.
///
/// # Errors
/// [`ArgsError::Parse`] with the parser's first line, which names the
/// option it refuses.
pub fn parse(command: &str, words: &[String]) -> Result<ExperimentArgs, ArgsError> {
    #[derive(clap::Parser)]
    #[command(name = "pushlearn experiment", no_binary_name = true)]
    struct Line {
        #[command(flatten)]
        args: ExperimentArgs,
    }
    let words = std::iter::once(command).chain(words.iter().map(String::as_str));
    let line = <Line as clap::Parser>::try_parse_from(words).map_err(|err| {
        let text = err.render().to_string();
        let first = text.lines().next().unwrap_or_default();
        ArgsError::Parse(first.strip_prefix("error: ").unwrap_or(first).to_owned())
    })?;
    Ok(line.args)
}

/// One option of `pushlearn experiment COMMAND`, as [`options`] lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OptionInfo {
    /// Its long name, without `--`.
    pub long: String,
    /// A switch (`--no-reuse`) rather than an option with a value.
    pub switch: bool,
    /// The values it takes, when it takes names.
    pub values: Vec<String>,
    /// Its default, as given on a command line (empty: none).
    pub default: Vec<String>,
}

/// Every option of `pushlearn experiment COMMAND`, from the command's own
/// definition (so a new option is listed without a change here); `None`
/// for an unknown command.
#[must_use]
pub fn options(command: &str) -> Option<Vec<OptionInfo>> {
    let mut experiment = ExperimentArgs::augment_args(clap::Command::new("experiment"));
    experiment.build();
    let sub = experiment.find_subcommand(command)?;
    Some(
        sub.get_arguments()
            .filter(|arg| arg.get_id() != "help")
            .filter_map(|arg| {
                let long = arg.get_long()?.to_owned();
                Some(OptionInfo {
                    long,
                    switch: !arg.get_action().takes_values(),
                    values: arg
                        .get_possible_values()
                        .iter()
                        .filter(|v| !v.is_hide_set())
                        .map(|v| v.get_name().to_owned())
                        .collect(),
                    default: arg
                        .get_default_values()
                        .iter()
                        .map(|v| v.to_string_lossy().into_owned())
                        .collect(),
                })
            })
            .collect(),
    )
}

impl WorldArgs {
    /// The run's plan for worlds of `scene`: the one place where a run
    /// decides where its worlds are and how many work at once (the command
    /// line's, a sweep's, the bench's and the reproduction's). `processes`
    /// gives the worker processes for `workers` embedded worlds, if the
    /// caller has any (the application re-runs itself; a Python
    /// interpreter has none).
    ///
    /// # Errors
    /// `--sim-bin` with `--world embedded`, embedded worlds in realtime, no
    /// daemon binary to spawn, or no worker processes.
    pub fn plan(
        &self,
        scene: &str,
        processes: &dyn Fn(usize) -> Result<Option<Arc<Processes>>, ArgsError>,
    ) -> Result<Plan, ArgsError> {
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
        let processes = match &source {
            WorldSource::Embedded { .. } => processes(workers)?,
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
            runs: (self.mode.reuses_runs() && !self.no_reuse).then(|| Arc::new(RunCache::new())),
            processes,
            recipe: None,
        })
    }

    /// Checks before the experiment runs that its outputs can be written —
    /// the figure directory created, the CSV directory created and
    /// writable, the JSON file's directory present — so
    /// that a typo does not cost a whole run.
    ///
    /// # Errors
    /// The first output that cannot be written, named.
    pub fn check_outputs(&self) -> Result<(), ArgsError> {
        if let Some(dir) = &self.plots {
            std::fs::create_dir_all(dir).map_err(|err| {
                ArgsError::Output(format!(
                    "cannot create the figure directory {}: {err}",
                    dir.display()
                ))
            })?;
        }
        if let Some(dir) = &self.csv {
            drive::output::check_writable_dir(dir).map_err(|err| {
                ArgsError::Output(format!(
                    "cannot write CSV files into {}: {err}",
                    dir.display()
                ))
            })?;
        }
        if let Some(path) = &self.json {
            drive::output::check_file(path, "--json")
                .map_err(|err| ArgsError::Output(err.to_string()))?;
        }
        Ok(())
    }

    /// Writes the outputs asked for (`--json`, `--plots`, `--csv`) of
    /// `document`, whose tables are `printout`; returns what it wrote, one
    /// line each, for the caller to tell.
    ///
    /// # Errors
    /// The first output that cannot be written, named.
    pub fn write_outputs(
        &self,
        document: &Document,
        printout: &Printout,
    ) -> Result<Vec<String>, ArgsError> {
        let mut wrote = Vec::new();
        if let Some(path) = &self.json {
            let json = document
                .to_json()
                .map_err(|err| ArgsError::Output(format!("cannot serialise the report: {err}")))?;
            drive::output::write_atomically(path, json.as_bytes()).map_err(|err| {
                ArgsError::Output(format!("cannot write --json {}: {err}", path.display()))
            })?;
        }
        if let Some(dir) = &self.plots {
            let written = document
                .plot(dir)
                .map_err(|err| ArgsError::Output(err.to_string()))?;
            wrote.push(format!(
                "wrote {} figures to {}",
                written.len(),
                dir.display()
            ));
        }
        if let Some(dir) = &self.csv {
            let written = printout.write_csv(dir).map_err(|err| {
                ArgsError::Output(format!("writing CSV files into {}: {err}", dir.display()))
            })?;
            wrote.push(format!(
                "wrote {} CSV files to {}",
                written.len(),
                dir.display()
            ));
        }
        Ok(wrote)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A value for every option that has neither a default nor names to
    /// choose from. A new option of that kind fails
    /// [`every_option_of_the_command_is_accepted`] until it has one here.
    const SAMPLES: &[(&str, &str)] = &[
        ("train-runs", "2"),
        ("folds", "2"),
        ("workers", "2"),
        ("sim-bin", "pushlearn-sim"),
        ("sim", "127.0.0.1:9"),
        ("json", "out.json"),
        ("plots", "figures"),
        ("csv", "tables"),
        ("learner", "true"),
        ("learner-connect", "127.0.0.1:9"),
        ("target", "0.6,0.7,0.75"),
        ("sample-targets", "3"),
    ];

    /// The words that give `option` a value other than its default where
    /// it has names to choose from, else its default or its sample.
    fn sample(command: &str, option: &OptionInfo) -> Vec<String> {
        let flag = format!("--{}", option.long);
        if option.switch {
            return vec![flag];
        }
        let value = option
            .values
            .iter()
            .find(|v| !option.default.contains(v))
            .or_else(|| option.default.first())
            .cloned()
            .or_else(|| {
                SAMPLES
                    .iter()
                    .find(|(long, _)| *long == option.long)
                    .map(|(_, v)| (*v).to_owned())
            })
            .unwrap_or_else(|| panic!("{command} --{}: add a sample value", option.long));
        vec![flag, value]
    }

    /// Every option of both commands, listed from the command's definition,
    /// parses and lowers (or is refused naming itself, where the command
    /// refuses it on its own): the list `pushlearn.bench` forwards is the
    /// command's, whole.
    #[test]
    fn every_option_of_the_command_is_accepted() {
        for command in ["push-task", "move-to-target"] {
            let listed = options(command).expect("a command of pushlearn experiment");
            assert!(listed.len() > 20, "{command}: {listed:?}");
            for option in &listed {
                let words = sample(command, option);
                let args = parse(command, &words)
                    .unwrap_or_else(|err| panic!("{command} {words:?}: {err}"));
                match args.lower() {
                    Ok(_) => {}
                    Err(err) => assert!(
                        err.to_string().contains(&format!("--{}", option.long)),
                        "{command} {words:?}: {err}"
                    ),
                }
            }
        }
        assert!(options("push-tasks").is_none());
    }

    /// The parser's refusals name the option; the lowering's name the
    /// options that do not go together.
    #[test]
    fn refusals_name_the_option() {
        let words = |w: &[&str]| w.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
        let err = parse("push-task", &words(&["--folds", "0"])).unwrap_err();
        assert!(matches!(err, ArgsError::Parse(_)), "{err}");
        assert!(err.to_string().contains("--folds"), "{err}");
        let err = parse("push-task", &words(&["--model", "teapot"])).unwrap_err();
        assert!(err.to_string().contains("--model"), "{err}");
        let args = parse(
            "push-task",
            &words(&["--mode", "lockstep", "--latency-max", "5"]),
        )
        .expect("parses");
        let err = args.lower().unwrap_err();
        assert!(err.to_string().contains("--latency-max"), "{err}");
        // The draft's default folds are the command's: one per row.
        let args = parse("push-task", &words(&["--variant", "draft"])).expect("parses");
        let lowered = args.lower().expect("lowers");
        let Spec::PushTask { folds, .. } = &*lowered.spec else {
            panic!("a push task")
        };
        assert_eq!(*folds, 1);
        // A learner object given instead of the options' learner.
        let args = parse("push-task", &[]).expect("parses");
        let lowered = args
            .lower_with(Some(&LearnerChoice::InProcess))
            .expect("lowers");
        assert_eq!(lowered.spec.model(), Some(&LearnerChoice::InProcess));
        let args = parse("push-task", &words(&["--report", "draft"])).expect("parses");
        assert!(args.lower_with(Some(&LearnerChoice::InProcess)).is_err());
    }

    /// The command the reproduction prints beside each of its documents
    /// (`Entry::command`, on the page and in `docs/results/timing.md`),
    /// parsed by this command's own parser, is the experiment it was
    /// printed for: the manifest's specs and the command line cannot drift
    /// apart.
    #[test]
    fn the_reproductions_commands_parse_back_into_their_experiments() {
        use crate::reproduce::manifest;

        let entries: Vec<_> = manifest::full()
            .into_iter()
            .chain(manifest::quick())
            .collect();
        assert!(entries.len() > 60, "the full set and the quick one");
        for entry in entries {
            let command = entry.command("docs/results");
            let words = shlex::split(&command).expect("the command is valid shell words");
            let words: Vec<&str> = words.iter().map(String::as_str).collect();
            let ["pushlearn", "experiment", name, rest @ ..] = words.as_slice() else {
                panic!("`{command}` is not pushlearn experiment COMMAND …")
            };
            let rest: Vec<String> = rest.iter().map(|w| (*w).to_owned()).collect();
            let args = parse(name, &rest)
                .unwrap_or_else(|err| panic!("`{command}` does not parse: {err}"));
            let lowered = args
                .lower()
                .unwrap_or_else(|err| panic!("`{command}` is refused: {err}"));
            assert_eq!(*lowered.spec, entry.spec, "`{command}`");
            let world = lowered.world;
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
