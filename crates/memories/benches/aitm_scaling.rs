//! How AITM query and update time grow with the node count (docs/spec/aitm.md §7;
//! issue "memory that does not slow down"): maps of 1 k, 10 k, 100 k and
//! 1 M nodes, searched through the spatial index, and the brute-force scan
//! beside it up to 100 k.
//!
//! `cargo bench -p memories --bench aitm_scaling` prints a table and writes
//! `target/aitm_scaling.csv`; `… -- runs` (or `uniform`) times one shape
//! only and writes `target/aitm_scaling-runs.csv` (or `-uniform`). Not
//! criterion: an update grows the map, so each timed batch runs on a fresh
//! copy of the map (the copy is not timed), and building a million-node map
//! once is all the setup it needs.
//!
//! Inputs are 8-dimensional like the object predictors' φ, outputs
//! 3-dimensional (BESTTWO), on the 3-decimal grid:
//! * `uniform`: every component uniform in [−1, 1] (the hard case for any
//!   spatial index: no structure at all);
//! * `runs`: points along random walks of 150 steps (as the inputs of push
//!   runs lie along trajectories), starting uniform in [−1, 1]⁸.
//!
//! Queries come in three kinds, timed separately because an exact search
//! costs very different amounts for them:
//! * `along`: the training inputs of whole stored walks, in order, each
//!   moved by one walk step (±0.005 per component): the states of a run like
//!   one the map has learnt, asked one after the other, which is how the
//!   learner asks (one state of a run per message);
//! * `near`: the same kind of probe, but each near a training input drawn
//!   at random, so that consecutive queries touch unrelated parts of the
//!   map (nothing of the previous query's path is left in the caches);
//! * `far`: the inputs of new, unseen walks (for `runs`, far from every
//!   stored input: the winner and second winner lie at a large distance, so
//!   many boxes intersect the ball an exact search must examine).
//!
//! Updates are the samples of new walks, as a learner meets new runs.
//! Every timed pass uses probes it has not seen.
use std::hint::black_box;
use std::io::Write;
use std::time::Instant;

use memories::aitm::{Aitm, AitmConfig, QueryMode};

const SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];
const QUERIES: usize = 2_000;
const UPDATES_PER_BATCH: usize = 100;
/// Steps of one walk of the `runs` shape (a push run's messages).
const WALK: usize = 150;

#[path = "support/rng.rs"]
mod rng;
use rng::Rng;

#[derive(Clone, Copy, PartialEq)]
enum Shape {
    Uniform,
    Runs,
}

/// An endless stream of (input, output) samples of one shape.
struct Samples {
    shape: Shape,
    rng: Rng,
    walk: [f64; 8],
    step: usize,
}

impl Samples {
    fn new(shape: Shape, seed: u64) -> Self {
        Self {
            shape,
            rng: Rng(seed),
            walk: [0.0; 8],
            step: 0,
        }
    }

    fn input(&mut self) -> [f64; 8] {
        let mut x = [0.0; 8];
        match self.shape {
            Shape::Uniform => x.iter_mut().for_each(|v| *v = self.rng.grid(1000)),
            Shape::Runs => {
                if self.step.is_multiple_of(WALK) {
                    self.walk.iter_mut().for_each(|v| *v = self.rng.grid(1000));
                }
                self.step += 1;
                for v in &mut self.walk {
                    *v = ((*v + self.rng.grid(5)) * 1000.0).round() / 1000.0;
                }
                x = self.walk;
            }
        }
        x
    }

