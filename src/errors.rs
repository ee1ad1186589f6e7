//! How every pushlearn binary reports a failure and colours its logs, so
//! that `pushlearn` and `pushlearn-sim` speak alike: `error: …` with one
//! `caused by: …` line per cause that the lines above do not already say,
//! exit status 1 (clap's usage errors exit with 2).

use std::error::Error;
use std::io::IsTerminal;

/// The report of `err`: `error: <message>`, then `  caused by: <cause>` for
/// each cause in its chain whose text is not already part of the line
/// before it (a message that embeds its source, as many do, is not
/// repeated by the source itself).
#[must_use]
pub fn describe(err: &(dyn Error + 'static)) -> String {
    let mut out = format!("error: {err}");
    let mut said = err.to_string();
    let mut cause = err.source();
    while let Some(source) = cause {
        let text = source.to_string();
        if !said.contains(&text) {
            out.push_str("\n  caused by: ");
            out.push_str(&text);
        }
        said = text;
        cause = source.source();
    }
    out
}

/// Whether log lines on stderr may carry colour codes: only on a terminal,
/// and never when `NO_COLOR` is set (<https://no-color.org>).
#[must_use]
pub fn colours() -> bool {
    std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty()) && std::io::stderr().is_terminal()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    enum Failure {
        #[error("cannot read scene file s.toml: {0}")]
        Embeds(#[source] std::io::Error),
        #[error("cannot load the scene")]
        Wraps(#[source] std::io::Error),
        #[error("cannot start")]
        Outer(#[source] Box<Failure>),
    }

    fn missing() -> std::io::Error {
        std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory")
    }

    #[test]
    fn a_cause_already_in_the_message_is_not_repeated() {
        assert_eq!(
            describe(&Failure::Embeds(missing())),
            "error: cannot read scene file s.toml: No such file or directory"
        );
    }

    #[test]
    fn every_other_cause_gets_its_own_line() {
        assert_eq!(
            describe(&Failure::Outer(Box::new(Failure::Wraps(missing())))),
            "error: cannot start\n  caused by: cannot load the scene\n  caused by: No such file or directory"
        );
    }
}
