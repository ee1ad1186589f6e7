//! A learner's output, as the experiment driver reads it
//! (`pushlearn_cli::external::untrusted`): decoded frame by frame and each
//! answer checked; nothing the checks accept breaks what they promise.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pushlearn_cli::external::untrusted::read_untrusted_replies;

fuzz_target!(|bytes: &[u8]| {
    if let Err(broken) = read_untrusted_replies(bytes) {
        panic!("{broken}");
    }
});
