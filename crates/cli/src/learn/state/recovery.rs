//! Recovery: the snapshot, then the journal records after it up to the
//! first damaged one, which is reported and (by [`super::Durable::open`])
//! cut off together with everything after it.

use std::fs::{self, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

use learner::Model;

use super::record::{read_records, Entry};
use super::segment::segments;
use super::snapshot::{decode_snapshot, SNAPSHOT_FILE};
use super::{io_error, Settings, StateError};
use crate::frame::StartHeights;
use crate::learn::Learner;

/// Where recovery stopped reading a damaged journal.
#[derive(Clone, Debug, PartialEq)]
pub struct Cut {
    /// The segment with the damaged record.
    pub segment: PathBuf,
    /// Byte offset of the damaged record (the segment is cut there).
    pub offset: u64,
    /// Bytes cut from that segment.
    pub bytes: u64,
    /// What is wrong with it.
    pub reason: String,
    /// Later segments removed with it.
    pub later_segments: Vec<PathBuf>,
}

impl std::fmt::Display for Cut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {} at byte {}; cut {} bytes",
            self.segment.display(),
            self.reason,
            self.offset,
            self.bytes
        )?;
        if !self.later_segments.is_empty() {
            write!(f, " and {} later segment(s)", self.later_segments.len())?;
        }
        Ok(())
    }
}

/// What recovery found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recovery {
    /// Records the snapshot covered.
    pub snapshot_records: u64,
    /// Records replayed from the journal after it.
    pub replayed: u64,
    /// The damaged tail, if any.
    pub cut: Option<Cut>,
}

impl Recovery {
    /// Records the recovered learner has handled.
    #[must_use]
    pub fn records(&self) -> u64 {
        self.snapshot_records + self.replayed
    }
}

impl std::fmt::Display for Recovery {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} records (snapshot of {} + {} replayed from the journal)",
            self.records(),
            self.snapshot_records,
            self.replayed
        )?;
        if let Some(cut) = &self.cut {
            write!(f, "; damaged journal tail cut: {cut}")?;
        }
        Ok(())
    }
}

/// Loads the learner stored in `dir` without changing anything there:
/// `None` if `dir` holds no memory yet.
///
/// # Errors
/// An unreadable directory, a damaged snapshot, or settings other than
/// `expected`.
pub fn recover<M: Model>(
    dir: &Path,
    expected: &Settings,
) -> Result<Option<(Learner<M>, Recovery)>, StateError> {
    let path = dir.join(SNAPSHOT_FILE);
    let bytes = match fs::read(&path) {
        Ok(bytes) => bytes,
        Err(err) if err.kind() == io::ErrorKind::NotFound => {
            if let Some((_, segment)) = segments(dir)?.first() {
                return Err(StateError::CorruptSnapshot {
                    path,
                    reason: format!("missing, though journal {} exists", segment.display()),
                });
            }
            return Ok(None);
        }
        Err(err) => return Err(io_error(&path)(err)),
    };
    let (snapshot_records, mut learner) = decode_snapshot::<M>(&bytes, &path, dir, expected)?;
    let mut recovery = Recovery {
        snapshot_records,
        ..Recovery::default()
    };
    let segments = segments(dir)?;
    let mut last = snapshot_records;
    for (i, (start, segment)) in segments.iter().enumerate() {
        // Entirely covered by the snapshot: left over from a crash between
        // writing it and removing the old segments.
        if segments
            .get(i + 1)
            .is_some_and(|(next, _)| *next <= snapshot_records)
        {
            continue;
        }
        let bytes = fs::read(segment).map_err(io_error(segment))?;
        let read = read_records(&bytes);
        let mut bad = read.bad;
        let mut good_end = 0;
        for (index, entry, end) in read.records {
            if index <= last && index > *start {
                // Already in the snapshot.
                good_end = end;
                continue;
            }
            if index != last + 1 || index <= *start {
                bad = Some((
                    good_end,
                    format!("record {index} out of sequence (expected {})", last + 1),
                ));
                break;
            }
            replay(&mut learner, entry);
            last = index;
            recovery.replayed += 1;
            good_end = end;
        }
        if let Some((offset, reason)) = bad {
            recovery.cut = Some(Cut {
                segment: segment.clone(),
                offset: offset as u64,
                bytes: (bytes.len() - offset) as u64,
                reason,
                later_segments: segments[i + 1..].iter().map(|(_, p)| p.clone()).collect(),
            });
            break;
        }
    }
    Ok(Some((learner, recovery)))
}

