//! The floor: a predictor that is the world itself (`docs/models.md`,
//! "The floor"). Not a learner: from the state it is shown it steps a copy
//! of the experiment's world — the same scene, so the true masses,
//! frictions and shapes — under the action, one message at a time, and
//! chains its own states as a model chains its predictions. What it does
//! not know is what no learner can know: when each of the world's Moves
//! took effect (the latency emulation's draws). Its error is the part of
//! every learner's error that no learning can remove.
//!
//! It implements [`Model`] so that an experiment runs it as it runs a
//! model; it learns nothing, plans nothing (Move to Target is refused) and
//! reports no maps.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use learner::features::{is_skipped, parse_frame_at, ActuatorYaw, ParseError, Precision};
use learner::stats::ModelStats;
use learner::{Action, BodyShape, Frame, Model, Observation, Poses, Target, TargetError};
use pushlearn::wire::{pb, Shapes};
use rand::Rng;
use serde::{Deserialize, Serialize};
use sim_plugin::world::{ActuatorMode, Command, Snapshot, World};
use sim_plugin::Scene;

use crate::scene::Object;

/// The name reports give the floor.
pub const NAME: &str = "floor";

/// The floor's world: the state shown or stepped, and which step of the
/// copy it is (0: a state the copy did not produce).
#[derive(Clone, Debug)]
pub struct FloorWorld {
    frame: Frame,
    poses: Poses,
    token: u64,
    /// What the world's bodies were shown as (empty until the copy
    /// stepped it).
    shown: Vec<Shown>,
}

/// The world copy and the token of the state it holds.
#[derive(Default)]
struct WorldCopy {
    world: Option<World>,
    /// The scene's bodies' outlines.
    shapes: Shapes,
    token: u64,
}

impl std::fmt::Debug for WorldCopy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldCopy")
            .field("built", &self.world.is_some())
            .field("token", &self.token)
            .finish()
    }
}

/// The world as a predictor of itself, latency draws unknown.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Floor {
    scene: String,
    publish_rate_hz: u32,
    training: bool,
    /// Built at the first prediction; shared by clones, which take turns
    /// (a fold's predictions are sequential).
    #[serde(skip)]
    copy: Arc<Mutex<WorldCopy>>,
}

/// Why the floor cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum FloorError {
    #[error("the floor needs a built-in scene: {0}")]
    Scene(String),
}

impl Floor {
    /// The floor of the built-in scene `scene` at `publish_rate_hz`.
    ///
    /// # Errors
    /// An unknown scene.
    pub fn new(scene: &str, publish_rate_hz: u32) -> Result<Self, FloorError> {
        Scene::builtin(scene).map_err(|err| FloorError::Scene(err.to_string()))?;
        Ok(Self {
            scene: scene.to_owned(),
            publish_rate_hz,
            training: true,
            copy: Arc::default(),
        })
    }

