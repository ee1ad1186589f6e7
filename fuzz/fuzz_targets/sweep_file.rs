//! A sweep file as `pushlearn sweep plan` reads it
//! (`pushlearn_cli::sweep::Sweep::parse`): refused with an error, or planned
//! into as many jobs as it says, each id once; never a panic or an
//! allocation that a few lines of TOML blow up.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pushlearn_cli::sweep::Sweep;

/// The options of `pushlearn experiment push-task` a sweep may set (the
/// parser takes the list from the command; any names serve here).
const KNOWN: [&str; 8] = [
    "model", "eta", "selector", "flag", "variant", "mode", "learner", "no-reuse",
];

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let known: Vec<String> = KNOWN.map(String::from).to_vec();
    if let Ok(sweep) = Sweep::parse(text, &known) {
        let jobs = sweep.jobs();
        assert_eq!(jobs.len(), sweep.len());
        assert!(!jobs.is_empty());
        let mut ids: Vec<&str> = jobs.iter().map(|j| j.id.as_str()).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), jobs.len());
    }
});
