//! Figures of the report documents, each written as PNG and SVG: learning
//! curves with error bars beside the thesis's (`docs/spec/reference-results.md` §3.2,
//! §3.4), per-position errors (§5, §6), top-down snapshots of actual versus
//! predicted end configurations (predicted bodies translucent, as in the
//! thesis's figures), constant-feedback errors per message (§7) and Move to
//! Target errors over steps with the final block poses (§8).
//!
//! Every entry point is a pure function from a report to files in a
//! directory; it returns the paths it wrote. Text is laid out with the
//! DejaVu Sans font embedded in the binary (`assets/fonts/`), so no system
//! font library is needed.
//!
//! * [`draw`]: the font, writing PNG and SVG, colours, axis ranges, and the
//!   panels of points with error bars that most figures are made of; the
//!   tools' own figures use it too (the soak's, `crate::soak::figure`, and
//!   the ablation sweep's, `crate::sweep::figure`), beside what they draw;
//! * `curves`, `positions`, `snapshots`: the push-task figures ([`push`]);
//! * `feedback`, `move_to_target`: those experiments' figures;
//! * `cost`, `scaling`: the performance figures of `docs/performance.md`.

mod cost;
mod curves;
pub mod draw;
mod feedback;
mod learners;
mod move_to_target;
mod positions;
mod push;
mod scaling;
mod snapshots;
#[cfg(test)]
mod test_support;

use std::path::PathBuf;

pub use cost::{cost_csv, cost_growth, CostPoint};
pub use feedback::feedback;
pub use learners::{by_condition, learners};
pub use move_to_target::move_to_target;
pub use push::push;
pub use scaling::{aitm_scaling, parse_scaling_csv, ScalingRow};
pub use snapshots::{footprints, Footprint};

/// What can go wrong while writing figures.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The output directory cannot be created.
    #[error("cannot create the figure directory {path}: {source}")]
    Dir {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The embedded font or scene cannot be read (a broken build).
    #[error("embedded {what} unusable: {reason}")]
    Embedded { what: &'static str, reason: String },
    /// Drawing or writing one figure failed.
    #[error("cannot write the figure {path}: {reason}")]
    Draw { path: PathBuf, reason: String },
    /// A line of a measurement table does not parse.
    #[error("line {line} of the measurements: {reason}")]
    Table { line: usize, reason: String },
    /// The document's model is unknown, so are the thesis's numbers to
    /// draw beside it.
    #[error(transparent)]
    Model(#[from] drive::results::UnknownModel),
}
