//! `pushlearn report`: tables and figures again from a saved `--json` file,
//! without re-running the experiment.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use pushlearn_cli::output;
use pushlearn_cli::results::ReadError;
use pushlearn_cli::spec::Document;

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
        /// Also write every printed table as CSV into DIR, as `--csv DIR`
        /// of `pushlearn experiment` does.
        #[arg(long, value_name = "DIR")]
        csv: Option<PathBuf>,
    },
}

/// The document in `file`, its model known ([`Document::read`]).
fn load(file: &std::path::Path) -> Result<Document> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    Document::read(&text).map_err(|e| match e {
        ReadError::UnknownModel(model) => anyhow::anyhow!("{}: {model}", file.display()),
        e => anyhow::Error::new(e).context(format!("reading {}", file.display())),
    })
}

/// Runs `pushlearn report`.
pub fn run(args: ReportArgs) -> Result<()> {
    match args.command {
        ReportCommand::Plot { file, out } => {
            let written = load(&file)?.plot(&out)?;
            let mut stdout = std::io::stdout().lock();
            for path in written {
                writeln!(stdout, "{}", path.display())?;
            }
            Ok(stdout.flush()?)
        }
        ReportCommand::Show { file, csv } => {
            if let Some(dir) = &csv {
                output::check_writable_dir(dir)
                    .with_context(|| format!("cannot write CSV files into {}", dir.display()))?;
            }
            let printout = load(&file)?.printout()?;
            if let Some(dir) = &csv {
                let written = printout
                    .write_csv(dir)
                    .with_context(|| format!("writing CSV files into {}", dir.display()))?;
                eprintln!("wrote {} CSV files to {}", written.len(), dir.display());
            }
            let mut out = std::io::stdout().lock();
            printout.write_text(&mut out)?;
            Ok(out.flush()?)
        }
    }
}
