//! An experiment as data: which experiment, which model and options, how
//! many folds ([`Spec`]), checked once into a [`Valid`] and run on a
//! [`Plan`] into its report document ([`Document`]). `pushlearn
//! experiment`, sweeps and `pushlearn.bench` build one from the command's
//! options (`crate::args`), `pushlearn reproduce` has a list of them
//! (`crate::reproduce`).

use learner::{Model, ObjectState};

use crate::experiments::constant_feedback::ConstantFeedback;
use crate::experiments::draft::{self, DraftReport, DraftRowResult, DraftTables};
use crate::experiments::move_to_target::MoveToTarget as MoveToTargetExperiment;
use crate::experiments::push_task::PushTask;
use crate::experiments::Experiment;
use crate::report::layout::Printout;
use crate::report::plot::PlotError;
use drive::experiment::processes::Recipe;
use drive::experiment::push_task::protocol::{Protocol, PushJob, Variant};
use drive::experiment::run::{self, Plan};
use drive::experiment::{ExperimentError, Mode};
use drive::external::{ExternalModel, LearnerChoice, LearnerError};
use drive::oracle::{Oracle, OracleError};
use drive::results::push_task::PushJobResult;
use drive::results::run_info::RunInfo;
use drive::results::LearnerRecord;
use drive::results::{
    AnyReport, FeedbackReport, MttReport, PushReport, ReadError, Setup, UnknownModel,
};
use drive::scene::{self, Transfer, LOW_RATE_HZ, RATE_HZ};
use learner::registry::{ModelKind, ModelOptions, ModelOptionsError, WithModel};

/// One experiment of `docs/spec/experiments.md`, fully configured.
#[derive(Clone, Debug, PartialEq)]
pub enum Spec {
    /// Push Task Simulation (§3.1–§3.3, and the draft's protocol).
    PushTask {
        model: LearnerChoice,
        options: ModelOptions,
        variant: Variant,
        /// The new-object experiments' objects (`objects` scene); `None`
        /// for the thesis's.
        transfer: Option<Transfer>,
        train_runs: Vec<usize>,
        folds: usize,
    },
    /// The push task with constant feedback at 10 Hz (§3.4).
    ConstantFeedback {
        model: LearnerChoice,
        options: ModelOptions,
    },
    /// Move to Target (§4).
    MoveToTarget {
        model: LearnerChoice,
        options: ModelOptions,
        targets: Vec<ObjectState>,
        repetitions: usize,
        max_steps: u64,
    },
    /// Every row of the thesis draft's Tables 6.1 and 6.2, each on the
    /// draft's protocol with `folds` folds.
    DraftTables { folds: usize },
}

/// What a [`Spec`] produced.
#[derive(Clone, Debug, PartialEq)]
pub enum Document {
    Push(PushReport),
    Feedback(FeedbackReport),
    MoveToTarget(MttReport),
    Draft(DraftReport),
}

