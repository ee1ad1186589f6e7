//! Steps the one-block push (x0 = 0.105) the same number of times as
//! `benches/reference.c`, for a like-for-like comparison of CPU time on a
//! busy machine, where wall-clock benchmarks are noisy:
//!
//!   cargo build --release -p sim-plugin --example push_timing
//!   /usr/bin/time -f '%U s user' target/release/examples/push_timing
//!   /usr/bin/time -f '%U s user' target/ode-reference

use std::time::Instant;

use sim_plugin::calibration::{run, BLUE_BLOCK};
use sim_plugin::{Scene, SweepOptions, World};

const RUNS: u32 = 200;
const STEPS: u32 = 1500;

fn main() -> anyhow::Result<()> {
    let scene_name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "one_block".into());
    let scene = Scene::load(&scene_name)?;
    let mut world = World::new(&scene)?;
    let options = SweepOptions::default();
    let start = Instant::now();
    for _ in 0..RUNS {
        run(&mut world, &options, 0.105)?;
    }
    let secs = start.elapsed().as_secs_f64();
    let snapshot = world.snapshot();
    if let Some(b) = snapshot.body(BLUE_BLOCK) {
        println!(
            "block after the push from x0 = 0.105: x {:.4} y {:.4} yaw {:.4}",
            b.position[0],
            b.position[1],
            b.yaw()
        );
    }
    let steps = f64::from(RUNS * STEPS);
    println!(
        "{:.2} us/step ({:.0} steps/s) over {steps} steps, scene {scene_name}",
        1e6 * secs / steps,
        steps / secs
    );
    Ok(())
}
