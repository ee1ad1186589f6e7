//! The daemon's side: a learner whose every input is journalled before it
//! acts on it, with a writer thread that group-commits the records and
//! writes the snapshots.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

use learner::{Frame, Model};

use super::record::encode_record;
use super::recovery::{cut_tail, recover, Recovery};
use super::segment::{open_segment, segments, sync_dir};
use super::snapshot::{write_snapshot, DAMAGED_SNAPSHOT_FILE};
use super::storage::{Disk, Storage, StorageFile};
use super::{io_error, Settings, StateError, StateLock};
use crate::frame::StartHeights;
use crate::learn::{Episodes, LearnError, Learner, OnState};
use pushlearn::wire::pb::client_message::Payload;

enum ToWriter<M: Model> {
    Records {
        last: u64,
        bytes: Vec<u8>,
    },
    Snapshot {
        records: u64,
        learner: Box<Learner<M>>,
    },
    Close,
}

#[derive(Debug, Default)]
struct WriterShared {
    acknowledged: AtomicU64,
    failure: Mutex<Option<String>>,
}

/// A learner whose every input is journalled, with snapshots, in a state
/// directory; see the module docs.
pub struct Durable<M: Model + 'static> {
    learner: Learner<M>,
    records: u64,
    since_snapshot: u64,
    snapshot_every: u64,
    tx: Option<mpsc::Sender<ToWriter<M>>>,
    shared: Arc<WriterShared>,
    thread: Option<JoinHandle<()>>,
    /// Released only when dropped, after `Drop` has joined the journal
    /// thread: nobody else may write the directory before it is done.
    _lock: StateLock,
}

impl<M: Model + 'static> std::fmt::Debug for Durable<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Durable")
            .field("records", &self.records)
            .field("acknowledged", &self.acknowledged())
            .finish_non_exhaustive()
    }
}

/// How [`Durable::open`] found the directory.
#[derive(Clone, Debug, PartialEq)]
pub enum Opened {
    /// No memory yet: a fresh learner.
    Fresh,
    /// An earlier learner, recovered.
    Resumed(Recovery),
}

