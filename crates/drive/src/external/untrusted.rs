//! The learner protocol read from untrusted bytes, without processes or
//! sockets: what a learner daemon (`pushlearn serve-learner --listen`)
//! makes of whatever a connection sends, and what the experiment driver
//! makes of whatever a learner writes. The code under fuzzing
//! (`fuzz/fuzz_targets/learner_requests.rs`, `learner_replies.rs`) and
//! under the tests that replay the fuzzers' corpora (`docs/reliability.md`).

use learner::{ObjectState, Poses, BLUE_ID};

use pushlearn::wire::decode_stream;
use pushlearn::wire::pb::learner::{reply::Answer, request::Call, Reply, Request};

use super::server::{serve_driver, Requests, ServeError};
use super::{bodies_of, chosen_action, greeting, predicted_poses, stats_of, Source};
use learner::registry::{ModelKind, ModelOptions};

/// What a learner daemon made of one connection's bytes.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Served {
    /// Requests in the bytes up to the first bad frame.
    pub requests: usize,
    /// Replies written.
    pub replies: usize,
    /// Why serving ended early, if it did.
    pub ended: Option<String>,
}

/// Serves `bytes` as everything one driver sent before closing, with the
/// built-in model `kind` (default options), and checks what was written:
/// only whole reply frames, in the order of the requests: an answer of the
/// right kind for each call that asks for one, at most one Error, last, and
/// no number in them that is not finite.
///
/// # Errors
/// The property that was broken (a panic is the fuzzer's to catch).
pub fn serve_untrusted_requests(kind: ModelKind, bytes: &[u8]) -> Result<Served, String> {
    let mut output = Vec::new();
    let ended = match serve_driver(
        kind,
        &ModelOptions::default(),
        Requests::new(bytes),
        &mut output,
    ) {
        Ok(()) => None,
        Err(ServeError::Write(err)) => return Err(format!("writing to memory failed: {err}")),
        Err(err) => Some(err.to_string()),
    };
    let (requests, _) = decode_stream::<Request>(bytes);
    let (replies, error) = decode_stream::<Reply>(&output);
    if let Some(error) = error {
        return Err(format!("the replies are not whole frames: {error}"));
    }
    // The replies, walked beside the requests in order: each answered call
    // gets its answer, and an Error (about the request it names) is the
    // last reply. Seqs need not be unique: a driver chooses them.
    let mut unread = replies.iter().peekable();
    for (k, request) in requests.iter().enumerate() {
        let Some(&reply) = unread.peek() else { break };
        if reply.seq == request.seq && matches!(reply.answer, Some(Answer::Error(_))) {
            unread.next();
            if let Some(after) = unread.next() {
                return Err(format!(
                    "a reply after the Error that ended serving: {after:?}"
                ));
            }
            break;
        }
        let answered = match request.call {
            Some(Call::Start(_)) => k == 0,
            Some(Call::Predict(_) | Call::SetTarget(_) | Call::Act(_) | Call::GetStats(_)) => true,
            _ => false,
        };
        if answered {
            unread.next();
            if reply.seq != request.seq {
                return Err(format!(
                    "message {} was answered with the seq {}",
                    request.seq, reply.seq
                ));
            }
            check_reply(request, reply)?;
        }
    }
    if let Some(extra) = unread.next() {
        return Err(format!("a reply no request called for: {extra:?}"));
    }
    Ok(Served {
        requests: requests.len(),
        replies: replies.len(),
        ended,
    })
}

