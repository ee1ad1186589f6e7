//! `pushlearn sweep`: a grid of push-task configurations as data, its jobs
//! (one fold of one configuration each) run on this machine or as a Slurm
//! job array, and merged into the reports `pushlearn experiment` writes
//! (`docs/sweeps.md`).

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use pushlearn_cli::experiment::run_cache::RunCache;
use pushlearn_cli::experiment::workers::{find_sim_binary, Worlds};
use pushlearn_cli::experiment::ExperimentError;
use pushlearn_cli::models::named;
use pushlearn_cli::output::write_atomically;
use pushlearn_cli::spec::Document;
use pushlearn_cli::sweep::output::{self, JobOutput, JOBS, MERGED, PLAN, SLURM, TIMING};
use pushlearn_cli::sweep::summary::Summary;
use pushlearn_cli::sweep::{slurm, Job, Sweep};

use super::experiment::{end_worlds_on_signal, progress, PushTaskLine};
use lab::args::choose_worlds;

/// Run a grid of push-task configurations — models, configuration bits,
/// selectors, η, any option of `pushlearn experiment push-task` — over
/// seeds, training-run counts and folds, as independent jobs: here, or as a
/// Slurm job array; then merge them into the same reports, tables and
/// figures a single `pushlearn experiment` run writes (docs/sweeps.md).
///
/// A job is one fold of one configuration under one seed; its id is derived
/// from those parameters, its output written whole under DIR/jobs/, and a
/// job whose output exists is skipped (resume). Its result does not depend
/// on where or with what else it ran, so every way of running a plan
/// merges into the same bytes.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  \
    pushlearn sweep plan sweeps/ablation.toml                        the jobs and how many\n  \
    pushlearn sweep run sweeps/ablation.toml --out runs/ablation     every job here, then merge\n  \
    pushlearn sweep slurm sweeps/ablation.toml --out /scratch/abl --partition short --time 01:00:00 --dry-run\n  \
    pushlearn sweep slurm sweeps/ablation.toml --out /scratch/abl   submit (again: only what is missing)\n  \
    pushlearn sweep merge /scratch/abl                               reports, tables, figures")]
pub struct SweepArgs {
    #[command(subcommand)]
    command: SweepCommand,
}

#[derive(Debug, Subcommand)]
enum SweepCommand {
    /// Print the sweep's jobs (id, seed, N_train, fold, options) and how
    /// many there are; with --out, which are done.
    Plan(PlanArgs),
    /// Run every job not done yet on this machine (one world process per
    /// CPU), then merge.
    Run(RunArgs),
    /// Write an sbatch job-array script (one array task per chunk of jobs
    /// not done yet) into DIR/slurm/ and submit it with sbatch.
    Slurm(SlurmArgs),
    /// Merge the job outputs of DIR into DIR/merged/: per configuration and
    /// seed the report (report.json), its tables (tables.txt, csv/) and
    /// figures (figures/), and summary.md / summary.csv over all of them.
    /// Refuses an incomplete set, naming the missing jobs.
    Merge(MergeArgs),
    /// One array task (what the sbatch script runs).
    #[command(hide = true)]
    Task(TaskArgs),
}

