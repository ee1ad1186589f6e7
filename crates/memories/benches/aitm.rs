//! AITM update and query time against node count (docs/spec/aitm.md §7: the original
//! is linear in the node count; ≈ 1100 nodes must fit a 0.02 s budget).
//!
//! Maps are grown with random inputs on a 3-decimal grid until they hold the
//! wanted number of nodes. Queries probe random grid points. Updates are
//! measured in steady state: samples that repeat stored nodes with their
//! outputs (full ranking, edge update, pruning; no growth), so the map size
//! stays put across iterations.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use memories::aitm::{Aitm, AitmConfig, QueryMode};

#[path = "support/rng.rs"]
mod rng;
use rng::Rng;

fn grown(mode: QueryMode, dim: usize, nodes: usize, rng: &mut Rng) -> Aitm {
    let mut map = Aitm::new(AitmConfig::regressor(mode), dim, 3);
    while map.len() < nodes {
        let x = rng.vec(dim, 500);
        let y = rng.vec(3, 50);
        map.update(&x, &y);
    }
    map
}

fn bench(c: &mut Criterion) {
    let mut rng = Rng(0x5eed);
    for dim in [8usize, 10] {
        for nodes in [100usize, 1_000, 10_000] {
            let map = grown(QueryMode::BestTwo, dim, nodes, &mut rng);
            let probes: Vec<Vec<f64>> = (0..256).map(|_| rng.vec(dim, 500)).collect();
            let label = format!("{dim}d/{nodes}");

            let mut group = c.benchmark_group("aitm_query");
            for mode in [QueryMode::Winner, QueryMode::BestTwo] {
                let mut i = 0;
                group.bench_function(BenchmarkId::new(format!("{mode:?}"), &label), |b| {
                    b.iter(|| {
                        i = (i + 1) % probes.len();
                        black_box(map.query_mode(black_box(&probes[i]), mode))
                    })
                });
            }
            group.finish();

            let samples: Vec<(Vec<f64>, Vec<f64>)> = map
                .nodes()
                .step_by((nodes / 256).max(1))
                .map(|v| (v.w_in.to_vec(), v.w_out.to_vec()))
                .collect();
            let mut steady = map.clone();
            let mut i = 0;
            c.bench_function(&format!("aitm_update/BestTwo/{label}"), |b| {
                b.iter(|| {
                    i = (i + 1) % samples.len();
                    let (x, y) = &samples[i];
                    steady.update(black_box(x), black_box(y));
                })
            });
            eprintln!(
                "{label}: after the update benchmark {} nodes (started with {})",
                steady.len(),
                map.len()
            );
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
