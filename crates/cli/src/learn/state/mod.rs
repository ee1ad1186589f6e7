//! The learner daemon's persistent memory (`pushlearn learn --state DIR`):
//! crash-safe snapshots plus an append-only, checksummed journal of every
//! world state handled since (`docs/reliability.md` has the whole design).
//!
//! * `DIR/snapshot`: the whole [`Learner`](super::Learner) after `S` journal records, written
//!   to `snapshot.tmp`, fsynced, read back, then the old one renamed to
//!   `snapshot.prev` and the new one into its place, and the directory
//!   fsynced; a checksum over its contents is verified on load. The
//!   previous snapshot and the journal after it are kept: a newest snapshot
//!   found damaged is never loaded, recovery starts from the previous one.
//! * `DIR/lock`: held (an OS advisory lock) by the one daemon using `DIR`.
//! * `DIR/log-S` (20 digits): the journal segment of the records `S+1, S+2,
//!   …` — each world state the learner handled (its bodies' poses, bit for
//!   bit) or a re-synchronisation. Replaying them through
//!   [`Learner::on_state`](super::Learner::on_state) repeats exactly what the live learner did, since
//!   the learner is deterministic given its state and its input.
//!
//! The hot path only encodes a record and hands it to a writer thread; the
//! thread appends whatever has queued up and fsyncs it (group commit). A
//! record is **acknowledged** once that fsync has returned
//! ([`Durable::acknowledged`]). Snapshots are taken from a clone of the
//! learner on the same thread, so serialising a large model never holds up a
//! message.
//!
//! Recovery loads the snapshot and replays the records that follow it; the
//! first record that is cut off, fails its checksum or is out of sequence
//! ends the replay, is reported and is cut off the file together with
//! everything after it — it is never loaded. Then a fresh snapshot is written
//! and a new segment started, so that every start begins from a clean state.
//!
//! A write that fails (a full or read-only file system) stops the journal
//! for good: the daemon stops at its next state with the error, and a
//! restart recovers every acknowledged record.
//!
//! The parts: `record` (the journal's record codec), `snapshot`, `segment`
//! (the journal's files), `recovery`, `durable` (the daemon's side: the
//! group-commit writer), `lock` (one daemon per directory) and `storage`
//! (the files written, and the tests' seam for a failing disk).

use std::io;
use std::path::{Path, PathBuf};

use learner::Model;
use serde::{Deserialize, Serialize};

use super::Policy;

mod durable;
mod lock;
mod record;
mod recovery;
mod segment;
mod snapshot;
mod storage;
#[cfg(test)]
mod testing;

pub use durable::{Durable, Opened};
pub use lock::{StateLock, LOCK_FILE};
pub use record::{decode_entry, read_records, Entry, SegmentRead};
pub use recovery::{recover, Cut, FellBack, Recovery};
pub use snapshot::{
    write_snapshot_file, DAMAGED_SNAPSHOT_FILE, PREVIOUS_SNAPSHOT_FILE, SNAPSHOT_FILE,
};

/// Records between two snapshots by default: 5 minutes at 100 Hz. Recovery
/// replays at most this many records (twice as many from the previous
/// snapshot, when the newest is damaged); a snapshot clones the learner once.
pub const DEFAULT_SNAPSHOT_EVERY: u64 = 30_000;

/// Why the memory cannot be loaded or kept.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: io::Error },
    #[error(
        "{} is damaged ({reason}); it is never loaded silently: move the directory \
         away to start afresh",
        path.display()
    )]
    CorruptSnapshot { path: PathBuf, reason: String },
    #[error(
        "{} holds the memory of a different learner ({differences}); run with the same \
         settings or give another --state directory",
        dir.display()
    )]
    Mismatch { dir: PathBuf, differences: String },
    #[error(
        "{} holds a model made otherwise ({differences}); start from it with the same \
         --model, model options and world publish rate",
        path.display()
    )]
    OtherModel { path: PathBuf, differences: String },
    #[error("cannot keep the learner's memory: {0}")]
    Writer(String),
    #[error(
        "{} is in use by another learner ({}); only one `pushlearn learn` may use a \
         --state directory at a time",
        dir.display(),
        match holder { Some(pid) => format!("pid {pid}"), None => "pid unknown".to_owned() }
    )]
    Locked { dir: PathBuf, holder: Option<u32> },
}

