//! `pushlearn reproduce`: every experiment behind `docs/results.md`, its
//! documents, figures and the page itself, regenerated — or checked against
//! the committed ones.

use std::cell::RefCell;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use pushlearn_cli::experiment::workers::{find_sim_binary, kill_all_worlds, Worlds};
use pushlearn_cli::models::named;
use pushlearn_cli::reproduce::compare::{first_json_difference, first_line_difference};
use pushlearn_cli::reproduce::{
    self, manifest, page, Progress, Reproduction, Settings, FIGURES_DIR, PAGE, QUICK_DIR,
    RESULTS_DIR, TEMPLATE, TIMING,
};

/// Regenerate docs/results.md, its documents (docs/results/*.json) and its
/// figures (docs/figures/) from scratch, or check that the committed ones
/// still match the code.
///
/// Runs the calibration sweep and every experiment the page reports (both
/// models' learning curves with the default latency, with the harsher
/// L_max = 5 and in lock-step; four more seeds for the targets; fixed
/// three; two objects; constant feedback; Move to Target; the draft's
/// tables and selectors), in one process. Experiments on the same world
/// share recorded runs, so each distinct run is simulated once. The
/// documents leave out what depends on the machine (wall and handling
/// times, which go to docs/results/timing.md), so two runs write the same
/// bytes. The page is docs/results/template.md with its placeholders
/// filled from the documents.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  \
    pushlearn reproduce                    regenerate everything (a few minutes on 2 cores)\n  \
    pushlearn reproduce --check            fail, naming the first differing value, if the committed results are stale\n  \
    pushlearn reproduce --quick --check    the reduced check CI runs (docs/results/quick/)\n  \
    pushlearn reproduce --quick            regenerate docs/results/quick/ after a change that moves a number\n  \
    pushlearn reproduce --only 'beyond-*'  rerun the \"Beyond the thesis\" experiments, the rest from the committed documents")]
pub struct ReproduceArgs {
    /// The reduced reproduction (2 folds, fewer training runs, 1 Move to
    /// Target repetition) into docs/results/quick/: no figures, no page.
    #[arg(long)]
    quick: bool,

    /// Run no experiment: regenerate docs/results.md and its figures from
    /// the committed documents (after editing docs/results/template.md);
    /// with --check, check the page against them.
    #[arg(long, conflicts_with = "quick")]
    page_only: bool,

    /// Regenerate into memory and compare with the committed files instead
    /// of writing; fails, naming each stale file's first differing value.
    #[arg(long)]
    check: bool,

    /// Run only these experiments (document names without `.json`,
    /// comma-separated; a trailing `*` matches every name with that
    /// prefix) and take every other document the page needs from the
    /// committed ones: for a change that moves only some numbers. Writes
    /// only their documents, the page and its figures; timing.md keeps the
    /// last full run's lines (this run's are printed).
    #[arg(long, value_name = "NAME,…", value_delimiter = ',', conflicts_with_all = ["quick", "page_only"])]
    only: Vec<String>,

    /// The repository root [default: the current directory].
    #[arg(long, value_name = "DIR", default_value = ".")]
    root: PathBuf,

    /// Worlds (workers) in parallel [default: the number of CPUs]; with
    /// embedded worlds, a built-in model's jobs run in as many worker
    /// processes.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    workers: Option<u32>,

    /// Where the experiments' worlds run; the documents are the same bit
    /// for bit either way.
    #[arg(long, value_parser = named::<Worlds>(), default_value = "embedded")]
    world: Worlds,

    /// The world daemon binary, for the calibration sweep, the sweeps and
    /// --world spawn [default: $PUSHLEARN_SIM_BIN, else `pushlearn-sim` next
    /// to this executable, else on PATH: docs/simulator.md].
    #[arg(long, value_name = "PATH")]
    sim_bin: Option<PathBuf>,

    /// Keep the sweeps' job outputs in DIR/NAME (DIR/ablation) instead of
    /// a temporary directory removed afterwards: an interrupted
    /// reproduction continues the sweep where it stopped, and a sweep run
    /// elsewhere (`pushlearn sweep run|slurm sweeps/ablation.toml --out
    /// DIR/ablation`) is merged instead of run again. Jobs already there
    /// are taken as they are: run them with this version.
    #[arg(long, value_name = "DIR")]
    sweep_dir: Option<PathBuf>,
}