#[derive(Debug, Args)]
struct PlanArgs {
    /// The sweep file (TOML; docs/sweeps.md).
    sweep: PathBuf,
    /// Also say which jobs have their output in DIR.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

#[derive(Debug, Args)]
struct RunArgs {
    /// The sweep file (TOML; docs/sweeps.md).
    sweep: PathBuf,
    /// The output directory (created if needed).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Worlds (workers) in parallel [default: the number of CPUs]; with
    /// embedded worlds, a built-in model's jobs run in as many worker
    /// processes.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    workers: Option<u32>,
    /// Where the jobs' worlds run [default: embedded; spawn with
    /// --sim-bin]; the outputs are the same bit for bit.
    #[arg(long, value_parser = named::<Worlds>())]
    world: Option<Worlds>,
    /// The world daemon binary to spawn (implies --world spawn) [default:
    /// $PUSHLEARN_SIM_BIN, else `pushlearn-sim` next to this executable, else
    /// on PATH: docs/simulator.md].
    #[arg(long, value_name = "PATH")]
    sim_bin: Option<PathBuf>,
    /// Run only these jobs (ids, comma-separated), if not done; merges only
    /// if that completes the sweep.
    #[arg(long, value_name = "ID,…", value_delimiter = ',')]
    only: Vec<String>,
    /// Do not merge at the end.
    #[arg(long)]
    no_merge: bool,
}

#[derive(Debug, Args)]
struct SlurmArgs {
    /// The sweep file (TOML; docs/sweeps.md).
    sweep: PathBuf,
    /// The output directory, on a disk every node sees (created if needed).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Jobs per array task.
    #[arg(long, value_name = "N", default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..))]
    chunk_size: u32,
    /// CPUs per array task: its world processes (--cpus-per-task).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    cpus_per_task: u32,
    /// The Slurm partition (--partition).
    #[arg(long, value_name = "NAME")]
    partition: Option<String>,
    /// Time limit of one array task, as sbatch takes it (--time), e.g.
    /// 30 or 01:00:00.
    #[arg(long, value_name = "TIME")]
    time: Option<String>,
    /// At most N array tasks at once (--array=…%N).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    max_running: Option<u32>,
    /// Another #SBATCH option, as sbatch takes it (repeatable), e.g.
    /// --sbatch-arg=--mem=2G --sbatch-arg=--account=lab.
    #[arg(long, value_name = "OPTION", allow_hyphen_values = true)]
    sbatch_arg: Vec<String>,
    /// The job name (--job-name).
    #[arg(long, value_name = "NAME", default_value = "pushlearn-sweep")]
    job_name: String,
    /// The world daemon binary the tasks run [default:
    /// $PUSHLEARN_SIM_BIN, else `pushlearn-sim` next to this executable, else
    /// on PATH: docs/simulator.md].
    #[arg(long, value_name = "PATH")]
    sim_bin: Option<PathBuf>,
    /// Submit only these jobs (ids, comma-separated), if not done.
    #[arg(long, value_name = "ID,…", value_delimiter = ',')]
    only: Vec<String>,
    /// Write the script and the job list, print the script's path, and do
    /// not submit.
    #[arg(long)]
    dry_run: bool,
}

#[derive(Debug, Args)]
struct MergeArgs {
    /// The sweep's output directory (holding sweep.toml and jobs/).
    dir: PathBuf,
    /// Leave out the figures (they take most of a large merge's time).
    #[arg(long)]
    no_figures: bool,
}

#[derive(Debug, Args)]
struct TaskArgs {
    plan: PathBuf,
    #[arg(long)]
    out: PathBuf,
    #[arg(long)]
    list: PathBuf,
    #[arg(long)]
    chunk_size: usize,
    #[arg(long)]
    index: usize,
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    workers: u32,
    #[arg(long)]
    sim_bin: PathBuf,
}

/// Runs `pushlearn sweep`.
pub fn run(args: SweepArgs) -> Result<()> {
    match args.command {
        SweepCommand::Plan(args) => plan(&args),
        SweepCommand::Run(args) => run_here(&args),
        SweepCommand::Slurm(args) => submit(&args),
        SweepCommand::Merge(args) => merge(&args.dir, !args.no_figures).map(|_| ()),
        SweepCommand::Task(args) => task(&args),
    }
}

/// A sweep file read and checked: its plan, and each configuration parsed
/// as `pushlearn experiment push-task` options.
struct Loaded {
    text: String,
    sweep: Sweep,
}

fn load(path: &Path) -> Result<Loaded> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the sweep file {}", path.display()))?;
    let sweep = Sweep::parse(&text, &super::experiment::push_task_options())
        .with_context(|| format!("in the sweep file {}", path.display()))?;
    for configuration in &sweep.configurations {
        PushTaskLine::parse(&configuration.args()).with_context(|| {
            format!(
                "in the sweep file {}: configuration `{}`",
                path.display(),
                configuration.label()
            )
        })?;
    }
    Ok(Loaded { text, sweep })
}

impl Loaded {
    /// The configuration of `job` under its seed, with the sweep's folds
    /// and training runs, and `world` (--workers, --sim-bin) appended.
    fn line(&self, job: &Job, world: &[String]) -> Result<PushTaskLine> {
        let mut args = self.sweep.configurations[job.configuration].args();
        args.extend([
            "--seed".to_owned(),
            job.seed.to_string(),
            "--folds".to_owned(),
            self.sweep.folds.to_string(),
            "--train-runs".to_owned(),
            self.sweep
                .train_runs
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(","),
        ]);
        args.extend(world.iter().cloned());
        PushTaskLine::parse(&args)
    }

