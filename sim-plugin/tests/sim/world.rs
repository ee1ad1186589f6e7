//! Commands, ghosts, publishing and scene files of the simulated world.

use sim_plugin::scene::SceneError;
use sim_plugin::{ActuatorMode, Command, Scene, Snapshot, World};

fn world(name: &str) -> World {
    World::new(&Scene::builtin(name).expect("embedded scene parses")).expect("world builds")
}

fn step_n(world: &mut World, n: u32) -> Vec<Snapshot> {
    (0..n)
        .filter_map(|_| world.step().expect("step succeeds"))
        .collect()
}

fn mv(vx: f64, vy: f64) -> Command {
    Command::Actuator {
        mode: ActuatorMode::Move,
        velocity: [vx, vy, 0.0],
    }
}

fn set_pose(name: &str, position: [f64; 3], orientation: [f64; 4]) -> Command {
    Command::SetPose {
        name: name.into(),
        position,
        orientation,
    }
}

/// Everything observable about a world.
fn observe(w: &World) -> (Snapshot, bool, u32, (ActuatorMode, [f64; 3])) {
    (
        w.snapshot(),
        w.is_paused(),
        w.publish_interval_steps(),
        w.actuator_command(),
    )
}

#[test]
fn invalid_commands_are_refused_and_change_nothing() {
    let mut w = world("two_blocks");
    w.apply(mv(0.1, 0.5)).expect("valid");
    step_n(&mut w, 123);
    let before = observe(&w);
    let nan = f64::NAN;
    let cases = [
        (
            Command::Actuator {
                mode: ActuatorMode::Move,
                velocity: [0.0, nan, 0.0],
            },
            "velocity must be finite",
        ),
        (mv(f64::INFINITY, 0.0), "velocity must be finite"),
        (
            set_pose(
                "blockA",
                [0.0, f64::NEG_INFINITY, 0.05],
                [0.0, 0.0, 0.0, 1.0],
            ),
            "position must be finite",
        ),
        (
            set_pose("blockA", [0.0, 0.2, 0.05], [0.0, 0.0, nan, 1.0]),
            "orientation must be finite",
        ),
        (
            set_pose("blockA", [0.0, 0.2, 0.05], [0.0; 4]),
            "zero length",
        ),
        (
            set_pose("blockC", [0.0, 0.2, 0.05], [0.0, 0.0, 0.0, 1.0]),
            "unknown body `blockC`",
        ),
        (
            set_pose("blockA", [1e6, 0.2, 0.05], [0.0, 0.0, 0.0, 1.0]),
            "beyond",
        ),
        (Command::SetPublishRate(0), "does not divide 1000"),
        (Command::SetPublishRate(3), "does not divide 1000"),
        (Command::SetPublishRate(2000), "does not divide 1000"),
    ];
    for (cmd, message) in cases {
        let err = w.apply(cmd.clone()).expect_err("invalid command");
        assert!(
            err.to_string().contains(message),
            "{cmd:?}: `{err}` does not say `{message}`"
        );
        assert_eq!(observe(&w), before, "{cmd:?} changed the world");
    }
    // A refused command also leaves the future untouched.
    let mut twin = world("two_blocks");
    twin.apply(mv(0.1, 0.5)).expect("valid");
    step_n(&mut twin, 123);
    assert_eq!(step_n(&mut w, 200), step_n(&mut twin, 200));
}

#[test]
fn commanded_speed_is_clamped_to_half_a_metre_per_second() {
    let mut w = world("one_block");
    w.apply(mv(3.0, 4.0)).expect("valid");
    let (mode, v) = w.actuator_command();
    assert_eq!(mode, ActuatorMode::Move);
    assert!(
        (v[0] - 0.3).abs() < 1e-12 && (v[1] - 0.4).abs() < 1e-12,
        "{v:?}"
    );
    step_n(&mut w, 100);
    let a = w.snapshot().body("actuator").cloned().expect("actuator");
    assert!((a.position[0] - 0.03).abs() < 1e-9, "{a:?}");
    assert!((a.position[1] - 0.04).abs() < 1e-9, "{a:?}");
}

