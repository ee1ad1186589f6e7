//! One driver's bytes, as a learner daemon (`pushlearn serve-learner
//! --listen`) reads and serves them with a built-in model
//! (`pushlearn_cli::external::untrusted`): no input may crash it, and what
//! it writes back is whole replies, each to a request that was sent, with
//! finite numbers.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pushlearn_cli::external::untrusted::{model_for_input, serve_untrusted_requests};

fuzz_target!(|bytes: &[u8]| {
    let (kind, requests) = model_for_input(bytes);
    if let Err(broken) = serve_untrusted_requests(kind, requests) {
        panic!("{broken}");
    }
});
