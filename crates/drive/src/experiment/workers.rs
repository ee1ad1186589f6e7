//! Workers: one world per worker and independent jobs spread over them.
//!
//! ODE's quick-step solver draws from one random generator per process, so
//! worlds that must be reproducible cannot share a process: every worker
//! starts its own `pushlearn-sim serve` child on a free port (or, in
//! realtime, uses one world that is already running). Each worker thread
//! owns its child, its connection and a single-threaded runtime, and takes
//! the next job index from a shared counter; results are put back in job
//! order, so the report does not depend on the number of workers or on
//! which worker ran which job.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc, Mutex, Weak};
use std::time::Duration;

use super::link::{Pacing, WorldLink};
use super::{ExperimentError, Mode};

/// File name of the world daemon.
pub const SIM_BIN: &str = "pushlearn-sim";

/// How long a fresh world may take to print its address.
const START_LIMIT: Duration = Duration::from_secs(30);

/// What the daemon prints once it accepts connections.
const LISTENING: &str = "listening on ";

/// The environment variable that names the world binary when no path is
/// given on the command line: the same name every lookup of it reads
/// (Python's `pushlearn.local_world.find_sim_binary`, the Python tests).
pub const SIM_BIN_ENV: &str = "PUSHLEARN_SIM_BIN";

/// Locates `pushlearn-sim` in the order `docs/simulator.md` ("Where
/// `pushlearn-sim` is found") gives for every lookup of it: `explicit`
/// (`--sim-bin`), else the file `PUSHLEARN_SIM_BIN` names, else next to the
/// running executable (where cargo puts both binaries, and where a wheel
/// carries them), else on `PATH`. A path given either way must be a file:
/// a typo is reported, not passed over for another binary.
///
/// # Errors
/// [`ExperimentError::SimNotFound`] naming where it looked and what to build.
pub fn find_sim_binary(explicit: Option<&Path>) -> Result<PathBuf, ExperimentError> {
    let from_env = std::env::var_os(SIM_BIN_ENV)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from);
    let beside = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_owned));
    locate_sim_binary(
        explicit,
        from_env.as_deref(),
        beside.as_deref(),
        std::env::var_os("PATH").as_deref(),
    )
}

/// [`find_sim_binary`] on its inputs: the explicit path, the environment
/// variable's value, the running executable's directory and `PATH`.
fn locate_sim_binary(
    explicit: Option<&Path>,
    from_env: Option<&Path>,
    exe_dir: Option<&Path>,
    path_var: Option<&std::ffi::OsStr>,
) -> Result<PathBuf, ExperimentError> {
    let given = explicit
        .map(|p| (p, p.display().to_string()))
        .or_else(|| from_env.map(|p| (p, format!("{SIM_BIN_ENV}={}", p.display()))));
    if let Some((path, described)) = given {
        return if path.is_file() {
            Ok(path.to_owned())
        } else {
            Err(ExperimentError::SimNotFound {
                looked: format!("{described}, which is not a file"),
            })
        };
    }
    let beside = exe_dir.map(|dir| dir.join(SIM_BIN));
    let on_path: Vec<PathBuf> = path_var
        .map(|paths| {
            std::env::split_paths(paths)
                .map(|dir| dir.join(SIM_BIN))
                .collect()
        })
        .unwrap_or_default();
    if let Some(found) = beside.iter().chain(&on_path).find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    Err(ExperimentError::SimNotFound {
        looked: match beside {
            Some(path) => format!("{} and on PATH", path.display()),
            None => "on PATH".into(),
        },
    })
}

/// The command that starts a world on a free port: `bin serve --port 0 ARGS…`.
#[must_use]
pub fn serve_command(bin: &Path, args: &[String]) -> Command {
    let mut command = Command::new(bin);
    command.arg("serve").args(["--port", "0"]).args(args);
    command
}

/// Every live world process of this program, so that a signal handler can
/// end them before the program exits (see [`kill_all_worlds`]).
static LIVE: Mutex<Vec<Weak<Mutex<Child>>>> = Mutex::new(Vec::new());

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Kills every world process still running. For signal handlers: a program
/// that is interrupted does not unwind, so the processes' `Drop` never runs.
pub fn kill_all_worlds() {
    let live = std::mem::take(&mut *lock(&LIVE));
    kill_each(&live);
}

fn kill_each(children: &[Weak<Mutex<Child>>]) {
    for child in children.iter().filter_map(Weak::upgrade) {
        let mut child = lock(&child);
        let _ = child.kill();
        let _ = child.wait();
    }
}

