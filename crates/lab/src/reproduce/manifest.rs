//! The experiments behind `docs/results.md` ([`full`]) and the reduced set
//! CI checks ([`quick`]), each with the `pushlearn experiment` command that
//! runs it alone.

use std::fmt::Write as _;

use learner::interaction::SelectorKind;

use crate::spec::Spec;
use drive::experiment::move_to_target::{sampled_targets, MAX_STEPS};
use drive::experiment::push_task::protocol::Variant;
use drive::experiment::{Mode, LATENCY_MAX_STEPS, LATENCY_MAX_STEPS_HARSH};
use drive::external::LearnerChoice;
use drive::oracle::OracleLatency;
use drive::results::move_to_target::{REPETITIONS, TARGETS};
use drive::scene::{Object, Transfer};
use learner::registry::{Improvement, ModelKind, ModelOptions, Parts};

/// The seeds whose spread `docs/results.md` shows beside seed 1 for the
/// issue's targets (20 folds each).
pub const SPREAD_SEEDS: [u64; 4] = [2, 3, 4, 5];

/// One experiment of a reproduction.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Its document's file name without `.json`.
    pub name: String,
    pub spec: Spec,
    pub mode: Mode,
    /// The latency maximum with `Mode::LockstepJitter`.
    pub latency_max: u32,
    pub seed: u64,
    /// Whether its figures go into `docs/figures/`.
    pub figures: bool,
}

impl Entry {
    fn new(name: impl Into<String>, spec: Spec) -> Self {
        Self {
            name: name.into(),
            spec,
            mode: Mode::LockstepJitter,
            latency_max: LATENCY_MAX_STEPS,
            seed: 1,
            figures: false,
        }
    }

    fn mode(self, mode: Mode) -> Self {
        Self { mode, ..self }
    }

    fn latency_max(self, latency_max: u32) -> Self {
        Self {
            latency_max,
            ..self
        }
    }

    fn seed(self, seed: u64) -> Self {
        Self { seed, ..self }
    }

    fn with_figures(self, figures: bool) -> Self {
        Self { figures, ..self }
    }

    /// The worlds this entry can share recorded runs with: the same scene,
    /// mode and latency maximum (`drive::experiment::run::Plan::runs`).
    #[must_use]
    pub fn world_key(&self) -> (&'static str, Mode, u32) {
        let latency = if self.mode.jitter() {
            self.latency_max
        } else {
            0
        };
        (self.spec.scene(), self.mode, latency)
    }

    /// The `pushlearn experiment` command that produces this entry's
    /// document alone (into `dir`).
    #[must_use]
    pub fn command(&self, dir: &str) -> String {
        let mut line = String::from("pushlearn experiment ");
        let default = ModelOptions::default();
        let options = |line: &mut String, options: &ModelOptions| {
            if options.selector != default.selector {
                let _ = write!(line, " --selector {}", options.selector.as_str());
            }
            if !options.improve.is_empty() {
                let _ = write!(line, " --improve {}", options.improvement_names().join(","));
            }
            if options.parts != default.parts {
                let _ = write!(line, " --parts {}", options.parts.as_str());
            }
        };
        match &self.spec {
            Spec::PushTask {
                model,
                options: o,
                variant,
                transfer,
                train_runs,
                folds,
            } => {
                let _ = write!(line, "push-task {model}");
                if *variant != Variant::Random {
                    let _ = write!(line, " --variant {}", variant.as_str());
                }
                if let Some(t) = transfer {
                    let _ = write!(
                        line,
                        " --train-on {} --test-on {}",
                        t.train_names(","),
                        t.test.as_str()
                    );
                }
                if *train_runs != variant.default_train_runs() {
                    let runs: Vec<String> = train_runs.iter().map(ToString::to_string).collect();
                    let _ = write!(line, " --train-runs {}", runs.join(","));
                }
                let default_folds = if *variant == Variant::Draft { 1 } else { 20 };
                if *folds != default_folds {
                    let _ = write!(line, " --folds {folds}");
                }
                options(&mut line, o);
            }
            Spec::ConstantFeedback { model, options: o } => {
                let _ = write!(line, "push-task {model} --variant constant-feedback");
                options(&mut line, o);
            }
            Spec::MoveToTarget {
                model,
                options: o,
                targets,
                repetitions,
                max_steps,
            } => {
                let _ = write!(line, "move-to-target {model}");
                if *targets == sampled_targets(targets.len(), self.seed) {
                    let _ = write!(line, " --sample-targets {}", targets.len());
                } else if targets[..] != TARGETS[..] {
                    for t in targets {
                        let _ = write!(line, " --target={},{},{}", t.x, t.y, t.theta);
                    }
                }
                if *repetitions != REPETITIONS {
                    let _ = write!(line, " --repetitions {repetitions}");
                }
                if *max_steps != MAX_STEPS {
                    let _ = write!(line, " --max-steps {max_steps}");
                }
                options(&mut line, o);
            }
            Spec::DraftTables { folds } => {
                line.push_str("push-task --report draft");
                if *folds != 1 {
                    let _ = write!(line, " --folds {folds}");
                }
            }
        }
        if self.mode != Mode::LockstepJitter {
            let _ = write!(line, " --mode {}", self.mode.as_str());
        } else if self.latency_max != LATENCY_MAX_STEPS {
            let _ = write!(line, " --latency-max {}", self.latency_max);
        }
        if self.seed != 1 {
            let _ = write!(line, " --seed {}", self.seed);
        }
        let _ = write!(line, " --json {dir}/{}.json", self.name);
        line
    }
}