/// Why a [`Spec`] did not produce its document.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The model options do not fit the model.
    #[error(transparent)]
    Options(#[from] ModelOptionsError),
    /// The experiment failed.
    #[error(transparent)]
    Experiment(#[from] ExperimentError),
    /// The external learner cannot be used.
    #[error(transparent)]
    Learner(#[from] LearnerError),
    /// The configuration cannot be run.
    #[error("{0}")]
    Invalid(String),
}

impl Spec {
    /// The scene the experiment's worlds must load.
    #[must_use]
    pub fn scene(&self) -> &'static str {
        match self {
            Spec::PushTask {
                transfer: Some(_), ..
            } => scene::SCENE,
            Spec::PushTask { variant, .. } => variant.scene(),
            Spec::ConstantFeedback { .. } => Variant::ConstantFeedback.scene(),
            Spec::MoveToTarget { .. } => "one_block",
            Spec::DraftTables { .. } => Variant::Draft.scene(),
        }
    }

    /// The learner the experiment runs (the draft has its own models).
    #[must_use]
    pub fn model(&self) -> Option<&LearnerChoice> {
        match self {
            Spec::PushTask { model, .. }
            | Spec::ConstantFeedback { model, .. }
            | Spec::MoveToTarget { model, .. } => Some(model),
            Spec::DraftTables { .. } => None,
        }
    }

    /// The task's name in the learner protocol's Start.
    #[must_use]
    pub fn task(&self) -> &'static str {
        match self {
            Spec::PushTask { .. } | Spec::DraftTables { .. } => "push-task",
            Spec::ConstantFeedback { .. } => "constant-feedback",
            Spec::MoveToTarget { .. } => "move-to-target",
        }
    }

    /// A few words for progress bars.
    #[must_use]
    pub fn title(&self) -> &'static str {
        match self {
            Spec::PushTask { .. } => "push task",
            Spec::ConstantFeedback { .. } => "constant feedback",
            Spec::MoveToTarget { .. } => "move to target",
            Spec::DraftTables { .. } => "draft tables",
        }
    }

    /// How many jobs the progress callback counts up to.
    #[must_use]
    pub fn jobs(&self) -> usize {
        match self {
            Spec::PushTask {
                train_runs, folds, ..
            } => train_runs.len() * folds,
            Spec::ConstantFeedback { .. } => 1,
            Spec::MoveToTarget {
                targets,
                repetitions,
                ..
            } => targets.len() * repetitions,
            Spec::DraftTables { folds } => draft::rows().len() * folds,
        }
    }

    /// Checks what can be checked before anything runs.
    ///
    /// # Errors
    /// A configuration the experiment cannot run, named.
    pub fn validate(&self) -> Result<(), SpecError> {
        if let Spec::PushTask {
            variant: Variant::TwoObjects,
            train_runs,
            ..
        } = self
        {
            let fixed = Variant::TwoObjects.fixed_starts().len();
            if train_runs.iter().any(|&n| n > fixed) {
                return Err(SpecError::Invalid(format!(
                    "the two-object experiment has {fixed} fixed training starts; --train-runs must not exceed {fixed}"
                )));
            }
        }
        if let Spec::PushTask {
            variant: Variant::ConstantFeedback,
            ..
        } = self
        {
            return Err(SpecError::Invalid(
                "constant feedback is its own experiment (Spec::ConstantFeedback)".into(),
            ));
        }
        if let Spec::PushTask {
            variant,
            transfer: Some(_),
            ..
        } = self
        {
            if *variant != Variant::Random {
                return Err(SpecError::Invalid(format!(
                    "the new-object experiments (--train-on, --test-on) use the random variant's protocol; drop --variant {}",
                    variant.as_str()
                )));
            }
        }
        if matches!(self.model(), Some(LearnerChoice::Oracle(_)))
            && matches!(self, Spec::MoveToTarget { .. })
        {
            return Err(SpecError::Invalid(
                "an oracle (--oracle) predicts but does not plan: it has no Move to Target".into(),
            ));
        }
        Ok(())
    }

    /// The spec, checked ([`validate`](Self::validate)): what runs take, so
    /// that a run checks its spec once, whoever made it.
    ///
    /// # Errors
    /// As [`validate`](Self::validate).
    pub fn validated(self) -> Result<Valid, SpecError> {
        self.validate()?;
        Ok(Valid(self))
    }

    /// The rate its learner is published world states at (the push
    /// protocol's, 10 Hz for constant feedback); `None` for the draft's
    /// tables, which run their own models.
    #[must_use]
    pub fn publish_rate_hz(&self) -> Option<u32> {
        self.learner().map(|(_, _, rate_hz)| rate_hz)
    }

    /// An experiment's learner, its model options and the learner's
    /// publish rate (the push protocol's, 10 Hz for constant feedback);
    /// `None` for the draft's tables, which run their own models.
    fn learner(&self) -> Option<(&LearnerChoice, &ModelOptions, u32)> {
        match self {
            Spec::PushTask { model, options, .. } => {
                Some((model, options, self.push_protocol()?.rate_hz))
            }
            Spec::ConstantFeedback { model, options } => Some((model, options, LOW_RATE_HZ)),
            Spec::MoveToTarget { model, options, .. } => Some((model, options, RATE_HZ)),
            Spec::DraftTables { .. } => None,
        }
    }
}

