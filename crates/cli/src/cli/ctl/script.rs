//! `ctl run` scripts: one [`Action`] per line in the command-line syntax,
//! `#` comments, blank lines ignored.
//!
//! The grammar is small and fixed, so it is parsed by hand rather than through
//! clap: that gives errors with line and column, and a whole file is checked
//! (including the wire validation of every command) before anything is sent.

use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use pushlearn::wire::{pb, validate};

use super::{check_yaw, Action};

/// One script command and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// `None` for a command given on the command line.
    pub origin: Option<Origin>,
    pub action: Action,
}

/// A script line, for error messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Origin {
    pub file: PathBuf,
    pub line: usize,
    pub text: String,
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: `{}`", self.file.display(), self.line, self.text)
    }
}

/// A syntax error; line and column are 1-based, the column counts characters.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{line}:{column}: {message}")]
pub struct ParseError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// Reads and parses the script at `path`.
pub fn load(path: &Path) -> Result<Vec<Step>> {
    let source = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read script {}", path.display()))?;
    let parsed = parse(&source).map_err(|err| anyhow::anyhow!("{}:{err}", path.display()))?;
    Ok(parsed
        .into_iter()
        .map(|(line, text, action)| Step {
            origin: Some(Origin {
                file: path.to_owned(),
                line,
                text,
            }),
            action,
        })
        .collect())
}

/// The actions of `source` with their line numbers and trimmed text.
pub fn parse(source: &str) -> Result<Vec<(usize, String, Action)>, ParseError> {
    let mut steps = Vec::new();
    for (index, raw) in source.lines().enumerate() {
        let line = index + 1;
        let code = raw.split('#').next().unwrap_or_default();
        let words = words(code);
        if let Some(action) = parse_line(line, &words, code.chars().count())? {
            steps.push((line, code.trim().to_owned(), action));
        }
    }
    Ok(steps)
}

/// A whitespace-separated word and its 1-based column.
#[derive(Debug, Clone, Copy)]
struct Word<'a> {
    text: &'a str,
    column: usize,
}

fn words(code: &str) -> Vec<Word<'_>> {
    let mut words = Vec::new();
    let mut start: Option<(usize, usize)> = None; // (byte offset, column)
    for (column, (offset, ch)) in code.char_indices().enumerate() {
        match (ch.is_whitespace(), start) {
            (false, None) => start = Some((offset, column + 1)),
            (true, Some((begin, col))) => {
                words.push(Word {
                    text: &code[begin..offset],
                    column: col,
                });
                start = None;
            }
            _ => {}
        }
    }
    if let Some((begin, col)) = start {
        words.push(Word {
            text: &code[begin..],
            column: col,
        });
    }
    words
}

/// Consumes one line's words; knows the command and where the line ends.
struct Cursor<'a> {
    line: usize,
    command: &'a str,
    rest: std::slice::Iter<'a, Word<'a>>,
    end_column: usize,
}

impl<'a> Cursor<'a> {
    fn error(&self, column: usize, message: impl Into<String>) -> ParseError {
        ParseError {
            line: self.line,
            column,
            message: message.into(),
        }
    }

    fn word(&mut self, what: &str) -> Result<Word<'a>, ParseError> {
        self.rest
            .next()
            .copied()
            .ok_or_else(|| self.error(self.end_column, format!("{}: missing {what}", self.command)))
    }

    fn number<T: std::str::FromStr>(&mut self, what: &str, kind: &str) -> Result<T, ParseError> {
        let word = self.word(what)?;
        word.text.parse().map_err(|_| {
            self.error(
                word.column,
                format!(
                    "{}: {what} must be {kind}, found '{}'",
                    self.command, word.text
                ),
            )
        })
    }

    fn real(&mut self, what: &str) -> Result<f64, ParseError> {
        self.number(what, "a number")
    }

    fn finish(mut self) -> Result<(), ParseError> {
        match self.rest.next() {
            None => Ok(()),
            Some(extra) => Err(self.error(
                extra.column,
                format!("{}: unexpected argument '{}'", self.command, extra.text),
            )),
        }
    }
}

const COMMANDS: &str = "pause, unpause, reset, set-pose, move, rate, advance, watch, info";