const MODELS: [ModelKind; 2] = [ModelKind::Gate, ModelKind::Interaction];

/// The numbers of training runs of "Beyond the thesis" (as the baselines').
pub const BEYOND_RUNS: [usize; 4] = BASELINE_RUNS;

/// Sampled Move-to-Target targets of "Beyond the thesis".
pub const BEYOND_SAMPLED_TARGETS: usize = 100;

/// The improved gate model of "Beyond the thesis": (document name suffix,
/// model, --improve). Each change alone on the thesis's gate model, the
/// one pair the page discusses, then all of them (`gate+`).
#[must_use]
pub fn beyond_models() -> Vec<(String, ModelKind, Vec<Improvement>)> {
    Improvement::EACH
        .into_iter()
        .map(|i| (i.as_str().to_owned(), ModelKind::Gate, vec![i]))
        // unrounded's gain with the actuator put right (docs/results.md).
        .chain([
            (
                "unrounded-adapt-actuator".to_owned(),
                ModelKind::Gate,
                vec![Improvement::Unrounded, Improvement::AdaptActuator],
            ),
            ("gate-plus".to_owned(), ModelKind::GatePlus, Vec::new()),
        ])
        .collect()
}

/// The hybrid model and its ablation (`docs/models.md` "The hybrid
/// model"): (document name suffix, parts), the whole model first.
pub const HYBRIDS: [(&str, Parts); 3] = [
    ("hybrid", Parts::Full),
    ("hybrid-identified", Parts::Identified),
    ("hybrid-mechanics", Parts::Mechanics),
];

/// The "Beyond the thesis" experiments: the push task's curve of each
/// change and of gate+, Move to Target on the thesis's targets for
/// forward-check and gate+, and on sampled targets for gate and gate+.
fn beyond() -> Vec<Entry> {
    let mut entries = Vec::new();
    let improved = |improve: Vec<Improvement>| ModelOptions {
        improve,
        ..ModelOptions::default()
    };
    for (name, kind, improve) in beyond_models() {
        entries.push(Entry::new(
            format!("beyond-push-{name}"),
            Spec::PushTask {
                model: kind.into(),
                options: improved(improve),
                variant: Variant::Random,
                transfer: None,
                train_runs: BEYOND_RUNS.to_vec(),
                folds: 20,
            },
        ));
    }
    for (name, parts) in HYBRIDS {
        entries.push(Entry::new(
            format!("beyond-push-{name}"),
            Spec::PushTask {
                model: ModelKind::Hybrid.into(),
                options: ModelOptions {
                    parts,
                    ..ModelOptions::default()
                },
                variant: Variant::Random,
                transfer: None,
                train_runs: BEYOND_RUNS.to_vec(),
                folds: 20,
            },
        ));
    }
    entries.push(Entry::new(
        "beyond-mtt-hybrid",
        Spec::MoveToTarget {
            model: ModelKind::Hybrid.into(),
            options: ModelOptions::default(),
            targets: TARGETS.to_vec(),
            repetitions: REPETITIONS,
            max_steps: MAX_STEPS,
        },
    ));
    for (name, kind, improve) in beyond_models() {
        if kind == ModelKind::GatePlus || improve == [Improvement::ForwardCheck] {
            entries.push(Entry::new(
                format!("beyond-mtt-{name}"),
                Spec::MoveToTarget {
                    model: kind.into(),
                    options: improved(improve),
                    targets: TARGETS.to_vec(),
                    repetitions: REPETITIONS,
                    max_steps: MAX_STEPS,
                },
            ));
        }
    }
    for (name, kind) in [
        ("gate", ModelKind::Gate),
        ("gate-plus", ModelKind::GatePlus),
        ("hybrid", ModelKind::Hybrid),
    ] {
        entries.push(Entry::new(
            format!("beyond-sampled-{name}"),
            Spec::MoveToTarget {
                model: kind.into(),
                options: ModelOptions::default(),
                targets: sampled_targets(BEYOND_SAMPLED_TARGETS, 1),
                repetitions: 1,
                max_steps: MAX_STEPS,
            },
        ));
    }
    entries
}

