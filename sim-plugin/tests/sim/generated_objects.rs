//! Generated objects (`sim_plugin::generate`, `docs/world.md` "Generated
//! objects") as the world runs them: written as scene files, loaded, and
//! pushed by the calibration push.

use sim_plugin::calibration::{run, SweepOptions};
use sim_plugin::generate::{generate, Distributions, Set};
use sim_plugin::{Scene, World};

/// Test and held-out objects of seed 1, each written to a file, loaded back
/// and pushed centrally (x₀ = 0, (0, 0.5) m/s, 150 messages): every one
/// loads, builds a world and moves. Run with `--nocapture` for the numbers
/// `docs/world.md` quotes.
#[test]
fn generated_objects_load_and_move_under_the_push() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("generated_objects");
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let options = SweepOptions {
        starts: vec![0.0],
        ..SweepOptions::default()
    };
    for (set, count) in [(Set::Test, 10), (Set::HeldOut, 3)] {
        let objects = generate(set, count, 1, &Distributions::default()).expect("generates");
        let mut moved = Vec::new();
        for g in &objects {
            let path = dir.join(format!("{}.toml", g.object.name));
            std::fs::write(&path, g.scene.to_toml_string().expect("TOML")).expect("written");
            let scene = Scene::load(path.to_str().expect("UTF-8 path")).expect("loads");
            assert_eq!(scene, g.scene);
            let mut world = World::new(&scene).expect("world builds");
            let row = run(&mut world, &options, 0.0).expect("push runs");
            println!(
                "{}: {:?} mass {:.3} com {:?} mu ground {:.3} pusher {:.3}: moved {:.4} m, turned {:.4} rad",
                g.object.name,
                g.object.shape,
                g.object.mass,
                g.object.centre_of_mass,
                g.object.ground_friction,
                g.object.pusher_friction,
                row.translation,
                row.rotation
            );
            assert!(row.first_contact_message.is_some(), "{}", g.object.name);
            assert!(row.translation > 0.05, "{}: {row:?}", g.object.name);
            moved.push(row.translation);
        }
        moved.sort_by(f64::total_cmp);
        println!(
            "{set}: moved min {:.4} median {:.4} max {:.4} m",
            moved[0],
            (moved[(count - 1) / 2] + moved[count / 2]) / 2.0,
            moved[count - 1]
        );
    }
}

/// Generated objects (centre of mass off the centre, full inertia tensors,
/// `[[friction]]` pairs) build on MuJoCo too, and at rest their published
/// pose is the shape's centre where the scene puts it: the MJCF body frame
/// is the shape's centre and the mass sits at the centre of mass.
#[cfg(feature = "mujoco")]
#[test]
fn generated_objects_rest_where_the_scene_puts_them_on_mujoco() {
    for set in [Set::Train, Set::HeldOut] {
        for g in generate(set, 3, 1, &Distributions::default()).expect("generates") {
            let mut world = World::on(&g.scene, sim_plugin::Engine::Mujoco).expect("world builds");
            let start = world.snapshot();
            for _ in 0..500 {
                world.step().expect("steps");
            }
            for (before, after) in start.bodies.iter().zip(&world.snapshot().bodies) {
                let moved = (0..3)
                    .map(|k| (after.position[k] - before.position[k]).abs())
                    .fold(0.0, f64::max);
                assert!(
                    moved < 1e-4,
                    "{}: {} moved {moved} m at rest",
                    g.object.name,
                    after.name
                );
            }
        }
    }
}
