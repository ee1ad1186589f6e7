//! What scene files can say about objects beyond the thesis's: friction per
//! pair of bodies, a centre of mass away from the shape's centre, inertia
//! computed from the shape, and any free id (`docs/world.md`, "Objects
//! beyond the thesis's").

use sim_plugin::{ActuatorMode, Command, Scene, Snapshot, World};

const ONE_BLOCK: &str = include_str!("../../scenes/one_block.toml");

/// `one_block` with `extra` appended (e.g. `[[friction]]` tables).
fn one_block_with(extra: &str) -> Scene {
    Scene::from_toml_str(&format!("{ONE_BLOCK}\n{extra}")).expect("scene is valid")
}

/// `one_block` with blockA's `inertia` line replaced by `lines`.
fn one_block_block(lines: &str) -> Scene {
    let from = "inertia = [1.66667e-3, 0.0216667, 0.0216667]";
    assert!(ONE_BLOCK.contains(from));
    Scene::from_toml_str(&ONE_BLOCK.replacen(from, lines, 1)).expect("scene is valid")
}

fn mv(vx: f64, vy: f64) -> Command {
    Command::Actuator {
        mode: ActuatorMode::Move,
        velocity: [vx, vy, 0.0],
    }
}

/// The calibration push (`docs/world.md`): the actuator from (x₀, 0)
/// along +y at 0.5 m/s for `push` messages, then still for `rest`
/// messages. Returns every published state.
fn push(scene: &Scene, x0: f64, push: u32, rest: u32) -> Vec<Snapshot> {
    let mut world = World::new(scene).expect("world builds");
    world
        .apply(Command::SetPose {
            name: "actuator".into(),
            position: [x0, 0.0, 0.03],
            orientation: [0.0, 0.0, 0.0, 1.0],
        })
        .expect("valid pose");
    let mut states = Vec::new();
    world.apply(mv(0.0, 0.5)).expect("valid command");
    collect(&mut world, &mut states, push);
    world.apply(mv(0.0, 0.0)).expect("valid command");
    collect(&mut world, &mut states, rest);
    states
}

/// Steps `world` until it has published `messages` more states.
fn collect(world: &mut World, states: &mut Vec<Snapshot>, messages: u32) {
    let target = states.len() + messages as usize;
    while states.len() < target {
        if let Some(s) = world.step().expect("steps") {
            states.push(s);
        }
    }
}

/// blockA's planar distance from its start and its yaw at the end.
fn moved(states: &[Snapshot]) -> (f64, f64) {
    let b = states
        .last()
        .and_then(|s| s.body("blockA"))
        .expect("blockA");
    let d = (b.position[0].powi(2) + (b.position[1] - 0.25).powi(2)).sqrt();
    (d, b.yaw())
}

#[test]
fn a_pair_friction_equal_to_the_minimum_rule_changes_nothing() {
    let plain = Scene::builtin("one_block").expect("built-in");
    let same = one_block_with(
        "[[friction]]\nbetween = [\"ground_plane\", \"blockA\"]\nmu1 = 0.9\nmu2 = 0.9\n\n\
         [[friction]]\nbetween = [\"blockA\", \"actuator\"]\nmu1 = 0.01\n",
    );
    assert_eq!(push(&plain, 0.105, 60, 40), push(&same, 0.105, 60, 40));
}

#[test]
fn a_higher_ground_friction_moves_the_block_less_under_the_same_push() {
    // 45 messages at 0.5 m/s: contact at message 36, then about 4.5 cm of
    // pushing; the block slides on after the actuator stops.
    let ground = |mu: f64| {
        let scene = one_block_with(&format!(
            "[[friction]]\nbetween = [\"blockA\", \"ground_plane\"]\nmu1 = {mu:?}\n"
        ));
        moved(&push(&scene, 0.0, 45, 100)).0
    };
    let (low, high) = (ground(0.3), ground(0.9));
    eprintln!("centred push, 45 messages: moved {low:.4} m at mu 0.3, {high:.4} m at mu 0.9");
    assert!(high > 0.02, "the push moved the block: {high}");
    assert!(low > high + 0.01, "mu 0.3: {low} m, mu 0.9: {high} m");
    // The pusher's friction alone (ground as before) changes an
    // off-centre push: the contact drags the block's face along.
    let pusher = |mu: f64| {
        let scene = one_block_with(&format!(
            "[[friction]]\nbetween = [\"actuator\", \"blockA\"]\nmu1 = {mu:?}\n"
        ));
        moved(&push(&scene, 0.105, 150, 0)).1
    };
    let (slippery, grippy) = (pusher(0.01), pusher(0.5));
    eprintln!("push at x0 = 0.105: yaw {slippery:.4} rad at pusher mu 0.01, {grippy:.4} at 0.5");
    assert!((slippery - grippy).abs() > 0.02, "{slippery} vs {grippy}");
}

