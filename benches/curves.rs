//! The paper's period curves by shooting and continuation: Fig. 1c (71 points, γ = 10 … 1e8 at
//! ξ = 0.7, ε = 0.72) and Fig. 1b (51 points, ε = 1.2 down towards ε_c at γ = 1e3, ξ = 0.7),
//! each the whole scene (`stickslip::engine::run` on data/scenes/fig1c.json and fig1b.json:
//! Hopf analysis, shooting at the start, continuation). Targets (issue #4): Fig. 1c under 2 s,
//! Fig. 1b under 1 s on 2 cores.
//!
//! Run: `cargo bench --bench curves` (results in docs/benchmarks.md).

use criterion::{Criterion, SamplingMode};
use std::hint::black_box;
use std::time::Duration;
use stickslip::{engine, scene};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("period_curves");
    group
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for name in ["fig1c", "fig1b"] {
        let path = format!("{}/data/scenes/{name}.json", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).expect("scene file");
        let parsed = scene::parse(&text, &path).expect("valid scene");
        group.bench_function(name, |b| {
            b.iter(|| {
                let report = engine::run(black_box(&parsed), engine::RunOptions::default())
                    .expect("the scene runs");
                assert!(report.continuation.as_ref().is_some_and(|c| c.points.len() >= 50));
                report
            })
        });
    }
    group.finish();
}

criterion::criterion_group!(benches, bench);
criterion::criterion_main!(benches);
