//! What the experiments report, rendered from the documents of
//! [`crate::results`]: pretty JSON ([`write_json`]), the terminal tables in
//! the thesis's layout beside the thesis's numbers ([`table`],
//! [`reference`], [`draft`]) and the figures ([`plot`]).

pub mod draft;
pub mod plot;
pub mod reference;
pub mod table;

use serde::Serialize;

/// Writes `report` as pretty JSON to `path`.
///
/// # Errors
/// The file cannot be written.
pub fn write_json<T: Serialize>(path: &std::path::Path, report: &T) -> std::io::Result<()> {
    let mut text = serde_json::to_string_pretty(report).map_err(std::io::Error::other)?;
    text.push('\n');
    std::fs::write(path, text)
}
