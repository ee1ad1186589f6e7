//! `pushlearn reproduce`: every experiment behind `docs/results.md` run in
//! one process, their documents written without machine-dependent numbers
//! (so two runs give the same bytes), the figures drawn, and the page
//! generated from the documents and a hand-written template.
//!
//! * [`manifest`]: which experiments, with their stand-alone commands;
//! * [`calibration`]: the world's calibration sweep, run by `pushlearn-sim`;
//! * [`page`]: the results page from the template and the documents;
//! * [`compare`]: the first value in which two documents differ (`--check`).
//!
//! Experiments on the same world (scene, mode, latency maximum) share one
//! [`RunCache`]: the push task's runs do not depend on the model, so both
//! models' curves simulate each run once.

pub mod calibration;
pub mod compare;
pub mod manifest;
pub mod page;

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use crate::args::{ArgsError, WorldArgs};
use crate::spec::{Document, SpecError};
use crate::sweep::summary::Summary;
use calibration::CalibrationRow;
use drive::experiment::processes::Processes;
use drive::experiment::run_cache::RunCache;
use drive::experiment::workers::Worlds;
use drive::experiment::Mode;
use drive::results::run_info::RunTiming;
use manifest::{Entry, SweepEntry};

/// Where the committed results live, relative to the repository root.
pub const RESULTS_DIR: &str = "docs/results";
/// The reduced results CI checks, relative to the repository root.
pub const QUICK_DIR: &str = "docs/results/quick";
/// The figures of the full reproduction.
pub const FIGURES_DIR: &str = "docs/figures";
/// The hand-written prose the page is generated from.
pub const TEMPLATE: &str = "docs/results/template.md";
/// The generated page.
pub const PAGE: &str = "docs/results.md";
/// The calibration sweep's document.
pub const CALIBRATION: &str = "calibration.json";
/// The machine-dependent numbers of the last run (not checked).
pub const TIMING: &str = "timing.md";

/// Why a reproduction failed.
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    #[error("{name}: {source}")]
    Experiment {
        name: String,
        #[source]
        source: SpecError,
    },
    #[error(transparent)]
    Calibration(#[from] calibration::CalibrationError),
    #[error(transparent)]
    Page(#[from] page::PageError),
    #[error("cannot write {path}: {source}")]
    Write {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "cannot read the document {path}: {reason} (run `pushlearn reproduce` to regenerate it)"
    )]
    Load { path: String, reason: String },
    #[error("cannot serialise {name}: {source}")]
    Json {
        name: String,
        #[source]
        source: serde_json::Error,
    },
}

/// What one experiment of a reproduction produced.
#[derive(Debug)]
pub struct Produced {
    pub entry: Entry,
    /// The document without its machine-dependent part.
    pub document: Document,
    /// That part of each of its runs (the draft's tables have one per
    /// row): wall time, handling times, states simulated.
    pub timing: Vec<RunTiming>,
}

/// What one sweep of a reproduction produced.
#[derive(Debug)]
pub struct Swept {
    pub entry: SweepEntry,
    pub summary: Summary,
    /// How it ran, when it did (a document read back has none).
    pub timing: Option<SweepTiming>,
}

/// A sweep's run: machine-dependent, so only in timing.md.
#[derive(Clone, Copy, Debug)]
pub struct SweepTiming {
    /// Jobs in the plan.
    pub jobs: usize,
    /// Of them, run by this reproduction (the rest had their output in the
    /// sweep directory already).
    pub ran: usize,
    pub wall_seconds: f64,
    pub workers: usize,
}

/// The documents of a whole reproduction.
#[derive(Debug)]
pub struct Reproduction {
    pub calibration: Vec<CalibrationRow>,
    pub produced: Vec<Produced>,
    pub sweeps: Vec<Swept>,
    pub wall_seconds: f64,
}

impl Reproduction {
    /// The summary of the sweep named `name`, if the reproduction has it.
    #[must_use]
    pub fn sweep(&self, name: &str) -> Option<&Summary> {
        self.sweeps
            .iter()
            .find(|s| s.entry.name == name)
            .map(|s| &s.summary)
    }