#[test]
fn actuator_is_held_at_the_clamp_height_with_no_spin_while_moving() {
    let mut w = world("one_block");
    w.apply(set_pose(
        "actuator",
        [-1.0, -0.5, 0.4],
        [0.0, 0.0, 0.0, 1.0],
    ))
    .expect("valid");
    w.apply(mv(0.5, 0.0)).expect("valid");
    step_n(&mut w, 1);
    let a = w.snapshot().body("actuator").cloned().expect("actuator");
    assert_eq!(a.position[2], 0.03);
    // Re-imposed before the step, then one step of world damping (1e-4).
    assert!((a.lin_vel[0] - 0.5 * (1.0 - 1e-4)).abs() < 1e-12, "{a:?}");
    assert_eq!(a.lin_vel[1..], [0.0, 0.0]);
    assert_eq!(a.ang_vel, [0.0; 3]);
}

#[test]
fn without_move_the_actuator_keeps_its_velocity_and_height() {
    let mut w = world("one_block");
    w.apply(mv(0.5, 0.0)).expect("valid");
    step_n(&mut w, 10);
    w.apply(Command::Actuator {
        mode: ActuatorMode::Nothing,
        velocity: [0.0; 3],
    })
    .expect("valid");
    w.apply(set_pose("actuator", [0.0, -0.5, 0.2], [0.0, 0.0, 0.0, 1.0]))
        .expect("valid");
    step_n(&mut w, 100);
    let a = w.snapshot().body("actuator").cloned().expect("actuator");
    // Gravity is off for the actuator: it coasts (minus world damping).
    assert!((a.position[2] - 0.2).abs() < 1e-12, "{a:?}");
    assert!(a.lin_vel[0] > 0.49, "{a:?}");
}

#[test]
fn movement_bound_stops_the_actuator() {
    let mut w = world("one_block");
    w.apply(set_pose(
        "actuator",
        [1.5, -1.0, 0.03],
        [0.0, 0.0, 0.0, 1.0],
    ))
    .expect("valid");
    w.apply(mv(0.5, 0.0)).expect("valid");
    step_n(&mut w, 3000);
    let a = w.snapshot().body("actuator").cloned().expect("actuator");
    // The look-ahead ‖(x + 0.5, -1, 0.03) − (0, 0, 1)‖ ≤ 2.5 holds up to
    // x = √(2.5² − 1 − 0.97²) − 0.5; the actuator stops at the first step
    // that starts beyond it, i.e. within one 0.5 mm step past it.
    let limit = (2.5_f64.powi(2) - 1.0 - 0.97_f64.powi(2)).sqrt() - 0.5;
    assert!(
        a.position[0] > limit && a.position[0] <= limit + 0.0005 + 1e-9,
        "stopped at {} (limit {limit})",
        a.position[0]
    );
    assert_eq!(a.lin_vel, [0.0; 3]);
    assert_eq!(w.actuator_command().1, [0.0; 3]);
}

#[test]
fn set_pose_moves_a_body_and_keeps_its_velocity() {
    let mut w = world("one_block");
    let yaw = 0.4_f64;
    let q = [0.0, 0.0, (yaw / 2.0).sin() * 3.0, (yaw / 2.0).cos() * 3.0];
    w.apply(set_pose("blockA", [0.3, 0.6, 0.05], q))
        .expect("valid");
    let b = w.snapshot().body("blockA").cloned().expect("blue block");
    assert_eq!(b.position, [0.3, 0.6, 0.05]);
    assert!((b.yaw() - yaw).abs() < 1e-12, "quaternion is normalised");
    assert_eq!(b.lin_vel, [0.0; 3]);
}

