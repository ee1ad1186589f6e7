//! What every experiment's report is made of, rendered from the documents
//! of [`drive::results`]: pretty JSON ([`write_json`]), the pieces of the
//! terminal tables in the thesis's layout ([`table`]; each table also as
//! CSV, [`layout`]), the thesis's numbers ([`reference`]) and the figures'
//! toolkit ([`plot`]). The tables and figures themselves live with their
//! experiments (`crate::experiments`).

pub mod layout;
pub mod plot;
pub mod reference;
pub mod table;

use serde::Serialize;

/// `n` and the noun, in the plural unless `n` is 1 ("1 fold", "20 folds"):
/// the tables and figures are read by people, and "1 folds" reads as a bug.
#[must_use]
pub fn plural(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// Writes `report` as pretty JSON to `path`.
///
/// # Errors
/// The file cannot be written.
pub fn write_json<T: Serialize>(path: &std::path::Path, report: &T) -> std::io::Result<()> {
    let mut text = serde_json::to_string_pretty(report).map_err(std::io::Error::other)?;
    text.push('\n');
    std::fs::write(path, text)
}

#[cfg(test)]
mod tests {
    #[test]
    fn one_of_a_thing_is_singular() {
        assert_eq!(super::plural(1, "fold"), "1 fold");
        assert_eq!(super::plural(0, "fold"), "0 folds");
        assert_eq!(super::plural(20, "training run"), "20 training runs");
    }
}
