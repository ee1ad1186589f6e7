//! The hybrid model through the [`Model`] trait, against a world that is
//! its own mechanics with known parameters: what it identifies, what each
//! part adds, and the trait's bookkeeping.

use nalgebra::Vector2;

use super::mechanics::{Outline, Parameters, Push, Slide, Twist};
use super::{HybridConfig, HybridModel, HybridWorld, Parts};
use crate::model::Model;
use crate::types::{Action, Frame, ObjectState, Observation, Target, TargetError, BLUE_ID};

/// The tipping of the made-up world: on the identification's grid.
const TRUE_TIPPING: f64 = 0.03;
const PUSH: Action = Action::new(0.0, 0.5);

fn truth() -> Parameters {
    Parameters {
        tipping: TRUE_TIPPING,
        slide: Slide {
            linear: 1.0,
            angular: 1.0,
        },
    }
}

fn frame(actuator: Vector2<f64>, block: ObjectState) -> Frame {
    let quaternion = |yaw: f64| [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
    Frame {
        objects: vec![
            Observation {
                name: "actuator".into(),
                id: 8,
                position: [actuator.x, actuator.y, 0.03],
                orientation: quaternion(0.0),
                shape: None,
            },
            Observation {
                name: "blockA".into(),
                id: BLUE_ID,
                position: [block.x, block.y, 0.05],
                orientation: quaternion(block.theta),
                shape: None,
            },
        ],
    }
}

/// One push-task run of the made-up world from `x0`: the frames, the
/// actuator moving exactly 5 mm a message.
fn run(x0: f64, messages: usize) -> Vec<Frame> {
    let outline = Outline::Box { half: [0.25, 0.05] };
    let parameters = truth();
    let push = Push {
        outline: &outline,
        parameters: &parameters,
        pusher_radius: 0.025,
    };
    let mut actuator = Vector2::new(x0, 0.0);
    let mut block = ObjectState::new(0.0, 0.25, 0.0);
    let mut motion = Twist::default();
    let mut frames = vec![frame(actuator, block)];
    let path = Vector2::new(0.0, 0.005);
    for _ in 0..messages {
        let stepped = push.step(block, motion, actuator, path);
        actuator += path;
        block = stepped.slider;
        motion = stepped.motion;
        frames.push(frame(actuator, block));
    }
    frames
}

fn model(parts: Parts) -> HybridModel {
    HybridModel::new(HybridConfig {
        parts,
        publish_rate_hz: 100,
    })
}

fn train(model: &mut HybridModel, x0: f64) {
    for (i, f) in run(x0, 150).iter().enumerate() {
        let world = model.parse(f).unwrap();
        if i == 0 {
            model.reset_objects(&world);
        } else {
            model.update(&world, PUSH);
        }
    }
}

/// The push task's test: 150 predictions chained from the first state;
/// the block's final position and orientation errors.
fn test_error(model: &mut HybridModel, x0: f64) -> (f64, f64) {
    let frames = run(x0, 150);
    let mut world: HybridWorld = model.parse(&frames[0]).unwrap();
    model.reset_objects(&world);
    for _ in 0..150 {
        world = model.predict(&world, PUSH);
        model.update(&world, PUSH);
    }
    let last = model.parse(&frames[150]).unwrap();
    let (p, t) = (world.poses.blocks[&BLUE_ID], last.poses.blocks[&BLUE_ID]);
    ((p.x - t.x).hypot(p.y - t.y), (p.theta - t.theta).abs())
}

#[test]
fn identification_finds_the_worlds_tipping_and_then_predicts_it() {
    let mut m = model(Parts::Identified);
    // A push that turns the block until the pusher slides off, and one
    // that turns it a little and then drives it straight: together they
    // tell every value of the grid apart.
    train(&mut m, 0.12);
    train(&mut m, 0.04);
    let stats = m.stats();
    let tipping = stats.as_other().unwrap().extra[&format!("tipping/{BLUE_ID}")];
    assert_eq!(tipping, TRUE_TIPPING);
    m.set_training(false);
    // An offset it was not trained on, on the other side.
    let (pos, ori) = test_error(&mut m, -0.07);
    assert!(pos < 1e-3 && ori < 0.01, "{pos} {ori}");

    // The shape's mechanics alone assume a level weight: the offset push
    // turns less, and the chain ends elsewhere.
    let mut alone = model(Parts::Mechanics);
    train(&mut alone, 0.12);
    train(&mut alone, 0.04);
    alone.set_training(false);
    let (pos_alone, ori_alone) = test_error(&mut alone, -0.07);
    assert!(ori_alone > 10.0 * ori.max(1e-3), "{ori_alone} vs {ori}");
    assert!(pos_alone > pos);
}

#[test]
fn the_residual_memory_learns_only_what_the_mechanics_miss() {
    let mut full = model(Parts::Full);
    train(&mut full, 0.12);
    train(&mut full, 0.04);
    let stats = full.stats();
    let memory = stats.as_other().unwrap().maps[&format!("residual/{BLUE_ID}")];
    // It remembers the messages near the block and nothing else…
    assert!(memory.nodes > 100 && memory.nodes < 300, "{memory:?}");
    full.set_training(false);
    // …and in a world that is its own mechanics there is nothing to add.
    let (pos, ori) = test_error(&mut full, 0.12);
    assert!(pos < 1e-3 && ori < 0.01, "{pos} {ori}");
}

#[test]
fn motion_is_read_from_the_stored_state_and_a_reset_stops_it() {
    let mut m = model(Parts::Full);
    let frames = run(0.0, 60);
    let first = m.parse(&frames[0]).unwrap();
    m.reset_objects(&first);
    for f in &frames[1..] {
        let w = m.parse(f).unwrap();
        m.update(&w, PUSH);
    }
    // The block is being pushed: 5 mm a message.
    let next = m.parse(&frames[60]).unwrap();
    assert!(
        next.motion[&BLUE_ID].dy.abs() < 1e-12,
        "the same state again"
    );
    let moving = m.parse(&run(0.0, 61)[61]).unwrap();
    assert!((moving.motion[&BLUE_ID].dy - 0.005).abs() < 1e-6);
    // A jump no push makes is a reset, not a motion.
    let far = m
        .parse(&frame(Vector2::zeros(), ObjectState::new(0.0, 0.9, 0.0)))
        .unwrap();
    assert_eq!(far.motion[&BLUE_ID], Twist::default());
}

#[test]
fn a_serialised_model_predicts_as_the_original() {
    let mut m = model(Parts::Full);
    train(&mut m, 0.05);
    let json = serde_json::to_string(&m).unwrap();
    let back: HybridModel = serde_json::from_str(&json).unwrap();
    let w = m.parse(&run(0.1, 40)[40]).unwrap();
    assert_eq!(m.predict(&w, PUSH), back.predict(&w, PUSH));
}

#[test]
fn targets_for_the_actuator_or_unknown_objects_are_refused() {
    let mut m = model(Parts::Full);
    assert_eq!(
        m.set_target(Some(Target::new(8, ObjectState::default()))),
        Err(TargetError::Actuator)
    );
    assert_eq!(
        m.set_target(Some(Target::new(99, ObjectState::default()))),
        Err(TargetError::UnknownObject { id: 99 })
    );
    assert!(!m.has_target());
    m.set_target(Some(Target::new(BLUE_ID, ObjectState::new(0.0, 0.6, 0.0))))
        .unwrap();
    assert!(m.has_target());
}

#[test]
fn the_observed_outline_decides_contact_and_the_shape_table_stands_in_without_one() {
    use crate::types::BodyShape;
    let m = model(Parts::Mechanics);
    // Beside the blue block's long face, 3 cm off its axis: a box there is
    // touched by a push across it, a disc of 0.1 m radius is not.
    let plain = frame(Vector2::new(0.2, 0.15), ObjectState::new(0.0, 0.25, 0.0));
    let mut disc = plain.clone();
    disc.objects[1].shape = Some(BodyShape::Cylinder {
        radius: 0.1,
        length: 0.1,
    });
    let as_box = m.parse(&plain).unwrap();
    let as_disc = m.parse(&disc).unwrap();
    assert_eq!(as_box.outline(BLUE_ID), Outline::Box { half: [0.25, 0.05] });
    assert_eq!(as_disc.outline(BLUE_ID), Outline::Disc { radius: 0.1 });
    let moved = |w: &HybridWorld| {
        let mut w = w.clone();
        for _ in 0..10 {
            w = m.predict(&w, PUSH);
        }
        w.poses.blocks[&BLUE_ID].y - 0.25
    };
    assert!(moved(&as_box) > 0.01, "{}", moved(&as_box));
    assert_eq!(moved(&as_disc), 0.0);
}
