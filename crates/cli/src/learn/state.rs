//! The learner daemon's persistent memory (`pushlearn learn --state DIR`):
//! crash-safe snapshots plus an append-only, checksummed journal of every
//! world state handled since (`docs/reliability.md` has the whole design).
//!
//! * `DIR/snapshot`: the whole [`Learner`] after `S` journal records, written
//!   to `snapshot.tmp`, fsynced, atomically renamed over the old one and the
//!   directory fsynced; a checksum over its contents is verified on load.
//! * `DIR/log-S` (20 digits): the journal segment of the records `S+1, S+2,
//!   …` — each world state the learner handled (its bodies' poses, bit for
//!   bit) or a re-synchronisation. Replaying them through
//!   [`Learner::on_state`] repeats exactly what the live learner did, since
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

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

use learner::{Frame, Model, Observation};
use serde::{Deserialize, Serialize};

use super::{LearnError, Learner, OnState, Policy};
use pushlearn::wire::pb::client_message::Payload;

/// The snapshot's file name in the state directory.
pub const SNAPSHOT_FILE: &str = "snapshot";
const SNAPSHOT_TMP: &str = "snapshot.tmp";
const SEGMENT_PREFIX: &str = "log-";
const SNAPSHOT_MAGIC: &[u8; 8] = b"PLSNAP01";
const FORMAT_VERSION: u32 = 1;

/// Records between two snapshots by default: 5 minutes at 100 Hz. Recovery
/// replays at most this many records; a snapshot clones the learner once.
pub const DEFAULT_SNAPSHOT_EVERY: u64 = 30_000;

/// Record header: payload length (u32), CRC-32 of index and payload (u32),
/// index (u64), all little-endian.
const RECORD_HEADER: usize = 16;

/// Largest record payload accepted on reading: far above any world's state
/// (a frame is about 70 bytes per body); a larger length is damage.
const MAX_RECORD: usize = 1 << 20;

const ENTRY_STATE: u8 = 1;
const ENTRY_RESYNC: u8 = 2;

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
    #[error("cannot keep the learner's memory: {0}")]
    Writer(String),
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
}

impl Settings {
    fn differences(&self, stored: &Settings) -> Vec<String> {
        let mut out = Vec::new();
        let mut differ = |what: &str, stored: String, now: String| {
            if stored != now {
                out.push(format!("{what}: stored {stored}, now {now}"));
            }
        };
        differ("model", stored.model.clone(), self.model.clone());
        differ(
            "publish rate",
            stored.publish_rate_hz.to_string(),
            self.publish_rate_hz.to_string(),
        );
        differ(
            "policy",
            format!("{:?}", stored.policy),
            format!("{:?}", self.policy),
        );
        differ(
            "shadows",
            stored.shadows.to_string(),
            self.shadows.to_string(),
        );
        differ("seed", stored.seed.to_string(), self.seed.to_string());
        differ(
            "model options",
            stored.model_options.clone(),
            self.model_options.clone(),
        );
        out
    }
}

/// CRC-32 (IEEE 802.3, reflected, as zlib's `crc32`).
fn crc32(parts: &[&[u8]]) -> u32 {
    const TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
                k += 1;
            }
            table[i] = c;
            i += 1;
        }
        table
    };
    let mut crc = !0u32;
    for part in parts {
        for &byte in *part {
            crc = TABLE[((crc ^ u32::from(byte)) & 0xff) as usize] ^ (crc >> 8);
        }
    }
    !crc
}

/// One journal record's content.
#[derive(Clone, Debug, PartialEq)]
pub enum Entry {
    /// A world state handed to [`Learner::on_state`].
    State(Frame),
    /// [`Learner::resync`]: the connection to the world was lost or the
    /// daemon restarted.
    Resync,
}