/// Repeats what the live learner did with `entry`.
fn replay<M: Model>(learner: &mut Learner<M>, entry: Entry) {
    match entry {
        Entry::Resync => learner.resync(),
        Entry::State(frame) => {
            // The live daemon stopped on this error; its learner is in the
            // state the replay leaves it in. The commands are not sent, so
            // the ghosts need no heights.
            if let Err(err) = learner.on_state(&frame, &StartHeights::default()) {
                tracing::debug!(%err, "replayed a state the learner refused");
            }
        }
    }
}

/// Cuts the damaged record and everything after it off the journal.
pub(super) fn cut_tail(cut: &Cut) -> Result<(), StateError> {
    let file = OpenOptions::new()
        .write(true)
        .open(&cut.segment)
        .map_err(io_error(&cut.segment))?;
    file.set_len(cut.offset).map_err(io_error(&cut.segment))?;
    file.sync_all().map_err(io_error(&cut.segment))?;
    for later in &cut.later_segments {
        fs::remove_file(later).map_err(io_error(later))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use learner::GateModel;

    use super::*;
    use crate::learn::state::record::{encode_record, RECORD_HEADER};
    use crate::learn::state::testing::{
        assert_same, fingerprint, frames, fresh, journal, reference, settings, TempDir,
    };
    use crate::learn::state::{Durable, Opened};

    #[test]
    fn a_torn_tail_is_reported_cut_and_never_loaded() {
        let dir = TempDir::new("torn");
        let segment = journal(&dir.0, 20);
        let good = fs::metadata(&segment).unwrap().len();
        // Half of a 21st record, as a write interrupted by the crash leaves it.
        let mut torn = Vec::new();
        encode_record(21, Some(&frames(21)[20]), &mut torn);
        let mut file = OpenOptions::new().append(true).open(&segment).unwrap();
        file.write_all(&torn[..torn.len() / 2]).unwrap();
        drop(file);

        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(recovery.records(), 20);
        let cut = recovery.cut.clone().unwrap();
        assert_eq!(cut.offset, good);
        assert_eq!(cut.bytes, (torn.len() / 2) as u64);
        assert!(cut.reason.contains("record 21 cut off"), "{}", cut.reason);
        assert_same(&fingerprint(&recovered), &reference(20));

        // Opening cuts it for good and starts afresh from a snapshot.
        let (d, opened) = Durable::open(&dir.0, &settings(), fresh, 1000).unwrap();
        assert_eq!(opened, Opened::Resumed(recovery));
        drop(d);
        let (_, again) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(again.cut, None);
        assert_eq!(again.records(), 21, "20 states and the resync");
    }

    #[test]
    fn a_corrupt_record_ends_the_replay_there() {
        let dir = TempDir::new("corrupt");
        let segment = journal(&dir.0, 30);
        let mut bytes = fs::read(&segment).unwrap();
        let offset = read_records(&bytes).records[11].2; // the end of record 12
        bytes[offset + RECORD_HEADER + 7] ^= 0x10; // inside record 13's payload
        fs::write(&segment, &bytes).unwrap();
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(recovery.records(), 12);
        let cut = recovery.cut.unwrap();
        assert_eq!(cut.offset, offset as u64);
        assert!(cut.reason.contains("record 13 fails its checksum"), "{cut}");
        assert_same(&fingerprint(&recovered), &reference(12));
    }

    #[test]
    fn a_damaged_snapshot_or_other_settings_are_refused() {
        let dir = TempDir::new("snapshot");
        journal(&dir.0, 5);
        let mut other = settings();
        other.seed = 8;
        other.model = "interaction".into();
        other.model_options = "eta 0.1".into();
        let err = recover::<GateModel>(&dir.0, &other).unwrap_err();
        assert!(
            matches!(&err, StateError::Mismatch { differences, .. }
                if differences == "model: stored gate, now interaction; seed: stored 7, now 8; \
                                   model options: stored eta 0, now eta 0.1"),
            "{err}"
        );
        let path = dir.0.join(SNAPSHOT_FILE);
        let mut bytes = fs::read(&path).unwrap();
        let last = bytes.len() - 3;
        bytes[last] ^= 1;
        fs::write(&path, &bytes).unwrap();
        let err = recover::<GateModel>(&dir.0, &settings()).unwrap_err();
        assert!(err.to_string().contains("checksum mismatch"), "{err}");
        fs::remove_file(&path).unwrap();
        let err = recover::<GateModel>(&dir.0, &settings()).unwrap_err();
        assert!(err.to_string().contains("missing, though journal"), "{err}");
    }
}
