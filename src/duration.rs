//! Durations given on a command line as a decimal number of seconds (`5`,
//! `0.25`, `1e-3`), for every binary's `--… SECONDS` option: what Rust's
//! `f64` parser accepts, as long as it is a duration (not negative, finite,
//! within [`Duration`]'s range).
//!
//! The error only says what is wrong; each option words its own message,
//! since the flags' help and error texts predate this module.

use std::time::Duration;

/// Why a text is not a duration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SecondsError {
    #[error("not a number")]
    NotANumber,
    /// Negative, infinite, NaN or beyond [`Duration::MAX`].
    #[error("not a duration")]
    OutOfRange,
    #[error("zero")]
    Zero,
}

/// A duration of zero or more seconds.
///
/// # Errors
/// `text` is not an `f64`, or not a representable duration.
pub fn parse_seconds(text: &str) -> Result<Duration, SecondsError> {
    let seconds: f64 = text.parse().map_err(|_| SecondsError::NotANumber)?;
    Duration::try_from_secs_f64(seconds).map_err(|_| SecondsError::OutOfRange)
}

/// A duration of more than zero seconds.
///
/// # Errors
/// As [`parse_seconds`], and zero.
pub fn parse_positive_seconds(text: &str) -> Result<Duration, SecondsError> {
    let duration = parse_seconds(text)?;
    if duration.is_zero() {
        Err(SecondsError::Zero)
    } else {
        Ok(duration)
    }
}

/// `d` as people read it: `10 s`, `0.25 s`.
#[must_use]
pub fn describe(d: Duration) -> String {
    format!("{} s", d.as_secs_f64())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_seconds_are_durations() {
        assert_eq!(parse_seconds("5"), Ok(Duration::from_secs(5)));
        assert_eq!(parse_seconds("0.25"), Ok(Duration::from_millis(250)));
        assert_eq!(parse_seconds("1e-3"), Ok(Duration::from_millis(1)));
        assert_eq!(parse_seconds("+2"), Ok(Duration::from_secs(2)));
        assert_eq!(parse_seconds("0"), Ok(Duration::ZERO));
        assert_eq!(parse_positive_seconds("60"), Ok(Duration::from_secs(60)));
    }

    #[test]
    fn everything_else_is_refused_with_its_reason() {
        for text in ["", "5s", " 5", "five", "1,5"] {
            assert_eq!(
                parse_seconds(text),
                Err(SecondsError::NotANumber),
                "{text:?}"
            );
        }
        for text in ["-1", "inf", "NaN", "1e300"] {
            assert_eq!(
                parse_seconds(text),
                Err(SecondsError::OutOfRange),
                "{text:?}"
            );
            assert_eq!(
                parse_positive_seconds(text),
                Err(SecondsError::OutOfRange),
                "{text:?}"
            );
        }
        assert_eq!(parse_positive_seconds("0"), Err(SecondsError::Zero));
        assert_eq!(parse_positive_seconds("0.0"), Err(SecondsError::Zero));
        assert_eq!(parse_positive_seconds("x"), Err(SecondsError::NotANumber));
    }
}
