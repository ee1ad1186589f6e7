//! The JSON messages between the viewer and its page (docs/viewer.md).

use serde::{Deserialize, Serialize};
use tokio_tungstenite::tungstenite::Utf8Bytes;

use pushlearn::wire::pb::{self, shape::Geometry};
use pushlearn::wire::{BodyName, GhostKind};

/// What a page may ask of the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Control {
    Pause,
    Unpause,
    Reset,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ControlRequest {
    control: Control,
}

impl Control {
    /// A page's request, `{"control": "pause" | "unpause" | "reset"}`.
    ///
    /// # Errors
    /// Anything else, with a message for the page.
    pub fn parse(text: &str) -> Result<Self, String> {
        serde_json::from_str::<ControlRequest>(text)
            .map(|request| request.control)
            .map_err(|err| {
                format!(
                    "cannot read the request {text:?}: {err} \
                     (expected {{\"control\": \"pause\" | \"unpause\" | \"reset\"}})"
                )
            })
    }
}

/// A body's size (`Hello.shapes`), as in the scene files.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Shape {
    Sphere {
        radius: f64,
    },
    /// Full edge lengths along the body's x, y, z.
    Box {
        size: [f64; 3],
    },
    /// Upright (its axis is the body's z); `length` is its height.
    Cylinder {
        radius: f64,
        length: f64,
    },
}

/// A body of the scene, at its start pose.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneBody {
    pub name: String,
    pub id: u32,
    /// `None` if the world did not say (a world older than `Hello.shapes`).
    pub shape: Option<Shape>,
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

/// What a published model is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A simulated body.
    Body,
    /// A ghost: the pose a learner predicted (`blockAShadow`).
    Shadow,
    /// A ghost marking a Move-to-Target goal (`blockAShadowTarget`).
    Target,
}

/// One published model, reduced to the plane.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Body {
    pub name: String,
    pub id: u32,
    pub kind: Kind,
    /// The scene body whose shape this is drawn with: the body itself, or
    /// the one a ghost stands for.
    pub of: String,
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

/// A message from the viewer to its pages; `type` tells which.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Outgoing {
    /// The scene: sent first, and again after a reconnection to the world.
    Hello {
        world: String,
        scene: String,
        timing_mode: String,
        publish_rate: u32,
        step_size: f64,
        bodies: Vec<SceneBody>,
    },
    /// A world state.
    State {
        step: u64,
        sim_time: f64,
        publish_seq: u64,
        bodies: Vec<Body>,
    },
    /// The world's answer to a control from any page.
    Control {
        action: Control,
        accepted: bool,
        #[serde(skip_serializing_if = "Option::is_none")]
        message: Option<String>,
    },
    /// An error not tied to a control: one from the world (`Error.seq = 0`,
    /// e.g. the physics blew up) or a request the viewer could not read.
    Error { message: String },
    /// The viewer's connection to the world.
    Status { connected: bool, message: String },
}

impl Outgoing {
    /// The scene of a world reached at `world`.
    #[must_use]
    pub fn hello(world: &str, hello: &pb::Hello) -> Self {
        let bodies = hello
            .bodies
            .iter()
            .map(|body| {
                let (x, y, yaw) = planar(body);
                SceneBody {
                    name: body.name.clone(),
                    id: body.id,
                    shape: hello
                        .shapes
                        .iter()
                        .find(|shape| shape.name == body.name)
                        .and_then(|shape| shape.geometry)
                        .map(|geometry| match geometry {
                            Geometry::SphereRadius(radius) => Shape::Sphere { radius },
                            Geometry::BoxSize(v) => Shape::Box {
                                size: [v.x, v.y, v.z],
                            },
                            Geometry::Cylinder(c) => Shape::Cylinder {
                                radius: c.radius,
                                length: c.length,
                            },
                        }),
                    x,
                    y,
                    yaw,
                }
            })
            .collect();
        Outgoing::Hello {
            world: world.to_owned(),
            scene: hello.scene.clone(),
            timing_mode: hello.timing_mode.clone(),
            publish_rate: hello.publish_rate,
            step_size: hello.step_size,
            bodies,
        }
    }

    /// A world state, its ghosts classified.
    #[must_use]
    pub fn state(state: &pb::WorldState) -> Self {
        let bodies = state
            .models()
            .iter()
            .filter(|model| model.name != pushlearn_core::GROUND_NAME)
            .map(|model| {
                let (kind, of) = classify(&model.name);
                let (x, y, yaw) = planar(model);
                Body {
                    name: model.name.clone(),
                    id: model.id,
                    kind,
                    of,
                    x,
                    y,
                    yaw,
                }
            })
            .collect();
        Outgoing::State {
            step: state.step,
            sim_time: state.sim_time,
            publish_seq: state.publish_seq,
            bodies,
        }
    }

    /// The world took `action`.
    #[must_use]
    pub fn accepted(action: Control) -> Self {
        Outgoing::Control {
            action,
            accepted: true,
            message: None,
        }
    }

    /// `action` did not reach the world or was refused, and why.
    #[must_use]
    pub fn refused(action: Control, message: String) -> Self {
        Outgoing::Control {
            action,
            accepted: false,
            message: Some(message),
        }
    }

    /// The message as a WebSocket text payload.
    #[must_use]
    pub fn to_json(&self) -> Utf8Bytes {
        // Plain data with string keys: serialising it cannot fail; NaN would
        // become `null`, which the page treats as "not drawable".
        serde_json::to_string(self)
            .unwrap_or_else(|err| {
                serde_json::json!({"type": "error", "message": err.to_string()}).to_string()
            })
            .into()
    }
}