    fn lock(&self) -> MutexGuard<'_, WorldCopy> {
        self.copy.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// One message of the copy from `from` under `action`: the copy's next
    /// state if it holds `from`, else from `from`'s poses at rest (what it
    /// is shown carries no velocities). `None` if the copy refused the
    /// state (a body the scene does not have) or could not step.
    fn step(&self, from: &FloorWorld, action: Action) -> Option<FloorWorld> {
        let mut copy = self.lock();
        let copy = &mut *copy;
        if copy.world.is_none() {
            let scene = Scene::builtin(&self.scene).ok()?;
            copy.shapes = Shapes::from_hello(&pb::Hello {
                shapes: sim_plugin::server::shapes(&scene),
                ..pb::Hello::default()
            });
            copy.world = Some(World::new(&scene).ok()?);
        }
        let world = copy.world.as_mut()?;
        let shown = if from.token == 0 || from.token != copy.token {
            let shown = shown_bodies(&from.frame, &copy.shapes)?;
            world.apply(Command::Reset).ok()?;
            world.apply(Command::Unpause).ok()?;
            world
                .apply(Command::SetPublishRate(self.publish_rate_hz))
                .ok()?;
            for (body, shown) in shown
                .iter()
                .zip(from.frame.objects.iter().filter(|o| !is_skipped(&o.name)))
            {
                if body.body != body.name {
                    // The new-object view: the object shown under another
                    // body's name took that body's start, and that body its
                    // parking place (`experiment::push_task::objects`).
                    let object = Object::ALL.into_iter().find(|o| o.body() == body.body)?;
                    let park = object.park()?;
                    let z = world.scene().bodies[world.scene().body_index(&body.name)?]
                        .start
                        .position()[2];
                    world
                        .apply(Command::SetPose {
                            name: body.name.as_str().into(),
                            position: [park.x, park.y, z],
                            orientation: pushlearn_core::orientation::from_yaw(park.theta),
                        })
                        .ok()?;
                }
                world
                    .apply(Command::SetPose {
                        name: body.body.as_str().into(),
                        position: shown.position,
                        orientation: shown.orientation,
                    })
                    .ok()?;
            }
            shown
        } else {
            from.shown.clone()
        };
        world
            .apply(Command::Actuator {
                mode: ActuatorMode::Move,
                velocity: [action.vx, action.vy, 0.0],
            })
            .ok()?;
        let snapshot = loop {
            if let Some(s) = world.step().ok()? {
                break s;
            }
        };
        let frame = view_of(&snapshot, &shown)?;
        let poses = parse_frame_at(&frame, ActuatorYaw::ForceZero, Precision::Full).ok()?;
        copy.token = copy.token.wrapping_add(1).max(1);
        Some(FloorWorld {
            frame,
            poses,
            token: copy.token,
            shown,
        })
    }
}

/// A body as the floor was shown it, and the world's body it is.
#[derive(Clone, Debug, PartialEq)]
struct Shown {
    name: String,
    id: u32,
    shape: Option<BodyShape>,
    body: String,
}

/// Which of the world's bodies each body shown is: the one of its name,
/// unless its observed outline is another body's (the new-object view
/// shows an object under the blue block's name). `None` if an outline
/// matches no body.
fn shown_bodies(frame: &Frame, shapes: &Shapes) -> Option<Vec<Shown>> {
    frame
        .objects
        .iter()
        .filter(|o| !is_skipped(&o.name))
        .map(|o| {
            let body = match o.shape {
                Some(f) if shapes.of(&o.name) != Some(f) => shapes.body_with(f)?,
                _ => o.name.as_str(),
            };
            Some(Shown {
                name: o.name.clone(),
                id: o.id,
                shape: o.shape,
                body: body.to_owned(),
            })
        })
        .collect()
}

/// The copy's state as the floor was shown the world: the bodies shown,
/// under the names they were shown with.
fn view_of(snapshot: &Snapshot, shown: &[Shown]) -> Option<Frame> {
    let objects = shown
        .iter()
        .map(|s| {
            let body = snapshot.bodies.iter().find(|b| b.name == s.body)?;
            Some(Observation {
                name: s.name.clone(),
                id: s.id,
                shape: s.shape,
                ..body.observation()
            })
        })
        .collect::<Option<Vec<_>>>()?;
    Some(Frame { objects })
}

impl Model for Floor {
    type World = FloorWorld;

    fn parse(&self, frame: &Frame) -> Result<FloorWorld, ParseError> {
        Ok(FloorWorld {
            poses: parse_frame_at(frame, ActuatorYaw::ForceZero, Precision::Full)?,
            frame: frame.clone(),
            token: 0,
            shown: Vec::new(),
        })
    }

    fn poses(world: &FloorWorld) -> Poses {
        world.poses.clone()
    }

    fn reset_objects(&mut self, _world: &FloorWorld) {}

    fn update(&mut self, _world: &FloorWorld, _action: Action) {}

    /// A state the copy refuses (a body its scene lacks) is predicted to
    /// stay as it is.
    fn predict(&self, world: &FloorWorld, action: Action) -> FloorWorld {
        self.step(world, action).unwrap_or_else(|| FloorWorld {
            token: 0,
            ..world.clone()
        })
    }

    fn set_training(&mut self, on: bool) {
        self.training = on;
    }

    fn is_training(&self) -> bool {
        self.training
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        match target {
            None => Ok(()),
            Some(t) => Err(TargetError::UnknownObject { id: t.id }),
        }
    }

