//! Sweeps (`pushlearn sweep`, `docs/sweeps.md`): a grid of push-task
//! configurations × seeds × training-run counts × folds, written as data
//! (`sweep.toml`), planned into independent jobs — one fold of one
//! configuration each, with an id derived from its parameters — run here or
//! on a Slurm cluster, and merged into the reports `pushlearn experiment`
//! writes.
//!
//! * this module: the sweep file, its grid and its jobs ([`Sweep`]);
//! * [`output`]: a job's output file, written atomically, and the
//!   output directory's layout (what is done, what is missing);
//! * [`slurm`]: the `sbatch` job-array script;
//! * [`summary`]: the merged sweep as one table of errors per
//!   configuration, N_train and seed.
//!
//! A job's result depends only on its configuration, its seed and its
//! (N_train, fold) (`drive::experiment::seed`), so neither the order jobs run
//! in, nor the machine, nor which other jobs share a process changes it: the
//! merged reports of any way of running a plan are the same bytes.

pub mod figure;
pub mod output;
pub mod slurm;
pub mod summary;

use std::collections::BTreeSet;
use std::fmt::Write as _;

use drive::experiment::seed::name_hash;

/// The only experiment a sweep runs: its folds are what makes jobs.
pub const EXPERIMENT: &str = "push-task";

/// Options of `pushlearn experiment push-task` that a sweep sets itself, or
/// that name outputs or processes of one run, with what to do instead.
const RESERVED: [(&str, &str); 11] = [
    ("seed", "the sweep's top-level `seeds` list sets it"),
    ("folds", "the sweep's top-level `folds` sets it"),
    ("train-runs", "the sweep's top-level `train-runs` sets it"),
    ("json", "the sweep writes its own outputs (--out DIR)"),
    ("plots", "`pushlearn sweep merge` draws the figures"),
    ("csv", "`pushlearn sweep merge` writes the CSV files"),
    ("workers", "pass --workers to `pushlearn sweep run`"),
    (
        "sim-bin",
        "pass --sim-bin to `pushlearn sweep run` or `slurm`",
    ),
    ("sim", "every job starts its own worlds"),
    ("connect", "every job starts its own worlds"),
    (
        "report",
        "a sweep runs push-task configurations, not the draft's tables",
    ),
];

/// Top-level keys of a sweep file.
const KEYS: [&str; 6] = [
    "experiment",
    "seeds",
    "folds",
    "train-runs",
    "options",
    "grid",
];

/// Why a sweep file cannot be planned.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SweepError {
    /// Not TOML.
    #[error("not a TOML file: {0}")]
    Toml(String),
    /// A key, value or list that does not fit.
    #[error("{0}")]
    Invalid(String),
}

fn invalid(text: impl Into<String>) -> SweepError {
    SweepError::Invalid(text.into())
}

/// The most jobs a sweep may plan: two hundred times the ablation's 4560,
/// about 100 core-hours at the ablation's cost per job. Planning holds every
/// job's id and options, about 130 bytes a job: the fuzzer found that two
/// lines of TOML just under the former cap of ten million took 1.3 GB and
/// 35 s to plan. A larger study is several sweeps.
pub const MAX_JOBS: usize = 1_000_000;

fn too_many(place: &str) -> SweepError {
    invalid(format!(
        "{place} has more than {MAX_JOBS} jobs (configurations × seeds × training-run counts × folds): split it into several sweeps"
    ))
}

/// One configuration: `pushlearn experiment push-task` options, sorted by
/// name (so the order of a file's keys does not change the id).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Configuration {
    /// 12 hex digits of the FNV-1a hash of [`Configuration::canonical`].
    pub id: String,
    /// (name, value) pairs; `None` is a switch without value (`true`).
    pub options: Vec<(String, Option<String>)>,
}

impl Configuration {
    fn new(mut options: Vec<(String, Option<String>)>) -> Self {
        options.sort();
        let mut configuration = Self {
            id: String::new(),
            options,
        };
        configuration.id = format!("{:016x}", name_hash(&configuration.canonical()))[..12].into();
        configuration
    }