/// A model name's kind and the scene body it is drawn as: `blockA` is a
/// body, `blockAShadow` its prediction, `blockAShadowTarget` its target; a
/// ghost with another suffix is shown as a prediction.
fn classify(name: &str) -> (Kind, String) {
    match BodyName::parse(name) {
        BodyName::Body(name) => (Kind::Body, name),
        BodyName::Ghost(ghost) => match ghost.kind {
            GhostKind::Target => (Kind::Target, ghost.of),
            GhostKind::Predicted | GhostKind::Other(_) => (Kind::Shadow, ghost.of),
        },
    }
}

/// Position in the plane and yaw of a model (0 for what it lacks).
fn planar(model: &pb::ModelState) -> (f64, f64, f64) {
    let pose = model.pose.unwrap_or_default();
    let position = pose.position.unwrap_or_default();
    let yaw = pose.orientation.map_or(0.0, |q| q.yaw());
    (position.x, position.y, yaw)
}

#[cfg(test)]
mod tests {
    use serde_json::{json, Value};

    use super::*;

    fn model(name: &str, id: u32, x: f64, y: f64, yaw: f64) -> pb::ModelState {
        pb::ModelState {
            name: name.into(),
            id,
            pose: Some(pb::Pose::from_position_yaw([x, y, 0.05], yaw)),
            ..Default::default()
        }
    }

    fn value(message: &Outgoing) -> Value {
        serde_json::from_str(&message.to_json()).unwrap()
    }

    #[test]
    fn ghosts_are_told_apart_by_name() {
        assert_eq!(classify("blockA"), (Kind::Body, "blockA".into()));
        assert_eq!(
            classify("actuatorShadow"),
            (Kind::Shadow, "actuator".into())
        );
        assert_eq!(
            classify("blockAShadowTarget"),
            (Kind::Target, "blockA".into())
        );
        assert_eq!(classify("blockBShadowOld"), (Kind::Shadow, "blockB".into()));
    }

    #[test]
    fn a_state_lists_bodies_and_ghosts_in_the_plane() {
        let state = pb::WorldState {
            model_v: Some(pb::ModelStateV {
                models: vec![
                    model("blockA", 15, 0.1, 0.3, 0.5),
                    model("ground_plane", 0, 0.0, 0.0, 0.0),
                    model("blockAShadowTarget", 15, 0.6, 0.7, -2.1),
                ],
            }),
            step: 20,
            sim_time: 0.02,
            publish_seq: 7,
            applied_seq: 3,
        };
        let got = value(&Outgoing::state(&state));
        assert_eq!(got["type"], "state");
        assert_eq!(got["step"], 20);
        assert_eq!(got["sim_time"], 0.02);
        assert_eq!(got["publish_seq"], 7);
        let bodies = got["bodies"].as_array().unwrap();
        assert_eq!(bodies.len(), 2, "the ground plane is not drawn: {got}");
        assert_eq!(bodies[0]["kind"], "body");
        assert_eq!(bodies[1]["kind"], "target");
        assert_eq!(bodies[1]["of"], "blockA");
        assert!((bodies[0]["yaw"].as_f64().unwrap() - 0.5).abs() < 1e-12);
        assert!((bodies[1]["yaw"].as_f64().unwrap() + 2.1).abs() < 1e-12);
        assert_eq!(
            (bodies[1]["x"].as_f64(), bodies[1]["y"].as_f64()),
            (Some(0.6), Some(0.7))
        );
    }

    #[test]
    fn hello_carries_the_sizes_it_knows() {
        let hello = pb::Hello {
            scene: "one_block".into(),
            step_size: 0.001,
            publish_rate: 100,
            timing_mode: "lockstep".into(),
            timing_kind: pb::hello::TimingKind::Lockstep.into(),
            bodies: vec![
                model("actuator", 8, 0.0, 0.0, 0.0),
                model("blockA", 15, 0.0, 0.25, 0.0),
            ],
            shapes: vec![pb::Shape {
                name: "blockA".into(),
                geometry: Some(Geometry::BoxSize(pb::Vector3d::new(0.5, 0.1, 0.1))),
            }],
            latency_max_steps: None,
            max_speed: None,
            engine: String::new(),
        };
        let got = value(&Outgoing::hello("127.0.0.1:1", &hello));
        assert_eq!(got["type"], "hello");
        assert_eq!(got["world"], "127.0.0.1:1");
        assert_eq!(got["timing_mode"], "lockstep");
        assert_eq!(got["bodies"][0]["shape"], Value::Null, "an older world");
        assert_eq!(
            got["bodies"][1]["shape"],
            json!({"type": "box", "size": [0.5, 0.1, 0.1]})
        );
        assert_eq!(got["bodies"][1]["y"], 0.25);
    }

    #[test]
    fn controls_round_trip_and_nonsense_is_explained() {
        assert_eq!(Control::parse(r#"{"control":"pause"}"#), Ok(Control::Pause));
        assert_eq!(Control::parse(r#"{"control":"reset"}"#), Ok(Control::Reset));
        let err = Control::parse(r#"{"control":"explode"}"#).unwrap_err();
        assert!(err.contains("expected"), "{err}");
        assert!(Control::parse(r#"{"control":"pause","x":1}"#).is_err());
        assert_eq!(
            value(&Outgoing::refused(Control::Unpause, "no".into())),
            json!({"type": "control", "action": "unpause", "accepted": false, "message": "no"})
        );
        assert_eq!(
            value(&Outgoing::accepted(Control::Pause)),
            json!({"type": "control", "action": "pause", "accepted": true})
        );
    }
}