/// A world daemon child process, killed when dropped.
#[derive(Debug)]
pub struct SimProcess {
    child: Arc<Mutex<Child>>,
    addr: String,
}

/// How long a world whose connection failed may take to be seen dead: the
/// kernel closes a dying process's sockets a moment before its exit status
/// can be collected.
const DEATH_NOTICE: Duration = Duration::from_secs(1);

impl SimProcess {
    /// Starts `command` (see [`serve_command`]) and waits for the line
    /// `listening on ADDR` on its stdout or stderr.
    ///
    /// # Errors
    /// The process cannot be started, or exits or stays silent before it
    /// prints its address.
    pub fn spawn(mut command: Command) -> Result<Self, ExperimentError> {
        command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let description = format!("{command:?}");
        let mut child = command.spawn().map_err(|err| ExperimentError::Spawn {
            command: description.clone(),
            reason: err.to_string(),
        })?;
        // Both streams are drained for the child's whole life so that it
        // never blocks on a full pipe.
        let (found, addresses) = mpsc::channel();
        let watch = |pipe: Box<dyn Read + Send>, stream: &'static str| {
            let found = found.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    match line.find(LISTENING) {
                        Some(at) => {
                            let addr = line[at + LISTENING.len()..].trim().to_owned();
                            let _ = found.send(addr);
                        }
                        None => tracing::debug!(target: "pushlearn_sim", stream, "{line}"),
                    }
                }
            });
        };
        if let Some(pipe) = child.stdout.take() {
            watch(Box::new(pipe), "stdout");
        }
        if let Some(pipe) = child.stderr.take() {
            watch(Box::new(pipe), "stderr");
        }
        drop(found);
        let child = Arc::new(Mutex::new(child));
        {
            let mut live = lock(&LIVE);
            live.retain(|w| w.strong_count() > 0);
            live.push(Arc::downgrade(&child));
        }
        let mut process = SimProcess {
            child,
            addr: String::new(),
        };
        match addresses.recv_timeout(START_LIMIT) {
            Ok(addr) => {
                tracing::debug!(%addr, "world started");
                process.addr = addr;
                Ok(process)
            }
            Err(_) => {
                // Both pipes closed (the child is gone) or it stayed silent.
                let exited = || lock(&process.child).try_wait().ok().flatten();
                let status = exited().or_else(|| {
                    std::thread::sleep(Duration::from_millis(50));
                    exited()
                });
                Err(ExperimentError::Spawn {
                    command: description,
                    reason: match status {
                        Some(status) => format!("exited ({status}) before listening"),
                        None => format!("printed no `{LISTENING}ADDR` within {START_LIMIT:?}"),
                    },
                })
            }
        }
    }

    /// `host:port` the world listens on.
    #[must_use]
    pub fn addr(&self) -> &str {
        &self.addr
    }

    /// The process's exit status if it has ended (or ends within `within`).
    fn exited(&self, within: Duration) -> Option<std::process::ExitStatus> {
        let deadline = std::time::Instant::now() + within;
        loop {
            match lock(&self.child).try_wait() {
                Ok(Some(status)) => return Some(status),
                Ok(None) if std::time::Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(10));
                }
                Ok(None) | Err(_) => return None,
            }
        }
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let mut child = lock(&self.child);
        let _ = child.kill();
        let _ = child.wait();
    }
}

/// Where an experiment's worlds run when it starts them itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Worlds {
    /// A lock-step world inside this process per worker.
    Embedded,
    /// A `pushlearn-sim` process per worker, over localhost TCP.
    Spawn,
}

impl pushlearn_core::Named for Worlds {
    const ALL: &'static [Self] = &[Worlds::Embedded, Worlds::Spawn];

    fn name(self) -> &'static str {
        match self {
            Worlds::Embedded => "embedded",
            Worlds::Spawn => "spawn",
        }
    }

    fn description(self) -> &'static str {
        match self {
            Worlds::Embedded => {
                "A lock-step world inside this process per worker: no round trip per state                  (the default in the lock-step modes)"
            }
            Worlds::Spawn => {
                "A pushlearn-sim process per worker over localhost TCP (the only choice with                  --mode realtime); the same states bit for bit"
            }
        }
    }
}

impl Worlds {
    /// The default for `mode`: embedded wherever it can run.
    #[must_use]
    pub fn default_for(mode: Mode) -> Self {
        if mode == Mode::Realtime {
            Worlds::Spawn
        } else {
            Worlds::Embedded
        }
    }