/// An answer fits its request: the kind the call asks for, with finite
/// numbers.
fn check_reply(request: &Request, reply: &Reply) -> Result<(), String> {
    let fits = matches!(
        (&request.call, &reply.answer),
        (Some(Call::Start(_)), Some(Answer::Hello(_)))
            | (Some(Call::Predict(_)), Some(Answer::Prediction(_)))
            | (Some(Call::SetTarget(_)), Some(Answer::Target(_)))
            | (Some(Call::Act(_)), Some(Answer::Action(_)))
            | (Some(Call::GetStats(_)), Some(Answer::Stats(_)))
    );
    if !fits {
        return Err(format!(
            "message {} was answered with {:?}",
            request.seq, reply.answer
        ));
    }
    let finite = match &reply.answer {
        Some(Answer::Prediction(p)) => p
            .bodies
            .iter()
            .all(|b| [b.x(), b.y(), b.theta()].iter().all(|v| v.is_finite())),
        Some(Answer::Action(a)) => a
            .action
            .is_some_and(|a| a.vx().is_finite() && a.vy().is_finite()),
        Some(Answer::Stats(s)) => s.extra.values().all(|v| v.is_finite()),
        _ => true,
    };
    if finite {
        Ok(())
    } else {
        Err(format!(
            "message {} was answered with a number that is not finite: {:?}",
            request.seq, reply.answer
        ))
    }
}

/// The world the driver asks a learner about while [`read_untrusted_replies`]
/// checks its predictions: the actuator and the blue block.
fn asked_about() -> Poses {
    Poses {
        actuator: ObjectState::new(0.0, -0.5, 0.0),
        blocks: [(BLUE_ID, ObjectState::new(0.0, -0.3, 0.0))].into(),
    }
}

/// Reads `bytes` as everything a learner wrote, frame by frame as the driver
/// does, and puts each answer through the driver's checks (the hello, a
/// prediction about [`asked_about`], an action, statistics). Returns how many
/// answers the checks accepted.
///
/// # Errors
/// An accepted answer that breaks what the checks promise the driver: a
/// prediction with a non-finite pose or other bodies than the world asked
/// about, a non-finite action.
pub fn read_untrusted_replies(bytes: &[u8]) -> Result<usize, String> {
    let (replies, _) = decode_stream::<Reply>(bytes);
    let from = asked_about();
    let source = Source::Command("fuzz".into());
    let mut accepted = 0;
    for reply in replies {
        let ok = match reply.answer {
            Some(Answer::Hello(hello)) => greeting(hello, &source).is_ok(),
            Some(Answer::Prediction(prediction)) => {
                match predicted_poses(bodies_of(&prediction), &from) {
                    Ok(poses) => {
                        let finite = poses.objects().all(|(_, s)| s.is_finite());
                        let same = poses.blocks.keys().eq(from.blocks.keys());
                        if !finite || !same {
                            return Err(format!("accepted the prediction {prediction:?}"));
                        }
                        true
                    }
                    Err(_) => false,
                }
            }
            Some(Answer::Action(reply)) => match chosen_action(&reply) {
                Ok(action) if !action.is_finite() => {
                    return Err(format!("accepted the action {action:?}"));
                }
                Ok(_) => true,
                Err(_) => false,
            },
            Some(Answer::Stats(stats)) => stats_of(stats).is_ok(),
            Some(Answer::Target(_) | Answer::Error(_)) | None => false,
        };
        accepted += usize::from(ok);
    }
    Ok(accepted)
}