fn parse_line(
    line: usize,
    words: &[Word<'_>],
    line_chars: usize,
) -> Result<Option<Action>, ParseError> {
    let Some((first, args)) = words.split_first() else {
        return Ok(None);
    };
    let mut cursor = Cursor {
        line,
        command: first.text,
        rest: args.iter(),
        end_column: line_chars + 1,
    };
    let action = match first.text {
        "pause" => Action::Pause,
        "unpause" => Action::Unpause,
        "reset" => Action::Reset,
        "info" => Action::Info,
        "set-pose" => Action::SetPose {
            name: cursor.word("NAME")?.text.to_owned(),
            x: cursor.real("X")?,
            y: cursor.real("Y")?,
            z: cursor.real("Z")?,
            yaw: {
                let column = cursor
                    .rest
                    .clone()
                    .next()
                    .map_or(cursor.end_column, |w| w.column);
                let yaw = cursor.real("YAW")?;
                check_yaw(yaw)
                    .map_err(|message| cursor.error(column, format!("set-pose: {message}")))?
            },
        },
        "move" => Action::Move {
            vx: cursor.real("VX")?,
            vy: cursor.real("VY")?,
        },
        "rate" => Action::Rate {
            hz: cursor.number("HZ", "a whole number of Hz")?,
        },
        "advance" => match cursor.rest.clone().next() {
            None => Action::Advance { n: 1 },
            Some(_) => Action::Advance {
                n: cursor.number("N", "a whole number")?,
            },
        },
        "watch" => {
            let flag = cursor.word("--count N (a script's watch must end)")?;
            if flag.text != "--count" {
                return Err(cursor.error(
                    flag.column,
                    format!("watch: expected --count, found '{}'", flag.text),
                ));
            }
            let count = Some(cursor.number("N", "a whole number")?);
            let mut bodies = Vec::new();
            while let Some(flag) = cursor.rest.next() {
                if flag.text != "--body" {
                    return Err(cursor.error(
                        flag.column,
                        format!("watch: expected --body, found '{}'", flag.text),
                    ));
                }
                bodies.push(cursor.word("NAME after --body")?.text.to_owned());
            }
            Action::Watch { count, bodies }
        }
        "run" => return Err(cursor.error(first.column, "run: scripts cannot run other scripts")),
        other => {
            return Err(cursor.error(
                first.column,
                format!("unknown command '{other}' (expected one of: {COMMANDS})"),
            ))
        }
    };
    cursor.finish()?;
    // The wire rules (finite numbers, rates dividing 1000, ...) are checked
    // here too, so that a bad line 10 stops the script before line 1 runs.
    if let Some(payload) = action.command_payload() {
        validate(&pb::ClientMessage::new(0, payload)).map_err(|err| ParseError {
            line,
            column: first.column,
            message: err.to_string(),
        })?;
    }
    Ok(Some(action))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn actions(source: &str) -> Vec<Action> {
        match parse(source) {
            Ok(steps) => steps.into_iter().map(|(_, _, action)| action).collect(),
            Err(err) => panic!("{source:?} failed: {err}"),
        }
    }

    fn error(source: &str) -> ParseError {
        match parse(source) {
            Ok(steps) => panic!("{source:?} parsed: {steps:?}"),
            Err(err) => err,
        }
    }

    #[test]
    fn every_command_parses() {
        let script = "\
# start of an experiment
reset
set-pose actuator 0 0 0.03 0
set-pose blockA -0.1 0.25 0.05 -1.5e-1   # rotated
move 0 0.5

rate 10
pause
unpause
advance
advance 20
watch --count 5
watch --count 2 --body blockA --body actuatorShadow
info
";
        assert_eq!(
            actions(script),
            vec![
                Action::Reset,
                Action::SetPose {
                    name: "actuator".into(),
                    x: 0.0,
                    y: 0.0,
                    z: 0.03,
                    yaw: 0.0
                },
                Action::SetPose {
                    name: "blockA".into(),
                    x: -0.1,
                    y: 0.25,
                    z: 0.05,
                    yaw: -0.15
                },
                Action::Move { vx: 0.0, vy: 0.5 },
                Action::Rate { hz: 10 },
                Action::Pause,
                Action::Unpause,
                Action::Advance { n: 1 },
                Action::Advance { n: 20 },
                Action::Watch {
                    count: Some(5),
                    bodies: Vec::new()
                },
                Action::Watch {
                    count: Some(2),
                    bodies: vec!["blockA".into(), "actuatorShadow".into()]
                },
                Action::Info,
            ]
        );
    }

    #[test]
    fn steps_keep_line_numbers_and_text() {
        let steps = parse("\n  # comment\n\tmove 0 0.5  # go\nreset").unwrap();
        let located: Vec<(usize, &str)> = steps
            .iter()
            .map(|(line, text, _)| (*line, text.as_str()))
            .collect();
        assert_eq!(located, vec![(3, "move 0 0.5"), (4, "reset")]);
    }

    #[test]
    fn unknown_command_points_at_it() {
        let err = error("reset\n   jump 1 2\n");
        assert_eq!((err.line, err.column), (2, 4));
        assert!(
            err.message.starts_with("unknown command 'jump'"),
            "{}",
            err.message
        );
    }

    #[test]
    fn bad_number_points_at_the_word() {
        let err = error("move 0 fast");
        assert_eq!((err.line, err.column), (1, 8));
        assert_eq!(err.message, "move: VY must be a number, found 'fast'");
        let err = error("rate -5");
        assert_eq!((err.line, err.column), (1, 6));
        assert!(
            err.message.starts_with("rate: HZ must be a whole number"),
            "{}",
            err.message
        );
    }

    #[test]
    fn missing_argument_points_past_the_line() {
        let err = error("set-pose blockA 0 0.25 0.05");
        assert_eq!((err.line, err.column), (1, 28));
        assert_eq!(err.message, "set-pose: missing YAW");
        let err = error("move 1 # only one");
        assert_eq!((err.line, err.column), (1, 8));
        assert_eq!(err.message, "move: missing VY");
    }

    #[test]
    fn extra_argument_is_refused() {
        let err = error("pause\nreset now");
        assert_eq!((err.line, err.column), (2, 7));
        assert_eq!(err.message, "reset: unexpected argument 'now'");
    }

    #[test]
    fn wire_rules_are_checked_at_parse_time() {
        let err = error("reset\nset-pose blockA nan 0.25 0.05 0");
        assert_eq!((err.line, err.column), (2, 1));
        assert_eq!(err.message, "set_pose: body 'blockA' position.x is NaN");
        let err = error("  rate 30");
        assert_eq!((err.line, err.column), (1, 3));
        assert!(
            err.message.contains("does not divide 1000"),
            "{}",
            err.message
        );
        let err = error("move inf 0");
        assert_eq!(err.message, "actuator: direction.x is infinite (+inf)");
    }

    #[test]
    fn watch_in_a_script_needs_a_count() {
        let err = error("watch");
        assert_eq!((err.line, err.column), (1, 6));
        assert!(
            err.message.starts_with("watch: missing --count N"),
            "{}",
            err.message
        );
        let err = error("watch 5");
        assert_eq!((err.line, err.column), (1, 7));
        assert_eq!(err.message, "watch: expected --count, found '5'");
    }

    #[test]
    fn a_yaw_too_large_to_mean_a_rotation_is_refused() {
        let err = error("set-pose blockA 0 0.25 0.05 1e300");
        assert_eq!((err.line, err.column), (1, 29));
        assert_eq!(
            err.message,
            "set-pose: yaw 1e300 rad is out of range: |yaw| must be at most 1000 rad"
        );
        assert_eq!(actions("set-pose blockA 0 0.25 0.05 -1000").len(), 1);
    }

    #[test]
    fn watch_body_needs_a_name() {
        let err = error("watch --count 1 --body");
        assert_eq!(err.message, "watch: missing NAME after --body");
        let err = error("watch --count 1 blockA");
        assert_eq!(err.message, "watch: expected --body, found 'blockA'");
    }

    #[test]
    fn scripts_cannot_nest() {
        let err = error("run other.ctl");
        assert_eq!((err.line, err.column), (1, 1));
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        let err = error("set-pose blöckA 0 0 0 x");
        assert_eq!((err.line, err.column), (1, 23));
    }

    #[test]
    fn load_names_the_file() {
        let dir =
            std::env::temp_dir().join(format!("pushlearn-script-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.ctl");
        std::fs::write(&path, "reset\nmove 0\n").unwrap();
        let message = format!("{:#}", load(&path).unwrap_err());
        assert_eq!(message, format!("{}:2:7: move: missing VY", path.display()));
        std::fs::write(&path, "reset\nmove 0 0.5\n").unwrap();
        let steps = load(&path).unwrap();
        assert_eq!(
            steps[1].origin.as_ref().map(ToString::to_string),
            Some(format!("{}:2: `move 0 0.5`", path.display()))
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