    /// The document named `name`, if the reproduction made one.
    #[must_use]
    pub fn document(&self, name: &str) -> Option<&Document> {
        self.produced
            .iter()
            .find(|p| p.entry.name == name)
            .map(|p| &p.document)
    }

    /// Every file the reproduction writes into its results directory, by
    /// name, with its bytes: the documents and the calibration sweep.
    ///
    /// # Errors
    /// A document cannot be serialised.
    pub fn files(&self) -> Result<Vec<(String, String)>, ReproduceError> {
        let mut files = vec![(
            CALIBRATION.to_owned(),
            calibration::to_json(&self.calibration).map_err(|source| ReproduceError::Json {
                name: CALIBRATION.into(),
                source,
            })?,
        )];
        for p in &self.produced {
            let text = p
                .document
                .to_json()
                .map_err(|source| ReproduceError::Json {
                    name: p.entry.name.clone(),
                    source,
                })?;
            files.push((format!("{}.json", p.entry.name), text));
        }
        for swept in &self.sweeps {
            let text = swept
                .summary
                .to_json()
                .map_err(|source| ReproduceError::Json {
                    name: swept.entry.name.to_owned(),
                    source,
                })?;
            files.push((format!("{}.json", swept.entry.name), text));
        }
        Ok(files)
    }

    /// The machine-dependent numbers, as a Markdown page: wall time and
    /// handling times per experiment, and the states the worlds simulated
    /// against the states the drivers saw.
    #[must_use]
    pub fn timing_page(&self, command: &str) -> String {
        let mut page = String::new();
        let _ = writeln!(page, "# Timing of the last `{command}`\n");
        let _ = writeln!(
            page,
            "Machine-dependent, so kept out of the checked documents; rewritten by every run.\n"
        );
        if !self.produced.is_empty() {
            let _ = writeln!(
                page,
                "| Experiment | Messages | Simulated states | ODE per state [µs] | Floor [s] | Wall [s] | Wall / floor | Handling p50 / p99 [µs] | Max [ms] | Over budget |"
            );
            let _ = writeln!(page, "|---|---|---|---|---|---|---|---|---|---|");
        }
        let (mut messages, mut simulated, mut wall) = (0u64, 0u64, 0.0);
        // The physics measured in the embedded worlds: states, and the
        // floor they imply with every worker's core stepping.
        let cores = std::thread::available_parallelism().map_or(1, usize::from);
        let (mut measured_states, mut physics_seconds, mut floor) = (0u64, 0.0, 0.0);
        let waited: f64 = self
            .produced
            .iter()
            .flat_map(|p| &p.timing)
            .filter_map(|t| t.physics_wait_seconds)
            .sum();
        for p in &self.produced {
            let run = p.document.runs();
            let m: u64 = run.iter().map(|r| r.messages).sum();
            let sim: u64 = p.timing.iter().map(|t| t.simulated_states).sum();
            let w: f64 = p.timing.iter().map(|t| t.wall_seconds).sum();
            let p50 = p
                .timing
                .iter()
                .map(|t| t.p50_handling_us)
                .fold(0.0, f64::max);
            let p99 = p
                .timing
                .iter()
                .map(|t| t.p99_handling_us)
                .fold(0.0, f64::max);
            let max = p
                .timing
                .iter()
                .map(|t| t.max_handling_ms)
                .fold(0.0, f64::max);
            let slow: u64 = p.timing.iter().map(|t| t.too_slow).sum();
            let measured = Floor::of(&p.timing, cores);
            messages += m;
            simulated += sim;
            wall += w;
            let (cost, its_floor, ratio) = match measured {
                Some(f) => {
                    measured_states += f.states;
                    physics_seconds += f.physics_seconds;
                    floor += f.floor_seconds;
                    (
                        format!("{:.1}", f.physics_seconds / f.states as f64 * 1e6),
                        format!("{:.1}", f.floor_seconds),
                        format!("{:.2}", w / f.floor_seconds),
                    )
                }
                None => ("–".into(), "–".into(), "–".into()),
            };
            let _ = writeln!(
                page,
                "| {} | {m} | {sim} | {cost} | {its_floor} | {w:.1} | {ratio} | {p50:.1} / {p99:.1} | {max:.2} | {slow} |",
                p.entry.name
            );
        }
        if self.sweeps.iter().any(|s| s.timing.is_some()) {
            let _ = writeln!(
                page,
                "\n| Sweep | File | Jobs | Run now | Worlds | Wall [s] |\n|---|---|---|---|---|---|"
            );
        }
        for swept in &self.sweeps {
            if let Some(t) = swept.timing {
                let _ = writeln!(
                    page,
                    "| {} | `{}` | {} | {} | {} | {:.1} |",
                    swept.entry.name, swept.entry.file, t.jobs, t.ran, t.workers, t.wall_seconds
                );
            }
        }
        let _ = write!(
            page,
            "\n{messages} messages handled, {simulated} world states simulated ({:.0} % of them; the rest \
             replayed from recorded runs). ",
            if messages == 0 {
                0.0
            } else {
                100.0 * simulated as f64 / messages as f64
            },
        );
        if measured_states > 0 {
            let _ = write!(
                page,
                "The embedded worlds stepped {measured_states} states at {:.1} µs of physics each \
                 (measured in this run): {physics_seconds:.1} s of physics, a floor of {floor:.1} s \
                 on this machine's {cores} cores. Their steps waited {waited:.1} s in all for each \
                 other's (ODE steps one world at a time per process). ",
                physics_seconds / measured_states as f64 * 1e6,
            );
        } else {
            let _ = write!(
                page,
                "The worlds ran behind sockets, so their physics was not measured (`--world embedded` measures it). "
            );
        }
        let _ = writeln!(
            page,
            "The experiments took {wall:.1} s{}, the whole reproduction {:.1} s of wall time.",
            if floor > 0.0 {
                format!(" ({:.2} × the floor)", wall / floor)
            } else {
                String::new()
            },
            self.wall_seconds
        );
        page
    }
}