#[test]
fn ghosts_are_published_but_never_physical() {
    let mut w = world("one_block");
    let mut plain = world("one_block");
    for x in [&mut w, &mut plain] {
        x.apply(mv(0.0, 0.5)).expect("valid");
    }
    // A ghost right inside the block and one in the actuator's path.
    w.apply(set_pose(
        "blockAShadow",
        [0.0, 0.1, 0.05],
        [0.0, 0.0, 0.0, 1.0],
    ))
    .expect("valid");
    w.apply(set_pose(
        "actuatorShadow",
        [0.0, 0.1, 0.03],
        [0.0, 0.0, 0.0, 2.0],
    ))
    .expect("valid");
    w.apply(set_pose(
        "blockAShadow",
        [0.0, 0.2, 0.05],
        [0.0, 0.0, 0.0, 1.0],
    ))
    .expect("valid");
    let with = step_n(&mut w, 1000);
    let without = step_n(&mut plain, 1000);
    let last = with.last().expect("published");
    assert_eq!(last.bodies, without.last().expect("published").bodies);
    let names: Vec<_> = last
        .ghosts
        .iter()
        .map(|g| (g.name.as_str(), g.id))
        .collect();
    assert_eq!(names, [("blockAShadow", 15), ("actuatorShadow", 8)]);
    assert_eq!(last.ghosts[0].position, [0.0, 0.2, 0.05]);
    assert_eq!(last.ghosts[1].orientation, [0.0, 0.0, 0.0, 1.0]);
    assert!(last.ghosts.iter().all(|g| g.is_static));
    w.apply(Command::Reset).expect("valid");
    assert!(w.snapshot().ghosts.is_empty());
}

#[test]
fn publishes_every_n_steps_since_the_last_reset() {
    let mut w = world("one_block");
    assert_eq!(w.publish_interval_steps(), 10);
    let published: Vec<_> = (1..=35)
        .filter_map(|i| w.step().expect("step").map(|s| (i, s.step)))
        .collect();
    assert_eq!(published, [(10, 10), (20, 20), (30, 30)]);
    w.apply(Command::SetPublishRate(10)).expect("valid");
    assert_eq!(w.publish_interval_steps(), 100);
    let steps: Vec<_> = step_n(&mut w, 200).iter().map(|s| s.step).collect();
    assert_eq!(steps, [100, 200]);
    w.apply(Command::Reset).expect("valid");
    let first = step_n(&mut w, 100);
    assert_eq!(first.len(), 1);
    assert_eq!(first[0].step, 100);
    assert!((first[0].sim_time - 0.1).abs() < 1e-12);
}

#[test]
fn nothing_happens_while_paused_but_commands_still_apply() {
    let mut w = world("one_block");
    w.apply(Command::Pause).expect("valid");
    assert!(w.is_paused());
    let before = w.snapshot();
    w.apply(mv(0.0, 0.5)).expect("valid");
    assert!(step_n(&mut w, 50).is_empty());
    assert_eq!(w.step_count(), 0);
    assert_eq!(w.snapshot(), before);
    w.apply(Command::Unpause).expect("valid");
    assert_eq!(step_n(&mut w, 10).len(), 1);
    assert_eq!(w.actuator_command().1, [0.0, 0.5, 0.0]);
}

#[test]
fn reset_keeps_the_actuator_command() {
    let mut w = world("one_block");
    w.apply(mv(0.0, 0.5)).expect("valid");
    step_n(&mut w, 20);
    w.apply(Command::Reset).expect("valid");
    assert_eq!(w.actuator_command(), (ActuatorMode::Move, [0.0, 0.5, 0.0]));
}

#[test]
fn snapshot_lists_dynamic_bodies_in_scene_order_with_their_ids() {
    let s = world("two_blocks").snapshot();
    let ids: Vec<_> = s.bodies.iter().map(|b| (b.name.as_str(), b.id)).collect();
    assert_eq!(ids, [("actuator", 8), ("blockA", 15), ("blockB", 27)]);
    assert!(s.bodies.iter().all(|b| !b.is_static));
    assert_eq!(s.bodies[2].position, [-0.6, 0.35, 0.05]);
}

