//! The snapshot: the whole learner after a number of journal records,
//! written crash-safely and verified by a checksum on load.

use std::fs;
use std::io::{self, Write};
use std::path::Path;

use learner::Model;
use serde::{Deserialize, Serialize};

use super::record::{crc32, Cursor};
use super::segment::sync_dir;
use super::storage::{Disk, Storage};
use super::{io_error, Settings, StateError};
use crate::learn::Learner;

/// The newest snapshot's file name in the state directory.
pub const SNAPSHOT_FILE: &str = "snapshot";
/// The snapshot before it, kept (with the journal after it) for when the
/// newest is found damaged.
pub const PREVIOUS_SNAPSHOT_FILE: &str = "snapshot.prev";
/// A newest snapshot found damaged, moved aside by the next start (kept for
/// a look, never read).
pub const DAMAGED_SNAPSHOT_FILE: &str = "snapshot.damaged";
/// A snapshot being written.
const TMP_FILE: &str = "snapshot.tmp";
const SNAPSHOT_MAGIC: &[u8; 8] = b"PLSNAP01";
const FORMAT_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct SnapshotHeader {
    version: u32,
    records: u64,
    settings: Settings,
}

/// `magic | payload length u64 | CRC-32 u32 | payload`, payload =
/// `header length u32 | header JSON | learner JSON` (JSON with exact float
/// round trips, so the restored learner is bit-identical).
fn encode_snapshot<M: Model>(
    records: u64,
    settings: &Settings,
    learner: &Learner<M>,
) -> Result<Vec<u8>, serde_json::Error> {
    let header = serde_json::to_vec(&SnapshotHeader {
        version: FORMAT_VERSION,
        records,
        settings: settings.clone(),
    })?;
    let mut payload = Vec::new();
    payload.extend_from_slice(&(header.len() as u32).to_le_bytes());
    payload.extend_from_slice(&header);
    serde_json::to_writer(&mut payload, learner)?;
    let mut out = Vec::with_capacity(payload.len() + 20);
    out.extend_from_slice(SNAPSHOT_MAGIC);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32(&[&payload]).to_le_bytes());
    out.extend_from_slice(&payload);
    Ok(out)
}

pub(super) fn decode_snapshot<M: Model>(
    bytes: &[u8],
    path: &Path,
    dir: &Path,
    expected: &Settings,
) -> Result<(u64, Learner<M>), StateError> {
    let (header, learner) = decode_header(bytes, path)?;
    let differences = expected.differences(&header.settings);
    if !differences.is_empty() {
        return Err(StateError::Mismatch {
            dir: dir.to_path_buf(),
            differences: differences.join("; "),
        });
    }
    let learner = serde_json::from_slice(learner).map_err(|err| StateError::CorruptSnapshot {
        path: path.to_path_buf(),
        reason: err.to_string(),
    })?;
    Ok((header.records, learner))
}

/// The settings a snapshot was written with.
///
/// # Errors
/// A file that is no intact snapshot.
pub(super) fn stored_settings(bytes: &[u8], path: &Path) -> Result<Settings, StateError> {
    Ok(decode_header(bytes, path)?.0.settings)
}

/// The checked header and the learner's bytes.
fn decode_header<'a>(
    bytes: &'a [u8],
    path: &Path,
) -> Result<(SnapshotHeader, &'a [u8]), StateError> {
    let corrupt = |reason: &str| StateError::CorruptSnapshot {
        path: path.to_path_buf(),
        reason: reason.to_owned(),
    };
    let mut c = Cursor { bytes };
    if c.take(8) != Some(SNAPSHOT_MAGIC.as_slice()) {
        return Err(corrupt("not a pushlearn snapshot"));
    }
    let len = c
        .array::<8>()
        .map(u64::from_le_bytes)
        .ok_or_else(|| corrupt("cut off"))?;
    let crc = c.u32().ok_or_else(|| corrupt("cut off"))?;
    if c.bytes.len() as u64 != len {
        return Err(corrupt(&format!(
            "{} bytes of contents instead of {len}",
            c.bytes.len()
        )));
    }
    if crc32(&[c.bytes]) != crc {
        return Err(corrupt("checksum mismatch"));
    }
    let header_len = c.u32().ok_or_else(|| corrupt("cut off"))? as usize;
    let header = c.take(header_len).ok_or_else(|| corrupt("cut off"))?;
    let header: SnapshotHeader =
        serde_json::from_slice(header).map_err(|err| corrupt(&err.to_string()))?;
    if header.version != FORMAT_VERSION {
        return Err(corrupt(&format!(
            "format version {} (this build reads {FORMAT_VERSION})",
            header.version
        )));
    }
    Ok((header, c.bytes))
}