    /// The worlds of `scene`, timed as `mode` and `latency_max` say; `bin`
    /// finds the daemon binary when they are spawned.
    ///
    /// # Errors
    /// Embedded worlds in realtime, or no daemon binary to spawn.
    pub fn source(
        self,
        mode: Mode,
        scene: &str,
        latency_max: u32,
        bin: impl FnOnce() -> Result<PathBuf, ExperimentError>,
    ) -> Result<WorldSource, ExperimentError> {
        match self {
            Worlds::Embedded => WorldSource::embedded(mode, scene, latency_max),
            Worlds::Spawn => Ok(WorldSource::Spawn {
                bin: bin()?,
                args: mode.serve_args(scene, latency_max),
            }),
        }
    }
}

/// Where workers get their worlds.
#[derive(Clone, Debug)]
pub enum WorldSource {
    /// Start `bin serve --port 0 ARGS…` per worker.
    Spawn { bin: PathBuf, args: Vec<String> },
    /// Use a running world (one worker).
    Connect(String),
    /// A lock-step world of `scene` in this process per worker, with
    /// latency emulation up to `latency_max` steps (`None`: none). The
    /// workers' worlds take turns at ODE (its random generator is one per
    /// process, `ode::World::step`), so their physics does not run in
    /// parallel; their learners do.
    Embedded {
        scene: String,
        latency_max: Option<u32>,
    },
}

impl WorldSource {
    /// How many workers can run at once: one for a running world.
    #[must_use]
    pub fn max_workers(&self, wanted: usize) -> usize {
        match self {
            WorldSource::Connect(_) => 1,
            WorldSource::Spawn { .. } | WorldSource::Embedded { .. } => wanted.max(1),
        }
    }

    /// Worlds of `scene` in this process, timed as `mode` times them.
    ///
    /// # Errors
    /// [`Mode::Realtime`]: a free-running world needs a daemon of its own.
    pub fn embedded(mode: Mode, scene: &str, latency_max: u32) -> Result<Self, ExperimentError> {
        let latency_max =
            match mode {
                Mode::Realtime => return Err(ExperimentError::Embedded(
                    "--mode realtime runs a free-running world daemon; use --world spawn or --sim"
                        .into(),
                )),
                Mode::Lockstep => None,
                Mode::LockstepJitter => Some(latency_max),
            };
        Ok(WorldSource::Embedded {
            scene: scene.to_owned(),
            latency_max,
        })
    }
}

/// One worker's world: the connection and, if started by us, the process.
#[derive(Debug)]
pub struct Worker {
    pub link: WorldLink,
    // Declared after the link so that it is dropped (killed) after the
    // connection is closed.
    _process: Option<SimProcess>,
}

impl Worker {
    /// Starts or connects to a world.
    ///
    /// # Errors
    /// Starting the process or connecting.
    pub fn start(source: &WorldSource, pacing: Pacing) -> Result<Self, ExperimentError> {
        match source {
            WorldSource::Spawn { bin, args } => {
                let process = SimProcess::spawn(serve_command(bin, args))?;
                let link = WorldLink::connect(process.addr(), pacing)?;
                Ok(Self {
                    link,
                    _process: Some(process),
                })
            }
            WorldSource::Connect(addr) => Ok(Self {
                link: WorldLink::connect(addr, pacing)?,
                _process: None,
            }),
            WorldSource::Embedded { scene, latency_max } => Ok(Self {
                link: WorldLink::embedded(scene, *latency_max)?,
                _process: None,
            }),
        }
    }

    /// How this worker's world process ended, if it has: after its
    /// connection failed, to tell a dead world from a refused command. A
    /// world this program did not start is never reported dead (it cannot
    /// be restarted either).
    #[must_use]
    pub fn world_death(&self) -> Option<String> {
        let process = self._process.as_ref()?;
        process
            .exited(DEATH_NOTICE)
            .map(|status| status.to_string())
    }
}

/// A world process that died during a job (`docs/reliability.md` §2): the
/// job, where in it the driver was, and the last commands the world got.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WorldDeath {
    /// The job, e.g. `N_train 10 fold 3`.
    pub job: String,
    /// The run and message, e.g. `test run 4 of 21, message 37 of the run`.
    pub at: String,
    /// The last batch sent, e.g. `move(0, 0.5) + advance`.
    pub last_sent: String,
    /// The process's exit status, e.g. `signal: 9 (SIGKILL)`.
    pub status: String,
    /// Whether this was the job's retry on a new world.
    pub retried: bool,
}

