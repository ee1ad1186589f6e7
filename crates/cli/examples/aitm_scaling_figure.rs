//! Draws the AITM-alone scaling figure of docs/performance.md §2 from the
//! table the `aitm_scaling` benchmark writes:
//!
//!   cargo bench -p memories --bench aitm_scaling
//!   cargo run --release -p pushlearn-cli --example aitm_scaling_figure
//!
//! µs per query (along a run, near at random, far) and per update through
//! the spatial index, and the scan's query, against the node count,
//! log-log, one panel per input shape.

use std::path::PathBuf;

use anyhow::Context;
use clap::Parser;
use pushlearn_cli::report::plot;

#[derive(Parser)]
#[command(about = "Draws aitm-scaling.{png,svg} from the aitm_scaling benchmark's CSV")]
struct Args {
    /// The benchmark's table.
    #[arg(default_value = "target/aitm_scaling.csv")]
    csv: PathBuf,
    /// Directory of the figure.
    #[arg(long, default_value = "docs/figures")]
    figures: PathBuf,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let text = std::fs::read_to_string(&args.csv).with_context(|| {
        format!(
            "cannot read {} (run `cargo bench -p memories --bench aitm_scaling` first)",
            args.csv.display()
        )
    })?;
    let rows =
        plot::parse_scaling_csv(&text).with_context(|| format!("in {}", args.csv.display()))?;
    for path in plot::aitm_scaling(&rows, &args.figures)? {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