fn io_error(path: &Path) -> impl FnOnce(io::Error) -> StateError + '_ {
    move |source| StateError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// What the stored learner was started with. A learner resumes only with
/// the same settings: its model, thresholds (set from the publish rate),
/// policy and generator all shape what it learns and does.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// `gate` or `interaction`.
    pub model: String,
    /// The world's publish rate the model was configured for.
    pub publish_rate_hz: u32,
    pub policy: Policy,
    pub shadows: bool,
    /// The generator's seed (the generator itself is stored with its
    /// position, so a resumed learner continues its sequence).
    pub seed: u64,
    /// The model's options (configuration bits, η, selector) as given on
    /// the command line: the stored model was built with them, so resuming
    /// under others would silently ignore the new ones.
    #[serde(default)]
    pub model_options: String,
    /// A target policy's attempts and their step limit (memories from
    /// before episodes existed made one attempt of the thesis's limit).
    #[serde(default)]
    pub episodes: EpisodeSettings,
}

/// See [`Settings::episodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EpisodeSettings {
    pub episodes: u32,
    pub max_steps: u64,
}

impl Default for EpisodeSettings {
    fn default() -> Self {
        EpisodeSettings {
            episodes: 1,
            max_steps: crate::experiment::move_to_target::MAX_STEPS,
        }
    }
}

/// Loads the model an earlier daemon kept — its `--state` directory (the
/// snapshot and the journal replayed after it) or a file of
/// `pushlearn learn --save-model` — without changing anything there, for a
/// daemon that starts from that experience. Only what made the model must
/// match (`expected`'s model, publish rate and options); policy, seed and
/// the rest are the new daemon's.
///
/// # Errors
/// Nothing stored at `path`, a damaged memory, or a model made otherwise.
pub fn load_model<M: Model>(path: &Path, expected: &Settings) -> Result<(M, u64), StateError> {
    let check = |stored: &Settings| {
        let made_otherwise = expected.differences_in(stored, MAKING_THE_MODEL);
        if made_otherwise.is_empty() {
            Ok(())
        } else {
            Err(StateError::OtherModel {
                path: path.to_path_buf(),
                differences: made_otherwise.join("; "),
            })
        }
    };
    if path.is_dir() {
        let stored = stored_settings_in(path)?;
        check(&stored)?;
        let (learner, recovery) = recover::<M>(path, &stored)?.ok_or_else(|| StateError::Io {
            path: path.join(SNAPSHOT_FILE),
            source: io::Error::from(io::ErrorKind::NotFound),
        })?;
        if let Some(fell_back) = &recovery.fell_back {
            tracing::warn!(
                "{}: damaged, not loaded ({}); starting from the previous snapshot",
                fell_back.snapshot.display(),
                fell_back.reason
            );
        }
        if let Some(cut) = &recovery.cut {
            tracing::warn!(
                "{}: damaged journal tail, not loaded: {cut}",
                path.display()
            );
        }
        Ok((learner.into_model(), recovery.records()))
    } else {
        let dir = path.parent().unwrap_or(Path::new("."));
        let bytes = std::fs::read(path).map_err(io_error(path))?;
        let stored = snapshot::stored_settings(&bytes, path)?;
        check(&stored)?;
        let (records, learner) = snapshot::decode_snapshot::<M>(&bytes, path, dir, &stored)?;
        Ok((learner.into_model(), records))
    }
}