/// A [`Spec`] that [`Spec::validate`] accepted ([`Spec::validated`]); it
/// runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Valid(Spec);

impl std::ops::Deref for Valid {
    type Target = Spec;
    fn deref(&self) -> &Spec {
        &self.0
    }
}

impl Valid {
    /// Runs the experiment on `plan` (whose model name is replaced by this
    /// spec's), calling `progress` with the number of jobs done.
    ///
    /// # Errors
    /// Options that do not fit the model, or the first failing job.
    pub fn run(&self, plan: &Plan, progress: impl Fn(usize)) -> Result<Document, SpecError> {
        let Some((model, options, rate_hz)) = self.learner() else {
            return match &self.0 {
                Spec::DraftTables { folds } => {
                    Ok(Document::Draft(draft_tables(*folds, plan, progress)?))
                }
                _ => Err(SpecError::Invalid(format!(
                    "{} has no learner",
                    self.title()
                ))),
            };
        };
        let mut plan = plan.clone();
        let ready = Ready::new(
            model,
            options,
            (self.task(), self.scene()),
            rate_hz,
            &mut plan,
        )?;
        if let (
            Ready::Builtin(kind),
            Spec::PushTask {
                train_runs, folds, ..
            },
            Some(protocol),
        ) = (&ready, &self.0, self.push_protocol())
        {
            // Worker processes build the model from the plan's recipe:
            // here its options are only checked.
            if plan.runs_in_workers(rate_hz) {
                kind.check(options, rate_hz)?;
                if let Some(report) =
                    run::push_task_in_workers(&protocol, train_runs, *folds, &plan, &progress)
                {
                    return Ok(Document::Push(report?));
                }
            }
        }
        ready.dispatch(
            options,
            rate_hz,
            Whole {
                spec: self,
                plan: &plan,
                progress: &progress,
            },
        )?
    }

    /// Runs the experiment with `untrained` as its learner: a model the
    /// caller made (the Python API's learner objects,
    /// [`LearnerChoice::InProcess`]), named in the reports by `plan`'s
    /// `model` and `learner`. Every fold starts from a clone of `untrained`
    /// ([`Model::start_fold`]), as with the spec's own learners.
    ///
    /// # Errors
    /// The draft's tables (they run their own models), an invalid
    /// configuration, or the first failing job.
    pub fn run_with<M: Model + 'static>(
        &self,
        plan: &Plan,
        untrained: M,
        progress: impl Fn(usize),
    ) -> Result<Document, SpecError> {
        Ok(match &self.0 {
            Spec::PushTask {
                train_runs, folds, ..
            } => {
                let protocol = self
                    .push_protocol()
                    .ok_or_else(|| SpecError::Invalid("a push task has a protocol".into()))?;
                Document::Push(run::push_task(
                    untrained, &protocol, train_runs, *folds, plan, progress,
                )?)
            }
            Spec::ConstantFeedback { .. } => {
                progress(0);
                let report = run::constant_feedback(untrained, plan)?;
                progress(1);
                Document::Feedback(report)
            }
            Spec::MoveToTarget {
                targets,
                repetitions,
                max_steps,
                ..
            } => Document::MoveToTarget(run::move_to_target(
                untrained,
                targets,
                *repetitions,
                *max_steps,
                plan,
                progress,
            )?),
            Spec::DraftTables { .. } => {
                return Err(SpecError::Invalid(
                    "the draft's tables run the draft's own models, not a given learner".into(),
                ))
            }
        })
    }

    /// Runs only the jobs `wanted` — (N_train, fold) pairs — of a
    /// [`Spec::PushTask`] on `plan`, calling `done` with the report's setup
    /// and each job's result as it finishes (`pushlearn sweep`: one fold of
    /// one configuration is a job). A job's seeds depend only on the plan's
    /// seed and its own (N_train, fold), so its result is the one the whole
    /// experiment would have given it.
    ///
    /// # Errors
    /// Not a push task, options that do not fit the model, the first failing job or the first
    /// error of `done`.
    pub fn run_push_jobs(
        &self,
        plan: &Plan,
        wanted: &[(usize, usize)],
        done: impl Fn(&Setup, &PushJobResult) -> Result<(), ExperimentError> + Sync,
        progress: impl Fn(usize),
    ) -> Result<(), SpecError> {
        let (Spec::PushTask { model, options, .. }, Some(protocol)) =
            (&self.0, self.push_protocol())
        else {
            return Err(SpecError::Invalid(format!(
                "a sweep job is one fold of a push task, not of {}",
                self.title()
            )));
        };
        let mut plan = plan.clone();
        let ready = Ready::new(
            model,
            options,
            (self.task(), self.scene()),
            protocol.rate_hz,
            &mut plan,
        )?;
        let setup = plan.setup(drive::results::push_task::EXPERIMENT);
        let mut all = PushJob::all(protocol.clone(), &[], 0, plan.seed);
        for &(n_train, fold) in wanted {
            all.extend(
                PushJob::all(protocol.clone(), &[n_train], fold + 1, plan.seed)
                    .into_iter()
                    .filter(|job| job.fold == fold),
            );
        }
        if let Ready::Builtin(kind) = &ready {
            // As in `run`: worker processes build the model themselves.
            if plan.runs_in_workers(protocol.rate_hz) {
                kind.check(options, protocol.rate_hz)?;
                let done = |result: &PushJobResult| done(&setup, result);
                if let Some(results) =
                    run::push_jobs_in_workers(protocol.rate_hz, &all, &plan, done, &progress)
                {
                    results?;
                    return Ok(());
                }
            }
        }
        ready.dispatch(
            options,
            protocol.rate_hz,
            PushSome {
                rate_hz: protocol.rate_hz,
                jobs: &all,
                plan: &plan,
                done: &|result: &PushJobResult| done(&setup, result),
                progress: &progress,
            },
        )??;
        Ok(())
    }
}