impl<M: Model + 'static> Durable<M> {
    /// Opens (creating if need be) the memory in `dir`: takes its lock
    /// ([`StateLock`]), recovers the stored learner, or starts `fresh()` if
    /// there is none; cuts a damaged journal tail; writes a snapshot of the
    /// result, starts a new journal segment and, for a resumed learner,
    /// journals a re-synchronisation (the world has moved on while the
    /// daemon was down). Snapshots follow every `snapshot_every` records.
    ///
    /// # Errors
    /// Another learner holds the directory ([`StateError::Locked`]); see
    /// [`recover`]; I/O errors writing the directory.
    pub fn open(
        dir: &Path,
        settings: &Settings,
        fresh: impl FnOnce() -> Learner<M>,
        snapshot_every: u64,
    ) -> Result<(Self, Opened), StateError> {
        fs::create_dir_all(dir).map_err(io_error(dir))?;
        Self::open_locked(StateLock::acquire(dir)?, settings, fresh, snapshot_every)
    }

    /// [`Durable::open`] with the lock already taken (the daemon takes it
    /// before connecting to the world, so that a second one is refused
    /// before it does anything).
    ///
    /// # Errors
    /// As [`Durable::open`].
    pub fn open_locked(
        lock: StateLock,
        settings: &Settings,
        fresh: impl FnOnce() -> Learner<M>,
        snapshot_every: u64,
    ) -> Result<(Self, Opened), StateError> {
        Self::open_on(Disk::shared(), lock, settings, fresh, snapshot_every)
    }

    /// [`Durable::open_locked`] writing through `storage` (the tests' seam
    /// for a disk that fails).
    pub(super) fn open_on(
        storage: Arc<dyn Storage>,
        lock: StateLock,
        settings: &Settings,
        fresh: impl FnOnce() -> Learner<M>,
        snapshot_every: u64,
    ) -> Result<(Self, Opened), StateError> {
        let dir = lock.dir().to_path_buf();
        let dir = dir.as_path();
        let (learner, opened) = match recover::<M>(dir, settings)? {
            None => (fresh(), Opened::Fresh),
            Some((learner, recovery)) => {
                if let Some(fell_back) = &recovery.fell_back {
                    tracing::warn!(
                        "the newest snapshot {} was not used ({}): recovered from the \
                         previous one and the journal after it",
                        fell_back.snapshot.display(),
                        fell_back.reason
                    );
                    set_aside(&fell_back.snapshot, dir)?;
                }
                if let Some(cut) = &recovery.cut {
                    tracing::warn!("damaged journal tail: {cut}");
                    cut_tail(cut)?;
                }
                (learner, Opened::Resumed(recovery))
            }
        };
        let (records, previous) = match &opened {
            Opened::Fresh => (0, 0),
            Opened::Resumed(recovery) => (recovery.records(), recovery.snapshot_records),
        };
        write_snapshot(&*storage, dir, records, settings, &learner)?;
        // The snapshot recovery started from is now the previous one: its
        // journal stays, for when the new one is found damaged.
        remove_segments_before(dir, previous)?;
        let (segment, segment_path) = open_segment(&*storage, dir, records)?;
        let shared = Arc::new(WriterShared::default());
        shared.acknowledged.store(records, Ordering::Relaxed);
        let (tx, rx) = mpsc::channel();
        let thread = {
            let shared = shared.clone();
            let writer_dir = dir.to_path_buf();
            let settings = settings.clone();
            std::thread::Builder::new()
                .name("journal".into())
                .spawn(move || {
                    let mut writer = Writer {
                        storage,
                        dir: writer_dir,
                        settings,
                        segment,
                        segment_path,
                        newest: records,
                        shared: &shared,
                    };
                    if let Err(err) = writer.run(&rx) {
                        // Never written to again: after a failed write the
                        // segment may end in part of a record, and records
                        // appended behind it would be cut by recovery with
                        // it. The daemon learns of it at its next state.
                        let acknowledged = shared.acknowledged.load(Ordering::Acquire);
                        let failure = format!(
                            "{err}; every record up to {acknowledged} is durable, none after \
                             it will be: restart once the directory can be written, nothing \
                             acknowledged is lost"
                        );
                        tracing::error!("the journal stopped: {failure}");
                        *shared
                            .failure
                            .lock()
                            .unwrap_or_else(PoisonError::into_inner) = Some(failure);
                    }
                })
                .map_err(io_error(dir))?
        };
        let mut durable = Durable {
            learner,
            records,
            since_snapshot: 0,
            snapshot_every: snapshot_every.max(1),
            tx: Some(tx),
            shared,
            thread: Some(thread),
            _lock: lock,
        };
        if matches!(opened, Opened::Resumed(_)) {
            durable.resync_journalled()?;
        }
        Ok((durable, opened))
    }

    /// The learner.
    #[must_use]
    pub fn learner(&self) -> &Learner<M> {
        &self.learner
    }

    /// Records journalled so far (world states and re-synchronisations).
    #[must_use]
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Records durably on disk: a restart recovers at least these.
    #[must_use]
    pub fn acknowledged(&self) -> u64 {
        self.shared.acknowledged.load(Ordering::Acquire)
    }

    fn check(&self) -> Result<(), StateError> {
        let failure = self
            .shared
            .failure
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        match &*failure {
            Some(message) => Err(StateError::Writer(message.clone())),
            None => Ok(()),
        }
    }

    fn send(&self, message: ToWriter<M>) -> Result<(), StateError> {
        self.check()?;
        let sent = self.tx.as_ref().is_some_and(|tx| tx.send(message).is_ok());
        if sent {
            Ok(())
        } else {
            // The thread ended: its failure says why, if it recorded one.
            self.check()?;
            Err(StateError::Writer("the journal thread has ended".into()))
        }
    }

    fn append(&mut self, frame: Option<&Frame>) -> Result<(), StateError> {
        self.records += 1;
        let mut bytes = Vec::with_capacity(256);
        encode_record(self.records, frame, &mut bytes);
        self.send(ToWriter::Records {
            last: self.records,
            bytes,
        })
    }

    /// Called once the learner has acted on the latest record: a snapshot
    /// must hold the learner *after* the records it covers.
    fn maybe_snapshot(&mut self) -> Result<(), StateError> {
        self.since_snapshot += 1;
        if self.since_snapshot >= self.snapshot_every {
            self.since_snapshot = 0;
            self.send(ToWriter::Snapshot {
                records: self.records,
                learner: Box::new(self.learner.clone()),
            })?;
        }
        Ok(())
    }

    fn resync_journalled(&mut self) -> Result<(), StateError> {
        self.append(None)?;
        self.learner.resync();
        self.maybe_snapshot()
    }

    /// Writes a final snapshot, waits until everything is on disk and stops
    /// the journal. Returns the records stored.
    ///
    /// # Errors
    /// The journal failed at some point.
    pub fn close(mut self) -> Result<u64, StateError> {
        self.send(ToWriter::Snapshot {
            records: self.records,
            learner: Box::new(self.learner.clone()),
        })?;
        self.finish();
        self.check()?;
        Ok(self.acknowledged())
    }

    fn finish(&mut self) {
        if let Some(tx) = self.tx.take() {
            let _ = tx.send(ToWriter::Close);
        }
        if let Some(thread) = self.thread.take() {
            if thread.join().is_err() {
                tracing::error!("the journal thread panicked");
            }
        }
    }
}