    fn has_target(&self) -> bool {
        false
    }

    fn act(&mut self, _rng: &mut dyn Rng) -> Action {
        Action::ZERO
    }

    fn stats(&self) -> ModelStats {
        ModelStats::Other(learner::stats::OtherStats::default())
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::ForceZero
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_plugin::push_run::record_push_run;

    #[test]
    fn the_floor_chains_a_latency_free_copy_of_the_world() {
        let scene = Scene::builtin("one_block").unwrap();
        let mut world = World::new(&scene).unwrap();
        world.apply(Command::SetPublishRate(100)).unwrap();
        let push = Action::new(0.0, 0.5);
        let run = record_push_run(&mut world, 0.1, [push.vx, push.vy], 120).unwrap();
        let floor = Floor::new("one_block", 100).unwrap();
        // Sent after the first message, the push moves the world into the
        // second.
        let mut predicted = floor.parse(&frame_of(&run[0])).unwrap();
        for _ in 1..run.len() {
            predicted = floor.predict(&predicted, push);
        }
        let seen = floor.parse(&frame_of(&run[run.len() - 1])).unwrap();
        let (p, s) = (
            Floor::poses(&predicted).blocks[&learner::BLUE_ID],
            Floor::poses(&seen).blocks[&learner::BLUE_ID],
        );
        let start =
            Floor::poses(&floor.parse(&frame_of(&run[0])).unwrap()).blocks[&learner::BLUE_ID];
        assert!(s.distance_to(&start) > 0.1, "the block was pushed");
        assert!(p.distance_to(&s) < 1e-3, "{p:?} against {s:?}");

        // A state it did not produce (token 0) is taken as shown, at rest:
        // from the last message the block, released, hardly moves.
        let shown = floor.parse(&frame_of(&run[run.len() - 1])).unwrap();
        let next = floor.predict(&shown, Action::ZERO);
        let b = |w: &FloorWorld| Floor::poses(w).blocks[&learner::BLUE_ID];
        assert!(b(&next).distance_to(&b(&shown)) < 1e-3);
        assert_ne!(next.token, 0);
    }

    fn frame_of(snapshot: &sim_plugin::Snapshot) -> Frame {
        Frame {
            objects: snapshot
                .bodies
                .iter()
                .map(sim_plugin::BodyState::observation)
                .collect(),
        }
    }

    #[test]
    fn an_object_shown_under_the_blue_blocks_name_is_found_by_its_outline() {
        let scene = Scene::builtin(crate::scene::SCENE).unwrap();
        let shapes = Shapes::from_hello(&pb::Hello {
            shapes: sim_plugin::server::shapes(&scene),
            ..pb::Hello::default()
        });
        let cylinder = shapes.of(Object::Cylinder.body()).unwrap();
        let shown = |shape| Observation {
            name: learner::BLUE_NAME.into(),
            id: learner::BLUE_ID,
            position: [0.0, 0.3, 0.05],
            orientation: [0.0, 0.0, 0.0, 1.0],
            shape,
        };
        let frame = |shape| Frame {
            objects: vec![shown(shape)],
        };
        let body = |shape| shown_bodies(&frame(shape), &shapes).map(|s| s[0].body.clone());
        assert_eq!(
            body(Some(cylinder)).as_deref(),
            Some(Object::Cylinder.body())
        );
        assert_eq!(body(None).as_deref(), Some(learner::BLUE_NAME));
        let blue = shapes.of(learner::BLUE_NAME);
        assert_eq!(body(blue).as_deref(), Some(learner::BLUE_NAME));
        assert_eq!(body(Some(BodyShape::Sphere { radius: 7.0 })), None);
    }

    #[test]
    fn it_refuses_unknown_scenes_and_targets() {
        assert!(Floor::new("no_such_scene", 100).is_err());
        let mut floor = Floor::new("one_block", 100).unwrap();
        let target = Target {
            id: learner::BLUE_ID,
            pose: learner::ObjectState::new(0.0, 0.5, 0.0),
        };
        assert!(floor.set_target(Some(target)).is_err());
        assert!(!floor.has_target());
    }
}