    /// The configuration as one command line's options, e.g. `--eta 0.1
    /// --model gate` (values are not quoted; this is a name, not a script).
    #[must_use]
    pub fn canonical(&self) -> String {
        let mut line = EXPERIMENT.to_owned();
        for (name, value) in &self.options {
            let _ = write!(line, " --{name}");
            if let Some(value) = value {
                let _ = write!(line, " {value}");
            }
        }
        line
    }

    /// The options as separate arguments, `["--eta", "0.1", …]`.
    #[must_use]
    pub fn args(&self) -> Vec<String> {
        let mut args = Vec::new();
        for (name, value) in &self.options {
            args.push(format!("--{name}"));
            args.extend(value.clone());
        }
        args
    }

    /// `name=value` pairs, for tables (`(defaults)` without options).
    #[must_use]
    pub fn label(&self) -> String {
        if self.options.is_empty() {
            return "(defaults)".into();
        }
        self.options
            .iter()
            .map(|(name, value)| match value {
                Some(value) => format!("{name}={value}"),
                None => name.clone(),
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// One job: one fold of one configuration under one seed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Job {
    /// `CONFIG-sSEED-nN_TRAIN-fFOLD`: stable as long as the configuration's
    /// options are (the total number of folds or seeds is not part of it, so
    /// adding folds to a sweep keeps the jobs already done).
    pub id: String,
    /// Index into [`Sweep::configurations`].
    pub configuration: usize,
    pub seed: u64,
    pub n_train: usize,
    pub fold: usize,
}

/// A planned sweep.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sweep {
    /// Every configuration, in the file's order grid by grid; within a
    /// grid, the product over its keys in alphabetical order, the last
    /// fastest (TOML tables are unordered); duplicates dropped.
    pub configurations: Vec<Configuration>,
    pub seeds: Vec<u64>,
    pub train_runs: Vec<usize>,
    pub folds: usize,
}

impl Sweep {
    /// Plans the sweep file `text`. `known` holds the option names of
    /// `pushlearn experiment push-task` (without `--`), so that a typo is
    /// named here rather than in the first job.
    ///
    /// # Errors
    /// [`SweepError`], naming the key or value at fault.
    pub fn parse(text: &str, known: &[String]) -> Result<Self, SweepError> {
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            SweepError::Toml(e.message().to_owned() + &location(text, e.span()))
        })?;
        if let Some(key) = table.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(invalid(format!(
                "unknown key `{key}` at the top level; a sweep file has {}",
                KEYS.join(", ")
            )));
        }
        match table.get("experiment") {
            None => {}
            Some(toml::Value::String(name)) if name == EXPERIMENT => {}
            Some(other) => {
                return Err(invalid(format!(
                    "`experiment` is {other}: a sweep runs `{EXPERIMENT}`, whose folds are its jobs"
                )))
            }
        }
        let seeds = integers(&table, "seeds", Some(1))?
            .into_iter()
            .collect::<Vec<_>>();
        let folds = match table.get("folds") {
            None => 20,
            Some(toml::Value::Integer(n)) if *n >= 1 => {
                usize::try_from(*n).map_err(|_| invalid(format!("`folds` = {n} is too large")))?
            }
            Some(other) => {
                return Err(invalid(format!(
                    "`folds` must be a whole number of at least 1, not {other}"
                )))
            }
        };
        let train_runs = integers(&table, "train-runs", None)?
            .into_iter()
            .map(|n| {
                usize::try_from(n).map_err(|_| invalid(format!("`train-runs` {n} is too large")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        if train_runs.contains(&0) {
            return Err(invalid("`train-runs` must be at least 1 each"));
        }
        let fixed = match table.get("options") {
            None => Vec::new(),
            Some(toml::Value::Table(t)) => t
                .iter()
                .map(|(name, value)| {
                    check_name(name, known, "[options]")?;
                    Ok((name.clone(), scalar(value, name, "[options]")?))
                })
                .collect::<Result<Vec<_>, SweepError>>()?,
            Some(_) => return Err(invalid("`options` must be a table ([options])")),
        };
        let grids: Vec<&toml::Table> = match table.get("grid") {
            None => Vec::new(),
            Some(toml::Value::Array(grids)) => grids
                .iter()
                .map(|g| match g {
                    toml::Value::Table(t) => Ok(t),
                    _ => Err(invalid("`grid` must be tables ([[grid]])")),
                })
                .collect::<Result<_, _>>()?,
            Some(toml::Value::Table(t)) => vec![t],
            Some(_) => return Err(invalid("`grid` must be tables ([[grid]])")),
        };
        let mut configurations = Vec::new();
        let mut seen = BTreeSet::new();
        let mut push = |options: Vec<(String, Option<Option<String>>)>| {
            let configuration = Configuration::new(
                options
                    .into_iter()
                    .filter_map(|(name, value)| value.map(|v| (name, v)))
                    .collect(),
            );
            if seen.insert(configuration.canonical()) {
                configurations.push(configuration);
            }
        };
        if grids.is_empty() {
            push(fixed.clone());
        }
        // Configurations the grids so far expand to (duplicates included).
        let mut planned = 0usize;
        for (g, grid) in grids.iter().enumerate() {
            let place = format!("[[grid]] number {}", g + 1);
            let mut axes: Vec<(String, Vec<Option<Option<String>>>)> = Vec::new();
            for (name, value) in grid.iter() {
                check_name(name, known, &place)?;
                if fixed.iter().any(|(n, _)| n == name) {
                    return Err(invalid(format!(
                        "`{name}` is in [options] and in {place}: give it in one place"
                    )));
                }
                let values = match value {
                    toml::Value::Array(values) if values.is_empty() => {
                        return Err(invalid(format!(
                            "`{name}` in {place} is an empty list: the grid would have no configuration"
                        )))
                    }
                    toml::Value::Array(values) => values
                        .iter()
                        .map(|v| scalar(v, name, &place))
                        .collect::<Result<_, _>>()?,
                    single => vec![scalar(single, name, &place)?],
                };
                axes.push((name.clone(), values));
            }
            // Bounded before it is expanded: a few lines of TOML can name
            // more configurations than memory holds.
            let size = axes
                .iter()
                .try_fold(1, |n: usize, (_, values)| n.checked_mul(values.len()))
                .and_then(|n| n.checked_add(planned))
                .filter(|&n| n <= MAX_JOBS);
            match size {
                Some(n) => planned = n,
                None => return Err(too_many(&place)),
            }
            // The product, the (alphabetically) last key fastest.
            let mut product: Vec<Vec<(String, Option<Option<String>>)>> = vec![fixed.clone()];
            for (name, values) in &axes {
                product = product
                    .into_iter()
                    .flat_map(|partial| {
                        values.iter().map(move |value| {
                            let mut next = partial.clone();
                            next.push((name.clone(), value.clone()));
                            next
                        })
                    })
                    .collect();
            }
            product.into_iter().for_each(&mut push);
        }
        let jobs = [seeds.len(), train_runs.len(), folds]
            .into_iter()
            .try_fold(configurations.len(), usize::checked_mul)
            .filter(|&n| n <= MAX_JOBS);
        if jobs.is_none() {
            return Err(too_many("the sweep"));
        }
        Ok(Self {
            configurations,
            seeds,
            train_runs,
            folds,
        })
    }

    /// Every job in the canonical order: configuration, seed, N_train (in
    /// the file's order), fold.
    #[must_use]
    pub fn jobs(&self) -> Vec<Job> {
        let mut jobs = Vec::with_capacity(self.len());
        for (c, configuration) in self.configurations.iter().enumerate() {
            for &seed in &self.seeds {
                for &n_train in &self.train_runs {
                    for fold in 0..self.folds {
                        jobs.push(Job {
                            id: format!("{}-s{seed}-n{n_train}-f{fold}", configuration.id),
                            configuration: c,
                            seed,
                            n_train,
                            fold,
                        });
                    }
                }
            }
        }
        jobs
    }

    /// The number of jobs.
    #[must_use]
    pub fn len(&self) -> usize {
        self.configurations.len() * self.seeds.len() * self.train_runs.len() * self.folds
    }

    /// Whether the sweep has no job (it cannot: [`Sweep::parse`] refuses
    /// empty lists).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `C configurations × S seeds × T training-run counts × F folds = J jobs`.
    #[must_use]
    pub fn shape(&self) -> String {
        format!(
            "{} configurations × {} seeds × {} training-run counts × {} folds = {} jobs",
            self.configurations.len(),
            self.seeds.len(),
            self.train_runs.len(),
            self.folds,
            self.len()
        )
    }
}

/// ` (line L, column C)` of a TOML error's span.
fn location(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    let Some(span) = span else {
        return String::new();
    };
    let before = &text[..span.start.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    format!(" (line {line}, column {column})")
}

/// A list of non-negative integers under `key`, `default` (one value) if
/// absent, required otherwise.
fn integers(table: &toml::Table, key: &str, default: Option<u64>) -> Result<Vec<u64>, SweepError> {
    let values = match (table.get(key), default) {
        (None, Some(d)) => return Ok(vec![d]),
        (None, None) => {
            return Err(invalid(format!(
                "`{key}` is missing: a list such as {key} = [1, 3, 10]"
            )))
        }
        (Some(toml::Value::Array(values)), _) => values,
        (Some(other), _) => {
            return Err(invalid(format!(
                "`{key}` must be a list of whole numbers, not {other}"
            )))
        }
    };
    if values.is_empty() {
        return Err(invalid(format!(
            "`{key}` is an empty list: the sweep would have no job"
        )));
    }
    let mut out = Vec::new();
    for value in values {
        match value {
            toml::Value::Integer(n) if *n >= 0 => {
                let n = u64::try_from(*n).map_err(|_| invalid(format!("`{key}`: {n}")))?;
                if out.contains(&n) {
                    return Err(invalid(format!("`{key}` lists {n} twice")));
                }
                out.push(n);
            }
            other => {
                return Err(invalid(format!(
                    "`{key}` must be a list of whole numbers ≥ 0, and {other} is not one"
                )))
            }
        }
    }
    Ok(out)
}

fn check_name(name: &str, known: &[String], place: &str) -> Result<(), SweepError> {
    let name = name.strip_prefix("--").unwrap_or(name);
    if let Some((_, instead)) = RESERVED.iter().find(|(n, _)| *n == name) {
        return Err(invalid(format!(
            "`{name}` in {place} cannot vary per configuration: {instead}"
        )));
    }
    if !known.iter().any(|k| k == name) {
        let mut options: Vec<&str> = known
            .iter()
            .map(String::as_str)
            .filter(|k| !RESERVED.iter().any(|(n, _)| n == k))
            .collect();
        options.sort_unstable();
        return Err(invalid(format!(
            "unknown option `{name}` in {place}; the options of `pushlearn experiment push-task` are: {}",
            options.join(", ")
        )));
    }
    Ok(())
}

/// One option value: `Some(Some(text))` an option with a value, `Some(None)`
/// a switch (`true`), `None` the option left out (`false` or `""`, its
/// default).
fn scalar(
    value: &toml::Value,
    name: &str,
    place: &str,
) -> Result<Option<Option<String>>, SweepError> {
    Ok(match value {
        toml::Value::String(s) if s.is_empty() => None,
        toml::Value::String(s) => Some(Some(s.clone())),
        toml::Value::Integer(n) => Some(Some(n.to_string())),
        toml::Value::Float(x) if x.is_finite() => Some(Some(x.to_string())),
        toml::Value::Boolean(true) => Some(None),
        toml::Value::Boolean(false) => None,
        other => {
            return Err(invalid(format!(
                "`{name}` in {place} is {other}: an option's value is a string, a number or true/false (a list only in [[grid]], for alternatives)"
            )))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn known() -> Vec<String> {
        [
            "model", "eta", "selector", "flag", "variant", "mode", "no-reuse", "learner", "seed",
            "folds",
        ]
        .map(String::from)
        .to_vec()
    }

    const FILE: &str = r#"
        seeds = [1, 2]
        folds = 3
        train-runs = [1, 10]
        [options]
        mode = "lockstep"
        [[grid]]
        model = "gate"
        flag = ["", "use-dyns"]
        [[grid]]
        model = ["interaction"]
        selector = ["aitm", "tree"]
        eta = [0.0, 0.1]
    "#;

    #[test]
    fn grids_expand_to_the_union_of_their_products_in_file_order() {
        let sweep = Sweep::parse(FILE, &known()).unwrap();
        let labels: Vec<String> = sweep
            .configurations
            .iter()
            .map(Configuration::label)
            .collect();
        assert_eq!(
            labels,
            [
                "mode=lockstep model=gate",
                "flag=use-dyns mode=lockstep model=gate",
                "eta=0 mode=lockstep model=interaction selector=aitm",
                "eta=0 mode=lockstep model=interaction selector=tree",
                "eta=0.1 mode=lockstep model=interaction selector=aitm",
                "eta=0.1 mode=lockstep model=interaction selector=tree",
            ]
        );
        assert_eq!(sweep.len(), 6 * 2 * 2 * 3);
        assert_eq!(sweep.jobs().len(), sweep.len());
        assert_eq!(
            sweep.shape(),
            "6 configurations × 2 seeds × 2 training-run counts × 3 folds = 72 jobs"
        );
        assert_eq!(
            sweep.configurations[1].args(),
            ["--flag", "use-dyns", "--mode", "lockstep", "--model", "gate"]
        );
    }

    #[test]
    fn job_ids_are_stable_unique_and_independent_of_key_order_and_sweep_size() {
        let sweep = Sweep::parse(FILE, &known()).unwrap();
        let jobs = sweep.jobs();
        let ids: BTreeSet<&str> = jobs.iter().map(|j| j.id.as_str()).collect();
        assert_eq!(ids.len(), jobs.len());
        // The id is a function of the parameters: fixed here so that a
        // change to the derivation (which would orphan every output
        // directory) fails this test.
        assert_eq!(
            sweep.configurations[0].canonical(),
            "push-task --mode lockstep --model gate"
        );
        assert_eq!(
            jobs[0].id,
            format!("{}-s1-n1-f0", sweep.configurations[0].id)
        );
        assert_eq!(sweep.configurations[0].id, "f5cacf13dd9d");
        let reordered = r#"
            train-runs = [10, 1]
            seeds = [2]
            folds = 5
            [[grid]]
            model = "gate"
            mode = "lockstep"
        "#;
        let other = Sweep::parse(reordered, &known()).unwrap();
        assert_eq!(other.configurations[0].id, sweep.configurations[0].id);
        let theirs: BTreeSet<String> = other.jobs().into_iter().map(|j| j.id).collect();
        assert!(theirs.contains(&format!("{}-s2-n1-f2", sweep.configurations[0].id)));
        // Canonical order: configuration, seed, N_train in the file's order, fold.
        let coords: Vec<(u64, usize, usize)> = other
            .jobs()
            .iter()
            .take(6)
            .map(|j| (j.seed, j.n_train, j.fold))
            .collect();
        assert_eq!(
            coords,
            [
                (2, 10, 0),
                (2, 10, 1),
                (2, 10, 2),
                (2, 10, 3),
                (2, 10, 4),
                (2, 1, 0)
            ]
        );
    }

    #[test]
    fn switches_defaults_and_duplicates() {
        let sweep = Sweep::parse(
            "train-runs = [1]\n[[grid]]\nno-reuse = [true, false]\nmodel = [\"gate\", \"\"]\n[[grid]]\nno-reuse = false",
            &known(),
        )
        .unwrap();
        let labels: Vec<String> = sweep
            .configurations
            .iter()
            .map(Configuration::label)
            .collect();
        // The second grid's only configuration is the defaults, already there.
        assert_eq!(
            labels,
            [
                "model=gate no-reuse",
                "model=gate",
                "no-reuse",
                "(defaults)"
            ]
        );
        assert_eq!(sweep.seeds, [1]);
        assert_eq!(sweep.folds, 20);
        assert_eq!(
            sweep.configurations[0].args(),
            ["--model", "gate", "--no-reuse"]
        );
    }

    #[test]
    fn bad_files_are_refused_naming_the_problem() {
        let err = |text: &str| Sweep::parse(text, &known()).unwrap_err().to_string();
        assert!(err("train-runs = [1]\n[options]\nmodle = \"gate\"").starts_with(
            "unknown option `modle` in [options]; the options of `pushlearn experiment push-task` are: eta, flag, learner, mode, model"
        ));
        assert_eq!(
            err("train-runs = [1]\n[[grid]]\neta = []"),
            "`eta` in [[grid]] number 1 is an empty list: the grid would have no configuration"
        );
        assert!(err("train-runs = []").contains("empty list"));
        assert!(err("seeds = [1]").contains("`train-runs` is missing"));
        assert!(err("train-runs = [1]\nfolds = 0").contains("at least 1"));
        assert!(err("train-runs = [1, 1]").contains("twice"));
        assert!(err("train-runs = [1]\n[[grid]]\nseed = [1, 2]").contains("top-level `seeds`"));
        assert!(err("train-runs = [1]\nfold = 2").starts_with("unknown key `fold`"));
        assert!(err("train-runs = [1]\nexperiment = \"move-to-target\"")
            .contains("a sweep runs `push-task`"));
        assert!(err("train-runs = [1]\n[[grid]]\neta = [[0.1]]").contains("an option's value is"));
        assert!(
            err("train-runs = [1]\n[options]\nmodel = \"gate\"\n[[grid]]\nmodel = [\"gate\"]")
                .contains("give it in one place")
        );
        assert!(
            err("train-runs = [1\n").starts_with("not a TOML file"),
            "{}",
            err("train-runs = [1\n")
        );
    }

    /// What the `sweep_file` fuzz target checks: any text is refused with
    /// an error or planned into as many jobs as it says, each id once.
    fn planned_or_refused(text: &str) -> Result<(), String> {
        let Ok(sweep) = Sweep::parse(text, &known()) else {
            return Ok(());
        };
        let jobs = sweep.jobs();
        let ids: BTreeSet<&str> = jobs.iter().map(|j| j.id.as_str()).collect();
        if jobs.len() != sweep.len() || ids.len() != jobs.len() || jobs.is_empty() {
            return Err(format!(
                "{} jobs, {} ids, len {}",
                jobs.len(),
                ids.len(),
                sweep.len()
            ));
        }
        Ok(())
    }

    #[test]
    fn a_sweep_too_large_to_plan_is_refused_before_it_is_expanded() {
        for text in [
            "train-runs = [1]\nfolds = 9223372036854775807\n",
            "train-runs = [1]\nfolds = 1000001\n",
        ] {
            let error = Sweep::parse(text, &known()).unwrap_err().to_string();
            assert!(error.contains("more than 1000000 jobs"), "{error}");
        }
        // 8 keys of 10 values: 10^8 configurations, named in one line each.
        let mut grid = String::from("train-runs = [1]\n[[grid]]\n");
        for key in [
            "model", "eta", "selector", "flag", "variant", "mode", "learner", "no-reuse",
        ] {
            let values: Vec<String> = (0..10).map(|v| format!("\"{v}\"")).collect();
            grid.push_str(&format!("{key} = [{}]\n", values.join(", ")));
        }
        let error = Sweep::parse(&grid, &known()).unwrap_err().to_string();
        assert!(error.contains("[[grid]] number 1 has more than"), "{error}");
        assert!(Sweep::parse("train-runs = [1]\nfolds = 1000000\n", &known()).is_ok());
    }

    #[test]
    fn the_fuzzers_kept_sweep_files_are_planned_or_refused() {
        let kept = sim_plugin::untrusted::kept_fuzz_inputs("sweep_file");
        assert!(
            kept.len() >= 3,
            "fuzz/corpus/sweep_file has {} inputs",
            kept.len()
        );
        for (path, bytes) in kept {
            let text = String::from_utf8_lossy(&bytes);
            assert_eq!(planned_or_refused(&text), Ok(()), "{}", path.display());
        }
    }

    proptest::proptest! {
        /// Any text, and any small edit of a valid file, is refused or
        /// planned consistently (the `sweep_file` fuzz target's property).
        #[test]
        fn any_text_is_planned_or_refused(text in "\\PC{0,200}") {
            proptest::prop_assert_eq!(planned_or_refused(&text), Ok(()));
        }

        #[test]
        fn an_edited_sweep_file_is_planned_or_refused(at in 0..FILE.len(), junk in "[\\[\\]=\",0-9a-z \\n-]{0,6}") {
            let mut text = FILE.to_owned();
            if text.is_char_boundary(at) {
                text.insert_str(at, &junk);
            }
            proptest::prop_assert_eq!(planned_or_refused(&text), Ok(()));
        }
    }
}