impl<M: Model + 'static> Drop for Durable<M> {
    /// Whatever stops the daemon, what was handed to the journal is written.
    fn drop(&mut self) {
        self.finish();
    }
}

impl<M: Model + 'static> OnState for Durable<M> {
    fn on_state(
        &mut self,
        frame: &Frame,
        heights: &StartHeights,
    ) -> Result<Vec<Payload>, LearnError> {
        // Write-ahead: journalled before the learner acts on it, so that the
        // replay repeats even a state the learner refuses.
        self.append(Some(frame))?;
        let commands = self.learner.on_state(frame, heights);
        self.maybe_snapshot()?;
        Ok(commands?)
    }

    fn resync(&mut self) -> Result<(), LearnError> {
        Ok(self.resync_journalled()?)
    }

    fn episodes(&self) -> Option<&Episodes> {
        self.learner.episodes()
    }
}

/// The journal thread.
struct Writer<'a> {
    storage: Arc<dyn Storage>,
    dir: PathBuf,
    settings: Settings,
    segment: Box<dyn StorageFile>,
    segment_path: PathBuf,
    /// Records of the newest snapshot.
    newest: u64,
    shared: &'a WriterShared,
}

impl Writer<'_> {
    /// Group commit: takes everything queued, appends it with one write and
    /// one fsync, then acknowledges it.
    fn run<M: Model>(&mut self, rx: &mpsc::Receiver<ToWriter<M>>) -> Result<(), StateError> {
        let mut batch = Vec::new();
        let mut last = self.shared.acknowledged.load(Ordering::Relaxed);
        while let Ok(first) = rx.recv() {
            let mut next = Some(first);
            while let Some(message) = next.take().or_else(|| rx.try_recv().ok()) {
                match message {
                    ToWriter::Records { last: l, bytes } => {
                        batch.extend_from_slice(&bytes);
                        last = l;
                    }
                    ToWriter::Snapshot { records, learner } => {
                        self.commit(&mut batch, last)?;
                        self.snapshot(records, &learner)?;
                    }
                    ToWriter::Close => return self.commit(&mut batch, last),
                }
            }
            self.commit(&mut batch, last)?;
        }
        self.commit(&mut batch, last)
    }

    fn commit(&mut self, batch: &mut Vec<u8>, last: u64) -> Result<(), StateError> {
        if batch.is_empty() {
            return Ok(());
        }
        let path = &self.segment_path;
        self.segment.write_all(batch).map_err(io_error(path))?;
        self.segment.sync_data().map_err(io_error(path))?;
        batch.clear();
        self.shared.acknowledged.store(last, Ordering::Release);
        tracing::trace!(acknowledged = last, "journal on disk");
        Ok(())
    }

    /// Starts the segment after `records`, writes the snapshot of them (the
    /// newest becoming the previous one), and removes the segments before
    /// the previous one: the previous snapshot and the journal after it
    /// stay, for when the new one is found damaged. A crash anywhere in
    /// between leaves a directory that recovers to the same learner.
    fn snapshot<M: Model>(&mut self, records: u64, learner: &Learner<M>) -> Result<(), StateError> {
        (self.segment, self.segment_path) = open_segment(&*self.storage, &self.dir, records)?;
        write_snapshot(&*self.storage, &self.dir, records, &self.settings, learner)?;
        let previous = std::mem::replace(&mut self.newest, records);
        remove_segments_before(&self.dir, previous)?;
        tracing::debug!(records, "snapshot written");
        Ok(())
    }
}