/// Appends record `index` holding `entry` (a frame, or `None` for a resync).
fn encode_record(index: u64, frame: Option<&Frame>, out: &mut Vec<u8>) {
    let start = out.len();
    out.extend_from_slice(&[0; RECORD_HEADER]);
    match frame {
        None => out.push(ENTRY_RESYNC),
        Some(frame) => {
            out.push(ENTRY_STATE);
            // Bodies and names are bounded by the 16 MiB wire frame.
            out.extend_from_slice(&(frame.objects.len() as u32).to_le_bytes());
            for o in &frame.objects {
                out.extend_from_slice(&o.id.to_le_bytes());
                out.extend_from_slice(&(o.name.len() as u32).to_le_bytes());
                out.extend_from_slice(o.name.as_bytes());
                for v in o.position.iter().chain(&o.orientation) {
                    out.extend_from_slice(&v.to_bits().to_le_bytes());
                }
            }
        }
    }
    let payload_len = out.len() - start - RECORD_HEADER;
    let index_bytes = index.to_le_bytes();
    let crc = crc32(&[&index_bytes, &out[start + RECORD_HEADER..]]);
    out[start..start + 4].copy_from_slice(&(payload_len as u32).to_le_bytes());
    out[start + 4..start + 8].copy_from_slice(&crc.to_le_bytes());
    out[start + 8..start + 16].copy_from_slice(&index_bytes);
}

/// A little-endian reader over untrusted bytes.
struct Cursor<'a> {
    bytes: &'a [u8],
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        if self.bytes.len() < n {
            return None;
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Some(head)
    }

    fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        self.take(N)?.try_into().ok()
    }

    fn u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }

    fn f64(&mut self) -> Option<f64> {
        self.array().map(|b| f64::from_bits(u64::from_le_bytes(b)))
    }
}

/// Decodes a record's payload; `None` if it is not a well-formed entry.
/// Public for the fuzz target and its property-test mirror.
pub fn decode_entry(payload: &[u8]) -> Option<Entry> {
    let mut c = Cursor { bytes: payload };
    let entry = match c.array::<1>()?[0] {
        ENTRY_RESYNC => Entry::Resync,
        ENTRY_STATE => {
            let n = c.u32()? as usize;
            // Each body takes at least 64 bytes: a huge count is damage, and
            // must not reserve memory.
            if n > c.bytes.len() / 64 {
                return None;
            }
            let mut objects = Vec::with_capacity(n);
            for _ in 0..n {
                let id = c.u32()?;
                let len = c.u32()? as usize;
                let name = std::str::from_utf8(c.take(len)?).ok()?.to_owned();
                let mut v = [0.0; 7];
                for x in &mut v {
                    *x = c.f64()?;
                }
                objects.push(Observation {
                    name,
                    id,
                    position: [v[0], v[1], v[2]],
                    orientation: [v[3], v[4], v[5], v[6]],
                });
            }
            Entry::State(Frame { objects })
        }
        _ => return None,
    };
    c.bytes.is_empty().then_some(entry)
}

/// The outcome of reading a segment: its records in order, and where and why
/// reading stopped early, if it did.
#[derive(Debug, Default)]
pub struct SegmentRead {
    /// Index, entry and the byte offset just after the record.
    pub records: Vec<(u64, Entry, usize)>,
    /// Byte offset of the first bad record and why it is bad.
    pub bad: Option<(usize, String)>,
}

/// Reads journal records from `bytes` until the end or the first damaged
/// record. Public for the fuzz target and its property-test mirror.
pub fn read_records(bytes: &[u8]) -> SegmentRead {
    let mut read = SegmentRead::default();
    let mut at = 0;
    while at < bytes.len() {
        let rest = &bytes[at..];
        let bad = |reason: String| Some((at, reason));
        if rest.len() < RECORD_HEADER {
            read.bad = bad(format!(
                "a record header cut off after {} of {RECORD_HEADER} bytes",
                rest.len()
            ));
            break;
        }
        let word = |i: usize| u32::from_le_bytes([rest[i], rest[i + 1], rest[i + 2], rest[i + 3]]);
        let len = word(0) as usize;
        let crc = word(4);
        let index_bytes = &rest[8..16];
        let mut index = [0; 8];
        index.copy_from_slice(index_bytes);
        let index = u64::from_le_bytes(index);
        if len > MAX_RECORD {
            read.bad = bad(format!("a record length of {len} bytes (damage)"));
            break;
        }
        let Some(payload) = rest.get(RECORD_HEADER..RECORD_HEADER + len) else {
            read.bad = bad(format!(
                "record {index} cut off after {} of {len} bytes",
                rest.len() - RECORD_HEADER
            ));
            break;
        };
        if crc32(&[index_bytes, payload]) != crc {
            read.bad = bad(format!("record {index} fails its checksum"));
            break;
        }
        let Some(entry) = decode_entry(payload) else {
            read.bad = bad(format!(
                "record {index} has a valid checksum but no valid entry"
            ));
            break;
        };
        at += RECORD_HEADER + len;
        read.records.push((index, entry, at));
    }
    read
}

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