/// Runs `pushlearn reproduce`.
/// The baselines are Python learners (`manifest::BASELINES`): with the
/// repository's virtual environment (`.venv`, made by
/// `scripts/ensure-deps.sh --test`, the package installed into it) first on
/// PATH, their `python3` is the one that has the package. Called before any
/// thread starts.
fn use_repository_python(root: &std::path::Path) {
    let bin = root.join(".venv").join("bin");
    if !bin.join("python3").is_file() {
        return;
    }
    let mut paths = vec![bin];
    if let Some(old) = std::env::var_os("PATH") {
        paths.extend(std::env::split_paths(&old));
    }
    if let Ok(joined) = std::env::join_paths(paths) {
        std::env::set_var("PATH", joined);
    }
}

pub fn run(args: ReproduceArgs) -> Result<()> {
    super::experiment::end_worlds_on_signal();
    let root = &args.root;
    let template_path = root.join(TEMPLATE);
    let template = if args.quick {
        None
    } else {
        Some(std::fs::read_to_string(&template_path).with_context(|| {
            format!(
                "cannot read the page's template {}; run from the repository root or pass --root",
                template_path.display()
            )
        })?)
    };
    if !root.join("docs").is_dir() {
        bail!(
            "{} has no docs/ directory; run from the repository root or pass --root",
            root.display()
        );
    }
    let entries = if args.quick {
        manifest::quick()
    } else {
        manifest::full()
    };
    let sweeps = manifest::sweeps(args.quick);
    let dir = root.join(if args.quick { QUICK_DIR } else { RESULTS_DIR });
    if !args.page_only {
        use_repository_python(root);
    }
    let chosen = chosen_entries(&entries, &sweeps, &args.only)?;
    let command = if args.quick {
        "pushlearn reproduce --quick".to_owned()
    } else if args.page_only {
        "pushlearn reproduce --page-only".to_owned()
    } else if chosen.is_some() {
        format!("pushlearn reproduce --only {}", args.only.join(","))
    } else {
        "pushlearn reproduce".to_owned()
    };
    // With --only, the timing of what ran (the loaded documents have none).
    let mut only_timing = None;
    let results = if args.page_only {
        reproduce::load(&entries, &sweeps, &dir)?
    } else {
        let cpus = std::thread::available_parallelism().map_or(1, usize::from);
        let workers = args.workers.map_or(cpus, |n| n as usize);
        let settings = Settings {
            sim_bin: find_sim_binary(args.sim_bin.as_deref())?,
            workers,
            worlds: args.world,
            processes: Some(super::experiment::worker_processes(workers)?),
        };
        let run_all = |entries: &[manifest::Entry], sweeps: &[manifest::SweepEntry]| {
            let mut ran = run_with_bars(entries, &settings)?;
            for sweep in sweeps {
                let swept = run_sweep(root, sweep, args.sweep_dir.as_deref(), &settings)?;
                ran.wall_seconds += swept.timing.map_or(0.0, |t| t.wall_seconds);
                ran.sweeps.push(swept);
            }
            anyhow::Ok(ran)
        };
        match &chosen {
            None => run_all(&entries, &sweeps)?,
            Some(chosen) => {
                let ran = run_all(&chosen.entries, &chosen.sweeps)?;
                only_timing = Some(ran.timing_page(&command));
                let others: Vec<manifest::Entry> = entries
                    .iter()
                    .filter(|e| !chosen.entries.contains(e))
                    .cloned()
                    .collect();
                let other_sweeps: Vec<manifest::SweepEntry> = sweeps
                    .iter()
                    .filter(|s| !chosen.sweeps.contains(s))
                    .cloned()
                    .collect();
                let loaded = reproduce::load(&others, &other_sweeps, &dir)?;
                reproduce::merge(&entries, &sweeps, ran, loaded)
            }
        }
    };
    let page = template.map(|t| page::generate(&t, &results)).transpose()?;
    // What this run ran: everything, or with --only the chosen entries.
    let ran: Vec<&reproduce::Produced> = results
        .produced
        .iter()
        .filter(|p| chosen.as_ref().is_none_or(|c| c.entries.contains(&p.entry)))
        .collect();
    let states: u64 = ran
        .iter()
        .flat_map(|p| p.document.runs())
        .map(|r| r.messages)
        .sum();
    if args.page_only {
        if args.check {
            check(root, &dir, None, false, page.as_deref())?;
            println!(
                "{command} --check: {PAGE} matches {TEMPLATE} and the documents in {RESULTS_DIR}"
            );
            return Ok(());
        }
        let figures = match &page {
            Some(page) => {
                let figures = draw_figures(root, &results, page)?;
                reproduce::write_atomically(&root.join(PAGE), page)?;
                figures
            }
            None => 0,
        };
        println!(
            "{command}: wrote {} and {figures} figures from the {} documents in {}",
            root.join(PAGE).display(),
            results.produced.len() + results.sweeps.len() + 1,
            dir.display()
        );
        return Ok(());
    }
    let mut files = results.files()?;
    if let Some(chosen) = &chosen {
        // Only what this run produced: the other documents are the
        // committed ones, read back, and stay as they are.
        files.retain(|(name, _)| {
            let name = name.strip_suffix(".json");
            chosen.entries.iter().any(|e| name == Some(e.name.as_str()))
                || chosen.sweeps.iter().any(|s| name == Some(s.name))
        });
    }
    if args.check {
        check(root, &dir, Some(&files), chosen.is_none(), page.as_deref())?;
        println!(
            "{command} --check: {} documents{} match the code ({} experiments, {states} messages, {:.1} s)",
            files.len(),
            if page.is_some() { " and the page" } else { "" },
            ran.len(),
            results.wall_seconds
        );
        return Ok(());
    }
    reproduce::write_files(&dir, &files)?;
    let timing = match only_timing {
        None => {
            // The other documents are only stale after a whole run.
            for stale in stale_documents(&dir, &files)? {
                std::fs::remove_file(&stale)
                    .with_context(|| format!("removing the stale {}", stale.display()))?;
                eprintln!(
                    "removed {}: no experiment produces it any more",
                    stale.display()
                );
            }
            results.timing_page(&command)
        }
        Some(timing) => {
            print!("{timing}");
            // timing.md keeps the last full run's lines and, after them,
            // the last --only run's (replacing an earlier one).
            let old = std::fs::read_to_string(dir.join(TIMING)).unwrap_or_default();
            let full = old.split(ONLY_TIMING_MARK).next().unwrap_or_default();
            format!("{}\n{ONLY_TIMING_MARK}\n\n{timing}", full.trim_end())
        }
    };
    reproduce::write_atomically(&dir.join(TIMING), &timing)?;
    let mut figures = 0;
    if let Some(page) = &page {
        figures = draw_figures(root, &results, page)?;
        reproduce::write_atomically(&root.join(PAGE), page)?;
    }
    println!(
        "{command}: {} experiments, {states} messages, in {:.1} s; wrote {} documents to {}{}{}",
        ran.len(),
        results.wall_seconds,
        files.len(),
        dir.display(),
        if figures > 0 {
            format!(
                ", {figures} figures to {}",
                root.join(FIGURES_DIR).display()
            )
        } else {
            String::new()
        },
        if page.is_some() {
            format!(" and {}", root.join(PAGE).display())
        } else {
            String::new()
        }
    );
    Ok(())
}