/// Removes the journal segments that start before record `start`.
fn remove_segments_before(dir: &Path, start: u64) -> Result<(), StateError> {
    for (first, path) in segments(dir)? {
        if first < start {
            fs::remove_file(&path).map_err(io_error(&path))?;
        }
    }
    Ok(())
}

/// Moves a damaged newest snapshot out of the way (replacing one set aside
/// earlier), so that the next snapshot's rotation does not make it the
/// previous one in place of the intact snapshot recovery used.
fn set_aside(snapshot: &Path, dir: &Path) -> Result<(), StateError> {
    match fs::rename(snapshot, dir.join(DAMAGED_SNAPSHOT_FILE)) {
        Ok(()) => sync_dir(dir),
        // Missing, not damaged: nothing to move.
        Err(err) if err.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(err) => Err(io_error(snapshot)(err)),
    }
}

#[cfg(test)]
mod tests {
    use learner::GateModel;

    use super::*;
    use crate::learn::state::testing::{
        assert_same, fingerprint, frames, fresh, heights, predictions, settings, FailingDisk,
        Fault, TempDir,
    };

    #[test]
    fn a_restart_resumes_a_bit_identical_learner_across_snapshots() {
        let dir = TempDir::new("resume");
        let all = frames(130);
        let mut reference = fresh();
        {
            let (mut d, opened) = Durable::open(&dir.0, &settings(), fresh, 25).unwrap();
            assert_eq!(opened, Opened::Fresh);
            for f in &all[..90] {
                let live = OnState::on_state(&mut d, f, &heights()).unwrap();
                assert_eq!(live, reference.on_state(f, &heights()).unwrap());
            }
            assert_eq!(d.records(), 90);
            // Dropped without close(): what was journalled is written, but
            // no final snapshot (a crash after the last fsync).
        }
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(recovery.snapshot_records, 75);
        assert_eq!(recovery.replayed, 15);
        assert_eq!(recovery.cut, None);
        assert_same(&fingerprint(&recovered), &fingerprint(&reference));
        assert_eq!(
            predictions(&recovered, &all[100]),
            predictions(&reference, &all[100])
        );

        // Resuming journals a re-synchronisation: the next state must not
        // train across the gap.
        let (mut d, opened) = Durable::open(&dir.0, &settings(), fresh, 25).unwrap();
        assert!(matches!(opened, Opened::Resumed(r) if r.records() == 90));
        reference.resync();
        for f in &all[90..] {
            assert_eq!(
                OnState::on_state(&mut d, f, &heights()).unwrap(),
                reference.on_state(f, &heights()).unwrap()
            );
        }
        assert_eq!(d.close().unwrap(), 91 + 40);
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        // close() wrote a final snapshot: nothing left to replay.
        assert_eq!((recovery.snapshot_records, recovery.replayed), (131, 0));
        assert_same(&fingerprint(&recovered), &fingerprint(&reference));
        // The current segment, and the one after the previous snapshot
        // (115), kept for when the newest is found damaged.
        assert_eq!(
            segments(&dir.0)
                .unwrap()
                .iter()
                .map(|s| s.0)
                .collect::<Vec<_>>(),
            [115, 131]
        );
    }

