//! The world's acceptance tests: the thesis's physical facts (`docs/spec/world.md`
//! §10) and the known issues of libode 0.16 (`docs/spec/world.md` §12).
//!
//! The tolerances are the project's calibration bounds; a world that misses
//! them is mis-configured (friction rule, actuator mass, z clamp, velocity
//! re-imposition, collision space), never a reason to widen them.

use std::sync::OnceLock;

use sim_plugin::calibration::{run, BLUE_BLOCK};
use sim_plugin::{sweep, Command, Scene, SpaceKind, SweepOptions, SweepRow, World};

/// The 21-start sweep on the default scene, computed once per test binary.
fn grid() -> &'static [SweepRow] {
    static GRID: OnceLock<Vec<SweepRow>> = OnceLock::new();
    GRID.get_or_init(|| {
        let scene = Scene::builtin("one_block").expect("embedded scene parses");
        sweep(&scene, &SweepOptions::default()).expect("sweep runs")
    })
}

/// The actuator (radius 0.025) misses the 0.5 m wide block beyond this.
const MISS: f64 = 0.275;

#[test]
fn grid_has_the_thesis_starts() {
    let g = grid();
    assert_eq!(g.len(), 21);
    assert!((g[0].x0 + 0.35).abs() < 1e-12 && (g[20].x0 - 0.35).abs() < 1e-12);
    assert!(g[10].x0.abs() < 1e-12);
}

#[test]
fn actuator_reaches_the_block_after_about_35_messages() {
    for r in grid().iter().filter(|r| r.x0.abs() < MISS) {
        let m = r.first_contact_message;
        assert!(
            matches!(m, Some(34..=37)),
            "x0 = {:.3}: first contact at {m:?}",
            r.x0
        );
    }
}

#[test]
fn a_missed_block_does_not_move() {
    let missed: Vec<_> = grid()
        .iter()
        .filter(|r| r.x0.abs() >= 0.28 - 1e-9)
        .collect();
    assert_eq!(missed.len(), 6);
    for r in missed {
        assert_eq!(r.first_contact_message, None, "x0 = {:.3}", r.x0);
        assert!(r.translation < 1e-3, "x0 = {:.3}: {r:?}", r.x0);
        assert!(r.rotation.abs() < 1e-3, "x0 = {:.3}: {r:?}", r.x0);
    }
}

#[test]
fn centre_push_translates_without_rotating() {
    let centre = &grid()[10];
    assert!(
        (0.55..=0.62).contains(&centre.translation),
        "translation {}",
        centre.translation
    );
    assert!(centre.rotation.abs() < 0.01, "rotation {}", centre.rotation);
}

#[test]
fn largest_rotation_is_at_0_105_and_about_a_radian() {
    let g = grid();
    let max = g
        .iter()
        .max_by(|a, b| a.rotation.abs().total_cmp(&b.rotation.abs()))
        .expect("non-empty grid");
    assert!(
        (max.x0.abs() - 0.105).abs() < 1e-9,
        "largest |rotation| at x0 = {}",
        max.x0
    );
    for x0 in [-0.105, 0.105] {
        let r = g.iter().find(|r| (r.x0 - x0).abs() < 1e-9).expect("start");
        assert!(
            (0.95..=1.10).contains(&r.rotation.abs()),
            "x0 = {x0}: rotation {}",
            r.rotation
        );
    }
}

#[test]
fn mirrored_starts_give_mirrored_outcomes() {
    let g = grid();
    for (a, b) in g.iter().zip(g.iter().rev()) {
        assert!((a.x0 + b.x0).abs() < 1e-9);
        assert!((a.block_x + b.block_x).abs() < 1e-3, "{a:?} vs {b:?}");
        assert!((a.block_y - b.block_y).abs() < 1e-3, "{a:?} vs {b:?}");
        assert!((a.rotation + b.rotation).abs() < 1e-3, "{a:?} vs {b:?}");
        assert!(
            (a.translation - b.translation).abs() < 1e-3,
            "{a:?} vs {b:?}"
        );
    }
}

#[test]
fn pushing_right_of_centre_turns_the_block_counter_clockwise() {
    let g = grid();
    assert!(g[13].rotation > 0.0, "x0 = 0.105: {:?}", g[13]);
    assert!(g[7].rotation < 0.0, "x0 = -0.105: {:?}", g[7]);
}

