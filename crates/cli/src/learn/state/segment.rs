//! The journal's files: `DIR/log-S` (20 digits) holds the records `S+1,
//! S+2, …`.

use std::fs::{self, File};
use std::path::{Path, PathBuf};

use super::storage::{Storage, StorageFile};
use super::{io_error, StateError};

const SEGMENT_PREFIX: &str = "log-";

fn segment_name(start: u64) -> String {
    format!("{SEGMENT_PREFIX}{start:020}")
}

/// The journal segments in `dir`, by start.
pub(super) fn segments(dir: &Path) -> Result<Vec<(u64, PathBuf)>, StateError> {
    let mut out = Vec::new();
    for entry in fs::read_dir(dir).map_err(io_error(dir))? {
        let entry = entry.map_err(io_error(dir))?;
        let name = entry.file_name();
        let Some(start) = name
            .to_str()
            .and_then(|n| n.strip_prefix(SEGMENT_PREFIX))
            .and_then(|n| n.parse().ok())
        else {
            continue;
        };
        out.push((start, entry.path()));
    }
    out.sort();
    Ok(out)
}

pub(super) fn sync_dir(dir: &Path) -> Result<(), StateError> {
    File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(io_error(dir))
}

/// Creates the segment of the records after `start` (empty).
pub(super) fn open_segment(
    storage: &dyn Storage,
    dir: &Path,
    start: u64,
) -> Result<(Box<dyn StorageFile>, PathBuf), StateError> {
    let path = dir.join(segment_name(start));
    let file = storage.create(&path).map_err(io_error(&path))?;
    sync_dir(dir)?;
    Ok((file, path))
}