    /// The jobs named by `only` (all if empty).
    fn selected(&self, only: &[String]) -> Result<Vec<Job>> {
        let jobs = self.sweep.jobs();
        if only.is_empty() {
            return Ok(jobs);
        }
        if let Some(unknown) = only.iter().find(|id| !jobs.iter().any(|j| &j.id == *id)) {
            bail!("--only: `{unknown}` is not a job of this sweep (`pushlearn sweep plan` lists them)");
        }
        Ok(jobs.into_iter().filter(|j| only.contains(&j.id)).collect())
    }
}

fn plan(args: &PlanArgs) -> Result<()> {
    let loaded = load(&args.sweep)?;
    let jobs = loaded.sweep.jobs();
    let mut out = std::io::stdout().lock();
    let done = |job: &Job| {
        args.out
            .as_ref()
            .is_some_and(|dir| output::job_path(dir, &job.id).is_file())
    };
    writeln!(out, "# id\tseed\tN_train\tfold\toptions")?;
    for job in &jobs {
        writeln!(
            out,
            "{}{}\t{}\t{}\t{}\t{}",
            job.id,
            if done(job) { " (done)" } else { "" },
            job.seed,
            job.n_train,
            job.fold,
            loaded.sweep.configurations[job.configuration].label()
        )?;
    }
    writeln!(out, "{}", loaded.sweep.shape())?;
    if let Some(dir) = &args.out {
        let finished = jobs.iter().filter(|j| done(j)).count();
        writeln!(
            out,
            "{finished} done in {}, {} to run",
            dir.display(),
            jobs.len() - finished
        )?;
    }
    Ok(())
}

/// Copies the plan into `dir` (what merge reads) and makes its folders.
fn prepare(dir: &Path, loaded: &Loaded) -> Result<()> {
    for sub in [JOBS, TIMING, SLURM] {
        pushlearn_cli::output::check_writable_dir(&dir.join(sub))
            .with_context(|| format!("cannot write into {}", dir.join(sub).display()))?;
    }
    write_atomically(&dir.join(PLAN), loaded.text.as_bytes())
        .with_context(|| format!("cannot write {}", dir.join(PLAN).display()))
}

fn run_here(args: &RunArgs) -> Result<()> {
    end_worlds_on_signal();
    let loaded = load(&args.sweep)?;
    let cpus = std::thread::available_parallelism().map_or(1, usize::from);
    let workers = args.workers.map_or(cpus, |n| n as usize);
    let worlds = JobWorlds::new(
        choose_worlds(args.world, args.sim_bin.is_some(), Worlds::Embedded)?,
        args.sim_bin.as_deref(),
    )?;
    let selected = loaded.selected(&args.only)?;
    run_pending(&loaded, &selected, &args.out, workers, &worlds)?;
    if args.no_merge {
        return Ok(());
    }
    if !args.only.is_empty() && output::complete(&args.out, &loaded.sweep).is_err() {
        // A part of the sweep on purpose: the merge would only list the rest.
        eprintln!(
            "not merged: other jobs of the sweep are still missing (`pushlearn sweep plan {} --out {}`)",
            args.sweep.display(),
            args.out.display()
        );
        return Ok(());
    }
    merge(&args.out, true).map(|_| ())
}

/// What [`run_and_merge`] did.
pub struct LocalRun {
    pub summary: Summary,
    /// Jobs in the plan, and how many of them this run ran (the others had
    /// their output in the directory already).
    pub jobs: usize,
    pub ran: usize,
    /// Wall time of running and merging.
    pub seconds: f64,
}