/// Draws the figures of the experiments that have them and keeps those the
/// page shows (`figures/NAME.png`) in docs/figures/, replacing the old ones;
/// a figure the page shows that no experiment draws is an error.
/// The baselines' learning curves beside the thesis's models.
const BASELINE_FIGURE: &str = "baselines-curve";
/// Where timing.md's lines of the last `--only` run begin.
const ONLY_TIMING_MARK: &str = "<!-- the last `pushlearn reproduce --only` run -->";

/// The learning curves of every model of "Beyond the thesis".
const BEYOND_FIGURE: &str = "beyond-curves";

/// The ablation sweep's errors, configuration by training runs.
const ABLATION_FIGURE: &str = "ablation";

/// The new-object experiments' errors, learner by condition.
const OBJECTS_FIGURE: &str = "beyond-objects";

fn draw_figures(root: &Path, results: &Reproduction, page: &str) -> Result<usize> {
    let figure_dir = root.join(FIGURES_DIR);
    let scratch = figure_dir.join(".reproduce");
    if scratch.exists() {
        std::fs::remove_dir_all(&scratch)
            .with_context(|| format!("removing {}", scratch.display()))?;
    }
    std::fs::create_dir_all(&scratch).with_context(|| format!("creating {}", scratch.display()))?;
    for p in results.produced.iter().filter(|p| p.entry.figures) {
        p.document
            .plot(&scratch)
            .with_context(|| format!("drawing the figures of {}", p.entry.name))?;
    }
    // Figures across documents: the §3 curves redrawn with the reference
    // rows, the baselines beside the thesis's models, and every model of
    // "Beyond the thesis" on one plot.
    if let Ok(curves) = page::curves_and_references(results) {
        for (model, report, references) in curves {
            pushlearn_cli::experiments::push_task::figures::curves_with_references(
                report,
                model,
                &references,
                &scratch,
            )
            .with_context(|| format!("drawing the {model} model's curves with the references"))?;
        }
    }
    if let Ok(curves) = page::baseline_curves(results) {
        pushlearn_cli::report::plot::learners(&curves, &scratch, BASELINE_FIGURE)
            .context("drawing the baselines' figure")?;
    }
    if let Ok(curves) = page::beyond_curves(results) {
        pushlearn_cli::report::plot::learners(&curves, &scratch, BEYOND_FIGURE)
            .context("drawing the figure of \"Beyond the thesis\"")?;
    }
    if let Some(summary) = results.sweep(manifest::ABLATION) {
        pushlearn_cli::sweep::figure::ablation(summary, &scratch, ABLATION_FIGURE)
            .context("drawing the ablation's figure")?;
    }
    if let Ok((conditions, rows)) = page::object_reports(results) {
        pushlearn_cli::report::plot::by_condition(&conditions, &rows, &scratch, OBJECTS_FIGURE)
            .context("drawing the new objects' figure")?;
    }
    let mut shown: Vec<&str> = page
        .match_indices("](figures/")
        .filter_map(|(at, _)| {
            let name = &page[at + "](figures/".len()..];
            name.find(')').map(|end| &name[..end])
        })
        .filter(|name| name.ends_with(".png"))
        .collect();
    shown.sort_unstable();
    shown.dedup();
    for name in &shown {
        let drawn = scratch.join(name);
        if !drawn.is_file() {
            bail!("{PAGE} shows figures/{name}, which no experiment of the reproduction draws");
        }
        std::fs::rename(&drawn, figure_dir.join(name))
            .with_context(|| format!("moving figures/{name} into place"))?;
    }
    std::fs::remove_dir_all(&scratch).with_context(|| format!("removing {}", scratch.display()))?;
    Ok(shown.len())
}