/// The latency settings an experiment is run with (name suffix, latency
/// maximum): the default, and the harsher robustness row.
const LATENCIES: [(&str, u32); 2] = [
    ("", LATENCY_MAX_STEPS),
    ("-latency5", LATENCY_MAX_STEPS_HARSH),
];

/// [`LATENCIES`] and lock-step, for the experiments reported in all three.
const TIMINGS: [(&str, Mode, u32); 3] = [
    ("", Mode::LockstepJitter, LATENCY_MAX_STEPS),
    ("-lockstep", Mode::Lockstep, LATENCY_MAX_STEPS),
    ("-latency5", Mode::LockstepJitter, LATENCY_MAX_STEPS_HARSH),
];

fn push(model: ModelKind, variant: Variant, train_runs: Vec<usize>, folds: usize) -> Spec {
    Spec::PushTask {
        model: model.into(),
        options: ModelOptions::default(),
        variant,
        transfer: None,
        train_runs,
        folds,
    }
}

fn move_to_target(model: ModelKind, repetitions: usize) -> Spec {
    Spec::MoveToTarget {
        model: model.into(),
        options: ModelOptions::default(),
        targets: TARGETS.to_vec(),
        repetitions,
        max_steps: MAX_STEPS,
    }
}

/// One baseline a reviewer asks for, a learner of the Python package
/// (`python/pushlearn/baselines.py`) served for the driver.
#[derive(Clone, Copy, Debug)]
pub struct Baseline {
    /// Its name: `python -m pushlearn.baselines NAME`'s (the key of the
    /// package's `BASELINES`) and the one it has in the new-object and
    /// cross-object documents.
    pub name: &'static str,
    /// The learner class, as `pushlearn.serve` takes it.
    pub class: &'static str,
    /// Seconds its slowest answer may take.
    pub timeout_s: u64,
}

impl Baseline {
    /// The name of its learning-curve document (`baseline-knn`).
    #[must_use]
    pub fn document(&self) -> String {
        format!("baseline-{}", self.name)
    }

    /// The learner the driver runs: the class served by `python3 -m
    /// pushlearn.serve`, its slowest answer allowed `timeout_s` seconds.
    fn learner(&self) -> LearnerChoice {
        LearnerChoice::External(drive::external::LearnerSpec {
            source: drive::external::Source::Command(python_learner(self.class)),
            timeout: std::time::Duration::from_secs(self.timeout_s),
        })
    }
}

/// The baselines, in the order the page shows them. A new one is a class
/// in the Python package's `BASELINES` and one entry here: the learning
/// curves, the baseline table and figure, "Beyond the thesis" and the
/// new-object table take every entry (the cross-object table only those
/// in [`CROSS_LEARNERS`]); `tests::the_baselines_are_the_python_packages`
/// keeps this list and the package's equal. A GP's fit when training ends
/// takes a few seconds (`baselines.py`: at most 600 samples, O(n³)), and so
/// do the MLP ensemble's last epochs over its memory; the timeout leaves
/// room for a machine ten times slower.
pub const BASELINES: &[Baseline] = &[
    Baseline {
        name: "knn",
        class: "pushlearn.baselines:KnnLearner",
        timeout_s: 60,
    },
    Baseline {
        name: "gp",
        class: "pushlearn.baselines:GpLearner",
        timeout_s: 60,
    },
    Baseline {
        name: "mlp",
        class: "pushlearn.baselines:MlpLearner",
        timeout_s: 60,
    },
];