impl std::fmt::Display for WorldDeath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}, {}: the world process died ({}); the last command sent was {}",
            self.job, self.at, self.status, self.last_sent
        )?;
        if self.retried {
            write!(f, "; it died again when the job was retried on a new world")?;
        }
        Ok(())
    }
}

/// Runs `job` on `worker`; if its world died ([`ExperimentError::WorldDied`]),
/// says so once, puts a worker from `restart` in its place and runs the job
/// again. Jobs are seeded and a fresh world is the same as a used one after
/// a reset, so the retry's result is the one the job would have had. A
/// second death ends the job with both in the error's message.
///
/// # Errors
/// The job's error; the restart's; [`ExperimentError::WorldDied`] with
/// `retried` set if the retry's world died too.
pub fn retry_if_the_world_dies<W, R>(
    worker: &mut W,
    restart: impl FnOnce() -> Result<W, ExperimentError>,
    mut job: impl FnMut(&mut W) -> Result<R, ExperimentError>,
) -> Result<R, ExperimentError> {
    match job(worker) {
        Err(ExperimentError::WorldDied(death)) => {
            tracing::warn!("{death}; restarting the world and retrying the job once");
            *worker = restart()?;
            job(worker).map_err(|err| match err {
                ExperimentError::WorldDied(again) => {
                    ExperimentError::WorldDied(Box::new(WorldDeath {
                        retried: true,
                        ..*again
                    }))
                }
                other => other,
            })
        }
        other => other,
    }
}

