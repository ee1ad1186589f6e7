//! `pushlearn report`: tables and figures again from a saved `--json` file,
//! without re-running the experiment.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use pushlearn_cli::models::ModelKind;
use pushlearn_cli::report::{plot, table};
use pushlearn_cli::results::AnyReport;

/// Print the table or draw the figures of a report saved with `--json`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(subcommand)]
    command: ReportCommand,
}

#[derive(Debug, Subcommand)]
enum ReportCommand {
    /// Draw the figures (PNG and SVG), as `--plots DIR` does.
    Plot {
        /// A file written by `pushlearn experiment … --json FILE`.
        file: PathBuf,
        /// Directory for the figures, created if needed.
        #[arg(long, value_name = "DIR", default_value = "results")]
        out: PathBuf,
    },
    /// Print the terminal table beside the thesis's numbers.
    Show {
        /// A file written by `pushlearn experiment … --json FILE`.
        file: PathBuf,
    },
}

fn load(file: &std::path::Path) -> Result<(AnyReport, ModelKind)> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let report =
        AnyReport::from_json(&text).with_context(|| format!("reading {}", file.display()))?;
    let model = report.setup().model.as_str();
    let model = <ModelKind as clap::ValueEnum>::from_str(model, false)
        .map_err(|_| anyhow::anyhow!("{}: unknown model {model:?}", file.display()))?;
    Ok((report, model))
}

/// Runs `pushlearn report`.
pub fn run(args: ReportArgs) -> Result<()> {
    match args.command {
        ReportCommand::Plot { file, out } => {
            let (report, model) = load(&file)?;
            let written = match &report {
                AnyReport::Push(r) => plot::push(r, model, &out)?,
                AnyReport::Feedback(r) => plot::feedback(r, model, &out)?,
                AnyReport::MoveToTarget(r) => plot::move_to_target(r, model, &out)?,
            };
            let mut stdout = std::io::stdout().lock();
            for path in written {
                writeln!(stdout, "{}", path.display())?;
            }
            Ok(stdout.flush()?)
        }
        ReportCommand::Show { file } => {
            let (report, model) = load(&file)?;
            let mut out = std::io::stdout().lock();
            match &report {
                AnyReport::Push(r) => table::push(&mut out, r, model)?,
                AnyReport::Feedback(r) => table::feedback(&mut out, r, model)?,
                AnyReport::MoveToTarget(r) => table::move_to_target(&mut out, r, model)?,
            }
            Ok(out.flush()?)
        }
    }
}
