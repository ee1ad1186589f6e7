//! One client's bytes, as the world daemon decodes, checks and applies them
//! (`sim_plugin::untrusted`): no input may crash it, stop its
//! physics, or make it publish a non-finite state.
#![no_main]

use std::cell::RefCell;

use libfuzzer_sys::fuzz_target;
use sim_plugin::untrusted::Harness;
use sim_plugin::Scene;

thread_local! {
    // One world for all inputs, as a daemon serves many clients: state left
    // by earlier inputs is part of what is explored.
    static HARNESS: RefCell<Option<Harness>> = const { RefCell::new(None) };
}

fuzz_target!(|bytes: &[u8]| {
    HARNESS.with(|cell| {
        let mut cell = cell.borrow_mut();
        let harness = cell.get_or_insert_with(|| {
            let scene = Scene::builtin("one_block").expect("built-in scene");
            Harness::new(scene).expect("world")
        });
        if let Err(fault) = harness.handle_untrusted_bytes(bytes) {
            panic!("{fault}");
        }
    });
});