    fn sample(&mut self) -> ([f64; 8], [f64; 3]) {
        let x = self.input();
        let y = [self.rng.grid(40), self.rng.grid(40), self.rng.grid(40)];
        (x, y)
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Mean ns per query over the second half of the probes. The first half,
/// of the same kind but other points, runs untimed first, so that every size
/// is timed with warm code and branch predictors, but not with the timed
/// probes' own paths already in the caches.
fn time_queries(map: &Aitm, probes: &[[f64; 8]]) -> f64 {
    let (warm_up, timed) = probes.split_at(probes.len() / 2);
    for p in warm_up {
        black_box(map.query(black_box(p)));
    }
    let start = Instant::now();
    for p in timed {
        black_box(map.query(black_box(p)));
    }
    start.elapsed().as_nanos() as f64 / timed.len() as f64
}

/// Median over batches of the mean ns per update, each batch on a copy.
fn time_updates(map: &Aitm, samples: &mut Samples, batches: usize) -> f64 {
    let mut per_batch = Vec::with_capacity(batches);
    for _ in 0..batches {
        let mut copy = map.clone();
        // A clone has no spare capacity: the first growth of each of its
        // arrays (rows, tree nodes, leaf slots) reallocates all of it, which
        // is the clone's cost, not an update's. An untimed batch first.
        for _ in 0..UPDATES_PER_BATCH {
            let (x, y) = samples.sample();
            copy.update(&x, &y);
        }
        let batch: Vec<_> = (0..UPDATES_PER_BATCH).map(|_| samples.sample()).collect();
        let start = Instant::now();
        for (x, y) in &batch {
            copy.update(black_box(x), black_box(y));
        }
        per_batch.push(start.elapsed().as_nanos() as f64 / UPDATES_PER_BATCH as f64);
    }
    median(per_batch)
}

/// `x` moved by one walk step.
fn step_from(mut x: [f64; 8], rng: &mut Rng) -> [f64; 8] {
    for v in &mut x {
        *v = ((*v + rng.grid(5)) * 1000.0).round() / 1000.0;
    }
    x
}

/// `2 · QUERIES` probes near training inputs drawn at random from `seen`.
fn near_probes(seen: &[[f64; 8]], rng: &mut Rng) -> Vec<[f64; 8]> {
    (0..2 * QUERIES)
        .map(|_| step_from(seen[(rng.next() % seen.len() as u64) as usize], rng))
        .collect()
}

/// `2 · QUERIES` probes along whole training walks drawn at random from `seen`
/// (the training samples in order: walk `k` is `seen[150k..150k + 150]`).
fn along_probes(seen: &[[f64; 8]], rng: &mut Rng) -> Vec<[f64; 8]> {
    let walks = seen.len() / WALK;
    let mut probes = Vec::with_capacity(2 * QUERIES + WALK);
    while probes.len() < 2 * QUERIES {
        let start = (rng.next() % walks as u64) as usize * WALK;
        for &x in &seen[start..start + WALK] {
            probes.push(step_from(x, rng));
        }
    }
    probes.truncate(2 * QUERIES);
    probes
}

fn main() -> std::io::Result<()> {
    // Cargo passes `--bench` to a bench without the test harness.
    let only = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    if let Some(shape) = only.as_deref().filter(|s| !["runs", "uniform"].contains(s)) {
        eprintln!("unknown shape {shape:?}: expected runs or uniform");
        std::process::exit(2);
    }
    let mut csv =
        String::from("shape,nodes,search,along_query_ns,near_query_ns,far_query_ns,update_ns\n");
    println!("shape    nodes      search  along µs  near µs   far µs  update µs");
    for (shape, name) in [(Shape::Runs, "runs"), (Shape::Uniform, "uniform")] {
        if only.as_ref().is_some_and(|o| o != name) {
            continue;
        }
        let mut map = Aitm::new(AitmConfig::regressor(QueryMode::BestTwo), 8, 3);
        let mut train = Samples::new(shape, 1);
        let mut fresh = Samples::new(shape, 2);
        let mut jitter = Rng(3);
        let mut seen: Vec<[f64; 8]> = Vec::new();
        let mut first = None;
        for n in SIZES {
            while map.len() < n {
                let (x, y) = train.sample();
                seen.push(x);
                map.update(&x, &y);
            }
            let batches = if n >= 1_000_000 { 5 } else { 20 };
            let mut searches = vec![("index", usize::MIN)];
            if n <= 100_000 {
                searches.push(("scan", usize::MAX));
            }
            for (search, threshold) in searches {
                let mut m = map.clone();
                m.set_index_min(threshold);
                let along = time_queries(&m, &along_probes(&seen, &mut jitter));
                let near = time_queries(&m, &near_probes(&seen, &mut jitter));
                let far_probes: Vec<[f64; 8]> = (0..2 * QUERIES).map(|_| fresh.input()).collect();
                let far = time_queries(&m, &far_probes);
                let u = time_updates(&m, &mut fresh, batches);
                println!(
                    "{name:8} {:>9} {search:6} {:8.2} {:8.2} {:8.2} {:10.2}",
                    m.len(),
                    along / 1e3,
                    near / 1e3,
                    far / 1e3,
                    u / 1e3
                );
                csv.push_str(&format!(
                    "{name},{},{search},{along:.0},{near:.0},{far:.0},{u:.0}\n",
                    m.len()
                ));
                if search == "index" {
                    match first {
                        None => first = Some((along, near, far, u)),
                        Some((a1, n1, f1, u1)) if n == SIZES[3] => println!(
                            "{name}: 1 M / 1 k ratio: along query {:.2}, near query {:.2}, \
                             far query {:.2}, update {:.2}",
                            along / a1,
                            near / n1,
                            far / f1,
                            u / u1
                        ),
                        Some(_) => {}
                    }
                }
            }
        }
    }
    let file = match &only {
        Some(shape) => format!("aitm_scaling-{shape}.csv"),
        None => "aitm_scaling.csv".to_owned(),
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../target")
        .join(file);
    std::fs::File::create(&path)?.write_all(csv.as_bytes())?;
    println!("wrote {}", path.display());
    Ok(())
}