fn decode_snapshot<M: Model>(
    bytes: &[u8],
    path: &Path,
    dir: &Path,
    expected: &Settings,
) -> Result<(u64, Learner<M>), StateError> {
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
    let differences = expected.differences(&header.settings);
    if !differences.is_empty() {
        return Err(StateError::Mismatch {
            dir: dir.to_path_buf(),
            differences: differences.join("; "),
        });
    }
    let learner = serde_json::from_slice(c.bytes).map_err(|err| corrupt(&err.to_string()))?;
    Ok((header.records, learner))
}

fn segment_name(start: u64) -> String {
    format!("{SEGMENT_PREFIX}{start:020}")
}

/// The journal segments in `dir`, by start.
fn segments(dir: &Path) -> Result<Vec<(u64, PathBuf)>, StateError> {
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

fn sync_dir(dir: &Path) -> Result<(), StateError> {
    File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(io_error(dir))
}

/// Writes the snapshot crash-safely: temporary file, fsync, atomic rename,
/// fsync of the directory (so that the rename itself is durable).
fn write_snapshot<M: Model>(
    dir: &Path,
    records: u64,
    settings: &Settings,
    learner: &Learner<M>,
) -> Result<(), StateError> {
    let bytes = encode_snapshot(records, settings, learner)
        .map_err(|err| StateError::Writer(format!("cannot serialise the learner: {err}")))?;
    let tmp = dir.join(SNAPSHOT_TMP);
    let mut file = File::create(&tmp).map_err(io_error(&tmp))?;
    file.write_all(&bytes).map_err(io_error(&tmp))?;
    file.sync_all().map_err(io_error(&tmp))?;
    drop(file);
    let path = dir.join(SNAPSHOT_FILE);
    fs::rename(&tmp, &path).map_err(io_error(&path))?;
    sync_dir(dir)
}

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
            // state the replay leaves it in.
            if let Err(err) = learner.on_state(&frame) {
                tracing::debug!(%err, "replayed a state the learner refused");
            }
        }
    }
}

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
    /// Opens (creating if need be) the memory in `dir`: recovers the stored
    /// learner, or starts `fresh()` if there is none; cuts a damaged journal
    /// tail; writes a snapshot of the result, starts a new journal segment
    /// and, for a resumed learner, journals a re-synchronisation (the world
    /// has moved on while the daemon was down). Snapshots follow every
    /// `snapshot_every` records.
    ///
    /// # Errors
    /// See [`recover`]; I/O errors writing the directory.
    pub fn open(
        dir: &Path,
        settings: &Settings,
        fresh: impl FnOnce() -> Learner<M>,
        snapshot_every: u64,
    ) -> Result<(Self, Opened), StateError> {
        fs::create_dir_all(dir).map_err(io_error(dir))?;
        let (learner, opened) = match recover::<M>(dir, settings)? {
            None => (fresh(), Opened::Fresh),
            Some((learner, recovery)) => {
                if let Some(cut) = &recovery.cut {
                    tracing::warn!("damaged journal tail: {cut}");
                    cut_tail(cut)?;
                }
                (learner, Opened::Resumed(recovery))
            }
        };
        let records = match &opened {
            Opened::Fresh => 0,
            Opened::Resumed(recovery) => recovery.records(),
        };
        write_snapshot(dir, records, settings, &learner)?;
        for (_, old) in segments(dir)? {
            fs::remove_file(&old).map_err(io_error(&old))?;
        }
        let (segment, segment_path) = open_segment(dir, records)?;
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
                        dir: writer_dir,
                        settings,
                        segment,
                        segment_path,
                        shared: &shared,
                    };
                    if let Err(err) = writer.run(&rx) {
                        tracing::error!("the journal stopped: {err}");
                        *shared
                            .failure
                            .lock()
                            .unwrap_or_else(PoisonError::into_inner) = Some(err.to_string());
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
    fn on_state(&mut self, frame: &Frame) -> Result<Vec<Payload>, LearnError> {
        // Write-ahead: journalled before the learner acts on it, so that the
        // replay repeats even a state the learner refuses.
        self.append(Some(frame))?;
        let commands = self.learner.on_state(frame);
        self.maybe_snapshot()?;
        Ok(commands?)
    }

    fn resync(&mut self) -> Result<(), LearnError> {
        Ok(self.resync_journalled()?)
    }
}

