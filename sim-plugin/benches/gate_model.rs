//! Gate model time per message after 1, 3, 10 and 30 training runs.
//!
//! The original needs, after 30 runs, ≈ 300 µs per learning update (p99
//! ≈ 0.8 ms) and 150–250 µs per prediction (`docs/spec/reference-results.md` §10);
//! the budget is 20 ms per message (`docs/spec/experiments.md` §6).
//!
//! Data: push-task runs recorded from the in-process world
//! (`sim_plugin::push_run::record_push_run`), 30 training runs at seeded random
//! starts (`docs/spec/experiments.md` §3, §5) trained as the driver does
//! (`learner::eval::train_on_run`), and the 21 test runs.
//!
//! * `gate_update/N`: a copy of the model trained on N runs learns one more
//!   run (one of the test runs, in turn): its 149 updates, training on;
//! * `gate_predict/N`: one prediction per message of the 21 test runs from
//!   the real state (training off; the model is not changed by predicting).
//!
//! Criterion reports the mean per message (throughput in elements). Before
//! that, single calls are timed with `Instant` to print per-message
//! percentiles (the spec's p99), since criterion only sees batches.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BatchSize, BenchmarkId, Criterion, Throughput};
use learner::eval::{self, MESSAGES_PER_RUN, PUSH_ACTION};
use learner::{Frame, GateModel, GateWorld, Model};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sim_plugin::{Scene, World};

#[path = "../tests/support/push_frames.rs"]
mod push_frames;
use push_frames::record_run;

const TRAINING_RUNS: [usize; 4] = [1, 3, 10, 30];

/// Models trained on N runs, and the parsed test runs.
struct Data {
    models: Vec<(usize, GateModel)>,
    /// 21 runs of 151 parsed messages.
    tests: Vec<Vec<GateWorld>>,
}

impl Data {
    fn record() -> Self {
        let scene = Scene::builtin("one_block").expect("embedded scene");
        let mut world = World::new(&scene).expect("world");
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let training: Vec<Vec<Frame>> = (0..30)
            .map(|_| {
                let x0 = eval::random_training_start(rng.random::<f64>());
                record_run(&mut world, x0)
            })
            .collect();
        let parser = GateModel::default();
        let tests = eval::test_positions()
            .iter()
            .map(|&x0| {
                record_run(&mut world, x0)
                    .iter()
                    .map(|f| parser.parse(f).expect("world frames parse"))
                    .collect()
            })
            .collect();
        let mut model = GateModel::default();
        let mut models = Vec::new();
        for (k, frames) in training.iter().enumerate() {
            eval::train_on_run(&mut model, frames, PUSH_ACTION).expect("world frames parse");
            if TRAINING_RUNS.contains(&(k + 1)) {
                models.push((k + 1, model.clone()));
            }
        }
        Self { models, tests }
    }
}

/// A copy of `model` at the start of test run `run`, ready to learn it.
fn ready(model: &GateModel, run: &[GateWorld]) -> GateModel {
    let mut m = model.clone();
    m.set_training(true);
    m.reset_objects(&run[0]);
    m
}

fn learn_run(m: &mut GateModel, run: &[GateWorld]) {
    for w in &run[1..MESSAGES_PER_RUN] {
        m.update(black_box(w), PUSH_ACTION);
    }
}

fn summary(label: &str, mut t: Vec<Duration>) {
    t.sort_unstable();
    let at = |q: f64| t[((t.len() - 1) as f64 * q).round() as usize];
    let mean = t.iter().sum::<Duration>() / t.len() as u32;
    println!(
        "{label}: n {}, mean {mean:.2?}, p50 {:.2?}, p99 {:.2?}, max {:.2?}",
        t.len(),
        at(0.5),
        at(0.99),
        at(1.0)
    );
}

fn percentiles(data: &Data) {
    for (n, model) in &data.models {
        let mut update = Vec::new();
        for run in &data.tests {
            let mut m = ready(model, run);
            for w in &run[1..MESSAGES_PER_RUN] {
                let t = Instant::now();
                m.update(black_box(w), PUSH_ACTION);
                update.push(t.elapsed());
            }
        }
        let mut predict = Vec::new();
        for _ in 0..3 {
            for run in &data.tests {
                for w in &run[..MESSAGES_PER_RUN] {
                    let t = Instant::now();
                    black_box(model.predict(black_box(w), PUSH_ACTION));
                    predict.push(t.elapsed());
                }
            }
        }
        let stats = model.stats();
        let nodes = |name| stats.map(&name).map_or(0, |m| m.nodes);
        println!(
            "after {n} runs: gate {} nodes, predictor {} nodes",
            nodes(learner::MapName::Gate),
            nodes(learner::MapName::Predictor(15))
        );
        summary(&format!("  update per message  (N = {n})"), update);
        summary(&format!("  predict per message (N = {n})"), predict);
    }
}

fn bench(c: &mut Criterion, data: &Data) {
    let mut group = c.benchmark_group("gate_update");
    group.throughput(Throughput::Elements(MESSAGES_PER_RUN as u64 - 1));
    for (n, model) in &data.models {
        let mut next = 0;
        group.bench_with_input(BenchmarkId::from_parameter(n), model, |b, model| {
            b.iter_batched(
                || {
                    let run = &data.tests[next % data.tests.len()];
                    next += 1;
                    (ready(model, run), run)
                },
                |(mut m, run)| {
                    learn_run(&mut m, run);
                    m
                },
                BatchSize::LargeInput,
            );
        });
    }
    group.finish();

    let mut group = c.benchmark_group("gate_predict");
    let messages: Vec<&GateWorld> = data
        .tests
        .iter()
        .flat_map(|run| &run[..MESSAGES_PER_RUN])
        .collect();
    group.throughput(Throughput::Elements(messages.len() as u64));
    for (n, model) in &data.models {
        group.bench_with_input(BenchmarkId::from_parameter(n), model, |b, model| {
            b.iter(|| {
                for w in &messages {
                    black_box(model.predict(black_box(w), PUSH_ACTION));
                }
            });
        });
    }
    group.finish();
}

fn main() {
    let data = Data::record();
    percentiles(&data);
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c, &data);
    c.final_summary();
}
