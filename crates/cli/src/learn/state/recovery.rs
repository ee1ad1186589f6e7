//! Recovery: the snapshot, then the journal records after it up to the
//! first damaged one, which is reported and (by [`super::Durable::open`])
//! cut off together with everything after it.

use std::fs::{self, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

use learner::Model;

use super::record::{read_records, Entry};
use super::segment::segments;
use super::snapshot::{decode_snapshot, PREVIOUS_SNAPSHOT_FILE, SNAPSHOT_FILE};
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

/// The newest snapshot, when recovery could not use it and started from the
/// previous one.
#[derive(Clone, Debug, PartialEq)]
pub struct FellBack {
    /// The newest snapshot's path.
    pub snapshot: PathBuf,
    /// What is wrong with it.
    pub reason: String,
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
    /// Set when the newest snapshot was damaged or missing and the previous
    /// one was loaded instead (`snapshot_records` is then the previous
    /// one's).
    pub fell_back: Option<FellBack>,
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
            "{} records ({} of {} + {} replayed from the journal)",
            self.records(),
            if self.fell_back.is_some() {
                "previous snapshot"
            } else {
                "snapshot"
            },
            self.snapshot_records,
            self.replayed
        )?;
        if let Some(fell_back) = &self.fell_back {
            write!(
                f,
                "; the newest snapshot {} was not used: {}",
                fell_back.snapshot.display(),
                fell_back.reason
            )?;
        }
        if let Some(cut) = &self.cut {
            write!(f, "; damaged journal tail cut: {cut}")?;
        }
        Ok(())
    }
}

/// Reads and checks the snapshot at `path`: `None` if there is none.
fn load_snapshot<M: Model>(
    path: &Path,
    dir: &Path,
    expected: &Settings,
) -> Result<Option<(u64, Learner<M>)>, StateError> {
    match fs::read(path) {
        Ok(bytes) => decode_snapshot(&bytes, path, dir, expected).map(Some),
        Err(err) if err.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(err) => Err(io_error(path)(err)),
    }
}

/// The snapshot recovery starts from: its records, the learner, and (for
/// the previous one) what was wrong with the newest.
type Start<M> = (u64, Learner<M>, Option<FellBack>);

/// The snapshot recovery starts from: the newest, or if that is damaged or
/// missing the previous one.
fn starting_snapshot<M: Model>(
    dir: &Path,
    expected: &Settings,
) -> Result<Option<Start<M>>, StateError> {
    let newest = dir.join(SNAPSHOT_FILE);
    let reason = match load_snapshot(&newest, dir, expected) {
        Ok(Some((records, learner))) => return Ok(Some((records, learner, None))),
        // Between the two renames of a snapshot being replaced.
        Ok(None) => None,
        Err(StateError::CorruptSnapshot { reason, .. }) => Some(reason),
        // Other settings or an unreadable file: not damage, nothing to fall
        // back from.
        Err(err) => return Err(err),
    };
    let previous = dir.join(PREVIOUS_SNAPSHOT_FILE);
    match (load_snapshot(&previous, dir, expected), reason) {
        (Ok(Some((records, learner))), reason) => {
            let reason = reason.unwrap_or_else(|| "missing".to_owned());
            Ok(Some((
                records,
                learner,
                Some(FellBack {
                    snapshot: newest,
                    reason,
                }),
            )))
        }
        (Ok(None), None) => {
            if let Some((_, segment)) = segments(dir)?.first() {
                return Err(StateError::CorruptSnapshot {
                    path: newest,
                    reason: format!("missing, though journal {} exists", segment.display()),
                });
            }
            Ok(None)
        }
        (Ok(None), Some(reason)) => Err(StateError::CorruptSnapshot {
            path: newest,
            reason: format!("{reason}; there is no previous snapshot to fall back to"),
        }),
        (Err(StateError::CorruptSnapshot { reason: old, .. }), reason) => {
            Err(StateError::CorruptSnapshot {
                path: newest,
                reason: format!(
                    "{}, and the previous snapshot {} is damaged too ({old})",
                    reason.as_deref().unwrap_or("missing"),
                    previous.display()
                ),
            })
        }
        (Err(err), _) => Err(err),
    }
}

