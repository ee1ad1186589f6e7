//! Scene files (`pushlearn-sim serve --scene FILE`): refused with an error
//! or simulated, never a crash or a non-finite state.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sim_plugin::untrusted::load_untrusted_scene;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(text) = std::str::from_utf8(bytes) {
        if let Err(fault) = load_untrusted_scene(text) {
            panic!("{fault}");
        }
    }
});
