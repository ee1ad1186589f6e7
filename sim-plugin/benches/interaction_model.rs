//! Interaction model: time per message of `update` (training on) and of
//! `predict` after 1, 3, 10 and 30 training runs (`docs/spec/experiments.md` §6: all
//! work for one message must fit 0.02 s; `docs/spec/reference-results.md` §10: the
//! original took ≈ 300 µs per update and 150 – 250 µs per prediction after
//! 30 runs).
//!
//! The frames are push-task runs of the in-process thesis world
//! (`sim_plugin`, lock-step, no latency): 30 training runs from random
//! starts in [−0.25, 0.25) and one held-out run from x0 = 0.07 (a push that
//! turns the block), whose 150 messages are the ones timed.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use learner::eval::{random_training_start, train_on_run, PUSH_ACTION};
use learner::{Frame, InteractionModel, InteractionWorld, Model};
use sim_plugin::{Command, Scene, World};

#[path = "../tests/support/push_frames.rs"]
mod push_frames;
use push_frames::record_run;

const TRAINING_RUNS: [usize; 4] = [1, 3, 10, 30];

/// SplitMix64 for the training starts: deterministic without an extra
/// dependency.
struct SplitMix(u64);

impl SplitMix {
    /// Uniform in [0, 1) from the top 53 bits.
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn bench(c: &mut Criterion) {
    let scene = Scene::builtin("one_block").expect("embedded scene parses");
    let mut world = World::new(&scene).expect("the thesis world builds");
    world
        .apply(Command::SetPublishRate(100))
        .expect("100 Hz divides 1000");
    let mut rng = SplitMix(0x5eed);
    let training: Vec<Vec<Frame>> = (0..TRAINING_RUNS[3])
        .map(|_| record_run(&mut world, random_training_start(rng.unit())))
        .collect();
    let parser = InteractionModel::default();
    let held_out: Vec<InteractionWorld> = record_run(&mut world, 0.07)
        .iter()
        .map(|f| parser.parse(f).expect("frames parse"))
        .collect();

    let mut update = c.benchmark_group("interaction_update");
    update.throughput(Throughput::Elements(held_out.len() as u64 - 1));
    update.sample_size(20);
    let mut models = Vec::new();
    for n in TRAINING_RUNS {
        let mut model = InteractionModel::default();
        for run in &training[..n] {
            train_on_run(&mut model, run, PUSH_ACTION).expect("frames parse");
        }
        let stats = model.stats();
        let stats = stats.as_interaction().expect("interaction statistics");
        eprintln!(
            "after {n} runs: {} ACs, ACS {} nodes, largest AC {} nodes",
            stats.collections.len(),
            stats.acs.nodes,
            stats.largest().map_or(0, |ac| ac.map.nodes),
        );
        // One held-out run of training updates per iteration, each on a
        // fresh copy of the trained model so that every iteration does the
        // same work.
        update.bench_with_input(BenchmarkId::from_parameter(n), &model, |b, model| {
            b.iter_batched(
                || model.clone(),
                |mut m| {
                    m.reset_objects(&held_out[0]);
                    for w in &held_out[1..] {
                        m.update(w, PUSH_ACTION);
                    }
                    m
                },
                BatchSize::LargeInput,
            );
        });
        models.push((n, model));
    }
    update.finish();

    let mut predict = c.benchmark_group("interaction_predict");
    predict.throughput(Throughput::Elements(held_out.len() as u64));
    for (n, model) in &models {
        predict.bench_with_input(BenchmarkId::from_parameter(n), model, |b, model| {
            b.iter(|| {
                for w in &held_out {
                    black_box(model.predict(black_box(w), PUSH_ACTION));
                }
            });
        });
    }
    predict.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
