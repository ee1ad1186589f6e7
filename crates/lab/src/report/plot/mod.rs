//! The figures' toolkit, each figure written as PNG and SVG. The
//! experiments' own figures live with them (`crate::experiments`); here
//! are what they are drawn with and the figures of no one experiment.
//!
//! Every entry point is a pure function from a report to files in a
//! directory; it returns the paths it wrote. Text is laid out with the
//! DejaVu Sans font embedded in the binary (`assets/fonts/`), so no system
//! font library is needed.
//!
//! * [`draw`]: the font, writing PNG and SVG, colours, axis ranges, and the
//!   panels of points with error bars that most figures are made of; the
//!   tools' own figures use it too (the soak's, `pushlearn_cli::soak::figure`, and
//!   the ablation sweep's, `crate::sweep::figure`), beside what they draw;
//! * `snapshots`: top-down snapshots of actual versus predicted end
//!   configurations (predicted bodies translucent, as in the thesis's
//!   figures), for the push task's and Move to Target's figures;
//! * `learners`: several learners' curves side by side (the results page);
//! * `cost`, `scaling`: the performance figures of `docs/performance.md`.

mod cost;
pub mod draw;
mod learners;
mod scaling;
pub(crate) mod snapshots;
#[cfg(test)]
pub(crate) mod test_support;

use std::path::PathBuf;

pub use cost::{cost_csv, cost_growth, CostPoint};
pub use learners::{by_condition, learners};
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