/// The numbers of training runs of the baseline table.
pub const BASELINE_RUNS: [usize; 4] = [1, 3, 10, 30];

/// The environment a Python learner runs in, as the assignments its
/// command starts with: what makes the baselines' numbers the same bit for
/// bit on every x86-64 machine (with the packages of
/// `python/constraints.txt`). Read when the libraries load, so they must be
/// in the process's environment before numpy is imported:
///
/// * `OPENBLAS_CORETYPE=Nehalem`: numpy's and scipy's OpenBLAS otherwise
///   pick their kernels by CPU, and the GP's fit and predictions differ in
///   the last bits between them (`Haswell`/`Zen` against `SkylakeX`).
///   Nehalem's (SSE4.2) needs no more than numpy itself does (x86-64-v2),
///   so every machine that runs numpy has it; a GP fit at 600 samples still
///   takes about a second (`docs/performance.md`);
/// * `OPENBLAS_NUM_THREADS=1`, `OMP_NUM_THREADS=1`: one thread, so a
///   learner uses one core beside the worlds, and no sum is split by
///   thread count;
/// * `NPY_DISABLE_CPU_FEATURES`: numpy's own SIMD loops beyond its x86-64-v2
///   baseline, chosen by CPU too (its AVX-512 `exp` differs from libm's);
/// * `GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA,-FMA4`: libm's `exp`, `log`, …
///   in their SSE2 variants, which every x86-64 machine has (the FMA ones
///   round differently).
///
/// On aarch64 the x86 names select nothing (OpenBLAS keeps the ARM kernel
/// it detects, numpy only warns, and glibc has no such hardware
/// capabilities): the GP's numbers there need not match the committed
/// ones, which were made on x86-64.
pub const PYTHON_LEARNER_ENV: &str = "OPENBLAS_CORETYPE=Nehalem OPENBLAS_NUM_THREADS=1 \
OMP_NUM_THREADS=1 NPY_DISABLE_CPU_FEATURES=X86_V3,X86_V4,AVX512_ICL,AVX512_SPR \
GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA,-FMA4";

/// The command that serves a learner class of the Python package on
/// stdin/stdout (`python -m pushlearn.serve`) in [`PYTHON_LEARNER_ENV`];
/// `python3` is the one on PATH, which `pushlearn reproduce` starts with
/// the repository's `.venv`.
#[must_use]
pub fn python_learner(class: &str) -> String {
    format!("{PYTHON_LEARNER_ENV} python3 -m pushlearn.serve {class}")
}

