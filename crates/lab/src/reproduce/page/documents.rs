//! One document's command and terminal report, and every experiment's
//! stand-alone command.

use std::fmt::Write as _;

use super::entry_of;
use crate::reproduce::{Reproduction, RESULTS_DIR};

pub(super) fn report(results: &Reproduction, name: &str) -> Result<String, String> {
    let entry = entry_of(results, name)?;
    let document = results
        .document(name)
        .ok_or_else(|| format!("no document `{name}`"))?;
    let mut text = Vec::new();
    document
        .write_tables(&mut text)
        .map_err(|e| format!("cannot render `{name}`: {e}"))?;
    let text = String::from_utf8_lossy(&text);
    Ok(format!(
        "```sh\n{}\n```\n\n```\n{}```\n",
        entry.command(RESULTS_DIR),
        text
    ))
}

pub(super) fn commands(results: &Reproduction) -> String {
    let mut out = String::from("```sh\n");
    for p in &results.produced {
        let _ = writeln!(out, "{}", p.entry.command(RESULTS_DIR));
    }
    for swept in &results.sweeps {
        let _ = writeln!(out, "{}", swept.entry.command());
    }
    out.push_str("```\n");
    out
}
