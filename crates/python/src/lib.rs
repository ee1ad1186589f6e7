//! `pushlearn._native`: the Rust models as a Python extension module (PyO3,
//! built by maturin from the root `pyproject.toml`; the Python package around
//! it lives in `python/pushlearn/`, its type stubs in
//! `python/pushlearn/_native.pyi`).
//!
//! * `GateModel` / `GateWorld`, `InteractionModel` / `InteractionWorld`:
//!   the two learners, one method per [`learner::Model`] method
//!   (`models.rs`), configured as the command line configures them
//!   (`options.rs`);
//! * `Aitm`: the memory-based regressor and classifier (`aitm.rs`).
//!
//! Nothing here is `unsafe`: the crate inherits the workspace's
//! `unsafe_code = "forbid"` and needs no exception. The FFI stays inside pyo3
//! and numpy; the `unsafe` blocks PyO3's macros generate are spanned in the
//! macro's own code, which the lint does not flag (`docs/architecture.md`).
//!
//! Every class is `Send + Sync` (PyO3 requires it of a class that is not
//! `unsendable`), so Python may use an object from any thread. No method
//! releases the GIL, so calls on one object from several threads run one
//! after another.

mod aitm;
mod args;
mod models;
mod options;

use learner::ModelStats;
use pyo3::prelude::*;
use serde_json::to_string;

/// `stats` in their serialised form (`{maps, extra, labels}`) through
/// `serde_json` and Python's `json.loads`: plain dicts, strings and numbers.
fn stats_to_python<'py>(py: Python<'py>, stats: &ModelStats) -> PyResult<Bound<'py, PyAny>> {
    let text = to_string(stats)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("cannot serialise: {e}")))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The pushlearn models, implemented in Rust: GateModel, InteractionModel
/// (with their worlds GateWorld and InteractionWorld) and Aitm.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<models::PyGateModel>()?;
    m.add_class::<models::PyGateWorld>()?;
    m.add_class::<models::PyInteractionModel>()?;
    m.add_class::<models::PyInteractionWorld>()?;
    m.add_class::<aitm::PyAitm>()?;
    // Where the extension was built: the Gymnasium environments look for the
    // checkout's own `target/release/pushlearn-sim` after `PUSHLEARN_SIM_BIN`
    // and `PATH`, so that `pip install .` after `cargo build --release` needs
    // no further set-up.
    m.add(
        "SOURCE_CHECKOUT",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
    )?;
    Ok(())
}