#[test]
fn a_centre_of_mass_off_centre_turns_a_centred_push() {
    let centred = moved(&push(
        &Scene::builtin("one_block").expect("built-in"),
        0.0,
        150,
        0,
    ));
    let offset = one_block_block(
        "inertia = [1.66667e-3, 0.0216667, 0.0216667]\ncentre_of_mass = [0.1, 0.0, 0.0]",
    );
    // At rest the published pose is the box's centre, not its centre of
    // mass 0.1 m to +x.
    let mut world = World::new(&offset).expect("world builds");
    let start = world.snapshot();
    let a = start.body("blockA").expect("blockA");
    assert_eq!(a.position, [0.0, 0.25, 0.05]);
    for _ in 0..300 {
        world.step().expect("steps");
    }
    let settled = world.snapshot();
    let a = settled.body("blockA").expect("blockA");
    assert!(
        a.position[0].abs() < 1e-4 && (a.position[1] - 0.25).abs() < 1e-4,
        "{a:?}"
    );
    assert!((a.position[2] - 0.05).abs() < 2e-3, "{a:?}");
    // A SetPose places the centre, and a Reset brings it back exactly.
    world
        .apply(Command::SetPose {
            name: "blockA".into(),
            position: [0.3, 0.4, 0.05],
            orientation: [0.0, 0.0, 0.5f64.sin(), 0.5f64.cos()],
        })
        .expect("valid pose");
    let placed = world.snapshot();
    let a = placed.body("blockA").expect("blockA");
    for (got, want) in a.position.iter().zip([0.3, 0.4, 0.05]) {
        assert!((got - want).abs() < 1e-12, "{a:?}");
    }
    world.apply(Command::Reset).expect("reset");
    assert_eq!(world.snapshot().bodies, start.bodies);

    // Pushed at the box's centre, left of its centre of mass, it turns
    // clockwise; the uniform block does not turn.
    let (distance, yaw) = moved(&push(&offset, 0.0, 150, 0));
    eprintln!(
        "centred push: uniform block {:.4} m, {:.2e} rad; centre of mass +0.1 m: {distance:.4} m, {yaw:.4} rad",
        centred.0, centred.1
    );
    assert!(centred.1.abs() < 1e-3, "{centred:?}");
    assert!(yaw < -0.1, "yaw {yaw}");
}

#[test]
fn inertia_is_computed_from_the_shape_when_absent() {
    let computed = one_block_block("");
    let b = &computed.bodies[computed.body_index("blockA").expect("blockA")];
    assert_eq!(b.inertia, None);
    let i = b.inertia_about_centre();
    let want = [0.02 / 12.0, 0.26 / 12.0, 0.26 / 12.0];
    for k in 0..3 {
        assert!((i[k] - want[k]).abs() < 1e-15, "{i:?}");
    }
    // The file's rounded values (1.66667e-3, 0.0216667) push the same.
    let given = moved(&push(
        &Scene::builtin("one_block").expect("built-in"),
        0.105,
        150,
        0,
    ));
    let solid = moved(&push(&computed, 0.105, 150, 0));
    assert!(
        (given.0 - solid.0).abs() < 1e-3 && (given.1 - solid.1).abs() < 1e-3,
        "{given:?} vs {solid:?}"
    );
}

#[test]
fn a_body_may_have_any_free_id() {
    let box_body = |id: u32| {
        format!(
            "[[body]]\nname = \"crate\"\nid = {id}\nshape = {{ type = \"box\", size = [0.2, 0.2, 0.1] }}\n\
             mass = 0.5\nmu1 = 0.5\nmu2 = 0.5\nstart = {{ x = 1.0, y = -0.8, z = 0.05 }}\n"
        )
    };
    for id in [1, 16, 4_000_000_000, u32::MAX] {
        let scene = one_block_with(&box_body(id));
        let mut world = World::new(&scene).expect("world builds");
        for _ in 0..10 {
            world.step().expect("steps");
        }
        let s = world.snapshot();
        assert_eq!(s.body("crate").map(|b| b.id), Some(id));
    }
    for (id, says) in [
        (27, "`blockB` must have id 27"),
        (33, "`cylinder` must have id 33"),
        (15, "15 is already the id of body[1] (`blockA`)"),
        (0, "0 is reserved"),
    ] {
        let text = format!("{ONE_BLOCK}\n{}", box_body(id));
        let err = Scene::from_toml_str(&text)
            .expect_err("refused")
            .to_string();
        assert!(err.contains("body[2].id") && err.contains(says), "{err}");
    }
    let text = format!(
        "{ONE_BLOCK}\n{}\n{}",
        box_body(40),
        box_body(40).replace("crate", "lid")
    );
    let err = Scene::from_toml_str(&text)
        .expect_err("refused")
        .to_string();
    assert!(
        err.contains("body[3].id") && err.contains("already the id of body[2] (`crate`)"),
        "{err}"
    );
}

#[test]
fn new_fields_round_trip_through_the_file() {
    let scene = one_block_with(
        "[[friction]]\nbetween = [\"blockA\", \"ground_plane\"]\nmu1 = 0.3\nmu2 = 0.25\n\n\
         [[friction]]\nbetween = [\"blockA\", \"actuator\"]\nmu1 = 0.5\n",
    );
    let mut scene = scene;
    let a = scene.body_index("blockA").expect("blockA");
    scene.bodies[a].centre_of_mass = Some([0.05, -0.01, 0.0]);
    scene.bodies[a].inertia = None;
    let text = scene.to_toml_string().expect("serialises");
    assert_eq!(Scene::from_toml_str(&text).expect("parses"), scene);
}
