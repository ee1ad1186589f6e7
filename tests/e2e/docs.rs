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
