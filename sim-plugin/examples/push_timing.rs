//! Steps the one-block push (x0 = 0.105) the same number of times as
//! `benches/reference.c`, for a like-for-like comparison of CPU time on a
//! busy machine, where wall-clock benchmarks are noisy:
//!
//!   cargo build --release -p sim-plugin --example push_timing
//!   /usr/bin/time -f '%U s user' target/release/examples/push_timing
//!   /usr/bin/time -f '%U s user' target/ode-reference
//!
//! A second argument picks the engine (`ode`, the default, or `mujoco`);
//! `both` times the two alternately in one process, three rounds each, for
//! the engines' comparison in docs/performance.md:
//!
//!   target/release/examples/push_timing one_block both

use std::time::Instant;

use sim_plugin::calibration::{run, BLUE_BLOCK};
use sim_plugin::{Engine, Scene, SweepOptions, World};

const RUNS: u32 = 200;
const STEPS: u32 = 1500;
/// Steps per published message at the push task's 100 Hz.
const STEPS_PER_MESSAGE: f64 = 10.0;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene_name = args.next().unwrap_or_else(|| "one_block".into());
    let engines: Vec<Engine> = match args.next().as_deref() {
        None => vec![Engine::Ode],
        Some("both") => [Engine::ALL; 3].concat(),
        Some(name) => vec![name.parse().map_err(anyhow::Error::msg)?],
    };
    let scene = Scene::load(&scene_name)?;
    for engine in engines {
        time(&scene, &scene_name, engine)?;
    }
    Ok(())
}

fn time(scene: &Scene, scene_name: &str, engine: Engine) -> anyhow::Result<()> {
    let mut world = World::on(scene, engine)?;
    let options = SweepOptions::default();
    let start = Instant::now();
    for _ in 0..RUNS {
        run(&mut world, &options, 0.105)?;
    }
    let secs = start.elapsed().as_secs_f64();
    let snapshot = world.snapshot();
    if let Some(b) = snapshot.body(BLUE_BLOCK) {
        println!(
            "{engine}: block after the push from x0 = 0.105: x {:.4} y {:.4} yaw {:.4}",
            b.position[0],
            b.position[1],
            b.yaw()
        );
    }
    let steps = f64::from(RUNS * STEPS);
    println!(
        "{engine}: {:.2} us/step, {:.1} us/message ({:.0} steps/s) over {steps} steps, scene {scene_name}",
        1e6 * secs / steps,
        1e6 * secs / steps * STEPS_PER_MESSAGE,
        steps / secs
    );
    Ok(())
}