    #[test]
    fn a_second_open_of_a_directory_in_use_is_refused_and_changes_nothing() {
        let dir = TempDir::new("two-opens");
        let all = frames(40);
        let (mut first, _) = Durable::open(&dir.0, &settings(), fresh, 1000).unwrap();
        for f in &all[..30] {
            OnState::on_state(&mut first, f, &heights()).unwrap();
        }
        let before = segments(&dir.0).unwrap();
        let err = Durable::open(&dir.0, &settings(), fresh, 1000).unwrap_err();
        assert!(
            matches!(&err, StateError::Locked { dir: d, holder: Some(pid) }
                if *d == dir.0 && *pid == std::process::id()),
            "{err:?}"
        );
        // The refused open neither recovered, snapshotted nor cut: the
        // first learner goes on undisturbed.
        assert_eq!(segments(&dir.0).unwrap(), before);
        for f in &all[30..] {
            OnState::on_state(&mut first, f, &heights()).unwrap();
        }
        assert_eq!(first.close().unwrap(), 40);
        // Closed, the directory is free again.
        let (second, opened) = Durable::open(&dir.0, &settings(), fresh, 1000).unwrap();
        assert!(matches!(opened, Opened::Resumed(r) if r.records() == 40));
        drop(second);
    }

    /// States journalled on the real disk before the faulty one takes over.
    const BEFORE: usize = 50;

    /// A memory of `BEFORE` states, dropped as by a crash.
    fn memory(dir: &Path) {
        let (mut d, _) = Durable::open(dir, &settings(), fresh, 1000).unwrap();
        for f in &frames(BEFORE) {
            OnState::on_state(&mut d, f, &heights()).unwrap();
        }
    }

    /// The learner after `records` records of a memory resumed once after
    /// `BEFORE` states: those states, the restart's resync, the next states.
    fn expected(records: u64) -> String {
        let all = frames(200);
        let records = usize::try_from(records).unwrap();
        let mut l = fresh();
        for f in &all[..records.min(BEFORE)] {
            l.on_state(f, &heights()).unwrap();
        }
        if records > BEFORE {
            l.resync();
            for f in &all[BEFORE..records - 1] {
                l.on_state(f, &heights()).unwrap();
            }
        }
        fingerprint(&l)
    }

    /// Where a faulty run stopped.
    #[derive(Debug, PartialEq, Eq, PartialOrd, Ord)]
    enum Stopped {
        /// Opening it (its snapshot, its new segment).
        Opening,
        /// Appending to the journal.
        Journal,
        /// Writing a snapshot while running (or the final one).
        Snapshot,
    }

    impl Stopped {
        /// A running learner's failure, by the file it names.
        fn at(message: &str) -> Stopped {
            if message.contains("snapshot.tmp") {
                Stopped::Snapshot
            } else {
                Stopped::Journal
            }
        }
    }

    /// Resumes a memory on `disk` and feeds it states until it fails;
    /// returns where, the error, and the records acknowledged by then.
    fn run_on(dir: &Path, disk: Arc<FailingDisk>) -> Option<(Stopped, String, u64)> {
        let all = frames(200);
        let lock = StateLock::acquire(dir).unwrap();
        let mut d = match Durable::open_on(disk, lock, &settings(), fresh, 40) {
            Ok((d, _)) => d,
            Err(err) => return Some((Stopped::Opening, err.to_string(), BEFORE as u64)),
        };
        for f in &all[BEFORE..] {
            if let Err(err) = OnState::on_state(&mut d, f, &heights()) {
                let acknowledged = d.acknowledged();
                // It stays stopped: nothing more is journalled or learnt.
                let before = fingerprint(d.learner());
                assert!(OnState::on_state(&mut d, f, &heights()).is_err());
                assert_eq!(fingerprint(d.learner()), before);
                assert_eq!(d.acknowledged(), acknowledged);
                let message = err.to_string();
                return Some((Stopped::at(&message), message, acknowledged));
            }
        }
        // The journal thread may fail after the last state was handed over:
        // close() reports it then (or the final snapshot's failure).
        let acknowledged = d.acknowledged();
        match d.close() {
            Ok(_) => None,
            Err(err) => {
                let message = err.to_string();
                Some((Stopped::at(&message), message, acknowledged))
            }
        }
    }

