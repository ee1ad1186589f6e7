//! One browser connection's bytes, as `pushlearn view` reads them
//! (`pushlearn_cli::view::untrusted`): the request head, and after a
//! WebSocket handshake the tab's frames. Every answer is a whole response
//! (or none), and no message above the cap reaches the tab's handling.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pushlearn_cli::view::untrusted::serve_untrusted_bytes;

fuzz_target!(|bytes: &[u8]| {
    if let Err(broken) = serve_untrusted_bytes(bytes) {
        panic!("{broken}");
    }
});