/// The physics an experiment's embedded worlds measured, and the floor it
/// implies: each state's physics once, spread over the machine's cores.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Floor {
    /// Simulated states whose physics was measured.
    states: u64,
    /// Their physics, seconds.
    physics_seconds: f64,
    /// The wall time that physics needs on the machine's cores, seconds.
    floor_seconds: f64,
}

impl Floor {
    /// `None` if no run measured its physics (worlds behind sockets).
    fn of(runs: &[RunTiming], cores: usize) -> Option<Floor> {
        let mut floor = Floor {
            states: 0,
            physics_seconds: 0.0,
            floor_seconds: 0.0,
        };
        for run in runs {
            let Some(us) = run.physics_us_per_state else {
                continue;
            };
            let seconds = run.simulated_states as f64 * us * 1e-6;
            floor.states += run.simulated_states;
            floor.physics_seconds += seconds;
            floor.floor_seconds += seconds / cores.max(1) as f64;
        }
        (floor.states > 0 && floor.floor_seconds > 0.0).then_some(floor)
    }
}

/// How to run a reproduction.
#[derive(Clone, Debug)]
pub struct Settings {
    /// The `pushlearn-sim` binary.
    pub sim_bin: PathBuf,
    /// Worlds (workers) per experiment.
    pub workers: usize,
    /// Where the experiments' worlds run.
    pub worlds: Worlds,
    /// Worker processes for embedded worlds (`drive::experiment::processes`).
    pub processes: Option<Arc<Processes>>,
}