fn push_from(space: SpaceKind, x0: f64) -> SweepRow {
    let scene = Scene::builtin("one_block").expect("embedded scene parses");
    let mut world = World::with_space(&scene, space).expect("world builds");
    run(&mut world, &SweepOptions::default(), x0).expect("run succeeds")
}

/// `docs/spec/world.md` §12: with libode 0.16.2's `dHashSpace` at the top level the
/// actuator passes through the block for starts with x0 > 0. The thesis
/// world therefore uses a simple space; a push from +0.105 must rotate the
/// block as much as one from −0.105, mirrored.
#[test]
fn hash_space_regression_positive_start_pushes_like_the_mirrored_one() {
    let plus = push_from(SpaceKind::Simple, 0.105);
    let minus = push_from(SpaceKind::Simple, -0.105);
    assert!(plus.rotation > 0.95, "{plus:?}");
    assert!(
        (plus.rotation + minus.rotation).abs() < 1e-3,
        "{plus:?} vs {minus:?}"
    );
    assert!(
        (plus.block_x + minus.block_x).abs() < 1e-3,
        "{plus:?} vs {minus:?}"
    );
}

/// Documents why the top-level space is simple: libode 0.16.2's hash space
/// misses the actuator–block contact here. If this starts failing, the
/// library was fixed and the note in `docs/spec/world.md` §12 can be revisited.
#[test]
fn hash_space_at_the_top_level_misses_the_contact() {
    let plus = push_from(SpaceKind::Hash, 0.105);
    assert_eq!(plus.first_contact_message, None, "{plus:?}");
    assert!(plus.rotation.abs() < 1e-3, "{plus:?}");
}

#[test]
fn identical_runs_are_bit_identical() {
    let scene = Scene::builtin("two_blocks").expect("embedded scene parses");
    let options = SweepOptions {
        starts: vec![0.07, -0.105, 0.0],
        ..SweepOptions::default()
    };
    let first = sweep(&scene, &options).expect("sweep runs");
    let second = sweep(&scene, &options).expect("sweep runs");
    // PartialEq on f64 fields: bit-identical up to the sign of zero, and
    // none of these values is zero.
    assert_eq!(first, second);
    // A world reused after other runs gives the same as a fresh one.
    let mut used = World::new(&scene).expect("world builds");
    sim_plugin::calibration::sweep_world(&mut used, &SweepOptions::default()).expect("sweep runs");
    let reused = sim_plugin::calibration::sweep_world(&mut used, &options).expect("sweep runs");
    assert_eq!(first, reused);
}

#[test]
fn reset_restores_every_body_exactly() {
    for name in ["one_block", "two_blocks"] {
        let scene = Scene::builtin(name).expect("embedded scene parses");
        let mut world = World::new(&scene).expect("world builds");
        let fresh = world.snapshot();
        run(&mut world, &SweepOptions::default(), 0.14).expect("run succeeds");
        let moved = world.snapshot();
        assert_ne!(moved.body(BLUE_BLOCK), fresh.body(BLUE_BLOCK));
        world.apply(Command::Reset).expect("reset is valid");
        assert_eq!(world.snapshot(), fresh, "scene {name}");
        assert_eq!(world.step_count(), 0);
        assert_eq!(world.sim_time(), 0.0);
    }
}

/// The block must not keep sliding once the actuator has swung off it
/// (`docs/spec/world.md` §10): by the end of a corner push it is at rest.
#[test]
fn block_stops_after_the_actuator_swings_off() {
    let scene = Scene::builtin("one_block").expect("embedded scene parses");
    let mut world = World::new(&scene).expect("world builds");
    run(&mut world, &SweepOptions::default(), 0.245).expect("run succeeds");
    let block = world
        .snapshot()
        .body(BLUE_BLOCK)
        .cloned()
        .expect("blue block");
    let speed = block.lin_vel[0].hypot(block.lin_vel[1]);
    assert!(speed < 1e-3, "still sliding at {speed} m/s");
}

