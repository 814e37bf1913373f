//! Speed of the plant simulator: one eq4 single jump at rtol 1e-8, and a 2,000-jump sweep on
//! two threads (targets on the 2-core machine: < 60 us and < 0.3 s).

use criterion::{Criterion, criterion_group, criterion_main};
use sandjumper_sim::*;
use std::hint::black_box;

fn one_jump(c: &mut Criterion) {
    let params = Params::preset(0.57).unwrap();
    let spec = JumpSpec {
        kind: JumpKind::Single,
        freq_hz: 10.0,
        tau_s: 0.0,
        model: ModelName::Eq4,
    };
    let opts = SimOptions {
        rtol: 1e-8,
        ..SimOptions::default()
    };
    c.bench_function("eq4 single jump, rtol 1e-8", |b| {
        b.iter(|| simulate_jump(black_box(&params), black_box(&spec), &opts).unwrap())
    });
}

fn sweep(c: &mut Criterion) {
    let params = Params::preset(0.57).unwrap();
    let opts = SimOptions {
        rtol: 1e-8,
        ..SimOptions::default()
    };
    // 2,000 jumps: 4 models x 2 kinds x 250 frequencies from 4 to 20 Hz... on two threads.
    let mut specs = Vec::with_capacity(2000);
    for model in ModelName::ALL {
        for kind in [JumpKind::Single, JumpKind::Stutter] {
            for i in 0..250 {
                let freq_hz = 4.0 + 16.0 * i as f64 / 249.0;
                specs.push(JumpSpec {
                    kind,
                    freq_hz,
                    tau_s: 0.0,
                    model,
                });
            }
        }
    }
    assert_eq!(specs.len(), 2000);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("sweep");
    group.sample_size(10);
    group.bench_function("2000 jumps, 2 threads", |b| {
        b.iter(|| pool.install(|| simulate_many(black_box(&params), &specs, &opts)))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    // No HTML plots: criterion's plotters backend needs system fonts a fresh machine lacks.
    config = Criterion::default().without_plots();
    targets = one_jump, sweep
}
criterion_main!(benches);
