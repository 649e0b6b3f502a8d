//! The weight stage of `full` refinement (`_native::refine`): 100 Adam steps on one NBRDF
//! (6 → w → w → 3, the widths `full` refines) against 4000 samples, the budget's sample
//! count. The PyTorch loop it replaced is timed against it, in the whole of `full`, by
//! `research/studies/refine_timing.py ../shared/data/rgl-measured/*.bsdf --against 1940711
//! --width 48 --weight-steps 1000` (research/performance.md).

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

use _native::refine::{Loss, WeightFit};

const SAMPLES: usize = 4000;
const STEPS: usize = 100;

fn steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("refine_weights");
    group.throughput(Throughput::Elements(STEPS as u64));
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(5));
    for width in [32, 48, 64] {
        let mut fit = WeightFit::synthetic(&[width, width], SAMPLES, Loss::L1, 7);
        group.bench_function(BenchmarkId::new("adam_steps_4000_samples", width), |b| {
            b.iter(|| fit.run(black_box(&[1e-4; STEPS]), None, 0).expect("valid steps"))
        });
    }
    group.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