/// Loads the learner stored in `dir` without changing anything there:
/// `None` if `dir` holds no memory yet. A newest snapshot that is damaged
/// (or missing, as a crash between its two renames leaves it) is not
/// loaded; the previous snapshot is, and the journal after it replayed,
/// which the snapshot writer keeps for this.
///
/// # Errors
/// An unreadable directory, no intact snapshot, or settings other than
/// `expected`; starting from the previous snapshot, a journal after it
/// that does not reach the end intact (it is never cut then: the records
/// behind the damage are the newest snapshot's, only damaged twice over).
pub fn recover<M: Model>(
    dir: &Path,
    expected: &Settings,
) -> Result<Option<(Learner<M>, Recovery)>, StateError> {
    let Some((snapshot_records, mut learner, fell_back)) = starting_snapshot::<M>(dir, expected)?
    else {
        return Ok(None);
    };
    let mut recovery = Recovery {
        snapshot_records,
        fell_back,
        ..Recovery::default()
    };
    let segments = segments(dir)?;
    let mut last = snapshot_records;
    let mut out_of_sequence = false;
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
                out_of_sequence = true;
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
    if let (Some(fell_back), Some(cut)) = (&recovery.fell_back, &recovery.cut) {
        // A torn last record is what a crash leaves; anything else means the
        // previous snapshot's journal cannot replace the newest snapshot.
        if out_of_sequence || !cut.later_segments.is_empty() {
            return Err(StateError::CorruptSnapshot {
                path: fell_back.snapshot.clone(),
                reason: format!(
                    "{}, and the journal after the previous snapshot is damaged ({cut})",
                    fell_back.reason
                ),
            });
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
    use crate::learn::state::snapshot::DAMAGED_SNAPSHOT_FILE;
    use crate::learn::state::testing::{
        assert_same, fingerprint, frames, fresh, heights, journal, predictions, reference,
        settings, TempDir,
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

    /// 90 states with a snapshot every 25, dropped as by a crash: the
    /// newest snapshot covers 75 records, the previous one 50, and the
    /// journal is kept from the previous one on.
    fn two_snapshots(dir: &Path) -> (String, Recovery) {
        let (mut d, _) = Durable::open(dir, &settings(), fresh, 25).unwrap();
        for f in &frames(90) {
            crate::learn::OnState::on_state(&mut d, f, &heights()).unwrap();
        }
        drop(d);
        let (learner, recovery) = recover::<GateModel>(dir, &settings()).unwrap().unwrap();
        assert_eq!((recovery.snapshot_records, recovery.replayed), (75, 15));
        assert_eq!(
            segments(dir)
                .unwrap()
                .iter()
                .map(|s| s.0)
                .collect::<Vec<_>>(),
            [50, 75]
        );
        (fingerprint(&learner), recovery)
    }

    fn flip_a_byte(path: &Path) {
        let mut bytes = fs::read(path).unwrap();
        let middle = bytes.len() / 2;
        bytes[middle] ^= 0x20;
        fs::write(path, &bytes).unwrap();
    }

    /// Every file in `dir` and its bytes.
    fn contents(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
        let mut all: Vec<_> = fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let path = e.unwrap().path();
                let bytes = fs::read(&path).unwrap();
                (path, bytes)
            })
            .collect();
        all.sort();
        all
    }

    #[test]
    fn a_damaged_newest_snapshot_falls_back_to_the_previous_one_and_its_journal() {
        let dir = TempDir::new("fallback");
        let (undamaged, _) = two_snapshots(&dir.0);
        let newest = dir.0.join(SNAPSHOT_FILE);
        flip_a_byte(&newest);
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(
            (recovery.snapshot_records, recovery.replayed, &recovery.cut),
            (50, 40, &None)
        );
        let fell_back = recovery.fell_back.clone().unwrap();
        assert_eq!(fell_back.snapshot, newest);
        assert!(fell_back.reason.contains("checksum mismatch"), "{recovery}");
        assert_same(&fingerprint(&recovered), &undamaged);
        assert_same(&undamaged, &reference(90));
        let probe = &frames(100)[95];
        assert_eq!(
            predictions(&recovered, probe),
            predictions(
                &recover::<GateModel>(&dir.0, &settings())
                    .unwrap()
                    .unwrap()
                    .0,
                probe
            )
        );

        // A later daemon's --memory DIR reads it the same way.
        let (model, records) =
            crate::learn::state::load_model::<GateModel>(&dir.0, &settings()).unwrap();
        assert_eq!(records, 90);
        assert_eq!(
            serde_json::to_string(&model).unwrap(),
            serde_json::to_string(recovered.model()).unwrap()
        );

        // Opening sets the damaged one aside, so that the intact previous
        // snapshot stays the fallback of the next.
        let (d, opened) = Durable::open(&dir.0, &settings(), fresh, 25).unwrap();
        assert_eq!(opened, Opened::Resumed(recovery));
        drop(d);
        assert!(dir.0.join(DAMAGED_SNAPSHOT_FILE).exists());
        let (_, again) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!((again.records(), again.fell_back), (91, None));
        fs::remove_file(&newest).unwrap();
        let (from_previous, again) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!((again.snapshot_records, again.records()), (50, 91));
        assert!(again.fell_back.unwrap().reason == "missing");
        let mut expected = fresh();
        for f in &frames(90) {
            expected.on_state(f, &heights()).unwrap();
        }
        expected.resync();
        assert_same(&fingerprint(&from_previous), &fingerprint(&expected));
    }

    #[test]
    fn a_newest_snapshot_missing_between_its_renames_falls_back_too() {
        let dir = TempDir::new("fallback-missing");
        let (undamaged, _) = two_snapshots(&dir.0);
        // What a crash between `snapshot` → `snapshot.prev` and
        // `snapshot.tmp` → `snapshot` leaves.
        fs::rename(
            dir.0.join(SNAPSHOT_FILE),
            dir.0.join(PREVIOUS_SNAPSHOT_FILE),
        )
        .unwrap();
        assert!(crate::learn::state::holds_memory(&dir.0));
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(
            (recovery.snapshot_records, recovery.records()),
            (75, 90),
            "{recovery}"
        );
        assert_same(&fingerprint(&recovered), &undamaged);
    }

    #[test]
    fn without_an_intact_snapshot_and_journal_to_fall_back_on_nothing_is_loaded_or_cut() {
        // Both snapshots damaged.
        let dir = TempDir::new("fallback-both");
        two_snapshots(&dir.0);
        flip_a_byte(&dir.0.join(SNAPSHOT_FILE));
        flip_a_byte(&dir.0.join(PREVIOUS_SNAPSHOT_FILE));
        let before = contents(&dir.0);
        let err = Durable::open(&dir.0, &settings(), fresh, 25).unwrap_err();
        assert!(
            err.to_string()
                .contains("checksum mismatch, and the previous snapshot")
                && err.to_string().contains("is damaged too"),
            "{err}"
        );
        assert_eq!(contents(&dir.0), before);

        // The newest damaged, and a record in the middle of the journal
        // after the previous one: its records up to the newest snapshot
        // cannot be replayed, and the later segment is not cut either.
        let dir = TempDir::new("fallback-journal");
        two_snapshots(&dir.0);
        flip_a_byte(&dir.0.join(SNAPSHOT_FILE));
        let (_, segment) = segments(&dir.0).unwrap()[0].clone();
        let mut bytes = fs::read(&segment).unwrap();
        let offset = read_records(&bytes).records[9].2; // the end of record 60
        bytes[offset + RECORD_HEADER + 7] ^= 0x10;
        fs::write(&segment, &bytes).unwrap();
        let before = contents(&dir.0);
        let err = Durable::open(&dir.0, &settings(), fresh, 25).unwrap_err();
        assert!(
            err.to_string()
                .contains("and the journal after the previous snapshot is damaged")
                && err.to_string().contains("record 61 fails its checksum"),
            "{err}"
        );
        assert_eq!(contents(&dir.0), before);
    }
}