/// Runs `run` on every job with up to `workers` workers, each with its own
/// resource from `start` (a world), and returns the results in job order.
/// `progress` is called on the calling thread after each finished job with
/// the number finished so far. The first error stops the workers after their
/// current job and is returned.
///
/// # Errors
/// The first error of any job or worker start; [`ExperimentError::JobLost`]
/// if a job produced nothing (a worker thread panicked).
pub fn run_jobs<J, W, R>(
    jobs: &[J],
    workers: usize,
    start: impl Fn() -> Result<W, ExperimentError> + Sync,
    run: impl Fn(&J, &mut W) -> Result<R, ExperimentError> + Sync,
    progress: impl FnMut(usize),
) -> Result<Vec<R>, ExperimentError>
where
    J: Sync,
    R: Send,
{
    let workers = workers.clamp(1, jobs.len().max(1));
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let (sender, results) = mpsc::channel::<Result<(usize, R), ExperimentError>>();
    std::thread::scope(|scope| {
        for id in 0..workers {
            let sender = sender.clone();
            let (next, stop, start, run) = (&next, &stop, &start, &run);
            scope.spawn(move || {
                let mut worker = match start() {
                    Ok(worker) => worker,
                    Err(err) => {
                        stop.store(true, Ordering::SeqCst);
                        let _ = sender.send(Err(err));
                        return;
                    }
                };
                tracing::debug!(worker = id, "worker ready");
                while !stop.load(Ordering::SeqCst) {
                    let index = next.fetch_add(1, Ordering::SeqCst);
                    let Some(job) = jobs.get(index) else { break };
                    let result = run(job, &mut worker);
                    if result.is_err() {
                        stop.store(true, Ordering::SeqCst);
                    }
                    if sender.send(result.map(|r| (index, r))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(sender);
        in_job_order(jobs.len(), results, progress)
    })
}

/// The results of `jobs` jobs as workers send them, `(index, result)` in
/// any order, put back in job order; `progress` is called with the number
/// finished after each. Waits until every sender is gone.
///
/// # Errors
/// The first error a worker sent; [`ExperimentError::JobLost`] for a job
/// without a result.
pub(crate) fn in_job_order<R>(
    jobs: usize,
    results: mpsc::Receiver<Result<(usize, R), ExperimentError>>,
    mut progress: impl FnMut(usize),
) -> Result<Vec<R>, ExperimentError> {
    let mut slots: Vec<Option<R>> = std::iter::repeat_with(|| None).take(jobs).collect();
    let mut first_error = None;
    let mut finished = 0;
    for message in results {
        match message {
            Ok((index, result)) => {
                slots[index] = Some(result);
                finished += 1;
                progress(finished);
            }
            Err(err) => {
                first_error.get_or_insert(err);
            }
        }
    }
    if let Some(err) = first_error {
        return Err(err);
    }
    slots
        .into_iter()
        .enumerate()
        .map(|(index, slot)| slot.ok_or(ExperimentError::JobLost { index }))
        .collect()
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;

    fn shell(script: &str) -> Command {
        let mut command = Command::new("sh");
        command.arg("-c").arg(script);
        command
    }

    #[test]
    fn an_explicit_sim_binary_must_exist() {
        let missing = Path::new("/nonexistent/pushlearn-sim");
        let err = find_sim_binary(Some(missing)).unwrap_err();
        assert!(
            err.to_string().contains("/nonexistent/pushlearn-sim"),
            "{err}"
        );
        assert!(err.to_string().contains("cargo build"), "{err}");
    }

    #[test]
    fn the_world_binary_is_looked_up_in_one_order() {
        let dir = std::env::temp_dir().join(format!("sim-lookup-{}", std::process::id()));
        let [given, env, beside, path_a, path_b] =
            ["given", "env", "beside", "path-a", "path-b"].map(|d| dir.join(d));
        for d in [&given, &env, &beside, &path_a, &path_b] {
            std::fs::create_dir_all(d).unwrap();
            std::fs::write(d.join(SIM_BIN), "").unwrap();
        }
        let path_var = std::env::join_paths([&path_a, &path_b]).unwrap();
        let find = |explicit: Option<&Path>, from_env: Option<&Path>, exe_dir: Option<&Path>| {
            locate_sim_binary(explicit, from_env, exe_dir, Some(&path_var))
        };
        let bin = |d: &Path| d.join(SIM_BIN);
        // --sim-bin, then PUSHLEARN_SIM_BIN, then beside the executable, then PATH in order.
        let everything = find(Some(&bin(&given)), Some(&bin(&env)), Some(&beside));
        assert_eq!(everything.unwrap(), bin(&given));
        let no_flag = find(None, Some(&bin(&env)), Some(&beside));
        assert_eq!(no_flag.unwrap(), bin(&env));
        assert_eq!(find(None, None, Some(&beside)).unwrap(), bin(&beside));
        assert_eq!(find(None, None, Some(&dir)).unwrap(), bin(&path_a));
        std::fs::remove_file(bin(&path_a)).unwrap();
        assert_eq!(find(None, None, None).unwrap(), bin(&path_b));
        // A variable naming nothing is an error naming it, not a fallback.
        let missing = dir.join("nothing");
        let err = find(None, Some(&missing), Some(&beside))
            .unwrap_err()
            .to_string();
        assert!(err.contains("PUSHLEARN_SIM_BIN="), "{err}");
        assert!(err.contains("nothing, which is not a file"), "{err}");
        std::fs::remove_file(bin(&path_b)).unwrap();
        let err = find(None, None, Some(&dir)).unwrap_err().to_string();
        assert!(err.contains("and on PATH"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_serve_command_asks_for_a_free_port() {
        let c = serve_command(
            Path::new("/x/pushlearn-sim"),
            &["--mode".into(), "lockstep".into()],
        );
        let args: Vec<_> = c
            .get_args()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        assert_eq!(args, ["serve", "--port", "0", "--mode", "lockstep"]);
    }

    #[test]
    fn the_address_comes_from_the_listening_line_on_either_stream() {
        let p = SimProcess::spawn(shell(
            "echo starting; echo 'INFO pushlearn_sim: listening on 127.0.0.1:4242' >&2; exec sleep 30",
        ))
        .unwrap();
        assert_eq!(p.addr(), "127.0.0.1:4242");
    }

    #[test]
    fn live_worlds_can_be_killed_from_outside() {
        let p = SimProcess::spawn(shell("echo 'listening on 127.0.0.1:1'; exec sleep 30")).unwrap();
        assert!(lock(&LIVE)
            .iter()
            .any(|w| w.ptr_eq(&Arc::downgrade(&p.child))));
        kill_each(&[Arc::downgrade(&p.child)]);
        // Killed and reaped: its status is known at once.
        assert!(lock(&p.child).try_wait().unwrap().is_some());
    }

    #[test]
    fn a_world_that_exits_before_listening_is_an_error() {
        let err = SimProcess::spawn(shell("echo 'no scene' >&2; exit 3")).unwrap_err();
        assert!(err.to_string().contains("before listening"), "{err}");
        let err = SimProcess::spawn(Command::new("/nonexistent/pushlearn-sim")).unwrap_err();
        assert!(matches!(err, ExperimentError::Spawn { .. }), "{err}");
    }

    /// Jobs of uneven length on 1, 2 and 3 workers: the results are the
    /// same list in job order, and every worker resource was used.
    #[test]
    fn results_come_back_in_job_order_whatever_the_worker_count() {
        let jobs: Vec<u64> = (0..12).collect();
        let run_with = |workers: usize| {
            let started = Mutex::new(0);
            let mut seen = Vec::new();
            let out = run_jobs(
                &jobs,
                workers,
                || {
                    let mut n = started.lock().unwrap();
                    *n += 1;
                    Ok(*n)
                },
                |job, _worker: &mut usize| {
                    std::thread::sleep(Duration::from_millis((job * 7) % 5));
                    Ok(job * job)
                },
                |done| seen.push(done),
            )
            .unwrap();
            assert_eq!(*started.lock().unwrap(), workers);
            assert_eq!(seen, (1..=12).collect::<Vec<_>>());
            out
        };
        let one = run_with(1);
        assert_eq!(one, jobs.iter().map(|j| j * j).collect::<Vec<_>>());
        assert_eq!(run_with(2), one);
        assert_eq!(run_with(3), one);
    }

    fn death(job: &str) -> ExperimentError {
        ExperimentError::WorldDied(Box::new(WorldDeath {
            job: job.into(),
            at: "test run 4 of 21, message 37 of the run".into(),
            last_sent: "move(0, 0.5) + advance".into(),
            status: "signal: 9 (SIGKILL)".into(),
            retried: false,
        }))
    }

    /// One death: the job runs again on a restarted worker and its result
    /// is returned. Two: the error says so, with the second death's place.
    /// Any other error: no retry.
    #[test]
    fn a_job_whose_world_dies_is_retried_once_on_a_new_world() {
        let mut worker = 1;
        let mut runs = Vec::new();
        let out = retry_if_the_world_dies(
            &mut worker,
            || Ok(2),
            |w: &mut u32| {
                runs.push(*w);
                if *w == 1 {
                    Err(death("N_train 1 fold 0"))
                } else {
                    Ok("result")
                }
            },
        );
        assert_eq!(out.unwrap(), "result");
        assert_eq!((runs, worker), (vec![1, 2], 2));

        let mut worker = 1;
        let err = retry_if_the_world_dies(
            &mut worker,
            || Ok(2),
            |_| Err::<(), _>(death("N_train 1 fold 0")),
        )
        .unwrap_err();
        let text = err.to_string();
        assert!(
            text.starts_with("N_train 1 fold 0, test run 4 of 21, message 37 of the run: the world process died (signal: 9 (SIGKILL)); the last command sent was move(0, 0.5) + advance"),
            "{text}"
        );
        assert!(
            text.ends_with("it died again when the job was retried on a new world"),
            "{text}"
        );

        let mut tries = 0;
        let err = retry_if_the_world_dies(
            &mut 1,
            || Ok(2),
            |_| {
                tries += 1;
                Err::<(), _>(ExperimentError::Incomplete("refused".into()))
            },
        )
        .unwrap_err();
        assert!(matches!(err, ExperimentError::Incomplete(_)));
        assert_eq!(tries, 1);
    }

    #[test]
    fn a_killed_world_process_is_reported_dead_with_its_signal() {
        let p = SimProcess::spawn(shell("echo 'listening on 127.0.0.1:1'; exec sleep 30")).unwrap();
        assert_eq!(p.exited(Duration::ZERO), None);
        let pid = lock(&p.child).id();
        let killed = Command::new("kill")
            .args(["-KILL", &pid.to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let status = p.exited(Duration::from_secs(30)).expect("dead").to_string();
        assert!(status.contains("SIGKILL"), "{status}");
    }

    #[test]
    fn the_first_error_stops_the_pool() {
        let jobs: Vec<usize> = (0..50).collect();
        let ran = AtomicUsize::new(0);
        let err = run_jobs(
            &jobs,
            2,
            || Ok(()),
            |job, _: &mut ()| {
                ran.fetch_add(1, Ordering::SeqCst);
                if *job == 3 {
                    Err(ExperimentError::JobLost { index: 3 })
                } else {
                    Ok(())
                }
            },
            |_| {},
        )
        .unwrap_err();
        assert!(matches!(err, ExperimentError::JobLost { index: 3 }));
        assert!(ran.load(Ordering::SeqCst) < 50);
        let err = run_jobs(
            &jobs,
            2,
            || Err::<(), _>(ExperimentError::JobLost { index: 9 }),
            |_, _| Ok(()),
            |_| {},
        );
        assert!(matches!(err, Err(ExperimentError::JobLost { index: 9 })));
    }
}