/// A whole experiment of a spec with the model [`Ready::dispatch`] makes.
struct Whole<'a> {
    spec: &'a Valid,
    plan: &'a Plan,
    progress: &'a dyn Fn(usize),
}

impl WithModel for Whole<'_> {
    type Output = Result<Document, SpecError>;
    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        self.spec.run_with(self.plan, untrained, self.progress)
    }
}

impl Spec {
    /// The push-task protocol of a [`Spec::PushTask`] (else `None`).
    #[must_use]
    pub fn push_protocol(&self) -> Option<Protocol> {
        match self {
            Spec::PushTask {
                options,
                variant,
                transfer,
                ..
            } => Some(
                Protocol::new(*variant, options.config_number()).with_transfer(transfer.clone()),
            ),
            _ => None,
        }
    }

    /// The report of a [`Spec::PushTask`] from its jobs' results (as
    /// [`Valid::run_push_jobs`] gave them) and the `setup` they ran under,
    /// without timing: what `pushlearn experiment` writes for the spec, less
    /// its machine-dependent part.
    ///
    /// # Errors
    /// Not a push task, or results that do not cover every N_train.
    pub fn push_report(
        &self,
        setup: Setup,
        results: &[PushJobResult],
    ) -> Result<PushReport, SpecError> {
        match (self, self.push_protocol()) {
            (
                Spec::PushTask {
                    train_runs, folds, ..
                },
                Some(protocol),
            ) => Ok(run::push_report(
                setup, &protocol, train_runs, *folds, results,
            )?),
            _ => Err(SpecError::Invalid(format!(
                "only a push task's report is made of fold jobs, not {}'s",
                self.title()
            ))),
        }
    }
}

/// Some jobs of a push task, for [`Valid::run_push_jobs`].
struct PushSome<'a> {
    rate_hz: u32,
    jobs: &'a [PushJob],
    plan: &'a Plan,
    done: &'a (dyn Fn(&PushJobResult) -> Result<(), ExperimentError> + Sync),
    progress: &'a dyn Fn(usize),
}

impl WithModel for PushSome<'_> {
    type Output = Result<Vec<PushJobResult>, ExperimentError>;
    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        run::push_jobs(
            untrained,
            self.rate_hz,
            self.jobs,
            self.plan,
            self.done,
            self.progress,
        )
    }
}

