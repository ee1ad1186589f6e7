//! Physics steps per second of the thesis world during a push.
//!
//! One iteration is one calibration run: Reset, place the actuator at
//! x0 = 0.105 (the start with the most contact work: the block swings off),
//! Move (0, 0.5), then 1500 steps of 1 ms. Criterion's throughput is in
//! steps, so "elem/s" is steps per second and time / 1500 is µs per step.
//!
//! Compare with plain C on the same machine: `benches/reference.c` (see its
//! header for the command).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sim_plugin::calibration::run;
use sim_plugin::{Scene, SweepOptions, World};

const STEPS_PER_RUN: u64 = 1500;

fn push_runs(c: &mut Criterion) {
    let mut group = c.benchmark_group("push_run");
    group.throughput(Throughput::Elements(STEPS_PER_RUN));
    group.sample_size(30);
    let options = SweepOptions::default();
    for name in ["one_block", "two_blocks"] {
        let Ok(scene) = Scene::builtin(name) else {
            panic!("embedded scene {name} does not parse");
        };
        let Ok(mut world) = World::new(&scene) else {
            panic!("world for {name} does not build");
        };
        group.bench_function(name, |b| {
            b.iter(|| run(&mut world, &options, std::hint::black_box(0.105)).is_ok())
        });
    }
    group.finish();
}

criterion_group!(benches, push_runs);
criterion_main!(benches);
