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