/// Every row of the draft's tables on the draft's protocol, one after the
/// other on `plan` (so with its cache, if it has one).
fn draft_tables(
    folds: usize,
    plan: &Plan,
    progress: impl Fn(usize),
) -> Result<DraftReport, SpecError> {
    let rows = draft::rows();
    let mut results = Vec::new();
    let mut reports = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        let mut plan = plan.clone();
        row.model.as_str().clone_into(&mut plan.model);
        let protocol = Protocol::new(Variant::Draft, row.options.config_number());
        plan.recipe = Some(Recipe::Builtin {
            kind: row.model,
            options: row.options.clone(),
            publish_rate_hz: protocol.rate_hz,
        });
        let in_workers = if plan.runs_in_workers(protocol.rate_hz) {
            row.model.check(&row.options, protocol.rate_hz)?;
            run::push_task_in_workers(&protocol, &[row.train_runs], folds, &plan, &|done| {
                progress(i * folds + done)
            })
        } else {
            None
        };
        let report = match in_workers {
            Some(report) => report?,
            None => row.model.dispatch(
                &row.options,
                protocol.rate_hz,
                Push {
                    protocol: &protocol,
                    train_runs: &[row.train_runs],
                    folds,
                    plan: &plan,
                    progress: &|done| progress(i * folds + done),
                },
            )??,
        };
        let entry = report
            .results
            .first()
            .ok_or_else(|| SpecError::Invalid(format!("draft row {} gave no results", row.name)))?;
        results.push(DraftRowResult::of(row, entry));
        reports.push(report);
    }
    let setup = reports
        .first()
        .map(|r| r.setup.clone())
        .ok_or_else(|| SpecError::Invalid("the draft has no rows".into()))?;
    Ok(DraftReport {
        setup,
        folds,
        test_positions: Protocol::from(Variant::Draft).test_positions,
        rows: results,
        reports,
    })
}

impl Document {
    /// The document's setup (its experiment, model, mode and seed).
    #[must_use]
    pub fn setup(&self) -> &Setup {
        match self {
            Document::Push(r) => PushTask::setup(r),
            Document::Feedback(r) => ConstantFeedback::setup(r),
            Document::MoveToTarget(r) => MoveToTargetExperiment::setup(r),
            Document::Draft(r) => DraftTables::setup(r),
        }
    }

    /// How its runs went: one, or one per row of the draft's tables.
    #[must_use]
    pub fn runs(&self) -> Vec<&RunInfo> {
        match self {
            Document::Push(r) => PushTask::runs(r),
            Document::Feedback(r) => ConstantFeedback::runs(r),
            Document::MoveToTarget(r) => MoveToTargetExperiment::runs(r),
            Document::Draft(r) => DraftTables::runs(r),
        }
    }

    /// The document without its machine-dependent parts, so that two runs
    /// of the same spec give the same bytes.
    #[must_use]
    pub fn without_timing(self) -> Self {
        match self {
            Document::Push(r) => Document::Push(PushTask::without_timing(r)),
            Document::Feedback(r) => Document::Feedback(ConstantFeedback::without_timing(r)),
            Document::MoveToTarget(r) => {
                Document::MoveToTarget(MoveToTargetExperiment::without_timing(r))
            }
            Document::Draft(r) => Document::Draft(DraftTables::without_timing(r)),
        }
    }

    /// The document without its fold-level detail
    /// ([`CurveEntry::without_folds`](drive::results::push_task::CurveEntry::without_folds)),
    /// as the reproduction keeps its documents.
    #[must_use]
    pub fn without_folds(self) -> Self {
        match self {
            Document::Push(r) => Document::Push(PushTask::without_folds(r)),
            Document::Feedback(r) => Document::Feedback(ConstantFeedback::without_folds(r)),
            Document::MoveToTarget(r) => {
                Document::MoveToTarget(MoveToTargetExperiment::without_folds(r))
            }
            Document::Draft(r) => Document::Draft(DraftTables::without_folds(r)),
        }
    }