    #[test]
    fn a_full_or_read_only_disk_stops_the_learner_and_a_restart_loses_no_acknowledged_update() {
        // Where a whole faultless run writes its bytes: every run writes
        // the same bytes in the same order (one thread writes them all,
        // batches or not), so a budget inside a region fails that write.
        let budgets: Vec<u64> = {
            let dir = TempDir::new("fault-measure");
            memory(&dir.0);
            let disk = FailingDisk::new(Fault::Full, u64::MAX);
            assert_eq!(run_on(&dir.0, disk.clone()), None);
            let regions = disk.regions();
            let snapshots = regions
                .iter()
                .filter(|r| r.file.ends_with("snapshot.tmp"))
                .count();
            // The opening's, three while running, the final one.
            assert_eq!(snapshots, 5, "{regions:?}");
            regions
                .iter()
                .flat_map(|r| [r.start, r.start + (r.end - r.start) / 2, r.end - 1])
                .collect()
        };
        for (fault, os_error) in [
            (Fault::Full, "No space left on device"),
            (Fault::ReadOnly, "Read-only file system"),
        ] {
            let mut seen = std::collections::BTreeSet::new();
            for (k, &budget) in budgets.iter().enumerate() {
                let dir = TempDir::new(&format!("fault-{fault:?}-{k}"));
                memory(&dir.0);
                let (at, message, acknowledged) = run_on(&dir.0, FailingDisk::new(fault, budget))
                    .unwrap_or_else(|| panic!("{fault:?} after {budget} bytes did not fail"));
                // One message naming the file and the OS error.
                assert!(
                    message.contains(&dir.0.display().to_string())
                        && (message.contains("/log-") || message.contains("/snapshot.tmp"))
                        && message.contains(os_error),
                    "{fault:?} after {budget} bytes: {message}"
                );
                // The restart, on a disk with room again, has every
                // acknowledged record and is the learner that saw them.
                let (recovered, recovery) =
                    recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
                assert!(
                    recovery.records() >= acknowledged,
                    "{fault:?} after {budget} bytes ({at:?}): {recovery}, {acknowledged} acknowledged"
                );
                assert_same(&fingerprint(&recovered), &expected(recovery.records()));
                let (d, opened) = Durable::open(&dir.0, &settings(), fresh, 40).unwrap();
                assert!(matches!(opened, Opened::Resumed(r) if r.records() == recovery.records()));
                drop(d);
                seen.insert(at);
            }
            // The budgets reached every kind of write.
            assert_eq!(
                seen.into_iter().collect::<Vec<_>>(),
                [Stopped::Opening, Stopped::Journal, Stopped::Snapshot],
                "{fault:?}"
            );
        }
    }

    #[test]
    fn a_snapshot_that_reads_back_otherwise_never_replaces_the_last_good_one() {
        let dir = TempDir::new("fault-flip");
        memory(&dir.0);
        // The first bytes written are those of the snapshot at opening.
        let lock = StateLock::acquire(&dir.0).unwrap();
        let err = Durable::open_on(
            FailingDisk::new(Fault::Flip, 100),
            lock,
            &settings(),
            fresh,
            40,
        )
        .unwrap_err();
        assert!(
            err.to_string()
                .contains("snapshot.tmp: the snapshot reads back otherwise"),
            "{err}"
        );
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        assert_eq!(
            (recovery.records(), recovery.fell_back),
            (BEFORE as u64, None)
        );
        assert_same(&fingerprint(&recovered), &expected(BEFORE as u64));
    }
}
