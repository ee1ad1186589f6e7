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

/// The frames of `docs/learner-protocol.md` §3, "A whole conversation", in
/// order: each ```text block after a line that starts with → (the driver's
/// request, `true`) or ← (the learner's reply, `false`).
fn conversation(doc: &str) -> Vec<(bool, Vec<u8>)> {
    let section = doc
        .split("\n## ")
        .find(|s| s.starts_with("3. A whole conversation"))
        .expect("docs/learner-protocol.md has §3, A whole conversation");
    let mut frames = Vec::new();
    let mut to_learner = None;
    let mut block: Option<Vec<u8>> = None;
    for line in section.lines() {
        let line = line.trim();
        match &mut block {
            None if line == "```text" => block = Some(Vec::new()),
            None if line.starts_with('→') => to_learner = Some(true),
            None if line.starts_with('←') => to_learner = Some(false),
            None => {}
            Some(bytes) if line == "```" => {
                let direction = to_learner
                    .take()
                    .expect("every frame of the conversation follows a → or ← line");
                frames.push((direction, std::mem::take(bytes)));
                block = None;
            }
            Some(bytes) => bytes.extend(line.split_whitespace().map(|t| {
                u8::from_str_radix(t, 16).unwrap_or_else(|_| panic!("not a hex byte: {t}"))
            })),
        }
    }
    frames
}

#[test]
fn learner_protocol_examples_are_real_frames() {
    use prost::Message;
    use pushlearn::wire::pb::learner as lp;
    let doc = read("docs/learner-protocol.md");
    let examples = hex_examples(&doc);
    assert!(examples.len() > 20, "{} examples", examples.len());
    for example in &examples {
        let n = u32::from_be_bytes([example[0], example[1], example[2], example[3]]) as usize;
        assert_eq!(
            n,
            example.len() - 4,
            "a wrong length in\n{}",
            hex_dump(example)
        );
        let body = &example[4..];
        assert!(
            lp::Request::decode(body).is_ok() || lp::Reply::decode(body).is_ok(),
            "not a learner-protocol message:\n{}",
            hex_dump(example)
        );
    }
    // The Error example says what the prose says.
    let error = lp::Reply {
        seq: 5,
        answer: Some(lp::reply::Answer::Error(lp::Error {
            message: "ValueError: k".into(),
        })),
    };
    let frame = encode_frame(&error).expect("encodes").to_vec();
    assert!(
        examples.contains(&frame),
        "no Error example:\n{}",
        hex_dump(&frame)
    );
}

/// The page's conversation is a valid one: a learner that writes its ←
/// frames, run through the driver's own push-task fold, receives exactly
/// its → frames and breaks no rule.
#[test]
fn the_learner_protocol_pages_conversation_is_what_the_driver_sends_and_accepts() {
    use std::time::Duration;

    use pushlearn_cli::external::check::page_example;
    use pushlearn_cli::external::{LearnerSpec, Source};

    let doc = read("docs/learner-protocol.md");
    let frames = conversation(&doc);
    let replies: Vec<u8> = frames
        .iter()
        .filter(|(to_learner, _)| !to_learner)
        .flat_map(|(_, f)| f.clone())
        .collect();
    let requests: Vec<u8> = frames
        .iter()
        .filter(|(to_learner, _)| *to_learner)
        .flat_map(|(_, f)| f.clone())
        .collect();
    assert!(!replies.is_empty() && !requests.is_empty());
    let dir = crate::experiment::TempDir::new("page-conversation");
    std::fs::write(dir.0.join("replies.bin"), &replies).expect("write replies");
    let received = dir.0.join("received.bin");
    let spec = LearnerSpec {
        source: Source::Command(format!(
            "cat '{}'; cat > '{}'",
            dir.0.join("replies.bin").display(),
            received.display()
        )),
        timeout: Duration::from_secs(10),
    };
    page_example(&spec).expect("the driver accepts the page's replies");
    let got = std::fs::read(&received).expect("the learner saved what it received");
    assert!(
        got == requests,
        "the driver sent\n{}\nthe page says\n{}",
        hex_dump(&got),
        hex_dump(&requests)
    );
}