/// Every experiment behind `docs/results.md`, in the order they run:
/// experiments that share a world (scene, mode, latency) are adjacent, so
/// that both models' runs are simulated once.
#[must_use]
pub fn full() -> Vec<Entry> {
    let mut entries = Vec::new();
    let curve = || Variant::Random.default_train_runs();
    for (suffix, mode, latency) in TIMINGS {
        for model in MODELS {
            let entry = Entry::new(
                format!("push-task-{model}{suffix}"),
                push(model, Variant::Random, curve(), 20),
            )
            .mode(mode)
            .latency_max(latency);
            // Only the default setting's figures go on the page.
            entries.push(entry.with_figures(suffix.is_empty()));
        }
        // The reference rows of this timing, on the curves' own runs (the
        // same world and jobs, so nothing is simulated twice).
        for (name, learner) in references() {
            entries.push(
                Entry::new(
                    reference_entry_name(name, suffix),
                    Spec::PushTask {
                        model: learner,
                        options: ModelOptions::default(),
                        variant: Variant::Random,
                        transfer: None,
                        train_runs: curve(),
                        folds: 20,
                    },
                )
                .mode(mode)
                .latency_max(latency),
            );
        }
        if suffix.is_empty() {
            // Beside the default curves: the same world, so the baselines'
            // runs are the curves' recorded ones.
            for b in BASELINES {
                entries.push(Entry::new(
                    b.document(),
                    Spec::PushTask {
                        model: b.learner(),
                        options: ModelOptions::default(),
                        variant: Variant::Random,
                        transfer: None,
                        train_runs: BASELINE_RUNS.to_vec(),
                        folds: 20,
                    },
                ));
            }
        }
    }
    for seed in SPREAD_SEEDS {
        for model in MODELS {
            entries.push(
                Entry::new(
                    format!("push-task-{model}-seed{seed}"),
                    push(model, Variant::Random, vec![10, 30], 20),
                )
                .seed(seed),
            );
        }
    }
    for (suffix, latency) in LATENCIES {
        for model in MODELS {
            let entry = Entry::new(
                format!("fixed-three-{model}{suffix}"),
                push(model, Variant::FixedThree, vec![3], 20),
            )
            .latency_max(latency);
            // Only the default setting's figures go on the page.
            entries.push(entry.with_figures(suffix.is_empty()));
        }
    }
    entries.push(
        Entry::new(
            "fixed-three-gate-lockstep",
            push(ModelKind::Gate, Variant::FixedThree, vec![3], 20),
        )
        .mode(Mode::Lockstep),
    );
    for (suffix, latency) in LATENCIES {
        for runs in [6, 7] {
            let entry = Entry::new(
                format!("two-objects-{runs}{suffix}"),
                push(ModelKind::Gate, Variant::TwoObjects, vec![runs], 20),
            )
            .latency_max(latency);
            // Only the default setting's figures go on the page.
            entries.push(entry.with_figures(suffix.is_empty()));
        }
    }
    for model in MODELS {
        entries.push(
            Entry::new(
                format!("constant-feedback-{model}"),
                Spec::ConstantFeedback {
                    model: model.into(),
                    options: ModelOptions::default(),
                },
            )
            .with_figures(true),
        );
    }
    for (suffix, mode, latency) in TIMINGS {
        for model in MODELS {
            let entry = Entry::new(
                format!("move-to-target-{model}{suffix}"),
                move_to_target(model, REPETITIONS),
            )
            .mode(mode)
            .latency_max(latency);
            // Only the default setting's figures go on the page.
            entries.push(entry.with_figures(suffix.is_empty()));
        }
    }
    for seed in SPREAD_SEEDS {
        for model in MODELS {
            entries.push(
                Entry::new(
                    format!("move-to-target-{model}-seed{seed}"),
                    move_to_target(model, REPETITIONS),
                )
                .seed(seed),
            );
        }
    }
    entries.push(Entry::new("draft", Spec::DraftTables { folds: 1 }));
    for selector in SelectorKind::ALL {
        entries.push(Entry::new(
            format!("selector-{}", selector.as_str()),
            Spec::PushTask {
                model: ModelKind::Interaction.into(),
                options: ModelOptions {
                    selector,
                    ..ModelOptions::default()
                },
                variant: Variant::Draft,
                transfer: None,
                train_runs: vec![3, 10, 30],
                folds: 5,
            },
        ));
    }
    entries.extend(beyond());
    entries.extend(objects());
    entries.extend(cross_objects());
    entries
}

/// Training runs of the new-object experiments: the number the issue's
/// forward-model targets are stated at.
pub const OBJECT_RUNS: usize = 10;

/// The new-object experiments' conditions (`docs/experiments.md` "New
/// objects"): trained on the blue block and tested on each object, then
/// trained on a mix of two and tested on the third.
#[must_use]
pub fn transfers() -> Vec<Transfer> {
    use Object::{Blue, Cylinder, Red};
    [
        (vec![Blue], Blue),
        (vec![Blue], Red),
        (vec![Blue], Cylinder),
        (vec![Blue, Red], Cylinder),
        (vec![Blue, Cylinder], Red),
    ]
    .into_iter()
    .map(|(train, test)| Transfer { train, test })
    .collect()
}