/// The model a `learner_requests` fuzz input is served with: its first byte
/// picks one of the built-in models.
#[must_use]
pub fn model_for_input(bytes: &[u8]) -> (ModelKind, &[u8]) {
    match bytes.split_first() {
        Some((&pick, rest)) => (
            match pick % 3 {
                0 => ModelKind::Gate,
                1 => ModelKind::Interaction,
                _ => ModelKind::GatePlus,
            },
            rest,
        ),
        None => (ModelKind::Gate, bytes),
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use pushlearn::wire::encode_frame;
    use pushlearn::wire::pb;
    use pushlearn::wire::pb::learner as lp;
    use pushlearn::wire::MAX_ACTION_SPEED;

    use super::*;

    fn frame(seq: u64, call: Call) -> Vec<u8> {
        encode_frame(&Request {
            seq,
            call: Some(call),
        })
        .unwrap()
        .to_vec()
    }

    fn start() -> Vec<u8> {
        frame(
            1,
            Call::Start(lp::Start {
                protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
                task: "push-task".into(),
                publish_rate_hz: 100,
            }),
        )
    }

    fn observed(x: f64) -> lp::StateRef {
        let body = |name: &str, id: u32, x: f64, y: f64| pb::ModelState {
            name: name.into(),
            id,
            pose: Some(pb::Pose::from_position_yaw([x, y, 0.05], 0.0)),
            ..pb::ModelState::default()
        };
        lp::StateRef {
            state: Some(lp::state_ref::State::Observed(lp::State {
                bodies: vec![
                    body("actuator", 8, x, -0.5),
                    body("blockA", BLUE_ID, 0.0, -0.3),
                ],
                shapes: vec![pb::Shape::of_body(
                    "blockA",
                    learner::BodyShape::Box {
                        size: [0.5, 0.1, 0.1],
                    },
                )],
            })),
        }
    }

    fn predict(seq: u64, vy: f64) -> Vec<u8> {
        frame(
            seq,
            Call::Predict(lp::Predict {
                from: Some(observed(0.0)),
                action: Some(lp::Action {
                    vx: Some(0.0),
                    vy: Some(vy),
                }),
            }),
        )
    }

    #[test]
    fn a_well_behaved_driver_gets_one_answer_per_answered_call() {
        let mut bytes = start();
        bytes.extend(predict(2, 0.5));
        bytes.extend(frame(3, Call::Act(lp::Act {})));
        bytes.extend(frame(4, Call::GetStats(lp::GetStats {})));
        bytes.extend(frame(5, Call::Bye(lp::Bye {})));
        for kind in [ModelKind::Gate, ModelKind::Interaction, ModelKind::GatePlus] {
            let served = serve_untrusted_requests(kind, &bytes).unwrap();
            assert_eq!(
                served,
                Served {
                    requests: 5,
                    replies: 4,
                    ended: None
                },
                "{kind}"
            );
        }
    }

    #[test]
    fn a_non_finite_action_is_refused_with_an_error_naming_it() {
        let mut bytes = start();
        bytes.extend(predict(2, f64::NAN));
        let served = serve_untrusted_requests(ModelKind::Gate, &bytes).unwrap();
        assert_eq!(served.replies, 2);
        let ended = served.ended.unwrap();
        assert!(
            ended.contains("message 2") && ended.contains("not finite"),
            "{ended}"
        );
    }

    /// Found by the `learner_requests` fuzz target: a block at x = −1.9e296
    /// (finite) in one state, back at 0 in the next, made the gate model
    /// predict NaN. Such a state is refused.
    #[test]
    fn a_state_outside_any_world_is_refused_with_an_error_naming_it() {
        let mut far = observed(0.0);
        if let Some(lp::state_ref::State::Observed(state)) = &mut far.state {
            state.bodies[1].pose = Some(pb::Pose::from_position_yaw([-1.9e296, 0.25, 0.05], 0.0));
        }
        let mut bytes = start();
        bytes.extend(frame(
            2,
            Call::Update(lp::Update {
                state: Some(far),
                action: Some(lp::Action {
                    vx: Some(0.0),
                    vy: Some(0.5),
                }),
            }),
        ));
        let served = serve_untrusted_requests(ModelKind::Gate, &bytes).unwrap();
        let ended = served.ended.unwrap();
        assert!(
            ended.contains("message 2")
                && ended.contains("'blockA' position.x")
                && ended.contains("outside any world"),
            "{ended}"
        );
    }

    /// A shape no world can have, a shape of a body the state does not
    /// list, or two shapes of one body are refused naming the body: a
    /// model that reads shapes must not silently fall back on its table.
    #[test]
    fn a_state_with_a_shape_no_world_has_is_refused_naming_the_body() {
        let bad = |shapes: Vec<pb::Shape>| {
            let mut state = observed(0.0);
            if let Some(lp::state_ref::State::Observed(observed)) = &mut state.state {
                observed.shapes = shapes;
            }
            let mut bytes = start();
            bytes.extend(frame(
                2,
                Call::Update(lp::Update {
                    state: Some(state),
                    action: Some(lp::Action {
                        vx: Some(0.0),
                        vy: Some(0.5),
                    }),
                }),
            ));
            serve_untrusted_requests(ModelKind::Hybrid, &bytes)
                .unwrap()
                .ended
                .unwrap_or_default()
        };
        let sphere = |name: &str, radius: f64| pb::Shape {
            name: name.into(),
            geometry: Some(pb::shape::Geometry::SphereRadius(radius)),
        };
        for (shapes, expected) in [
            (vec![sphere("blockA", -0.1)], "shape of body 'blockA'"),
            (vec![sphere("blockA", f64::NAN)], "shape of body 'blockA'"),
            (
                vec![pb::Shape {
                    name: "blockA".into(),
                    geometry: None,
                }],
                "shape of body 'blockA'",
            ),
            (vec![sphere("ghost", 0.1)], "body 'ghost', which the state"),
            (
                vec![sphere("blockA", 0.1), sphere("blockA", 0.2)],
                "two shapes for body 'blockA'",
            ),
        ] {
            let ended = bad(shapes);
            assert!(
                ended.contains("message 2") && ended.contains(expected),
                "{expected}: {ended}"
            );
        }
        assert_eq!(bad(vec![sphere("blockA", 0.1)]), "");
    }

    /// A body the learner uses, published without a pose (or half of one),
    /// is refused naming it, with the in-process driver's own parse error:
    /// `pushlearn serve-learner` once read a missing pose as zeros and
    /// trained on a made-up body at the origin.
    #[test]
    fn a_state_with_a_missing_pose_is_refused_naming_the_body_as_in_process() {
        let half = pb::Pose {
            position: Some(pb::Vector3d::new(0.0, -0.3, 0.05)),
            orientation: None,
        };
        for (name, pose) in [("actuator", None), ("blockA", None), ("blockA", Some(half))] {
            let mut missing = observed(0.0);
            let Some(lp::state_ref::State::Observed(state)) = &mut missing.state else {
                unreachable!("observed() sends a state")
            };
            let body = state.bodies.iter_mut().find(|b| b.name == name).unwrap();
            body.pose = pose;
            let in_process = learner::features::parse_frame(
                &crate::frame::frame_from_state(
                    &pb::WorldState {
                        model_v: Some(pb::ModelStateV {
                            models: state.bodies.clone(),
                        }),
                        ..pb::WorldState::default()
                    },
                    &crate::frame::Shapes::default(),
                ),
                learner::features::ActuatorYaw::ForceZero,
            )
            .unwrap_err()
            .to_string();
            assert!(in_process.contains(&format!("{name:?}")), "{in_process}");

            let mut bytes = start();
            bytes.extend(frame(
                2,
                Call::Update(lp::Update {
                    state: Some(missing),
                    action: Some(lp::Action {
                        vx: Some(0.0),
                        vy: Some(0.5),
                    }),
                }),
            ));
            for kind in [ModelKind::Gate, ModelKind::Interaction] {
                let served = serve_untrusted_requests(kind, &bytes).unwrap();
                let ended = served.ended.unwrap_or_default();
                assert!(
                    ended.contains("message 2") && ended.ends_with(&in_process),
                    "{kind} {name} {pose:?}: {ended}"
                );
            }
        }
    }

    /// Found by the `learner_requests` fuzz target: gate+ (which learns
    /// the actuator's response) trained on an action of −7.4e283 m/s
    /// predicted NaN. Such an action is refused.
    #[test]
    fn an_action_faster_than_any_world_drives_is_refused() {
        let mut bytes = start();
        bytes.extend(predict(2, -7.4e283));
        let served = serve_untrusted_requests(ModelKind::GatePlus, &bytes).unwrap();
        let ended = served.ended.unwrap();
        assert!(
            ended.contains("message 2") && ended.contains("faster"),
            "{ended}"
        );
        let mut bytes = start();
        bytes.extend(predict(2, -MAX_ACTION_SPEED));
        let served = serve_untrusted_requests(ModelKind::GatePlus, &bytes).unwrap();
        assert_eq!(served.ended, None);
    }

    #[test]
    fn a_model_that_cannot_be_built_is_refused_in_an_error_reply_to_the_start() {
        let options = ModelOptions {
            selector: learner::interaction::SelectorKind::Tree,
            ..ModelOptions::default()
        };
        let mut output = Vec::new();
        let err = serve_driver(
            ModelKind::Gate,
            &options,
            Requests::new(start().as_slice()),
            &mut output,
        )
        .unwrap_err();
        assert!(err.to_string().contains("--selector"), "{err}");
        let (replies, None) = decode_stream::<Reply>(&output) else {
            panic!("the refusal is not a whole frame");
        };
        assert!(
            matches!(&replies[..], [Reply { seq: 1, answer: Some(Answer::Error(e)) }]
                if e.message == "cannot serve the gate model at 100 Hz: --selector does not apply to the gate model"),
            "{replies:?}"
        );
    }

    #[test]
    fn the_driver_accepts_only_predictions_of_the_world_it_asked_about() {
        let body = |id, x: f64| lp::BodyPose {
            id,
            x: Some(x),
            y: Some(0.0),
            theta: Some(0.0),
        };
        let reply = |bodies| Reply {
            seq: 2,
            answer: Some(Answer::Prediction(lp::Prediction { bodies })),
        };
        let bytes = |r: Reply| encode_frame(&r).unwrap().to_vec();
        let good = bytes(reply(vec![body(8, 0.0), body(BLUE_ID, 0.1)]));
        assert_eq!(read_untrusted_replies(&good), Ok(1));
        for bad in [
            vec![body(8, f64::INFINITY), body(BLUE_ID, 0.1)],
            vec![body(8, 0.0)],
            vec![body(8, 0.0), body(BLUE_ID, 0.1), body(BLUE_ID, 0.2)],
            vec![body(8, 0.0), body(BLUE_ID, 0.1), body(99, 0.2)],
        ] {
            assert_eq!(read_untrusted_replies(&bytes(reply(bad))), Ok(0));
        }
    }

    /// The fuzz targets' kept inputs, through their properties. Each target
    /// must have some: an emptied folder fails instead of passing.
    #[test]
    fn the_fuzzers_kept_learner_protocol_inputs_keep_their_properties() {
        let requests = sim_plugin::untrusted::kept_fuzz_inputs("learner_requests");
        assert!(requests.len() >= 5, "{} kept inputs", requests.len());
        for (path, bytes) in requests {
            let (kind, rest) = model_for_input(&bytes);
            let served = serve_untrusted_requests(kind, rest);
            assert!(served.is_ok(), "{}: {served:?}", path.display());
        }
        let replies = sim_plugin::untrusted::kept_fuzz_inputs("learner_replies");
        assert!(replies.len() >= 5, "{} kept inputs", replies.len());
        for (path, bytes) in replies {
            let read = read_untrusted_replies(&bytes);
            assert!(read.is_ok(), "{}: {read:?}", path.display());
        }
    }

    proptest! {
        #[test]
        fn any_bytes_after_a_start_are_served_safely(
            pick in 0_u8..3,
            tail in proptest::collection::vec(any::<u8>(), 0..256),
        ) {
            let mut bytes = start();
            bytes.extend(tail);
            let (kind, _) = model_for_input(&[pick]);
            let served = serve_untrusted_requests(kind, &bytes);
            prop_assert!(served.is_ok(), "{served:?}");
        }

        #[test]
        fn any_bytes_read_as_a_learner_s_output_are_safe(
            bytes in proptest::collection::vec(any::<u8>(), 0..256),
        ) {
            let read = read_untrusted_replies(&bytes);
            prop_assert!(read.is_ok(), "{read:?}");
        }
    }
}
