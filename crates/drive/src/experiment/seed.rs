//! Seeds (`docs/spec/experiments.md` §5): every job gets its own generator for training
//! starts and the planner's exploration, and its own seed for the world's
//! latency emulation, both derived from the user's `--seed`, the experiment
//! and the job's coordinates. A job's results therefore do not depend on
//! which worker ran it or what ran before.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// What a derived seed is for; part of the derivation so the streams differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// Training starts and exploration (the learner side).
    Driver,
    /// `SimControl.latency_seed` (the world side).
    Latency,
}

/// One step of SplitMix64: a bijective mixer with good avalanche, enough to
/// turn structured inputs (small integers) into independent-looking seeds.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// FNV-1a of `name` (an experiment's, a sweep job's parameters): stable
/// across builds and platforms, unlike `std`'s hasher.
#[must_use]
pub fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The seed of `stream` for one job of `experiment` at coordinates `job`
/// (e.g. `[n_train, fold]` or `[target, repetition]`).
#[must_use]
pub fn derive(seed: u64, experiment: &str, job: &[u64], stream: Stream) -> u64 {
    let stream_tag = match stream {
        Stream::Driver => 1,
        Stream::Latency => 2,
    };
    [name_hash(experiment), stream_tag]
        .into_iter()
        .chain(job.iter().copied())
        .fold(mix(seed), |acc, part| mix(acc ^ mix(part)))
}

/// The job's generator for training starts and exploration.
#[must_use]
pub fn driver_rng(seed: u64, experiment: &str, job: &[u64]) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(derive(seed, experiment, job, Stream::Driver))
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    #[test]
    fn seeds_differ_by_every_coordinate_and_stream() {
        let base = derive(1, "push-task", &[3, 0], Stream::Driver);
        let others = [
            derive(2, "push-task", &[3, 0], Stream::Driver),
            derive(1, "move-to-target", &[3, 0], Stream::Driver),
            derive(1, "push-task", &[3, 1], Stream::Driver),
            derive(1, "push-task", &[0, 3], Stream::Driver),
            derive(1, "push-task", &[3, 0], Stream::Latency),
            derive(1, "push-task", &[3], Stream::Driver),
        ];
        for other in others {
            assert_ne!(base, other);
        }
        assert_eq!(base, derive(1, "push-task", &[3, 0], Stream::Driver));
    }

    #[test]
    fn the_generator_is_reproducible() {
        let a: Vec<f64> = (0..4)
            .map(|_| 0.0)
            .scan(driver_rng(7, "x", &[1]), |r, _| Some(r.random::<f64>()))
            .collect();
        let mut r = driver_rng(7, "x", &[1]);
        let b: Vec<f64> = (0..4).map(|_| r.random::<f64>()).collect();
        assert_eq!(a, b);
        assert!(a.iter().all(|u| (0.0..1.0).contains(u)));
    }
}
