//! The world's calibration sweep (`docs/spec/world.md` §10), run as
//! `pushlearn-sim sweep --json` and kept as a document of its own.

use std::path::Path;
use std::process::Command;

use serde::{Deserialize, Serialize};

/// One start of the sweep, as `pushlearn-sim sweep --json` prints it: the
/// blue block's outcome of the push (0, 0.5) m/s from `x0` (metres,
/// radians).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationRow {
    pub x0: f64,
    /// The first message whose interval had an actuator–block contact.
    pub first_contact_message: Option<u32>,
    pub block_x: f64,
    pub block_y: f64,
    pub block_yaw: f64,
    pub translation: f64,
    pub rotation: f64,
}

/// Why the sweep did not run.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    #[error("cannot run `{command}`: {source}")]
    Spawn {
        command: String,
        #[source]
        source: std::io::Error,
    },
    #[error("`{command}` failed ({status}): {stderr}")]
    Failed {
        command: String,
        status: std::process::ExitStatus,
        stderr: String,
    },
    #[error("`{command}` printed no sweep: {source}")]
    Output {
        command: String,
        #[source]
        source: serde_json::Error,
    },
    #[error("`{command}` printed {rows} rows, the sweep has 21 starts")]
    Rows { command: String, rows: usize },
}

/// Runs the sweep on the default scene with `sim_bin`.
///
/// # Errors
/// The binary cannot run, fails, or prints something else than the sweep.
pub fn sweep(sim_bin: &Path) -> Result<Vec<CalibrationRow>, CalibrationError> {
    let command = format!("{} sweep --json", sim_bin.display());
    let output = Command::new(sim_bin)
        .args(["sweep", "--json"])
        .output()
        .map_err(|source| CalibrationError::Spawn {
            command: command.clone(),
            source,
        })?;
    if !output.status.success() {
        return Err(CalibrationError::Failed {
            command,
            status: output.status,
            stderr: String::from_utf8_lossy(&output.stderr).trim().to_owned(),
        });
    }
    let rows: Vec<CalibrationRow> =
        serde_json::from_slice(&output.stdout).map_err(|source| CalibrationError::Output {
            command: command.clone(),
            source,
        })?;
    if rows.len() != 21 {
        return Err(CalibrationError::Rows {
            command,
            rows: rows.len(),
        });
    }
    Ok(rows)
}

/// The sweep's document: pretty JSON, one trailing newline.
///
/// # Errors
/// Not expected for these types.
pub fn to_json(rows: &[CalibrationRow]) -> Result<String, serde_json::Error> {
    let mut text = serde_json::to_string_pretty(rows)?;
    text.push('\n');
    Ok(text)
}