/// What `--only` chose.
#[derive(Debug)]
struct Chosen {
    entries: Vec<manifest::Entry>,
    sweeps: Vec<manifest::SweepEntry>,
}

/// The experiments and sweeps `--only` names, in the manifest's order;
/// `None` without `--only`. A pattern that matches nothing is an error
/// listing the names.
fn chosen_entries(
    entries: &[manifest::Entry],
    sweeps: &[manifest::SweepEntry],
    patterns: &[String],
) -> Result<Option<Chosen>> {
    if patterns.is_empty() {
        return Ok(None);
    }
    let matches = |pattern: &str, name: &str| match pattern.strip_suffix('*') {
        Some(prefix) => name.starts_with(prefix),
        None => name == pattern,
    };
    let names = || {
        entries
            .iter()
            .map(|e| e.name.as_str())
            .chain(sweeps.iter().map(|s| s.name))
    };
    for pattern in patterns {
        if !names().any(|name| matches(pattern, name)) {
            bail!(
                "--only {pattern}: no experiment or sweep of the reproduction is called that; they are: {}",
                names().collect::<Vec<_>>().join(", ")
            );
        }
    }
    let chosen = |name: &str| patterns.iter().any(|p| matches(p, name));
    Ok(Some(Chosen {
        entries: entries
            .iter()
            .filter(|e| chosen(&e.name))
            .cloned()
            .collect(),
        sweeps: sweeps.iter().filter(|s| chosen(s.name)).cloned().collect(),
    }))
}