/// `pushlearn sweep run SWEEP --out DIR` for `pushlearn reproduce`: every
/// job of the sweep file not done in `dir` yet, with `workers` worlds, then
/// the merge (without figures).
///
/// # Errors
/// The sweep file is invalid, a job fails, or an output cannot be written.
pub fn run_and_merge(
    sweep_file: &Path,
    dir: &Path,
    workers: usize,
    worlds: &JobWorlds,
) -> Result<LocalRun> {
    let started = Instant::now();
    let loaded = load(sweep_file)?;
    let jobs = loaded.sweep.jobs();
    let ran = run_pending(&loaded, &jobs, dir, workers, worlds)?;
    let summary = merge(dir, false)?;
    Ok(LocalRun {
        summary,
        jobs: jobs.len(),
        ran,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// Writes the plan into `dir` and runs those of `selected` whose output is
/// not there yet; returns how many ran.
fn run_pending(
    loaded: &Loaded,
    selected: &[Job],
    dir: &Path,
    workers: usize,
    worlds: &JobWorlds,
) -> Result<usize> {
    prepare(dir, loaded)?;
    let pending: Vec<Job> = output::pending(dir, selected)
        .into_iter()
        .cloned()
        .collect();
    eprintln!(
        "{}; {} to run, {} done before",
        loaded.sweep.shape(),
        pending.len(),
        selected.len() - pending.len()
    );
    let started = Instant::now();
    run_jobs(loaded, &pending, dir, workers, worlds)?;
    let seconds = started.elapsed().as_secs_f64();
    eprintln!(
        "ran {} jobs in {seconds:.1} s with {workers} worlds",
        pending.len()
    );
    Ok(pending.len())
}

/// Where a sweep's jobs get their worlds, as `pushlearn experiment`
/// options.
#[derive(Debug)]
pub enum JobWorlds {
    Embedded,
    /// Spawned from this daemon binary.
    Spawn(PathBuf),
}

impl JobWorlds {
    /// `worlds`; a spawned world's binary is `sim_bin` or found as
    /// `pushlearn experiment` finds it.
    ///
    /// # Errors
    /// No daemon binary to spawn.
    pub fn new(worlds: Worlds, sim_bin: Option<&Path>) -> Result<Self> {
        Ok(match worlds {
            Worlds::Embedded => JobWorlds::Embedded,
            Worlds::Spawn => JobWorlds::Spawn(find_sim_binary(sim_bin)?),
        })
    }

    fn args(&self) -> Vec<String> {
        match self {
            JobWorlds::Embedded => vec!["--world".into(), "embedded".into()],
            JobWorlds::Spawn(bin) => vec![
                "--world".into(),
                "spawn".into(),
                "--sim-bin".into(),
                bin.display().to_string(),
            ],
        }
    }
}

/// Runs `jobs` (none done yet) into `dir`, grouped by configuration and
/// seed (one experiment each, its worlds started once), writing each job's
/// output as it finishes.
fn run_jobs(
    loaded: &Loaded,
    jobs: &[Job],
    dir: &Path,
    workers: usize,
    worlds: &JobWorlds,
) -> Result<()> {
    let mut world = vec!["--workers".to_owned(), workers.to_string()];
    world.extend(worlds.args());
    let mut groups: Vec<Vec<&Job>> = Vec::new();
    for job in jobs {
        match groups.last_mut() {
            Some(group)
                if group[0].configuration == job.configuration && group[0].seed == job.seed =>
            {
                group.push(job);
            }
            _ => groups.push(vec![job]),
        }
    }
    let bar = progress(jobs.len(), "sweep");
    // Runs recorded by one configuration are replayed for the next on the
    // same world (the same pushes under another model): bit-identical, as
    // in `pushlearn reproduce`.
    let mut caches: BTreeMap<String, Arc<RunCache>> = BTreeMap::new();
    let mut finished = 0;
    for group in groups {
        let line = loaded.line(group[0], &world)?;
        let mut plan = line.plan()?;
        if plan.runs.is_some() {
            let key = format!("{:?} {:?} {}", plan.source, plan.mode, plan.latency_max);
            plan.runs = Some(Arc::clone(
                caches
                    .entry(key)
                    .or_insert_with(|| Arc::new(RunCache::new())),
            ));
        }
        let wanted: Vec<(usize, usize)> = group.iter().map(|j| (j.n_train, j.fold)).collect();
        let by_coords: BTreeMap<(usize, usize), &Job> =
            group.iter().map(|j| ((j.n_train, j.fold), *j)).collect();
        line.spec
            .run_push_jobs(
                &plan,
                &wanted,
                |setup, result| {
                    let job = by_coords
                        .get(&(result.n_train, result.fold))
                        .ok_or_else(|| {
                            ExperimentError::Incomplete(format!(
                                "a result for N_train {} fold {} that was not asked for",
                                result.n_train, result.fold
                            ))
                        })?;
                    JobOutput::new(&loaded.sweep, job, setup.clone(), result)
                        .write(dir, &result.timing)
                        .map_err(|e| ExperimentError::Output {
                            job: job.id.clone(),
                            why: e.to_string(),
                        })
                },
                |done| bar.set_position((finished + done) as u64),
            )
            .with_context(|| {
                format!(
                    "configuration `{}` seed {}",
                    loaded.sweep.configurations[group[0].configuration].label(),
                    group[0].seed
                )
            })?;
        finished += group.len();
    }
    bar.finish_and_clear();
    Ok(())
}

fn submit(args: &SlurmArgs) -> Result<()> {
    let loaded = load(&args.sweep)?;
    prepare(&args.out, &loaded)?;
    let selected = loaded.selected(&args.only)?;
    let pending = output::pending(&args.out, &selected);
    if pending.is_empty() {
        eprintln!(
            "all {} jobs have their output in {}; nothing to submit (`pushlearn sweep merge {}`)",
            selected.len(),
            args.out.display(),
            args.out.display()
        );
        return Ok(());
    }
    // Absolute paths: the tasks start in whatever directory Slurm gives them.
    let out = std::fs::canonicalize(&args.out)
        .with_context(|| format!("cannot resolve {}", args.out.display()))?;
    let sim_bin = std::fs::canonicalize(find_sim_binary(args.sim_bin.as_deref())?)
        .context("cannot resolve the world daemon's path")?;
    let exe = std::env::current_exe().context("cannot find this executable")?;
    let slurm_dir = out.join(SLURM);
    let n = (1..)
        .find(|n| !slurm_dir.join(format!("submit-{n}.sh")).exists())
        .unwrap_or(1);
    let name = |ext: &str| slurm_dir.join(format!("submit-{n}.{ext}"));
    // The submission's own copy of the plan and job list: editing the sweep
    // file or finishing jobs meanwhile does not move a queued task's chunk.
    let (plan, list) = (name("toml"), name("jobs"));
    write_atomically(&plan, loaded.text.as_bytes())
        .with_context(|| format!("cannot write {}", plan.display()))?;
    let ids: String = pending.iter().map(|j| format!("{}\n", j.id)).collect();
    write_atomically(&list, ids.as_bytes())
        .with_context(|| format!("cannot write {}", list.display()))?;
    let script = slurm::Script {
        exe,
        sim_bin,
        plan,
        out: out.clone(),
        list,
        jobs: pending.len(),
        chunk_size: args.chunk_size as usize,
        log: slurm_dir.join(format!("submit-{n}-%A_%a.log")),
        job_name: args.job_name.clone(),
        cpus_per_task: args.cpus_per_task,
        max_running: args.max_running,
        partition: args.partition.clone(),
        time: args.time.clone(),
        extra: args.sbatch_arg.clone(),
    };
    let path = name("sh");
    write_atomically(&path, script.text().as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!(
        "{}; {} to run in {} array tasks of up to {}, {} done before",
        loaded.sweep.shape(),
        pending.len(),
        script.tasks(),
        args.chunk_size,
        selected.len() - pending.len()
    );
    if args.dry_run {
        println!("{}", path.display());
        eprintln!(
            "not submitted (--dry-run); submit with `sbatch {}`",
            path.display()
        );
        return Ok(());
    }
    let result = std::process::Command::new("sbatch")
        .arg("--parsable")
        .arg(&path)
        .output()
        .with_context(|| {
            format!(
                "cannot run sbatch (is this a Slurm login node?); the script is {}, or pass --dry-run",
                path.display()
            )
        })?;
    if !result.status.success() {
        bail!(
            "sbatch {} failed ({}): {}",
            path.display(),
            result.status,
            String::from_utf8_lossy(&result.stderr).trim()
        );
    }
    let stdout = String::from_utf8_lossy(&result.stdout);
    let id = stdout.trim().split(';').next().unwrap_or_default();
    println!("{id}");
    eprintln!(
        "submitted array job {id} ({}); follow it with `squeue -j {id}`, then `pushlearn sweep merge {}`",
        path.display(),
        out.display()
    );
    Ok(())
}

fn task(args: &TaskArgs) -> Result<()> {
    end_worlds_on_signal();
    let loaded = load(&args.plan)?;
    let list = std::fs::read_to_string(&args.list)
        .with_context(|| format!("cannot read the job list {}", args.list.display()))?;
    let ids = slurm::chunk(&list, args.chunk_size, args.index);
    let jobs = loaded.sweep.jobs();
    let mine: Vec<Job> = ids
        .iter()
        .map(|id| {
            jobs.iter().find(|j| j.id == *id).cloned().with_context(|| {
                format!(
                    "job `{id}` of {} is not in {}",
                    args.list.display(),
                    args.plan.display()
                )
            })
        })
        .collect::<Result<_>>()?;
    let pending: Vec<Job> = output::pending(&args.out, &mine)
        .into_iter()
        .cloned()
        .collect();
    eprintln!(
        "array task {}: {} jobs, {} to run",
        args.index,
        mine.len(),
        pending.len()
    );
    let started = Instant::now();
    run_jobs(
        &loaded,
        &pending,
        &args.out,
        args.workers as usize,
        &JobWorlds::Spawn(args.sim_bin.clone()),
    )?;
    eprintln!(
        "array task {}: ran {} jobs in {:.1} s",
        args.index,
        pending.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn merge(dir: &Path, figures: bool) -> Result<Summary> {
    let loaded = load(&dir.join(PLAN)).with_context(|| {
        format!(
            "{} is not a sweep's output directory (it has no readable {PLAN})",
            dir.display()
        )
    })?;
    let sweep = &loaded.sweep;
    let merged = dir.join(MERGED);
    // Only what this merge writes is in merged/ afterwards.
    if merged.exists() {
        std::fs::remove_dir_all(&merged)
            .with_context(|| format!("cannot clear {}", merged.display()))?;
    }
    pushlearn_cli::output::check_writable_dir(&merged)
        .with_context(|| format!("cannot write into {}", merged.display()))?;
    if let Err(incomplete) = output::complete(dir, sweep) {
        let list: String = incomplete
            .missing
            .iter()
            .map(|id| format!("{id}\n"))
            .collect();
        write_atomically(&merged.join("missing.txt"), list.as_bytes())?;
        return Err(incomplete.into());
    }
    let jobs = sweep.jobs();
    let mut summary = Summary::new(sweep);
    let started = Instant::now();
    for group in jobs.chunk_by(|a, b| a.configuration == b.configuration && a.seed == b.seed) {
        let first = &group[0];
        let configuration = &sweep.configurations[first.configuration];
        let outputs: Vec<JobOutput> = group
            .iter()
            .map(|job| JobOutput::read(dir, sweep, job))
            .collect::<Result<_, _>>()?;
        let setup = outputs[0].setup.clone();
        if let Some(other) = outputs.iter().find(|o| o.setup != setup) {
            bail!(
                "the jobs of `{}` seed {} ran under different setups ({} has model `{}`, {} `{}`): rerun them with one version of the learner",
                configuration.label(), first.seed, outputs[0].id, setup.model, other.id, other.setup.model
            );
        }
        let results: Vec<_> = outputs.into_iter().map(|o| o.result).collect();
        let line = loaded.line(first, &[])?;
        let document = Document::Push(line.spec.push_report(setup, &results)?);
        let run_dir = merged.join(format!("{}-s{}", configuration.id, first.seed));
        std::fs::create_dir_all(&run_dir)?;
        write_atomically(&run_dir.join("report.json"), document.to_json()?.as_bytes())?;
        let printout = document.printout()?;
        let mut text = Vec::new();
        writeln!(
            text,
            "{}  --seed {}\n",
            configuration.canonical(),
            first.seed
        )?;
        printout.write_text(&mut text)?;
        write_atomically(&run_dir.join("tables.txt"), &text)?;
        std::fs::create_dir_all(run_dir.join("csv"))?;
        printout
            .write_csv(&run_dir.join("csv"))
            .with_context(|| format!("writing CSV files into {}", run_dir.display()))?;
        if figures {
            std::fs::create_dir_all(run_dir.join("figures"))?;
            document.plot(&run_dir.join("figures"))?;
        }
        if let Document::Push(report) = &document {
            summary.add(configuration, first.seed, report);
        }
    }
    write_atomically(&merged.join("summary.md"), summary.markdown().as_bytes())?;
    write_atomically(&merged.join("summary.csv"), summary.csv().as_bytes())?;
    eprintln!(
        "merged {} jobs of {} configurations × {} seeds into {} in {:.1} s",
        jobs.len(),
        sweep.configurations.len(),
        sweep.seeds.len(),
        merged.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(summary)
}
