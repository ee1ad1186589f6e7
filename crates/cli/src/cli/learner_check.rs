//! `pushlearn learner-check`: a learner's conformance to the learner
//! protocol, checked in seconds before a twenty-fold run.

use std::time::Duration;

use anyhow::{bail, Result};
use clap::Args;
use pushlearn_cli::external::check::{check, Findings, Outcome};
use pushlearn_cli::external::{LearnerSpec, Source};

/// Check a learner against the learner protocol (docs/learner-protocol.md)
/// before running an experiment with it.
///
/// Runs short scripted conversations through the experiment driver's own
/// client, so the learner meets exactly the requests and checks of
/// `pushlearn experiment … --learner CMD`: the hello; a push-task fold
/// (NewFold, a training run of Reset, Update and Predict, SetTraining,
/// GetStats, a test run of predictions chained from LAST_PREDICTION); a
/// second fold with the same seed and states, which must predict the same
/// (a fold boundary forgets everything); and, if the learner announces
/// INVERSE, a short Move to Target (SetTarget, Update and Act). Each rule
/// broken is reported with the driver's own error; a broken conversation
/// ends, the next starts afresh.
///
/// Exit status 0 when no rule is broken (warnings are printed), 1 otherwise.
///
/// Example: pushlearn learner-check "python3 -m pushlearn.serve mylearner.py:MyLearner"
#[derive(Debug, Args)]
pub struct LearnerCheckArgs {
    /// The learner's command (run by `sh -c`, as `--learner CMD` runs it).
    #[arg(value_name = "CMD", required_unless_present = "connect")]
    command: Option<String>,

    /// Check a learner daemon at HOST:PORT instead (as `--learner-connect`).
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "command")]
    connect: Option<String>,

    /// How long the learner may take over one answer, in seconds.
    #[arg(long, value_name = "SECS", default_value_t = 10.0, value_parser = parse_timeout)]
    timeout: f64,

    /// The publish rate the conversations announce in Start (100 or 10 Hz,
    /// as the experiments' config bit 2 chooses).
    #[arg(long, value_name = "HZ", default_value_t = 100, value_parser = parse_rate)]
    rate: u32,
}

fn parse_timeout(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0 && *v <= 3600.0)
        .ok_or_else(|| format!("'{text}' is not a number of seconds in (0, 3600]"))
}

fn parse_rate(text: &str) -> Result<u32, String> {
    match text.parse::<u32>() {
        Ok(rate @ (10 | 100)) => Ok(rate),
        _ => Err(format!(
            "'{text}' is not a rate the experiments use (100 or 10)"
        )),
    }
}

/// # Errors
/// A rule was broken.
pub fn run(args: LearnerCheckArgs) -> Result<()> {
    let source = match (args.command, args.connect) {
        (Some(command), _) => Source::Command(command),
        (None, Some(addr)) => Source::Connect(addr),
        (None, None) => bail!("give the learner's command, or --connect HOST:PORT"),
    };
    let spec = LearnerSpec {
        source,
        timeout: Duration::from_secs_f64(args.timeout),
    };
    let found = check(&spec, args.rate);
    print!("{}", render(&spec, &found));
    // Counted by check, not by rule: one broken rule can fail several checks.
    match found.broken() {
        0 => Ok(()),
        n => bail!(
            "the learner failed {n} of the {} checks of the learner protocol",
            found.findings.len()
        ),
    }
}

/// The findings as the terminal shows them.
fn render(spec: &LearnerSpec, found: &Findings) -> String {
    let mut out = match &found.learner {
        Some(l) => format!(
            "learner '{}' {} ({}): {}\n",
            l.name,
            l.version,
            spec.source,
            if l.inverse {
                "FORWARD, INVERSE"
            } else {
                "FORWARD"
            }
        ),
        None => format!("learner {}\n", spec.source),
    };
    for f in &found.findings {
        let (tag, detail) = match &f.outcome {
            Outcome::Kept => ("ok     ", None),
            Outcome::Broken(why) => ("BROKEN ", Some(why)),
            Outcome::Warning(why) => ("warning", Some(why)),
            Outcome::Skipped(why) => ("skipped", Some(why)),
        };
        out.push_str(&format!("  {tag}  {}\n", f.rule));
        if let Some(detail) = detail {
            out.push_str(&format!("           {detail}\n"));
        }
    }
    out
}