/// Progress of a reproduction, for bars.
#[derive(Clone, Copy, Debug)]
pub enum Progress<'a> {
    /// `entry` starts; it has `jobs` jobs.
    Started { entry: &'a Entry, jobs: usize },
    /// `done` of its jobs are done.
    Jobs { entry: &'a Entry, done: usize },
    /// It finished.
    Finished { entry: &'a Entry },
}

/// Runs the calibration sweep and every entry, in order; entries on the
/// same world share recorded runs.
///
/// # Errors
/// The first experiment that fails, named.
pub fn run(
    entries: &[Entry],
    settings: &Settings,
    progress: impl Fn(Progress<'_>),
) -> Result<Reproduction, ReproduceError> {
    let started = Instant::now();
    let calibration = calibration::sweep(&settings.sim_bin)?;
    let mut caches: HashMap<(&'static str, Mode, u32), Arc<RunCache>> = HashMap::new();
    let mut produced = Vec::new();
    for entry in entries {
        let cache = caches.entry(entry.world_key()).or_default();
        // The command line's plan for the entry's command, with this
        // reproduction's worlds, workers and shared recorded runs.
        let world = WorldArgs {
            mode: entry.mode,
            latency_max: entry.latency_max,
            world: Some(settings.worlds),
            workers: Some(u32::try_from(settings.workers).unwrap_or(u32::MAX)),
            sim_bin: (settings.worlds == Worlds::Spawn).then(|| settings.sim_bin.clone()),
            sim: None,
            no_reuse: false,
            seed: entry.seed,
            json: None,
            plots: None,
            csv: None,
        };
        let processes = |_| Ok(settings.processes.clone());
        let mut plan = world.plan(entry.spec.scene(), &processes).map_err(|err| {
            ReproduceError::Experiment {
                name: entry.name.clone(),
                source: match err {
                    ArgsError::Worlds(err) => err.into(),
                    ArgsError::Spec(err) => err,
                    other => SpecError::Invalid(other.to_string()),
                },
            }
        })?;
        plan.runs = entry.mode.reuses_runs().then(|| Arc::clone(cache));
        progress(Progress::Started {
            entry,
            jobs: entry.spec.jobs(),
        });
        let document = entry
            .spec
            .clone()
            .validated()
            .map_err(|source| ReproduceError::Experiment {
                name: entry.name.clone(),
                source,
            })?
            .run(&plan, |done| progress(Progress::Jobs { entry, done }))
            .map_err(|source| ReproduceError::Experiment {
                name: entry.name.clone(),
                source,
            })?;
        progress(Progress::Finished { entry });
        let timing = document
            .runs()
            .into_iter()
            .filter_map(|r| r.timing.clone())
            .collect();
        produced.push(Produced {
            entry: entry.clone(),
            // The documents are the page's sources, checked byte for byte:
            // no machine-dependent timing, and no fold-level detail, which
            // is for users' own analysis of `--json` and would change (and
            // multiply the size of) every committed document.
            document: document.without_timing().without_folds(),
            timing,
        });
    }
    Ok(Reproduction {
        calibration,
        produced,
        sweeps: Vec::new(),
        wall_seconds: started.elapsed().as_secs_f64(),
    })
}

/// One reproduction of `entries` and `sweeps` from the documents `ran`
/// produced and the ones `loaded` read back, in the manifest's order; the
/// calibration and the wall time are `ran`'s.
#[must_use]
pub fn merge(
    entries: &[Entry],
    sweeps: &[SweepEntry],
    ran: Reproduction,
    loaded: Reproduction,
) -> Reproduction {
    let mut pool: Vec<Produced> = ran.produced.into_iter().chain(loaded.produced).collect();
    let mut produced = Vec::with_capacity(pool.len());
    for entry in entries {
        if let Some(at) = pool.iter().position(|p| p.entry.name == entry.name) {
            produced.push(pool.swap_remove(at));
        }
    }
    let mut pool: Vec<Swept> = ran.sweeps.into_iter().chain(loaded.sweeps).collect();
    let mut swept = Vec::with_capacity(pool.len());
    for entry in sweeps {
        if let Some(at) = pool.iter().position(|s| s.entry.name == entry.name) {
            swept.push(pool.swap_remove(at));
        }
    }
    Reproduction {
        calibration: ran.calibration,
        produced,
        sweeps: swept,
        wall_seconds: ran.wall_seconds,
    }
}

/// The reproduction whose documents are in `dir` (as [`Reproduction::files`]
/// wrote them), without running anything: for regenerating the page after
/// its template changed.
///
/// # Errors
/// A document is missing or unreadable, named.
pub fn load(
    entries: &[Entry],
    sweeps: &[SweepEntry],
    dir: &Path,
) -> Result<Reproduction, ReproduceError> {
    let read = |name: &str| {
        let path = dir.join(name);
        std::fs::read_to_string(&path).map_err(|e| ReproduceError::Load {
            path: path.display().to_string(),
            reason: e.to_string(),
        })
    };
    let calibration_text = read(CALIBRATION)?;
    let calibration =
        serde_json::from_str(&calibration_text).map_err(|e| ReproduceError::Load {
            path: dir.join(CALIBRATION).display().to_string(),
            reason: e.to_string(),
        })?;
    let mut produced = Vec::new();
    for entry in entries {
        let name = format!("{}.json", entry.name);
        let document = Document::from_json(&read(&name)?, &entry.spec).map_err(|reason| {
            ReproduceError::Load {
                path: dir.join(&name).display().to_string(),
                reason,
            }
        })?;
        produced.push(Produced {
            entry: entry.clone(),
            document,
            timing: Vec::new(),
        });
    }
    let mut swept = Vec::new();
    for entry in sweeps {
        let name = format!("{}.json", entry.name);
        let summary = serde_json::from_str(&read(&name)?).map_err(|e| ReproduceError::Load {
            path: dir.join(&name).display().to_string(),
            reason: e.to_string(),
        })?;
        swept.push(Swept {
            entry: entry.clone(),
            summary,
            timing: None,
        });
    }
    Ok(Reproduction {
        calibration,
        produced,
        sweeps: swept,
        wall_seconds: 0.0,
    })
}

/// Writes `files` into `dir` (created if needed), each through a
/// temporary name and a rename, so that an interrupted run leaves no half
/// file.
///
/// # Errors
/// A file cannot be written.
pub fn write_files(dir: &Path, files: &[(String, String)]) -> Result<(), ReproduceError> {
    std::fs::create_dir_all(dir).map_err(|source| ReproduceError::Write {
        path: dir.display().to_string(),
        source,
    })?;
    for (name, text) in files {
        write_atomically(&dir.join(name), text)?;
    }
    Ok(())
}

/// [`drive::output::write_atomically`], with the reproduction's error.
///
/// # Errors
/// The file cannot be written or renamed.
pub fn write_atomically(path: &Path, text: &str) -> Result<(), ReproduceError> {
    drive::output::write_atomically(path, text.as_bytes()).map_err(|source| ReproduceError::Write {
        path: path.display().to_string(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(simulated_states: u64, workers: usize, physics: Option<f64>) -> RunTiming {
        RunTiming {
            workers,
            simulated_states,
            physics_us_per_state: physics,
            ..RunTiming::default()
        }
    }

    #[test]
    fn the_floor_is_each_measured_states_physics_spread_over_the_cores() {
        let runs = [run(1_000, 2, Some(80.0)), run(500, 1, Some(100.0))];
        let floor = Floor::of(&runs, 2).expect("measured");
        assert_eq!(floor.states, 1_500);
        assert!((floor.physics_seconds - 0.13).abs() < 1e-12);
        assert!((floor.floor_seconds - 0.065).abs() < 1e-12);
        // Runs behind sockets measure nothing and add nothing.
        let mixed = [run(1_000, 2, Some(80.0)), run(9_000, 2, None)];
        assert_eq!(Floor::of(&mixed, 2), Floor::of(&mixed[..1], 2));
        assert_eq!(Floor::of(&[run(1_000, 2, None)], 2), None);
        assert_eq!(Floor::of(&[], 2), None);
    }
}