/// One number per fact: how long `pushlearn reproduce` or the ablation
/// sweep takes depends on the machine and on the day, and lives in one
/// place, `docs/results/timing.md`, which every run rewrites; every other
/// page links to it. A sentence of a hand-written page that speaks of the
/// reproduction or the ablation and names a duration is a copy that will
/// go stale — unless it states a target (a goal, not a measurement).
#[test]
fn only_the_generated_timing_page_names_the_reproductions_durations() {
    let root = crate::process::repo_root();
    let mut pages: Vec<std::path::PathBuf> =
        ["README.md", "python/README.md", "docs/results/template.md"]
            .iter()
            .map(|p| root.join(p))
            .collect();
    for entry in std::fs::read_dir(root.join("docs")).expect("docs/") {
        let path = entry.expect("an entry of docs/").path();
        // The page generated from the template is checked through it.
        if path.extension().is_some_and(|e| e == "md") && !path.ends_with("results.md") {
            pages.push(path);
        }
    }
    let mut copies = Vec::new();
    for page in &pages {
        let text =
            std::fs::read_to_string(page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
        for (line, sentence) in sentences(&text) {
            let lower = sentence.to_lowercase();
            let about = lower.contains("reproduce") || lower.contains("ablation");
            // A target is stated as `Target: …` (a goal, not a measurement).
            if about && !lower.contains("target:") {
                if let Some(duration) = duration_in(&sentence) {
                    copies.push(format!(
                        "{}:{line}: `{duration}`",
                        page.strip_prefix(&root).unwrap_or(page).display()
                    ));
                }
            }
        }
    }
    assert!(
        copies.is_empty(),
        "durations of the reproduction outside docs/results/timing.md (link to it instead):\n{}",
        copies.join("\n")
    );
}

/// The sentences of a page with the line each starts on: split at a full
/// stop followed by white space, and at blank lines and table rows.
fn sentences(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current = String::new();
    let mut start = 1;
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.trim_start().starts_with('|') {
            if !current.trim().is_empty() {
                out.push((start, std::mem::take(&mut current)));
            }
            current.clear();
            if line.trim_start().starts_with('|') {
                out.push((i + 1, line.to_owned()));
            }
            start = i + 2;
            continue;
        }
        if current.is_empty() {
            start = i + 1;
        }
        for word in line.split_whitespace() {
            current.push_str(word);
            current.push(' ');
            let ends = word.trim_end_matches([')', '*']).ends_with('.');
            if ends && !word.ends_with("..") && word.len() > 2 {
                out.push((start, std::mem::take(&mut current)));
                start = i + 1;
            }
        }
    }
    if !current.trim().is_empty() {
        out.push((start, current));
    }
    out
}

/// The first duration written in `text` (`884 s`, `1 348.8 s`, `15
/// minutes`, `about an hour`, `ten minutes`), if any.
fn duration_in(text: &str) -> Option<String> {
    let words: Vec<&str> = text
        .split(|c: char| c.is_whitespace() || matches!(c, '(' | ')' | ',' | ';' | ':' | '*' | '`'))
        .filter(|w| !w.is_empty())
        .collect();
    let unit = |w: &str| {
        let w = w.trim_end_matches(['.', ')']);
        matches!(
            w,
            "s" | "sec"
                | "seconds"
                | "second"
                | "min"
                | "mins"
                | "minute"
                | "minutes"
                | "h"
                | "hour"
                | "hours"
        )
    };
    let number = |w: &str| {
        (w.chars().any(|c| c.is_ascii_digit())
            && w.chars()
                .all(|c| c.is_ascii_digit() || matches!(c, '.' | '\u{a0}' | '≈' | '~')))
            || matches!(
                w.to_lowercase().as_str(),
                "an" | "half"
                    | "one"
                    | "two"
                    | "three"
                    | "five"
                    | "ten"
                    | "fifteen"
                    | "twenty"
                    | "thirty"
                    | "forty"
                    | "fifty"
                    | "sixty"
                    | "few"
                    | "several"
            )
    };
    for (i, pair) in words.windows(2).enumerate() {
        if number(pair[0]) && unit(pair[1]) {
            let start = i.saturating_sub(1);
            return Some(words[start..i + 2].join(" "));
        }
    }
    None
}
