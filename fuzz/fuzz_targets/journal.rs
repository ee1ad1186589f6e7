//! The learner's journal as recovery reads it after a crash
//! (`pushlearn_cli::learn::state::read_records`): damage is detected, never a
//! crash or an unbounded allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pushlearn_cli::learn::state::read_records;

fuzz_target!(|bytes: &[u8]| {
    let read = read_records(bytes);
    let end = read.records.last().map_or(0, |r| r.2);
    match read.bad {
        Some((offset, _)) => assert_eq!(offset, end),
        None => assert_eq!(end, bytes.len()),
    }
});
