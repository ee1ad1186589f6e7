//! A recording file, as `pushlearn-sim replay FILE` reads and replays it
//! (`sim_plugin::untrusted::load_untrusted_recording`): refused, or
//! read without losing or inventing anything and played back.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sim_plugin::untrusted::load_untrusted_recording;

fuzz_target!(|bytes: &[u8]| {
    if let Err(fault) = load_untrusted_recording(bytes) {
        panic!("{fault}");
    }
});