/// Runs `sweep`'s jobs as `pushlearn sweep run` does, in `sweep_dir/NAME`
/// (kept, and what is done there is not run again) or a temporary
/// directory (removed afterwards), and keeps its merged summary.
fn run_sweep(
    root: &Path,
    sweep: &manifest::SweepEntry,
    sweep_dir: Option<&Path>,
    settings: &Settings,
) -> Result<reproduce::Swept> {
    let file = root.join(sweep.file);
    let (dir, temporary) = match sweep_dir {
        Some(dir) => (dir.join(sweep.name), false),
        None => (
            std::env::temp_dir().join(format!(
                "pushlearn-reproduce-{}-{}",
                sweep.name,
                std::process::id()
            )),
            true,
        ),
    };
    eprintln!(
        "reproduce: the sweep {} ({}) in {} …",
        sweep.name,
        sweep.file,
        dir.display()
    );
    let worlds = match settings.worlds {
        Worlds::Embedded => super::sweep::JobWorlds::Embedded,
        Worlds::Spawn => super::sweep::JobWorlds::Spawn(settings.sim_bin.clone()),
    };
    let run = super::sweep::run_and_merge(&file, &dir, settings.workers, &worlds)
        .with_context(|| format!("the sweep {} ({})", sweep.name, sweep.file));
    if temporary {
        // Kept only on purpose (--sweep-dir); a failed run's half is of no
        // use to a next run that starts afresh anyway.
        let _ = std::fs::remove_dir_all(&dir);
    }
    let run = run?;
    Ok(reproduce::Swept {
        entry: sweep.clone(),
        summary: run.summary,
        timing: Some(reproduce::SweepTiming {
            jobs: run.jobs,
            ran: run.ran,
            wall_seconds: run.seconds,
            workers: settings.workers,
        }),
    })
}

/// Runs the reproduction with one progress bar per experiment (on stderr,
/// when it is a terminal).
fn run_with_bars(entries: &[manifest::Entry], settings: &Settings) -> Result<Reproduction> {
    let terminal = std::io::stderr().is_terminal();
    let bars = if terminal {
        MultiProgress::new()
    } else {
        MultiProgress::with_draw_target(ProgressDrawTarget::hidden())
    };
    let style = ProgressStyle::with_template(
        "{prefix:>34} {wide_bar} {pos}/{len} jobs [{elapsed_precise}]",
    )
    .ok();
    let current: RefCell<Option<ProgressBar>> = RefCell::new(None);
    let total = bars.add(ProgressBar::new(entries.len() as u64));
    if let Ok(style) = ProgressStyle::with_template(
        "{prefix:>34} {wide_bar} {pos}/{len} experiments [{elapsed_precise}]",
    ) {
        total.set_style(style);
    }
    total.set_prefix("pushlearn reproduce");
    let result = reproduce::run(entries, settings, |event| match event {
        Progress::Started { entry, jobs } => {
            if !terminal {
                // Logs get one line per experiment instead of bars.
                let plural = if jobs == 1 { "" } else { "s" };
                eprintln!("reproduce: {} ({jobs} job{plural}) …", entry.name);
            }
            let bar = bars.insert_before(&total, ProgressBar::new(jobs as u64));
            if let Some(style) = &style {
                bar.set_style(style.clone());
            }
            bar.set_prefix(entry.name.clone());
            *current.borrow_mut() = Some(bar);
        }
        Progress::Jobs { done, .. } => {
            if let Some(bar) = current.borrow().as_ref() {
                bar.set_position(done as u64);
            }
        }
        Progress::Finished { .. } => {
            if let Some(bar) = current.borrow_mut().take() {
                bar.finish();
            }
            total.inc(1);
        }
    });
    total.finish_and_clear();
    if result.is_err() {
        kill_all_worlds();
    }
    Ok(result?)
}