/// The reference rows of every table (`docs/models.md` "Reference rows"):
/// (document name part, learner): `still`, which predicts that nothing
/// moves, and the oracles, copies of the world with its true parameters
/// that know the latency draws or predict their median outcome. The
/// tables' normalised score is a learner's place between `still` (0) and
/// the oracle that does not know the latency (1).
#[must_use]
pub fn references() -> [(&'static str, LearnerChoice); 3] {
    [
        (STILL, ModelKind::Still.into()),
        (
            OracleLatency::Known.report_name(),
            LearnerChoice::Oracle(OracleLatency::Known),
        ),
        (
            OracleLatency::Unknown.report_name(),
            LearnerChoice::Oracle(OracleLatency::Unknown),
        ),
    ]
}

/// The reference that predicts nothing moves, by its document name part.
pub const STILL: &str = "still";

/// The document name of a reference row of the learning curves at one
/// timing (`suffix`: "", "-lockstep" or "-latency5").
#[must_use]
pub fn reference_entry_name(reference: &str, suffix: &str) -> String {
    format!("reference-{reference}{suffix}")
}

/// The learners of the new-object table: (document name part, learner):
/// both faithful models, gate+, the hybrid model, every baseline and the
/// reference rows.
#[must_use]
pub fn object_learners() -> Vec<(&'static str, LearnerChoice)> {
    let mut learners = vec![
        ("gate", ModelKind::Gate.into()),
        ("interaction", ModelKind::Interaction.into()),
        ("gate-plus", ModelKind::GatePlus.into()),
        ("hybrid", ModelKind::Hybrid.into()),
    ];
    learners.extend(BASELINES.iter().map(|b| (b.name, b.learner())));
    learners.extend(references());
    learners
}

/// The document name of one learner on one new-object condition.
#[must_use]
pub fn object_entry_name(learner: &str, transfer: &Transfer) -> String {
    format!("objects-{learner}-{}", transfer.slug())
}

/// The numbers of training runs of the cross-object table.
pub const CROSS_RUNS: [usize; 3] = [1, 3, 10];

/// The cross-object table's conditions: trained on one object, tested on
/// each other one.
#[must_use]
pub fn cross_transfers() -> Vec<Transfer> {
    let mut out = Vec::new();
    for train in Object::ALL {
        for test in Object::ALL {
            if train != test {
                out.push(Transfer {
                    train: vec![train],
                    test,
                });
            }
        }
    }
    out
}

/// The learners of the cross-object table (names as in
/// [`object_learners`]): the thesis's gate model, the hybrid model, the
/// kNN and MLP baselines and the reference rows. The interaction model,
/// gate+ and the GP are in the new-object table; here they would add a
/// third to the reproduction's time and nothing the table is for.
pub const CROSS_LEARNERS: [&str; 7] = [
    "gate",
    "hybrid",
    "knn",
    "mlp",
    STILL,
    "oracle-known",
    "oracle-unknown",
];

/// The document name of one learner on one cross-object condition.
#[must_use]
pub fn cross_entry_name(learner: &str, transfer: &Transfer) -> String {
    format!("cross-{learner}-{}", transfer.slug())
}

/// The cross-object experiments, condition by condition.
fn cross_objects() -> Vec<Entry> {
    let mut entries = Vec::new();
    for transfer in cross_transfers() {
        for (name, learner) in object_learners() {
            if !CROSS_LEARNERS.contains(&name) {
                continue;
            }
            entries.push(Entry::new(
                cross_entry_name(name, &transfer),
                Spec::PushTask {
                    model: learner,
                    options: ModelOptions::default(),
                    variant: Variant::Random,
                    transfer: Some(transfer.clone()),
                    train_runs: CROSS_RUNS.to_vec(),
                    folds: 20,
                },
            ));
        }
    }
    entries
}

/// The new-object experiments, condition by condition (the learners of one
/// condition share its recorded runs).
fn objects() -> Vec<Entry> {
    let mut entries = Vec::new();
    for transfer in transfers() {
        for (name, learner) in object_learners() {
            entries.push(Entry::new(
                object_entry_name(name, &transfer),
                Spec::PushTask {
                    model: learner,
                    options: ModelOptions::default(),
                    variant: Variant::Random,
                    transfer: Some(transfer.clone()),
                    train_runs: vec![OBJECT_RUNS],
                    folds: 20,
                },
            ));
        }
    }
    entries
}

/// A sweep (`docs/sweeps.md`) whose merged errors a reproduction keeps as
/// a document ([`crate::sweep::summary::Summary`]); its jobs run as
/// `pushlearn sweep run` runs them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SweepEntry {
    /// Its document's file name without `.json`.
    pub name: &'static str,
    /// The sweep file, relative to the repository root.
    pub file: &'static str,
}

