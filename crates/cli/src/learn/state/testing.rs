//! What the journal's tests share: a temporary directory, one learner's
//! settings and inputs, and bit-for-bit comparisons.

use std::fs;
use std::path::{Path, PathBuf};

use learner::{Action, Frame, GateConfig, GateModel, Model, ObjectState};

use super::segment::segments;
use super::{Durable, Settings};
use crate::experiment::driver::test_support::frame;
pub(super) use crate::learn::tests::heights;
use crate::learn::{Learner, OnState, Policy};

/// A directory of its own under the system's temporary directory,
/// removed when dropped.
pub(super) struct TempDir(pub(super) PathBuf);

impl TempDir {
    pub(super) fn new(name: &str) -> TempDir {
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

pub(super) const GOAL: ObjectState = ObjectState {
    x: 0.1,
    y: 0.5,
    theta: 0.3,
};

pub(super) fn settings() -> Settings {
    Settings {
        model: "gate".into(),
        publish_rate_hz: 100,
        policy: Policy::Target(GOAL),
        shadows: true,
        seed: 7,
        model_options: "eta 0".into(),
        episodes: super::EpisodeSettings::default(),
    }
}

pub(super) fn fresh() -> Learner<GateModel> {
    Learner::new(
        GateModel::new(GateConfig::hz100()),
        Policy::Target(GOAL),
        true,
        7,
    )
}

/// The actuator sweeps towards the block and pushes it: the model learns
/// and the planner explores (drawing from the generator).
pub(super) fn frames(n: usize) -> Vec<Frame> {
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
pub(super) fn fingerprint(l: &Learner<GateModel>) -> String {
    serde_json::to_string(l).unwrap()
}

/// Panics with the first difference (the whole learner is too long to
/// print).
pub(super) fn assert_same(a: &str, b: &str) {
    if let Some(i) = a.bytes().zip(b.bytes()).position(|(x, y)| x != y) {
        let around = |s: &str| s[i.saturating_sub(150)..(i + 60).min(s.len())].to_owned();
        panic!("learners differ at byte {i}:\n{}\n{}", around(a), around(b));
    }
    assert_eq!(a.len(), b.len());
}

pub(super) fn predictions(l: &Learner<GateModel>, probe: &Frame) -> learner::Poses {
    let world = l.model().parse(probe).unwrap();
    GateModel::poses(&l.model().predict(&world, Action::new(0.1, 0.4)))
}

/// Journals `n` frames and drops the daemon; returns the segment.
pub(super) fn journal(dir: &Path, n: usize) -> PathBuf {
    let (mut d, _) = Durable::open(dir, &settings(), fresh, 1000).unwrap();
    for f in &frames(n) {
        OnState::on_state(&mut d, f, &heights()).unwrap();
    }
    drop(d);
    let all = segments(dir).unwrap();
    assert_eq!(all.len(), 1);
    all[0].1.clone()
}

pub(super) fn reference(n: usize) -> String {
    let mut l = fresh();
    for f in &frames(n) {
        l.on_state(f, &heights()).unwrap();
    }
    fingerprint(&l)
}

/// `ENOSPC` and `EROFS` (the same numbers on Linux and macOS).
pub(super) const ENOSPC: i32 = 28;
pub(super) const EROFS: i32 = 30;

/// What a [`FailingDisk`] does once its budget is spent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Fault {
    /// Writes fail with ENOSPC; files can still be created.
    Full,
    /// Writes and creating files fail with EROFS.
    ReadOnly,
    /// Nothing fails, but the byte at the budget is written flipped: a disk
    /// that lies.
    Flip,
}

/// Real files under a byte budget shared by all of them: the write that
/// crosses it is short, as the kernel's is, and the next one fails.
pub(super) struct FailingDisk {
    fault: Fault,
    budget: u64,
    written: std::sync::Arc<std::sync::atomic::AtomicU64>,
    /// Each file's runs of bytes, in the order written.
    regions: std::sync::Arc<std::sync::Mutex<Vec<Region>>>,
}

/// Bytes `start..end` of everything a [`FailingDisk`] wrote went to `file`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Region {
    pub(super) file: PathBuf,
    pub(super) start: u64,
    pub(super) end: u64,
}

impl FailingDisk {
    pub(super) fn new(fault: Fault, budget: u64) -> std::sync::Arc<FailingDisk> {
        std::sync::Arc::new(FailingDisk {
            fault,
            budget,
            written: std::sync::Arc::default(),
            regions: std::sync::Arc::default(),
        })
    }

    /// Where the bytes went: consecutive writes to one file are one region.
    pub(super) fn regions(&self) -> Vec<Region> {
        self.regions
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone()
    }

    /// Bytes written so far, over every file.
    pub(super) fn written(&self) -> u64 {
        self.written.load(std::sync::atomic::Ordering::SeqCst)
    }

    fn errno(&self) -> i32 {
        match self.fault {
            Fault::ReadOnly => EROFS,
            Fault::Full | Fault::Flip => ENOSPC,
        }
    }
}

impl super::storage::Storage for FailingDisk {
    fn create(&self, path: &Path) -> std::io::Result<Box<dyn super::storage::StorageFile>> {
        if self.fault == Fault::ReadOnly && self.written() >= self.budget {
            return Err(std::io::Error::from_raw_os_error(self.errno()));
        }
        let file = fs::File::create(path)?;
        Ok(Box::new(FailingFile {
            file,
            path: path.to_path_buf(),
            regions: self.regions.clone(),
            fault: self.fault,
            budget: self.budget,
            written: self.written.clone(),
            errno: self.errno(),
        }))
    }
}

struct FailingFile {
    file: fs::File,
    path: PathBuf,
    regions: std::sync::Arc<std::sync::Mutex<Vec<Region>>>,
    fault: Fault,
    budget: u64,
    written: std::sync::Arc<std::sync::atomic::AtomicU64>,
    errno: i32,
}

impl std::io::Write for FailingFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        use std::sync::atomic::Ordering;
        let written = self.written.load(Ordering::SeqCst);
        if self.fault == Fault::Flip {
            let mut bytes = buf.to_vec();
            if let Some(at) = self.budget.checked_sub(written) {
                if let Some(byte) = usize::try_from(at).ok().and_then(|at| bytes.get_mut(at)) {
                    *byte ^= 0x01;
                }
            }
            let n = self.file.write(&bytes)?;
            self.wrote(n);
            return Ok(n);
        }
        let left = self.budget.saturating_sub(written);
        if left == 0 && !buf.is_empty() {
            return Err(std::io::Error::from_raw_os_error(self.errno));
        }
        let take = buf.len().min(usize::try_from(left).unwrap_or(usize::MAX));
        let n = self.file.write(&buf[..take])?;
        self.wrote(n);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl FailingFile {
    fn wrote(&self, n: usize) {
        let n = n as u64;
        let start = self
            .written
            .fetch_add(n, std::sync::atomic::Ordering::SeqCst);
        let mut regions = self
            .regions
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        match regions.last_mut() {
            Some(last) if last.file == self.path && last.end == start => last.end += n,
            _ => regions.push(Region {
                file: self.path.clone(),
                start,
                end: start + n,
            }),
        }
    }
}

impl super::storage::StorageFile for FailingFile {
    fn sync_data(&mut self) -> std::io::Result<()> {
        self.file.sync_data()
    }

    fn sync_all(&mut self) -> std::io::Result<()> {
        self.file.sync_all()
    }
}