/// Compares the regenerated files with the committed ones; fails naming
/// every stale file and its first differing value. `files` is `None` when
/// no document was regenerated (`--page-only`); `whole` when every
/// experiment ran, so that a committed document none wrote is stale.
fn check(
    root: &Path,
    dir: &Path,
    files: Option<&[(String, String)]>,
    whole: bool,
    page: Option<&str>,
) -> Result<()> {
    let mut problems = Vec::new();
    for (name, now) in files.unwrap_or_default() {
        let path = dir.join(name);
        match std::fs::read_to_string(&path) {
            Err(e) => problems.push(format!(
                "{}: cannot read the committed file: {e}",
                path.display()
            )),
            Ok(committed) if committed == *now => {}
            Ok(committed) => match first_json_difference(&committed, now) {
                Ok(Some(difference)) => problems.push(format!("{}: {difference}", path.display())),
                Ok(None) => problems.push(format!(
                    "{}: same values, different bytes (regenerate it)",
                    path.display()
                )),
                Err(e) => problems.push(format!("{}: {e}", path.display())),
            },
        }
    }
    let stale = match files {
        Some(files) if whole => stale_documents(dir, files)?,
        _ => Vec::new(),
    };
    for stale in stale {
        problems.push(format!(
            "{}: committed, but no experiment produces it any more",
            stale.display()
        ));
    }
    if let Some(page) = page {
        let path = root.join(PAGE);
        match std::fs::read_to_string(&path) {
            Err(e) => problems.push(format!(
                "{}: cannot read the committed page: {e}",
                path.display()
            )),
            Ok(committed) => {
                if let Some(difference) = first_line_difference(&committed, page) {
                    problems.push(format!("{}: {difference}", path.display()));
                }
            }
        }
    }
    if problems.is_empty() {
        return Ok(());
    }
    bail!(
        "the committed results no longer match the code ({} stale):\n  {}\nregenerate them with `pushlearn reproduce{}` and commit the result",
        problems.len(),
        problems.join("\n  "),
        if dir.ends_with("quick") { " --quick" } else { "" }
    )
}

/// JSON files in `dir` that the reproduction does not write.
fn stale_documents(dir: &Path, files: &[(String, String)]) -> Result<Vec<PathBuf>> {
    let mut stale = Vec::new();
    let listing = match std::fs::read_dir(dir) {
        Ok(listing) => listing,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(stale),
        Err(e) => return Err(e).with_context(|| format!("listing {}", dir.display())),
    };
    for item in listing {
        let path = item
            .with_context(|| format!("listing {}", dir.display()))?
            .path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        if path.extension().is_some_and(|e| e == "json") && !files.iter().any(|(f, _)| f == name) {
            stale.push(path);
        }
    }
    stale.sort();
    Ok(stale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_picks_names_and_prefixes_in_the_manifests_order_and_refuses_unknown_ones() {
        let entries = manifest::full();
        let sweeps = manifest::sweeps(false);
        assert!(chosen_entries(&entries, &sweeps, &[]).unwrap().is_none());
        let picked = chosen_entries(
            &entries,
            &sweeps,
            &["beyond-sampled-*".to_owned(), "push-task-gate".to_owned()],
        )
        .unwrap()
        .unwrap();
        assert!(picked.sweeps.is_empty());
        let names: Vec<&str> = picked.entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "push-task-gate",
                "beyond-sampled-gate",
                "beyond-sampled-gate-plus",
                "beyond-sampled-hybrid"
            ]
        );
        let error = chosen_entries(&entries, &sweeps, &["beyond-typo".to_owned()])
            .unwrap_err()
            .to_string();
        assert!(error.contains("--only beyond-typo") && error.contains("beyond-push-gate-plus"));
        assert!(error.contains("ablation"), "{error}");
        let ablation = chosen_entries(&entries, &sweeps, &["ablation".to_owned()])
            .unwrap()
            .unwrap();
        assert!(ablation.entries.is_empty());
        assert_eq!(ablation.sweeps, sweeps);
    }
}