// ---------------------------------------------------------------- scenes

const ONE_BLOCK: &str = include_str!("../../scenes/one_block.toml");

fn scene_error(text: &str) -> String {
    match Scene::from_toml_str(text) {
        Ok(_) => panic!("scene was accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn builtin_scenes_load_by_name() {
    let names: Vec<_> = Scene::builtin_names().collect();
    assert_eq!(names, ["one_block", "two_blocks", "objects"]);
    for name in names {
        let scene = Scene::load(name).expect("loads");
        assert_eq!(scene.name, name);
        // The original's red-block inertia is kept (docs/spec/world.md §12).
        if let Some(red) = scene.body_index("blockB") {
            assert_eq!(
                scene.bodies[red].inertia,
                Some([1.66667e-3, 1.66667e-3, 0.0216667])
            );
        }
    }
    assert!(matches!(
        Scene::load("three_blocks"),
        Err(SceneError::UnknownBuiltin(_))
    ));
}

#[test]
fn the_object_scene_is_the_two_block_world_with_the_red_block_parked_and_a_cylinder() {
    let two = Scene::load("two_blocks").expect("loads");
    let objects = Scene::load("objects").expect("loads");
    assert_eq!(
        (&objects.physics, &objects.ground, &objects.drive),
        (&two.physics, &two.ground, &two.drive)
    );
    for body in &two.bodies {
        let i = objects.body_index(&body.name).expect("every thesis body");
        let mut parked = body.clone();
        parked.start = objects.bodies[i].start;
        assert_eq!(objects.bodies[i], parked, "{}", body.name);
    }
    let cylinder = &objects.bodies[objects.body_index("cylinder").expect("a cylinder")];
    assert_eq!(cylinder.id, 33);
    // Parked bodies stay out of the push task's area (the actuator drives
    // from y = 0 towards +y).
    for name in ["blockB", "cylinder"] {
        let start = objects.bodies[objects.body_index(name).expect("parked")].start;
        assert!(start.y < -0.5, "{name} parked at {start:?}");
    }
    // It stands on its flat end, as tall as the blocks.
    let mut world = World::new(&objects).expect("world");
    step_n(&mut world, 500);
    let snapshot = world.snapshot();
    let pose = snapshot.body("cylinder").expect("cylinder");
    assert!((pose.position[2] - 0.05).abs() < 2e-3, "{pose:?}");
}

#[test]
fn scene_files_load_from_a_path_and_round_trip() {
    let scene = Scene::builtin("two_blocks").expect("parses");
    let path = std::env::temp_dir().join(format!("pushlearn-scene-{}.toml", std::process::id()));
    std::fs::write(&path, scene.to_toml_string().expect("serialises")).expect("writable");
    let loaded = Scene::load(path.to_str().expect("utf-8 path"));
    std::fs::remove_file(&path).ok();
    assert_eq!(loaded.expect("loads"), scene);
    let missing = Scene::load("/nonexistent/scene.toml").expect_err("missing file");
    assert!(
        missing.to_string().contains("/nonexistent/scene.toml"),
        "{missing}"
    );
}

#[test]
fn unknown_fields_are_named() {
    let text = ONE_BLOCK.replace("max_speed = 0.5", "max_speed = 0.5\nmax_sped = 1.0");
    let err = scene_error(&text);
    assert!(err.contains("max_sped"), "{err}");
    let text = ONE_BLOCK.replace("radius = 0.025 }", "radius = 0.025, height = 1.0 }");
    let err = scene_error(&text);
    assert!(err.contains("height"), "{err}");
    let text = ONE_BLOCK.replace("type = \"sphere\"", "type = \"cylinder\"");
    let err = scene_error(&text);
    assert!(err.contains("cylinder"), "{err}");
}

#[test]
fn invalid_values_are_named() {
    let cases = [
        (("mass = 1.0", "mass = -1.0"), "body[1].mass"),
        (("mass = 10.0", "mass = 0.0"), "body[0].mass"),
        (
            ("size = [0.5, 0.1, 0.1]", "size = [0.5, 0.0, 0.1]"),
            "body[1].shape.size",
        ),
        (("radius = 0.025", "radius = nan"), "body[0].shape.radius"),
        (
            ("inertia = [1.66667e-3", "inertia = [-1.66667e-3"),
            "body[1].inertia",
        ),
        (("id = 15", "id = 16"), "body[1].id"),
        (("id = 8", "id = 9"), "body[0].id"),
        (("name = \"blockA\"", "name = \"actuator\""), "body"),
        (
            ("name = \"blockA\"", "name = \"blockAShadow\""),
            "body[1].name",
        ),
        (
            ("publish_rate_hz = 100", "publish_rate_hz = 7"),
            "publish_rate_hz",
        ),
        (
            ("step_size = 0.001", "step_size = 0.002"),
            "physics.step_size",
        ),
        (("erp = 0.2", "erp = 2.0"), "erp"),
        (
            (
                "gravity = [0.0, 0.0, -9.81]",
                "gravity = [0.0, 0.0, -1e300]",
            ),
            "physics.gravity",
        ),
        (
            ("x = 0.0, y = 0.25", "x = inf, y = 0.25"),
            "body[1].start.x",
        ),
        (("mu1 = 0.9", "mu1 = -0.9"), "body[1].mu1"),
    ];
    for ((from, to), field) in cases {
        assert!(
            ONE_BLOCK.contains(from),
            "test case `{from}` not in the scene"
        );
        let err = scene_error(&ONE_BLOCK.replacen(from, to, 1));
        assert!(
            err.contains(field),
            "`{to}`: `{err}` does not name `{field}`"
        );
    }
}

#[test]
fn scene_without_actuator_is_refused() {
    let text = ONE_BLOCK.replace("name = \"actuator\"", "name = \"pusher\"");
    let err = scene_error(&text);
    assert!(err.contains("actuator"), "{err}");
}

#[test]
fn world_can_move_to_a_physics_thread() {
    let mut w = world("one_block");
    w.apply(mv(0.0, 0.5)).expect("valid");
    let published = std::thread::spawn(move || step_n(&mut w, 100).len())
        .join()
        .expect("physics thread finishes");
    assert_eq!(published, 10);
}

/// Issue 49, item 12: `World(scene)` read a FIFO forever (waiting for a
/// writer) and `/dev/zero` until memory ran out. Only regular files of at
/// most `MAX_SCENE_FILE_BYTES` are read.
#[test]
fn only_regular_scene_files_of_bounded_size_are_read() {
    use sim_plugin::scene::MAX_SCENE_FILE_BYTES;
    let err = Scene::load("/dev/zero").expect_err("a device");
    assert!(
        err.to_string().contains("a device, not a regular file"),
        "{err}"
    );
    let dir = std::env::temp_dir().join(format!("pushlearn-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let fifo = dir.join("scene.fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    // Before the fix this open waited for a writer that never comes.
    let err = Scene::load(fifo.to_str().expect("utf-8")).expect_err("a FIFO");
    assert!(
        err.to_string().contains("a FIFO, not a regular file"),
        "{err}"
    );
    let big = dir.join("big.toml");
    let mut text = ONE_BLOCK.to_owned();
    while (text.len() as u64) <= MAX_SCENE_FILE_BYTES {
        text.push_str("# padding padding padding padding padding padding padding\n");
    }
    std::fs::write(&big, &text).expect("writable");
    let err = Scene::load(big.to_str().expect("utf-8")).expect_err("too large");
    assert!(
        err.to_string().contains("larger than 1048576 bytes"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 49, item 12: no cap on bodies (1600 boxes took 2.9 s a message),
/// and item 10's cap on names holds for scene files too.
#[test]
fn a_scene_has_at_most_max_bodies_with_names_of_bounded_length() {
    use sim_plugin::scene::MAX_BODIES;
    let block = |i: usize| {
        format!(
            "\n[[body]]\nname = \"box{i}\"\nid = {}\nshape = {{ type = \"box\", size = [0.1, 0.1, 0.1] }}\n\
             mass = 1.0\ninertia = [1e-3, 1e-3, 1e-3]\nmu1 = 0.9\nmu2 = 0.9\ngravity = true\n\
             start = {{ x = {}, y = 5.0, z = 0.05, yaw = 0.0 }}\nkp = 1e12\nkd = 1.0\n",
            1000 + i,
            i as f64 * 0.2
        )
    };
    let at_cap: String = ONE_BLOCK.to_owned() + &(0..MAX_BODIES - 2).map(block).collect::<String>();
    Scene::from_toml_str(&at_cap).expect("MAX_BODIES bodies are fine");
    let over = at_cap + &block(MAX_BODIES);
    let err = scene_error(&over);
    assert!(
        err.contains("65 entries; a scene has at most 64 bodies"),
        "{err}"
    );
    let long = ONE_BLOCK.replace(
        "name = \"blockA\"",
        &format!("name = \"{}\"", "b".repeat(300)),
    );
    let err = scene_error(&long);
    assert!(err.contains("is 300 bytes long (at most 256)"), "{err}");
}

/// Issue 49, item 12: bodies placed overlapping are shot apart, and reached
/// 1130 m, past the ±1000 m a SetPose may reach. The world now treats a
/// body beyond its bounds as a blow-up: it resets and says so, and never
/// publishes one.
#[test]
fn a_body_shot_beyond_the_worlds_bounds_resets_the_world() {
    use pushlearn::wire::BodyName;
    use sim_plugin::world::StepError;
    let mut world = world("two_blocks");
    // Overlapping in the air at the edge of the world: blockB is shot out.
    for (name, x) in [("blockA", 999.99), ("blockB", 999.9)] {
        world
            .apply(Command::SetPose {
                name: BodyName::parse(name),
                position: [x, 0.0, 0.5],
                orientation: [0.0, 0.0, 0.0, 1.0],
            })
            .expect("within the bounds");
    }
    let mut reset = None;
    for _ in 0..2000 {
        match world.step() {
            Ok(Some(snapshot)) => {
                for body in &snapshot.bodies {
                    assert!(
                        body.position.iter().all(|v| v.abs() <= 1000.0),
                        "published {} at {:?}",
                        body.name,
                        body.position
                    );
                }
            }
            Ok(None) => {}
            Err(err @ StepError::Diverged { .. }) => {
                reset = Some(err.to_string());
                break;
            }
            Err(err) => panic!("{err}"),
        }
    }
    let reset = reset.expect("a body left the world");
    assert!(reset.contains("a position beyond ±1000 m"), "{reset}");
    assert_eq!(world.step_count(), 0, "the world was reset");
}

/// Issue 49, item 8: an actuator placed at (999, 999) was accepted and could
/// never move again (the drive stops a Move that leaves its bound).
#[test]
fn the_actuator_cannot_be_placed_outside_its_drive_bound() {
    use pushlearn::wire::BodyName;
    let mut world = world("one_block");
    let place = |x: f64, y: f64| Command::SetPose {
        name: BodyName::parse("actuator"),
        position: [x, y, 0.03],
        orientation: [0.0, 0.0, 0.0, 1.0],
    };
    let err = world
        .apply(place(999.0, 999.0))
        .expect_err("outside the bound");
    assert!(err.to_string().contains("outside its drive bound"), "{err}");
    world.apply(place(1.0, -1.0)).expect("within the bound");
    world.apply(mv(0.5, 0.0)).expect("a Move");
    let states = step_n(&mut world, 20);
    let x = states.last().expect("published").bodies[0].position[0];
    assert!(x > 1.005, "the actuator moves: x = {x}");
}