fn open_segment(dir: &Path, start: u64) -> Result<(File, PathBuf), StateError> {
    let path = dir.join(segment_name(start));
    let file = OpenOptions::new()
        .create(true)
        .truncate(true)
        .write(true)
        .open(&path)
        .map_err(io_error(&path))?;
    sync_dir(dir)?;
    Ok((file, path))
}

/// Cuts the damaged record and everything after it off the journal.
fn cut_tail(cut: &Cut) -> Result<(), StateError> {
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

/// The journal thread.
struct Writer<'a> {
    dir: PathBuf,
    settings: Settings,
    segment: File,
    segment_path: PathBuf,
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

    /// Starts the segment after `records`, writes the snapshot of them, and
    /// removes the segments it covers. A crash anywhere in between leaves a
    /// directory that recovers to the same learner.
    fn snapshot<M: Model>(&mut self, records: u64, learner: &Learner<M>) -> Result<(), StateError> {
        let old = segments(&self.dir)?;
        (self.segment, self.segment_path) = open_segment(&self.dir, records)?;
        write_snapshot(&self.dir, records, &self.settings, learner)?;
        for (start, path) in old {
            if start < records {
                fs::remove_file(&path).map_err(io_error(&path))?;
            }
        }
        tracing::debug!(records, "snapshot written");
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use learner::{Action, GateConfig, GateModel, ObjectState};
    use proptest::prelude::*;

    use super::*;
    use crate::experiment::driver::test_support::frame;

    /// A directory of its own under the system's temporary directory,
    /// removed when dropped.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(name: &str) -> TempDir {
            let dir =
                std::env::temp_dir().join(format!("pushlearn-state-{}-{name}", std::process::id()));
            let _ = fs::remove_dir_all(&dir);
            TempDir(dir)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    const GOAL: ObjectState = ObjectState {
        x: 0.1,
        y: 0.5,
        theta: 0.3,
    };

    fn settings() -> Settings {
        Settings {
            model: "gate".into(),
            publish_rate_hz: 100,
            policy: Policy::Target(GOAL),
            shadows: true,
            seed: 7,
            model_options: "eta 0".into(),
        }
    }

    fn fresh() -> Learner<GateModel> {
        Learner::new(
            GateModel::new(GateConfig::hz100()),
            Policy::Target(GOAL),
            true,
            7,
        )
    }

    /// The actuator sweeps towards the block and pushes it: the model learns
    /// and the planner explores (drawing from the generator).
    fn frames(n: usize) -> Vec<Frame> {
        (0..n)
            .map(|k| {
                let t = k as f64;
                let ax = 0.02 * (t * 0.3).sin();
                let ay = 0.004 * (t % 80.0);
                let by = (ay + 0.06).max(0.25);
                frame(
                    (ax, ay),
                    &[(learner::BLUE_ID, ObjectState::new(0.0, by, 0.002 * t))],
                )
            })
            .collect()
    }

    /// Everything the learner holds, bit for bit.
    fn fingerprint(l: &Learner<GateModel>) -> String {
        serde_json::to_string(l).unwrap()
    }

    /// Panics with the first difference (the whole learner is too long to
    /// print).
    fn assert_same(a: &str, b: &str) {
        if let Some(i) = a.bytes().zip(b.bytes()).position(|(x, y)| x != y) {
            let around = |s: &str| s[i.saturating_sub(150)..(i + 60).min(s.len())].to_owned();
            panic!("learners differ at byte {i}:\n{}\n{}", around(a), around(b));
        }
        assert_eq!(a.len(), b.len());
    }

    fn predictions(l: &Learner<GateModel>, probe: &Frame) -> learner::Poses {
        let world = l.model().parse(probe).unwrap();
        GateModel::poses(&l.model().predict(&world, Action::new(0.1, 0.4)))
    }

    #[test]
    fn crc32_is_the_ieee_checksum() {
        assert_eq!(crc32(&[b"123456789"]), 0xCBF4_3926);
        assert_eq!(crc32(&[b"1234", b"56789"]), 0xCBF4_3926);
    }

    #[test]
    fn records_keep_every_bit_of_a_frame() {
        let mut f = frames(3).pop().unwrap();
        f.objects[0].position[0] = -0.0;
        f.objects[0].orientation[1] = f64::from_bits(0x7ff8_0000_0000_1234);
        f.objects[0].name = "Aktuator-ä".into();
        let mut bytes = Vec::new();
        encode_record(41, Some(&f), &mut bytes);
        encode_record(42, None, &mut bytes);
        let read = read_records(&bytes);
        assert_eq!(read.bad, None);
        assert_eq!(read.records.len(), 2);
        let (index, Entry::State(back), _) = &read.records[0] else {
            panic!("{:?}", read.records[0]);
        };
        assert_eq!(*index, 41);
        let bits = |f: &Frame| -> Vec<u64> {
            f.objects
                .iter()
                .flat_map(|o| o.position.iter().chain(&o.orientation).map(|v| v.to_bits()))
                .collect()
        };
        assert_eq!(bits(back), bits(&f));
        assert_eq!(back.objects[0].name, "Aktuator-ä");
        assert_eq!(read.records[1].0, 42);
        assert_eq!(read.records[1].1, Entry::Resync);
        assert_eq!(read.records[1].2, bytes.len());
    }

    #[test]
    fn a_restart_resumes_a_bit_identical_learner_across_snapshots() {
        let dir = TempDir::new("resume");
        let all = frames(130);
        let mut reference = fresh();
        {
            let (mut d, opened) = Durable::open(&dir.0, &settings(), fresh, 25).unwrap();
            assert_eq!(opened, Opened::Fresh);
            for f in &all[..90] {
                let live = OnState::on_state(&mut d, f).unwrap();
                assert_eq!(live, reference.on_state(f).unwrap());
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
                OnState::on_state(&mut d, f).unwrap(),
                reference.on_state(f).unwrap()
            );
        }
        assert_eq!(d.close().unwrap(), 91 + 40);
        let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings()).unwrap().unwrap();
        // close() wrote a final snapshot: nothing left to replay.
        assert_eq!((recovery.snapshot_records, recovery.replayed), (131, 0));
        assert_same(&fingerprint(&recovered), &fingerprint(&reference));
        // Only the current segment is left.
        assert_eq!(segments(&dir.0).unwrap().len(), 1);
    }

    /// Journals `n` frames and drops the daemon; returns the segment.
    fn journal(dir: &Path, n: usize) -> PathBuf {
        let (mut d, _) = Durable::open(dir, &settings(), fresh, 1000).unwrap();
        for f in &frames(n) {
            OnState::on_state(&mut d, f).unwrap();
        }
        drop(d);
        let all = segments(dir).unwrap();
        assert_eq!(all.len(), 1);
        all[0].1.clone()
    }

    fn reference(n: usize) -> String {
        let mut l = fresh();
        for f in &frames(n) {
            l.on_state(f).unwrap();
        }
        fingerprint(&l)
    }

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

    proptest! {
        /// The journal reader takes any bytes without panicking, and never
        /// returns a record it did not verify (the same code path as the
        /// `journal` fuzz target).
        #[test]
        fn any_bytes_read_as_a_journal_are_safe(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let read = read_records(&bytes);
            let mut end = 0;
            for (_, _, e) in &read.records {
                prop_assert!(*e > end && *e <= bytes.len());
                end = *e;
            }
            match read.bad {
                Some((offset, _)) => prop_assert_eq!(offset, end),
                None => prop_assert_eq!(end, bytes.len()),
            }
        }

        #[test]
        fn any_frame_survives_the_journal(
            names in proptest::collection::vec("[a-zA-Z_]{0,12}", 0..5),
            values in proptest::collection::vec(any::<u64>(), 35),
            index in any::<u64>(),
        ) {
            let objects = names.iter().enumerate().map(|(i, name)| Observation {
                name: name.clone(),
                id: i as u32,
                position: [0, 1, 2].map(|k| f64::from_bits(values[7 * i + k])),
                orientation: [3, 4, 5, 6].map(|k| f64::from_bits(values[7 * i + k])),
            }).collect();
            let f = Frame { objects };
            let mut bytes = Vec::new();
            encode_record(index, Some(&f), &mut bytes);
            let read = read_records(&bytes);
            prop_assert!(read.bad.is_none());
            let Entry::State(back) = &read.records[0].1 else { panic!("not a state") };
            prop_assert_eq!(format!("{:?}", back.objects.iter().map(|o| (&o.name, o.id, o.position.map(f64::to_bits), o.orientation.map(f64::to_bits))).collect::<Vec<_>>()),
                format!("{:?}", f.objects.iter().map(|o| (&o.name, o.id, o.position.map(f64::to_bits), o.orientation.map(f64::to_bits))).collect::<Vec<_>>()));
        }
    }
}