impl SweepEntry {
    /// The stand-alone command that runs it (its summary is then
    /// `DIR/merged/summary.md`; `pushlearn reproduce --sweep-dir runs`
    /// takes it from there).
    #[must_use]
    pub fn command(&self) -> String {
        format!("pushlearn sweep run {} --out runs/{}", self.file, self.name)
    }
}

/// The ablation's document name (docs/results.md "Ablation").
pub const ABLATION: &str = "ablation";

/// The sweeps of a reproduction: the ablation, or for `--quick` its reduced
/// version (the one the Slurm test runs), so CI checks the sweep's path
/// into a document too.
#[must_use]
pub fn sweeps(quick: bool) -> Vec<SweepEntry> {
    vec![SweepEntry {
        name: ABLATION,
        file: if quick {
            "sweeps/ablation-ci.toml"
        } else {
            "sweeps/ablation.toml"
        },
    }]
}

/// A reduced reproduction that still exercises every experiment and both
/// models with latency emulation, in a few seconds: what CI compares with
/// the committed `docs/results/quick/`.
#[must_use]
pub fn quick() -> Vec<Entry> {
    let mut entries = Vec::new();
    for model in MODELS {
        entries.push(Entry::new(
            format!("push-task-{model}"),
            push(model, Variant::Random, vec![1, 3, 10], 2),
        ));
    }
    entries.push(
        Entry::new(
            "push-task-gate-latency5",
            push(ModelKind::Gate, Variant::Random, vec![1, 3, 10], 2),
        )
        .latency_max(LATENCY_MAX_STEPS_HARSH),
    );
    entries.push(Entry::new(
        "fixed-three-interaction",
        push(ModelKind::Interaction, Variant::FixedThree, vec![3], 2),
    ));
    entries.push(Entry::new(
        "two-objects-6",
        push(ModelKind::Gate, Variant::TwoObjects, vec![6], 2),
    ));
    entries.push(Entry::new(
        "constant-feedback-gate",
        Spec::ConstantFeedback {
            model: ModelKind::Gate.into(),
            options: ModelOptions::default(),
        },
    ));
    for model in MODELS {
        entries.push(Entry::new(
            format!("move-to-target-{model}"),
            move_to_target(model, 1),
        ));
    }
    // The reference rows on the curves' runs: every kind of reference
    // checked in CI, for a second or two.
    for (name, learner) in references() {
        entries.push(Entry::new(
            reference_entry_name(name, ""),
            Spec::PushTask {
                model: learner,
                options: ModelOptions::default(),
                variant: Variant::Random,
                transfer: None,
                train_runs: vec![1, 3, 10],
                folds: 2,
            },
        ));
    }
    entries
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_commands_name_their_document() {
        for entries in [full(), quick()] {
            let mut names: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
            names.sort_unstable();
            let before = names.len();
            names.dedup();
            assert_eq!(names.len(), before, "duplicate names");
            for e in &entries {
                let command = e.command("docs/results");
                assert!(
                    command.ends_with(&format!("--json docs/results/{}.json", e.name)),
                    "{command}"
                );
                e.spec.validate().expect("every entry is runnable");
            }
        }
    }

    #[test]
    fn every_baseline_runs_in_the_baselines_and_new_object_tables() {
        let names: Vec<String> = full().into_iter().map(|e| e.name).collect();
        let objects: Vec<&str> = object_learners().into_iter().map(|(n, _)| n).collect();
        for b in BASELINES {
            let name = b.document();
            assert!(names.contains(&name), "{name} is not run");
            assert!(
                objects.contains(&b.name),
                "{} is not in the new-object table",
                b.name
            );
            for transfer in transfers() {
                let entry = object_entry_name(b.name, &transfer);
                assert!(names.contains(&entry), "{entry} is not run");
            }
            assert!(b.class.starts_with("pushlearn.baselines:"), "{}", b.class);
        }
        assert!(BASELINES.iter().any(|b| b.name == "mlp"));
    }

    /// The package's `BASELINES` (`python/pushlearn/baselines.py`), read
    /// from its source: (name, class) in order. The Rust tests run without
    /// the package installed, and the dict is a literal of one
    /// `"name": Class,` line per baseline.
    fn python_baselines() -> Vec<(String, String)> {
        let source = include_str!("../../../../python/pushlearn/baselines.py");
        let start = "BASELINES: dict[str, type[BaselineLearner]] = {";
        let Some((_, rest)) = source.split_once(start) else {
            panic!("baselines.py has no `{start}`");
        };
        let Some((body, _)) = rest.split_once('}') else {
            panic!("baselines.py's BASELINES does not end");
        };
        body.lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .map(|l| {
                let Some((key, class)) = l.trim_end_matches(',').split_once(':') else {
                    panic!("not a `\"name\": Class,` line in BASELINES: {l}");
                };
                (
                    key.trim().trim_matches('"').to_owned(),
                    class.trim().to_owned(),
                )
            })
            .collect()
    }

    #[test]
    fn the_baselines_are_the_python_packages() {
        let ours: Vec<(String, String)> = BASELINES
            .iter()
            .map(|b| {
                let class = b.class.trim_start_matches("pushlearn.baselines:");
                (b.name.to_owned(), class.to_owned())
            })
            .collect();
        assert_eq!(ours, python_baselines());
    }

    #[test]
    fn commands_spell_out_only_what_differs_from_the_defaults() {
        let entries = full();
        let find = |name: &str| {
            entries
                .iter()
                .find(|e| e.name == name)
                .map(|e| e.command("d"))
                .expect("entry")
        };
        assert_eq!(
            find("push-task-gate"),
            "pushlearn experiment push-task --model gate --json d/push-task-gate.json"
        );
        assert_eq!(
            find("push-task-interaction-latency5"),
            "pushlearn experiment push-task --model interaction --latency-max 5 --json d/push-task-interaction-latency5.json"
        );
        assert_eq!(
            find("two-objects-7"),
            "pushlearn experiment push-task --model gate --variant two-objects --train-runs 7 --json d/two-objects-7.json"
        );
        assert_eq!(
            find("selector-tree"),
            "pushlearn experiment push-task --model interaction --variant draft --train-runs 3,10,30 --folds 5 --selector tree --json d/selector-tree.json"
        );
        assert_eq!(
            find("move-to-target-gate-seed3"),
            "pushlearn experiment move-to-target --model gate --seed 3 --json d/move-to-target-gate-seed3.json"
        );
        assert_eq!(
            find("beyond-push-unrounded"),
            "pushlearn experiment push-task --model gate --train-runs 1,3,10,30 --improve unrounded --json d/beyond-push-unrounded.json"
        );
        assert_eq!(
            find("beyond-mtt-gate-plus"),
            "pushlearn experiment move-to-target --model gate+ --json d/beyond-mtt-gate-plus.json"
        );
        assert_eq!(
            find("beyond-sampled-gate"),
            "pushlearn experiment move-to-target --model gate --sample-targets 100 --repetitions 1 --json d/beyond-sampled-gate.json"
        );
        assert_eq!(
            find("draft"),
            "pushlearn experiment push-task --report draft --json d/draft.json"
        );
        assert_eq!(
            find("beyond-push-hybrid-mechanics"),
            "pushlearn experiment push-task --model hybrid --train-runs 1,3,10,30 --parts mechanics --json d/beyond-push-hybrid-mechanics.json"
        );
        assert_eq!(
            find("reference-oracle-unknown-latency5"),
            "pushlearn experiment push-task --oracle unknown --latency-max 5 --json d/reference-oracle-unknown-latency5.json"
        );
        assert_eq!(
            find("reference-still-lockstep"),
            "pushlearn experiment push-task --model still --mode lockstep --json d/reference-still-lockstep.json"
        );
    }

    #[test]
    fn every_reference_is_in_every_table_of_learners() {
        let names: Vec<String> = full().into_iter().map(|e| e.name).collect();
        let objects: Vec<&str> = object_learners().into_iter().map(|(n, _)| n).collect();
        for (reference, _) in references() {
            for (suffix, ..) in TIMINGS {
                let entry = reference_entry_name(reference, suffix);
                assert!(names.contains(&entry), "{entry} is not run");
            }
            assert!(objects.contains(&reference), "{reference}");
            assert!(CROSS_LEARNERS.contains(&reference), "{reference}");
        }
        assert!(
            !names.iter().any(|n| n.contains("floor")),
            "the floor is gone"
        );
    }
}