/// `docs/spec/world.md` §10: the red block rotates only when pushed near its corners.
#[test]
fn red_block_turns_only_when_pushed_near_a_corner() {
    let scene = Scene::builtin("two_blocks").expect("embedded scene parses");
    let mut world = World::new(&scene).expect("world builds");
    let mut rotation = |x0: f64| {
        run(&mut world, &SweepOptions::default(), x0).expect("run succeeds");
        world.snapshot().body("blockB").expect("red block").yaw()
    };
    let centre = rotation(-0.6);
    let corner = rotation(-0.6 + 0.14);
    assert!(centre.abs() < 0.01, "centre push turned it by {centre}");
    assert!(corner.abs() > 0.1, "corner push turned it by only {corner}");
}

/// The new objects' sweep (`docs/world.md` "New objects"): the pushed body
/// takes the blue block's start, so the contact comes when the gap to its
/// near face closes, and a centred push drives it straight ahead.
#[test]
fn the_new_objects_calibrate_like_the_blue_block() {
    let scene = Scene::builtin("objects").expect("embedded scene parses");
    let sweep_of = |body: &str, starts: Vec<f64>| {
        let options = SweepOptions {
            starts,
            body: body.to_owned(),
            ..SweepOptions::default()
        };
        sweep(&scene, &options).expect("sweep runs")
    };
    // Gap from the actuator's surface (0.025) to the near face (0.25 − half
    // depth) at 0.5 m/s is 10·gap/0.5·100 messages in, less one.
    for (body, half_depth, contact) in [("blockB", 0.15, 16), ("cylinder", 0.1, 26)] {
        let rows = sweep_of(body, vec![-0.05, 0.0, 0.05, 0.3]);
        let [left, centre, right, missed] = [rows[0], rows[1], rows[2], rows[3]];
        let gap: f64 = 0.25 - half_depth - 0.025;
        assert_eq!(
            centre.first_contact_message,
            Some(contact),
            "{body}: gap {gap} m"
        );
        assert!(
            centre.translation > 0.5 && centre.rotation.abs() < 1e-3,
            "{body}: {centre:?}"
        );
        // Mirror starts, mirror outcomes.
        assert!(
            (left.block_x + right.block_x).abs() < 1e-3,
            "{body}: {left:?} {right:?}"
        );
        // The cylinder's yaw, which its shape does not show, comes from the
        // friction at the contact points and is not mirror-symmetric.
        if body == "blockB" {
            assert!((left.rotation + right.rotation).abs() < 1e-3, "{body}");
        }
        assert_eq!(missed.first_contact_message, None, "{body}: {missed:?}");
        assert!(missed.translation < 1e-3, "{body}: {missed:?}");
    }
    // The blue block's own sweep in this scene is the one-block world's to
    // within the constraint-row order.
    let blue = sweep_of("blockA", vec![0.105])[0];
    assert!((blue.rotation - 1.0396).abs() < 2e-3, "{blue:?}");
    let unknown = SweepOptions {
        body: "sphere".into(),
        ..SweepOptions::default()
    };
    assert!(sweep(&scene, &unknown).is_err());
}

/// The second engine against the first (`docs/world.md`, "Two engines"):
/// the same first contacts, the centred push's distance within 10 %, and
/// every start's rotation of the same sign where both move the block. A
/// MuJoCo model that breaks these is mis-mapped from the scene (sizes,
/// masses, friction pairs, the drive), never a reason to tune it.
#[cfg(feature = "mujoco")]
#[test]
fn mujoco_agrees_with_ode_on_the_calibration_targets() {
    let scene = Scene::builtin("one_block").expect("embedded scene parses");
    let options = SweepOptions {
        engine: sim_plugin::Engine::Mujoco,
        ..SweepOptions::default()
    };
    let mujoco = sweep(&scene, &options).expect("sweep runs on MuJoCo");
    for (o, m) in grid().iter().zip(&mujoco) {
        assert_eq!(
            o.first_contact_message, m.first_contact_message,
            "x0 = {}",
            o.x0
        );
        let moved = |r: &SweepRow| r.translation > 1e-3;
        assert_eq!(moved(o), moved(m), "x0 = {}", o.x0);
        if moved(o) && o.rotation.abs() > 1e-3 {
            assert_eq!(o.rotation.signum(), m.rotation.signum(), "x0 = {}", o.x0);
        }
    }
    let (o, m) = (&grid()[10], &mujoco[10]);
    assert_eq!(o.x0, 0.0);
    let gap = (m.translation - o.translation).abs() / o.translation;
    assert!(
        gap < 0.1,
        "centred push: ODE {} m, MuJoCo {} m",
        o.translation,
        m.translation
    );
}