/// Writes the snapshot of `records` into `dir` crash-safely: `snapshot.tmp`
/// first, fsynced and read back; only once it holds exactly what was meant
/// does the current `snapshot` become `snapshot.prev` (replacing the one
/// before) and the new one `snapshot` — two renames, each atomic — and the
/// directory is fsynced so that they are durable. Until the new snapshot is
/// verified the previous two stay as they were; at every moment one intact
/// snapshot is in the directory, which recovery falls back to when the
/// newest is damaged or (between the renames) missing.
pub(super) fn write_snapshot<M: Model>(
    storage: &dyn Storage,
    dir: &Path,
    records: u64,
    settings: &Settings,
    learner: &Learner<M>,
) -> Result<(), StateError> {
    let bytes = encode(records, settings, learner)?;
    let tmp = dir.join(TMP_FILE);
    write_synced(storage, &tmp, &bytes)?;
    let back = fs::read(&tmp).map_err(io_error(&tmp))?;
    if back != bytes {
        return Err(StateError::Writer(format!(
            "{}: the snapshot reads back otherwise than it was written; the previous \
             snapshots are kept",
            tmp.display()
        )));
    }
    let newest = dir.join(SNAPSHOT_FILE);
    match fs::rename(&newest, dir.join(PREVIOUS_SNAPSHOT_FILE)) {
        Ok(()) => {}
        // The first snapshot, or the newest was damaged and moved aside.
        Err(err) if err.kind() == io::ErrorKind::NotFound => {}
        Err(err) => return Err(io_error(&newest)(err)),
    }
    fs::rename(&tmp, &newest).map_err(io_error(&newest))?;
    sync_dir(dir)
}

fn encode<M: Model>(
    records: u64,
    settings: &Settings,
    learner: &Learner<M>,
) -> Result<Vec<u8>, StateError> {
    encode_snapshot(records, settings, learner)
        .map_err(|err| StateError::Writer(format!("cannot serialise the learner: {err}")))
}

fn write_synced(storage: &dyn Storage, path: &Path, bytes: &[u8]) -> Result<(), StateError> {
    let mut file = storage.create(path).map_err(io_error(path))?;
    file.write_all(bytes).map_err(io_error(path))?;
    file.sync_all().map_err(io_error(path))
}

/// A snapshot to any file: `path.tmp` first, fsynced, then renamed over
/// `path` and the directory fsynced (`pushlearn learn --save-model`).
///
/// # Errors
/// The learner cannot be serialised or the file written.
pub fn write_snapshot_file<M: Model>(
    path: &Path,
    records: u64,
    settings: &Settings,
    learner: &Learner<M>,
) -> Result<(), StateError> {
    let bytes = encode(records, settings, learner)?;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp);
    write_synced(&Disk, &tmp, &bytes)?;
    fs::rename(&tmp, path).map_err(io_error(path))?;
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    sync_dir(dir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learn::state::testing::{fingerprint, fresh, settings};

    #[test]
    fn a_snapshot_is_magic_length_checksum_then_header_and_learner() {
        let bytes = encode_snapshot(42, &settings(), &fresh()).unwrap();
        assert_eq!(&bytes[..8], b"PLSNAP01");
        let payload = &bytes[20..];
        assert_eq!(bytes[8..16], (payload.len() as u64).to_le_bytes());
        assert_eq!(bytes[16..20], crc32(&[payload]).to_le_bytes());
        let header_len = u32::from_le_bytes(payload[..4].try_into().unwrap()) as usize;
        let header = std::str::from_utf8(&payload[4..4 + header_len]).unwrap();
        assert_eq!(
            header,
            r#"{"version":1,"records":42,"settings":{"model":"gate","publish_rate_hz":100,"policy":{"Target":{"x":0.1,"y":0.5,"theta":0.3}},"shadows":true,"seed":7,"model_options":"eta 0","episodes":{"episodes":1,"max_steps":3000}}}"#
        );
        let path = Path::new("snapshot");
        let (records, back) =
            decode_snapshot::<learner::GateModel>(&bytes, path, Path::new("."), &settings())
                .unwrap();
        assert_eq!(records, 42);
        assert_eq!(fingerprint(&back), fingerprint(&fresh()));
    }
}
