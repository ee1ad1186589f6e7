//! `pushlearn-sim`: the thesis world on ODE.
//!
//! Each subcommand lives in its own function; the daemon is meant to join as
//! one more variant of [`Cmd`] (`serve`) with its own `run_*` function.

use std::io::Write;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use sim_plugin::scene::DEFAULT_SCENE;
use sim_plugin::{Scene, SweepOptions, SweepRow};

#[derive(Debug, Parser)]
#[command(
    name = "pushlearn-sim",
    version,
    about = "The thesis's table-top pushing world on ODE",
    long_about = "The thesis's table-top pushing world on ODE (Debian's libode, double precision): \
                  an actuator sphere driven by velocity commands pushes blocks on a plane in 1 ms steps.\n\n\
                  Scenes are TOML files or the embedded `one_block` (default) and `two_blocks`; \
                  see docs/world.md for the format."
)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Run the calibration sweep: the push (0, 0.5) m/s from 21 starts x0 = -0.35 … 0.35,
    /// 150 messages at 100 Hz each, and report the blue block's outcome.
    #[command(long_about = "Run the thesis's calibration sweep (world.md §10).\n\n\
                      For each start x0 = -0.35 + 0.035·i (i = 0…20): reset, place the actuator at \
                      (x0, 0, 0.03), command Move (0, 0.5) m/s, step 150 messages at 100 Hz \
                      (1500 steps of 1 ms), and report the blue block (blockA): the first message \
                      whose interval contained an actuator–block contact, its final x, y and yaw, \
                      its translation from the start and its rotation.")]
    Sweep(SweepArgs),
}

#[derive(Debug, Args)]
struct SweepArgs {
    /// Built-in scene name (`one_block`, `two_blocks`) or path to a scene TOML file.
    #[arg(long, value_name = "NAME_OR_FILE", default_value = DEFAULT_SCENE)]
    scene: String,
    /// Print a JSON array of objects with the keys x0, first_contact_message, block_x,
    /// block_y, block_yaw, translation, rotation (metres, radians) instead of a table.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    let result = match cli.command {
        Cmd::Sweep(args) => run_sweep(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("pushlearn-sim: {err:#}");
            ExitCode::FAILURE
        }
    }
}

fn run_sweep(args: &SweepArgs) -> anyhow::Result<()> {
    let scene =
        Scene::load(&args.scene).with_context(|| format!("loading scene `{}`", args.scene))?;
    tracing::info!(scene = %scene.name, "running the calibration sweep");
    let rows = sim_plugin::sweep(&scene, &SweepOptions::default()).context("running the sweep")?;
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &rows)?;
        writeln!(out)?;
    } else {
        write_table(&mut out, &scene.name, &rows)?;
    }
    Ok(())
}

fn write_table(out: &mut impl Write, scene: &str, rows: &[SweepRow]) -> std::io::Result<()> {
    writeln!(
        out,
        "calibration sweep, scene {scene}: push (0, 0.5) m/s, 150 messages at 100 Hz; blue block"
    )?;
    writeln!(
        out,
        "{:>7}  {:>13}  {:>8}  {:>8}  {:>9}  {:>11}  {:>9}",
        "x0", "first contact", "x", "y", "yaw", "translation", "rotation"
    )?;
    for r in rows {
        let contact = r
            .first_contact_message
            .map_or_else(|| "-".to_owned(), |m| m.to_string());
        writeln!(
            out,
            "{:>7.3}  {:>13}  {:>8.4}  {:>8.4}  {:>9.4}  {:>11.4}  {:>9.4}",
            r.x0, contact, r.block_x, r.block_y, r.block_yaw, r.translation, r.rotation
        )?;
    }
    Ok(())
}