/// The settings of the memory in `dir`: its newest intact snapshot's.
fn stored_settings_in(dir: &Path) -> Result<Settings, StateError> {
    let mut first_error = None;
    for name in [SNAPSHOT_FILE, PREVIOUS_SNAPSHOT_FILE] {
        let path = dir.join(name);
        let read = std::fs::read(&path)
            .map_err(io_error(&path))
            .and_then(|bytes| snapshot::stored_settings(&bytes, &path));
        match read {
            Ok(settings) => return Ok(settings),
            Err(err) => {
                first_error.get_or_insert(err);
            }
        }
    }
    Err(first_error.unwrap_or_else(|| StateError::Io {
        path: dir.join(SNAPSHOT_FILE),
        source: io::Error::from(io::ErrorKind::NotFound),
    }))
}

/// Whether `dir` holds a learner's memory (a snapshot, the newest or the
/// previous one): a daemon started on it resumes it.
#[must_use]
pub fn holds_memory(dir: &Path) -> bool {
    [SNAPSHOT_FILE, PREVIOUS_SNAPSHOT_FILE]
        .iter()
        .any(|name| dir.join(name).exists())
}

/// What a `--state` directory holds, as read while a daemon may be writing
/// it: a record being appended reads as a torn tail and is not counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OnDisk {
    /// Whole records in the journal's segments.
    pub journal_records: u64,
    pub journal_bytes: u64,
    /// The newest and the previous snapshot together.
    pub snapshot_bytes: u64,
}

/// Reads what `dir` holds ([`OnDisk`]).
///
/// # Errors
/// The directory cannot be listed. (A file that disappears while it is read
/// — a segment or snapshot replaced by compaction — counts as empty.)
pub fn on_disk(dir: &Path) -> Result<OnDisk, StateError> {
    let mut found = OnDisk::default();
    for (_, path) in segment::segments(dir)? {
        let Ok(bytes) = std::fs::read(&path) else {
            continue;
        };
        found.journal_bytes += bytes.len() as u64;
        found.journal_records += read_records(&bytes).records.len() as u64;
    }
    found.snapshot_bytes = [SNAPSHOT_FILE, PREVIOUS_SNAPSHOT_FILE]
        .iter()
        .filter_map(|name| std::fs::metadata(dir.join(name)).ok())
        .map(|meta| meta.len())
        .sum();
    Ok(found)
}

/// The settings that made a model: a kept model (`load_model`) must match
/// in these, whatever the new daemon's policy and seed.
const MAKING_THE_MODEL: &[&str] = &["model", "publish rate", "model options"];

impl Settings {
    /// Each setting by name, as (name, stored, now).
    fn compared(&self, stored: &Settings) -> [(&'static str, String, String); 7] {
        [
            ("model", stored.model.clone(), self.model.clone()),
            (
                "publish rate",
                stored.publish_rate_hz.to_string(),
                self.publish_rate_hz.to_string(),
            ),
            (
                "policy",
                format!("{:?}", stored.policy),
                format!("{:?}", self.policy),
            ),
            (
                "shadows",
                stored.shadows.to_string(),
                self.shadows.to_string(),
            ),
            ("seed", stored.seed.to_string(), self.seed.to_string()),
            (
                "model options",
                stored.model_options.clone(),
                self.model_options.clone(),
            ),
            (
                "episodes",
                format!("{:?}", stored.episodes),
                format!("{:?}", self.episodes),
            ),
        ]
    }

    fn differences(&self, stored: &Settings) -> Vec<String> {
        self.differences_where(stored, |_| true)
    }

    /// [`Settings::differences`] in the settings named `names` only.
    fn differences_in(&self, stored: &Settings, names: &[&str]) -> Vec<String> {
        self.differences_where(stored, |what| names.contains(&what))
    }

    fn differences_where(&self, stored: &Settings, pick: impl Fn(&str) -> bool) -> Vec<String> {
        self.compared(stored)
            .into_iter()
            .filter(|(what, stored, now)| pick(what) && stored != now)
            .map(|(what, stored, now)| format!("{what}: stored {stored}, now {now}"))
            .collect()
    }
}