    /// The terminal tables beside the thesis's numbers, as `pushlearn
    /// experiment` prints them, each also as CSV.
    ///
    /// # Errors
    /// A model the thesis's numbers cannot be chosen for
    /// ([`Setup::reference_model`]; never a document of a run or one read
    /// back by [`AnyReport::from_json`]).
    pub fn printout(&self) -> Result<Printout, UnknownModel> {
        match self {
            Document::Push(r) => PushTask::printout(r),
            Document::Feedback(r) => ConstantFeedback::printout(r),
            Document::MoveToTarget(r) => MoveToTargetExperiment::printout(r),
            Document::Draft(r) => DraftTables::printout(r),
        }
    }

    /// The terminal tables beside the thesis's numbers, as `pushlearn
    /// experiment` prints them.
    ///
    /// # Errors
    /// Writing to `out`, or an unknown model (as [`Document::printout`]).
    pub fn write_tables(&self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        let printout = self
            .printout()
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))?;
        printout.write_text(out)
    }

    /// Draws the document's figures into `dir` (the draft's tables have
    /// none).
    ///
    /// # Errors
    /// A figure cannot be drawn or written, or an unknown model (as
    /// [`Document::printout`]).
    pub fn plot(&self, dir: &std::path::Path) -> Result<Vec<std::path::PathBuf>, PlotError> {
        match self {
            Document::Push(r) => PushTask::figures(r, dir),
            Document::Feedback(r) => ConstantFeedback::figures(r, dir),
            Document::MoveToTarget(r) => MoveToTargetExperiment::figures(r, dir),
            Document::Draft(r) => DraftTables::figures(r, dir),
        }
    }

    /// Reads any document `pushlearn experiment --json` writes: one of the
    /// engine's reports ([`AnyReport::from_json`]), or the draft's tables,
    /// told apart by their `rows` of the draft's configurations.
    ///
    /// # Errors
    /// Not JSON, not one of the documents, or a model that is neither
    /// built in nor an external learner.
    pub fn read(text: &str) -> Result<Self, ReadError> {
        let value: serde_json::Value = serde_json::from_str(text)?;
        if value.get("rows").is_some() && value.get("reports").is_some() {
            return serde_json::from_value(value)
                .map(Document::Draft)
                .map_err(|source| ReadError::Shape {
                    experiment: "draft tables".to_owned(),
                    source,
                });
        }
        Ok(Document::from(AnyReport::from_json(text)?))
    }

    /// Reads back a document `spec` produced (as [`Document::to_json`]
    /// wrote it).
    ///
    /// # Errors
    /// Not JSON, not a report, or a report of another experiment.
    pub fn from_json(text: &str, spec: &Spec) -> Result<Self, String> {
        let document = Document::read(text).map_err(|e| e.to_string())?;
        let fits = matches!(
            (&document, spec),
            (Document::Push(_), Spec::PushTask { .. })
                | (Document::Feedback(_), Spec::ConstantFeedback { .. })
                | (Document::MoveToTarget(_), Spec::MoveToTarget { .. })
                | (Document::Draft(_), Spec::DraftTables { .. })
        );
        if fits {
            Ok(document)
        } else {
            Err(format!(
                "a {} document, expected one of {}",
                document.setup().experiment,
                spec.title()
            ))
        }
    }

    /// Pretty JSON, one trailing newline.
    ///
    /// # Errors
    /// Serialisation failed (not expected for these types).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        let mut text = match self {
            Document::Push(r) => serde_json::to_string_pretty(r),
            Document::Feedback(r) => serde_json::to_string_pretty(r),
            Document::MoveToTarget(r) => serde_json::to_string_pretty(r),
            Document::Draft(r) => serde_json::to_string_pretty(r),
        }?;
        text.push('\n');
        Ok(text)
    }
}

impl From<AnyReport> for Document {
    fn from(report: AnyReport) -> Self {
        match report {
            AnyReport::Push(r) => Document::Push(r),
            AnyReport::Feedback(r) => Document::Feedback(r),
            AnyReport::MoveToTarget(r) => Document::MoveToTarget(r),
        }
    }
}

