//! The memory-based learners pushlearn's models are built from, each usable
//! on its own (`docs/models.md`):
//!
//! * [`aitm`]: the Adapted Instantaneous Topological Map (`docs/spec/aitm.md`),
//!   the one memory-based regressor/classifier of both learners;
//! * [`aim`]: the Averaging Inverse Model (`docs/spec/inverse-model.md`);
//! * [`tree`]: the decision trees of the thesis draft's AC selector.
//!
//! Pure and deterministic like the models (no I/O, no global state), and
//! depending on no crate of ours: they know nothing of bodies, frames or
//! features, only of vectors. The models' crate re-exports them
//! (`memories::aitm`, `memories::aim`, `memories::tree`).

pub mod aim;
pub mod aitm;
pub mod tree;
