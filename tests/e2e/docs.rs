//! `docs/protocol.md` must stay true: its hex examples are checked against the
//! real encoder and its schema listing against `proto/pushlearn.proto`.

use pushlearn::wire::encode_frame;
use pushlearn::wire::pb::{ClientMessage, ServerMessage};

fn read(relative: &str) -> String {
    let path = crate::process::repo_root().join(relative);
    std::fs::read_to_string(&path)
        .unwrap_or_else(|err| panic!("cannot read {}: {err}", path.display()))
}

/// Lowercase hex, 16 bytes per line, as printed in the document.
fn hex_dump(bytes: &[u8]) -> String {
    bytes
        .chunks(16)
        .map(|line| {
            line.iter()
                .map(|b| format!("{b:02x}"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn hex_examples_match_the_encoder() {
    let doc = read("docs/protocol.md");
    let examples = [
        (
            "Move(0, 0.5) with seq 1",
            encode_frame(&ClientMessage::move_(1, 0.0, 0.5)),
        ),
        ("Reset with seq 2", encode_frame(&ClientMessage::reset(2))),
        (
            "barrier with seq 3",
            encode_frame(&ClientMessage::barrier(3)),
        ),
        (
            "Error answering seq 7",
            encode_frame(&ServerMessage::error(
                7,
                pushlearn::wire::pb::error::Kind::InvalidCommand,
                "advance: the world is paused; unpause it first",
            )),
        ),
    ];
    for (name, frame) in examples {
        let dump = hex_dump(&frame.expect("encodable"));
        assert!(
            doc.contains(&dump),
            "docs/protocol.md lacks the frame for {name}:\n{dump}"
        );
    }
}

#[test]
fn schema_listing_is_the_proto_file() {
    let doc = read("docs/protocol.md");
    let proto = read("proto/pushlearn.proto");
    let schema = proto
        .find("syntax = ")
        .map(|start| &proto[start..])
        .unwrap_or_default();
    assert!(
        !schema.is_empty(),
        "proto/pushlearn.proto has no syntax line"
    );
    assert!(
        doc.contains(schema),
        "docs/protocol.md must list proto/pushlearn.proto from `syntax` to the end"
    );
}

/// Every hex example of a page: the leading two-digit hex tokens of each
/// line of a ```text block, or an inline code span, that starts with a
/// length prefix (`00 00`).
fn hex_examples(doc: &str) -> Vec<Vec<u8>> {
    let byte = |t: &str| {
        (t.len() == 2)
            .then(|| u8::from_str_radix(t, 16).ok())
            .flatten()
    };
    let leading = |line: &str| -> Vec<u8> { line.split_whitespace().map_while(byte).collect() };
    let mut examples = Vec::new();
    let mut block: Option<Vec<u8>> = None;
    for line in doc.lines() {
        match (&mut block, line.trim()) {
            (None, "```text") => block = Some(Vec::new()),
            (Some(bytes), "```") => {
                if bytes.starts_with(&[0, 0]) {
                    examples.push(std::mem::take(bytes));
                }
                block = None;
            }
            (Some(bytes), text) => bytes.extend(leading(text)),
            (None, text) => {
                for span in text.split('`').skip(1).step_by(2) {
                    let bytes = leading(span);
                    if bytes.starts_with(&[0, 0]) && bytes.len() > 4 {
                        examples.push(bytes);
                    }
                }
            }
        }
    }
    examples
}

#[test]
fn learner_protocol_examples_are_real_frames() {
    use prost::Message;
    use pushlearn::wire::pb::{learner as lp, Pose, Quaternion, Vector3d};
    let doc = read("docs/learner-protocol.md");
    let examples = hex_examples(&doc);
    let action = Some(lp::Action {
        vx: Some(0.0),
        vy: Some(0.5),
    });
    let request = |seq, call| lp::Request {
        seq,
        call: Some(call),
    };
    let actuator = pushlearn::wire::pb::ModelState {
        name: "actuator".into(),
        id: 8,
        pose: Some(Pose {
            position: Some(Vector3d::new(0.1, 0.0, 0.03)),
            orientation: Some(Quaternion {
                w: 1.0,
                ..Quaternion::default()
            }),
        }),
        ..Default::default()
    };
    let recent = |r: lp::Recent| {
        Some(lp::StateRef {
            state: Some(lp::state_ref::State::Recent(r as i32)),
        })
    };
    use lp::request::Call;
    let requests = [
        request(
            1,
            Call::Start(lp::Start {
                protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
                task: "push-task".into(),
                publish_rate_hz: 100,
            }),
        ),
        request(2, Call::NewFold(lp::NewFold { seed: 7 })),
        request(
            3,
            Call::Reset(lp::Reset {
                state: Some(lp::StateRef {
                    state: Some(lp::state_ref::State::Observed(lp::State {
                        bodies: vec![actuator],
                    })),
                }),
            }),
        ),
        request(
            4,
            Call::Update(lp::Update {
                state: recent(lp::Recent::LastPrediction),
                action,
            }),
        ),
        request(
            5,
            Call::Predict(lp::Predict {
                from: recent(lp::Recent::LastObserved),
                action,
            }),
        ),
    ];
    use lp::reply::Answer;
    let replies = [
        lp::Reply {
            seq: 1,
            answer: Some(Answer::Hello(lp::Hello {
                protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
                name: "knn".into(),
                version: "0.1".into(),
                capabilities: vec![lp::Capability::Forward as i32],
                ignores_actuator_yaw: false,
            })),
        },
        lp::Reply {
            seq: 5,
            answer: Some(Answer::Prediction(lp::Prediction {
                bodies: vec![lp::BodyPose {
                    id: 8,
                    x: Some(0.1),
                    y: Some(0.005),
                    theta: Some(0.0),
                }],
            })),
        },
        lp::Reply {
            seq: 4,
            answer: Some(Answer::Error(lp::Error {
                message: "ValueError: k".into(),
            })),
        },
    ];
    let frames: Vec<Vec<u8>> = requests
        .iter()
        .map(|r| encode_frame(r).expect("encodes").to_vec())
        .chain(
            replies
                .iter()
                .map(|r| encode_frame(r).expect("encodes").to_vec()),
        )
        .collect();
    for frame in &frames {
        assert!(
            examples.contains(frame),
            "docs/learner-protocol.md lacks the frame\n{}",
            hex_dump(frame)
        );
    }
    // And nothing else: every example is one of them.
    for example in &examples {
        assert!(
            frames.contains(example),
            "docs/learner-protocol.md has an example the encoder does not make:\n{}",
            hex_dump(example)
        );
        let body = &example[4..];
        assert!(lp::Request::decode(body).is_ok() || lp::Reply::decode(body).is_ok());
    }
}