/// A learner ready to run: a built-in model's kind, or a connected
/// external learner. Getting ready names the plan's model.
enum Ready {
    Builtin(ModelKind),
    External(Box<ExternalModel>),
    Oracle(Box<Oracle>),
}

impl Ready {
    fn new(
        choice: &LearnerChoice,
        options: &ModelOptions,
        (task, scene): (&str, &str),
        publish_rate_hz: u32,
        plan: &mut Plan,
    ) -> Result<Self, SpecError> {
        Ok(match choice {
            LearnerChoice::Oracle(latency) => {
                options.check_external()?;
                if plan.mode == Mode::Realtime {
                    return Err(SpecError::Invalid(OracleError::Realtime.to_string()));
                }
                let latency_max = if plan.mode.jitter() {
                    plan.latency_max
                } else {
                    0
                };
                let oracle = Oracle::new(scene, publish_rate_hz, *latency, latency_max)
                    .map_err(|err| SpecError::Invalid(err.to_string()))?;
                latency.report_name().clone_into(&mut plan.model);
                plan.learner = None;
                plan.recipe = Some(Recipe::Oracle {
                    scene: scene.to_owned(),
                    publish_rate_hz,
                    latency: *latency,
                    latency_max,
                });
                Ready::Oracle(Box::new(oracle))
            }
            LearnerChoice::Builtin(kind) => {
                plan.model = options.report_name(*kind);
                plan.learner = None;
                plan.recipe = Some(Recipe::Builtin {
                    kind: *kind,
                    options: options.clone(),
                    publish_rate_hz,
                });
                Ready::Builtin(*kind)
            }
            LearnerChoice::InProcess => {
                return Err(SpecError::Invalid(
                    "a learner object runs through Valid::run_with, which is handed the object"
                        .into(),
                ))
            }
            LearnerChoice::External(spec) => {
                options.check_external()?;
                let model = ExternalModel::connect(spec, task, publish_rate_hz)?;
                model.info().name.clone_into(&mut plan.model);
                plan.learner = Some(LearnerRecord {
                    version: model.info().version.clone(),
                    source: spec.source.to_string(),
                });
                plan.recipe = Some(Recipe::External {
                    spec: spec.clone(),
                    task: task.to_owned(),
                    publish_rate_hz,
                });
                Ready::External(Box::new(model))
            }
        })
    }

    fn dispatch<W: WithModel>(
        self,
        options: &ModelOptions,
        publish_rate_hz: u32,
        job: W,
    ) -> Result<W::Output, ModelOptionsError> {
        match self {
            Ready::Builtin(kind) => kind.dispatch(options, publish_rate_hz, job),
            Ready::External(model) => Ok(job.run(*model)),
            Ready::Oracle(oracle) => Ok(job.run(*oracle)),
        }
    }
}

struct Push<'a> {
    protocol: &'a Protocol,
    train_runs: &'a [usize],
    folds: usize,
    plan: &'a Plan,
    progress: &'a dyn Fn(usize),
}

impl WithModel for Push<'_> {
    type Output = Result<PushReport, ExperimentError>;
    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        run::push_task(
            untrained,
            self.protocol,
            self.train_runs,
            self.folds,
            self.plan,
            self.progress,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drive::results::test_support::{mtt_report, push_report};

    /// Every kind of document reads back as itself, the draft's tables
    /// (which are not one of the engine's reports) included.
    #[test]
    fn every_kind_of_document_reads_back() {
        let push = Document::Push(push_report("random", &[1, 3]));
        let mtt = Document::MoveToTarget(mtt_report());
        let draft = Document::Draft(DraftReport {
            setup: push.setup().clone(),
            folds: 1,
            test_positions: vec![0.1, -0.2],
            rows: Vec::new(),
            reports: vec![push_report("draft", &[3])],
        });
        for document in [push, mtt, draft] {
            let text = document.to_json().expect("serialises");
            assert_eq!(Document::read(&text).expect("reads back"), document);
        }
        let err = Document::read(r#"{"rows": [], "reports": 3}"#).unwrap_err();
        assert!(
            err.to_string().starts_with("not a draft tables document"),
            "{err}"
        );
    }
}
