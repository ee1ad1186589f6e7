//! How the per-message work of each model grows with experience
//! (docs/performance.md §5): both models learn the same push-task training
//! runs of the in-process world, one after the other; after every window of
//! runs this writes the model's node count (all maps) and the p50/p99 of the
//! window's per-message work as CSV, then draws `cost-growth.{png,svg}`:
//!
//!   cargo run --release -p pushlearn-cli --example cost_growth -- --runs 300
//!
//! One point per window of `--window` runs (the node count at its end, the
//! percentiles over all its messages): a single run's 150 messages make a
//! noisy p99 on a shared machine.
//!
//! Per-message work is what the learner daemon does with a parsed state
//! (`crates/cli/src/learn/mod.rs`): `update` (or `reset_objects` on a run's first
//! message), `act` towards a Move-to-Target target (the planner's inverse
//! queries; its action is not sent, since the runs are recorded pushes) and
//! `predict` under the push. Parsing and the socket are left out. Runs start
//! at seeded random positions (`docs/spec/experiments.md` §3, §5) and end, as the
//! driver's do, when the actuator leaves the area.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Parser;
use learner::eval::{self, MESSAGES_PER_RUN, PUSH_ACTION};
use learner::{Frame, GateModel, InteractionModel, Model, Target, BLUE_ID};
use pushlearn_cli::latency::Latencies;
use pushlearn_cli::report::plot::{self, CostPoint};
use pushlearn_cli::results::move_to_target::TARGETS;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sim_plugin::{Scene, World};

#[path = "../../../sim-plugin/tests/support/push_frames.rs"]
mod push_frames;
use push_frames::record_run;

#[derive(Parser)]
#[command(about = "Per-message work of the gate and interaction models against their node count")]
struct Args {
    /// Training runs each model learns.
    #[arg(long, default_value_t = 300)]
    runs: usize,
    /// Directory of the figure (cost-growth.png and .svg).
    #[arg(long, default_value = "docs/figures")]
    figures: PathBuf,
    /// Where the measurements go as CSV.
    #[arg(long, default_value = "target/cost_growth.csv")]
    csv: PathBuf,
    /// Runs per point.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..))]
    window: u64,
    /// Seed of the training starts.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// One model learning run after run, with its name.
struct Learner<M: Model> {
    name: &'static str,
    model: M,
    rng: ChaCha8Rng,
    /// Per-message times of the current window.
    times: Latencies,
}

impl<M: Model> Learner<M> {
    fn new(name: &'static str, model: M) -> Self {
        Self {
            name,
            model,
            rng: ChaCha8Rng::seed_from_u64(1),
            times: Latencies::default(),
        }
    }

    /// Learns one recorded run, timing every message's work.
    fn learn(&mut self, frames: &[Frame]) -> anyhow::Result<()> {
        let target = Target::new(BLUE_ID, TARGETS[0]);
        self.model.set_training(true);
        for (k, frame) in frames.iter().take(MESSAGES_PER_RUN).enumerate() {
            let world = self.model.parse(frame)?;
            if eval::actuator_left_area(&M::poses(&world)) {
                break;
            }
            let start = Instant::now();
            if k == 0 {
                self.model.reset_objects(&world);
            } else {
                self.model.update(&world, PUSH_ACTION);
            }
            // The target is cleared once reached; the planner's work is
            // measured only while it has one.
            if !self.model.has_target() {
                self.model.set_target(Some(target))?;
            }
            std::hint::black_box(self.model.act(&mut self.rng));
            std::hint::black_box(self.model.predict(&world, PUSH_ACTION));
            self.times.record(start.elapsed());
        }
        Ok(())
    }

    /// The point of the window that ends after `runs` runs; starts the next.
    fn point(&mut self, runs: usize) -> CostPoint {
        let times = std::mem::take(&mut self.times);
        let us = |q: f64| times.quantile(q).as_secs_f64() * 1e6;
        CostPoint {
            model: self.name.to_owned(),
            runs,
            nodes: self.model.stats().maps().iter().map(|(_, m)| m.nodes).sum(),
            p50_us: us(0.5),
            p99_us: us(0.99),
        }
    }
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let scene = Scene::builtin("one_block").context("the embedded scene")?;
    let mut world = World::new(&scene)?;
    let mut starts = ChaCha8Rng::seed_from_u64(args.seed);
    let mut gate = Learner::new("gate", GateModel::default());
    let mut interaction = Learner::new("interaction", InteractionModel::default());
    let mut points = Vec::with_capacity(2 * args.runs);
    for run in 1..=args.runs {
        let frames = record_run(
            &mut world,
            eval::random_training_start(starts.random::<f64>()),
        );
        gate.learn(&frames)?;
        interaction.learn(&frames)?;
        if !(run as u64).is_multiple_of(args.window) && run != args.runs {
            continue;
        }
        let g = gate.point(run);
        let i = interaction.point(run);
        if run % 50 == 0 || run == args.runs {
            eprintln!(
                "run {run}/{}: gate {} nodes p50 {:.1} µs p99 {:.1} µs; interaction {} nodes p50 {:.1} µs p99 {:.1} µs",
                args.runs, g.nodes, g.p50_us, g.p99_us, i.nodes, i.p50_us, i.p99_us
            );
        }
        points.push(g);
        points.push(i);
    }
    std::fs::write(&args.csv, plot::cost_csv(&points))
        .with_context(|| format!("cannot write {}", args.csv.display()))?;
    let title = format!(
        "Per-message work (update + act + predict) against node count: {} push-task training runs, a point per {}",
        args.runs, args.window
    );
    for path in plot::cost_growth(&points, &title, &args.figures)? {
        eprintln!("wrote {}", path.display());
    }
    eprintln!("wrote {}", args.csv.display());
    Ok(())
}
